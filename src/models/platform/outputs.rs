//! The platform's outputs by cache block, each computed on its first read after a change:
//! the legs, the pose, the legs' other values, the values read off the state, the actuators'
//! states, the input-dependent forces, `kappa`; and what makes them stale.

use super::PlatformModel;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::LEG_COUNT;
use crate::simulation::outputs::{
    ActuatorStateOutputs, LegLoadOutputs, PoseOutputs, StateOutputs, condition_number,
};
use crate::simulation::state::{actuator_forces, body, power_unit_outputs, supply_flow};
use crate::simulation::{LegOutputs, SimulationState};

/// `f()`, computed out of line: a block's values, whose accessor stays small enough to inline
/// into the fill of each of its variables.
#[inline(never)]
fn out_of_line<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// The condition number of the current state's leg arrangement (a cache block of its own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Condition {
    pub kappa: f64,
}

/// The actuators' and the joints' forces alone (the fields of `PlatformOutputs` of the same
/// names): they depend on the inputs, so they are a cache block of their own.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InputDependentOutputs {
    pub joint_force: [nalgebra::Vector3<f64>; LEG_COUNT],
    pub actuator_force: [f64; LEG_COUNT],
    /// `Qsupply` (it depends on the input `pS`).
    pub supply_flow: f64,
    /// `supply.pressure`, `supply.pumpFlow`, `supply.reliefFlow`, `accumulator.oilVolume` (they
    /// depend on the inputs `pS` and `pump.speed`).
    pub power_unit: [f64; 4],
}

impl PlatformModel {
    /// The pose of the current state, computed on the first read after a change.
    #[inline]
    pub(super) fn pose(&mut self) -> &PoseOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.pose.get_or_insert_with(|| out_of_line(|| match simulation {
            Some((sim, _)) => PoseOutputs::of(&sim.body_state()),
            None => PoseOutputs::of(&parameters.initial_state()),
        }))
    }

    /// The energy, the end stops' forces and the joint angles of the current state, computed on
    /// their first read after a change.
    #[inline]
    pub(super) fn leg_loads(&mut self) -> &LegLoadOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.leg_loads.get_or_insert_with(|| out_of_line(|| match simulation {
            Some((sim, _)) => LegLoadOutputs::at(&sim.form, &sim.state),
            None => LegLoadOutputs::at(&parameters.special_form(), &parameters.initial_simulation_state()),
        }))
    }

    /// The values read off the current state, on their first read after a change.
    #[inline]
    pub(super) fn state_values(&mut self) -> &StateOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.state_values.get_or_insert_with(|| out_of_line(|| match simulation {
            Some((sim, _)) => StateOutputs::of(&sim.state),
            None => StateOutputs::of(&parameters.initial_simulation_state()),
        }))
    }

    /// The actuators' and the joints' forces of the current state and inputs, computed on the
    /// first read after a change.
    #[inline]
    pub(super) fn input_dependent_outputs(&mut self) -> &InputDependentOutputs {
        let inputs = self.inputs();
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.input_dependent.get_or_insert_with(|| {
            let forces = |form: &SpecialForm, y: &SimulationState| {
                let actuator_force = actuator_forces(form, y, &inputs);
                InputDependentOutputs {
                    joint_force: form.joint_forces(body(y), &actuator_force),
                    actuator_force,
                    supply_flow: supply_flow(form, y),
                    power_unit: power_unit_outputs(form, y, form.supply()),
                }
            };
            match simulation {
                Some((sim, _)) => forces(&sim.form, &sim.state),
                None => forces(&parameters.special_form(), &parameters.initial_simulation_state()),
            }
        })
    }

    /// The legs' lengths and rates of the current state, computed on the first read after a
    /// change.
    #[inline]
    pub(super) fn leg_outputs(&mut self) -> &LegOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.legs.get_or_insert_with(|| match simulation {
            Some((sim, _)) => LegOutputs::compute(&sim.form, &sim.state),
            None => LegOutputs::compute(&parameters.special_form(), &parameters.initial_simulation_state()),
        })
    }

    /// The actuators' states of the current state, copied on the first read after a change.
    #[inline]
    pub(super) fn actuators(&mut self) -> &ActuatorStateOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.actuator_states.get_or_insert_with(|| match simulation {
            Some((sim, _)) => ActuatorStateOutputs::of(&sim.state),
            None => ActuatorStateOutputs::of(&parameters.initial_simulation_state()),
        })
    }

    /// `kappa` of the current state, computed on its first read after a change.
    #[inline]
    pub(super) fn condition(&mut self) -> &Condition {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.kappa.get_or_insert_with(|| Condition {
            kappa: match simulation {
                Some((sim, _)) => condition_number(sim.stand(), &sim.state),
                None => condition_number(&parameters.stand, &parameters.initial_simulation_state()),
            },
        })
    }

    /// After a set of values: in Initialization Mode the outputs follow the parameters; the
    /// actuators' and the joints' forces follow the inputs always.
    pub(super) fn values_set(&mut self) {
        self.input_dependent = None;
        if self.simulation.is_none() {
            self.invalidate_outputs();
        }
    }

    /// The current state changed: the cached outputs are stale.
    pub(super) fn invalidate_outputs(&mut self) {
        self.pose = None;
        self.leg_loads = None;
        self.state_values = None;
        self.legs = None;
        self.kappa = None;
        self.actuator_states = None;
        self.input_dependent = None;
    }
}
