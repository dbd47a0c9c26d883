//! Model Exchange and derivatives of the platform: the state rate, the derivative
//! variables, event indicators and updates, and every exact derivative (directional, adjoint
//! through the instance, output time derivatives), all from the physics' one definition
//! evaluated on duals.

use super::variables::{ACTUATOR_INPUTS, BINDINGS, GROUPS, group, output_element};
use super::{INFO, PlatformModel};
use crate::integration::{Crossing, switching_sides};
use crate::models::EventUpdate;
use crate::models::declare::Binding;
use crate::models::machine::Drive;
use crate::models::variables::VariableRef;
use crate::physics::actuators::{HeldForces, Supply};
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::number::{Dual, Number};
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::LEG_COUNT;
use crate::simulation::outputs::condition_number_tangent;
use crate::simulation::state::{
    SIMULATION_DIM, SimulationState, accumulator_switching, body, state_rate, state_rate_supplied, switching,
};
use crate::simulation::{PlatformDynamics, PlatformOutputs, Stabilisation};

impl PlatformModel {
    /// Runs `f` with the special form and the state the model is at: the simulation's, or
    /// before initialisation the one the parameters describe.
    fn with_current<R>(&self, f: impl FnOnce(&SpecialForm, &SimulationState) -> R) -> R {
        match self.sim() {
            Some(sim) => f(&sim.form, &sim.state),
            None => f(&self.parameters.special_form(), &self.parameters.initial_simulation_state()),
        }
    }

    /// A derivative variable's value (`der(v)`, `der(R)`, ...): an element of the state rate.
    pub(super) fn derivative_value(&self, var: VariableRef) -> Option<f64> {
        let i = INFO.derivative_state_index(var)?;
        let inputs = self.inputs();
        self.with_current(|form, y| state_rate(form, y, &inputs).get(i).copied())
    }

    /// The event indicators (the switching functions): stroke margins, the determinant, the
    /// joints' limits and the accumulator's precharge.
    pub(super) fn switching_values(&self, z: &mut [f64]) {
        let law = HeldForces::constant(self.inputs());
        if let Some(slot) = z.get_mut(switching::ACCUMULATOR) {
            *slot = self.with_current(accumulator_switching);
        }
        match self.sim() {
            Some(sim) => sim.switching_values(&law, z),
            None => {
                // Before initialisation: the parameters' initial pose (for Initialization Mode).
                let form = self.parameters.special_form();
                let y = self.parameters.initial_simulation_state();
                let guard = ConfigurationGuard {
                    min_leg_length: 0.0,
                    base_plane: 0.0,
                    side: 1.0,
                    characteristic_length: form.stand.characteristic_length().max(f64::MIN_POSITIVE),
                };
                PlatformDynamics::new(&form, &law, Stabilisation::Projection, &guard, false)
                    .switching_values(body(&y), z);
            }
        }
    }

    /// An event update at the current time and state: the indicators' signs become the new
    /// reference; each change is described.
    pub(super) fn update_events(&mut self, sink: &mut dyn FnMut(&str)) -> EventUpdate {
        let inputs = self.inputs();
        let Some(sim) = self.sim_mut() else { return EventUpdate::default() };
        let law = HeldForces::constant(inputs);
        let now = switching_sides(&sim.dynamics(&law), sim.time, &sim.state);
        let changed = now.bits ^ sim.integrator.sides.bits;
        let mut update = EventUpdate::default();
        for i in (0..switching::EVENT_INDICATORS).filter(|i| changed >> i & 1 == 1) {
            let c = Crossing { index: i, t: sim.time, rising: now.bits >> i & 1 == 1, y: sim.state };
            let message = Self::describe_crossing(sim, &c);
            if i == switching::DETERMINANT && sim.stop_at_singularity {
                update.terminate = Some(format!("{message}, and stopAtSingularity is on"));
            }
            sink(&message);
        }
        sim.integrator.sides = now;
        update
    }

    /// `out = J seeds` for the Jacobian of `unknowns` (outputs, states, derivatives) with
    /// respect to `knowns` (states, inputs): the outputs and the state rate evaluated once on
    /// duals seeded with the direction.
    pub(super) fn jacobian_product(
        &mut self,
        unknowns: &[VariableRef],
        knowns: &[VariableRef],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        let mut dy = [0.0; SIMULATION_DIM];
        let mut du = [0.0; LEG_COUNT];
        let (mut d_supply, mut d_speed) = (0.0, 0.0);
        for (k, &seed) in knowns.iter().zip(seeds) {
            if k.group == group::PS {
                d_supply += seed;
                continue;
            }
            if k.group == group::PUMP_SPEED {
                d_speed += seed;
                continue;
            }
            let input = *ACTUATOR_INPUTS.get(self.parameters.drive);
            let slot = match INFO.state_index(*k) {
                Some(i) => dy.get_mut(i),
                None if k.group == input => du.get_mut(k.index),
                // Another actuator's inputs: nothing depends on them.
                None if Drive::ALL.iter().any(|&d| *ACTUATOR_INPUTS.get(d) == k.group) => continue,
                None => None,
            };
            let Some(slot) = slot else {
                return Err(format!(
                    "known {} is neither a state nor an input (derivatives are with respect to the states, the \
                     actuators' inputs, pS and pump.speed)",
                    element_name(*k)
                ));
            };
            *slot += seed;
        }
        let inputs = self.inputs();
        let needs_kappa = unknowns.iter().any(|u| u.group == group::KAPPA);
        let (rate, outputs, dkappa) = self.with_current(|form, y| {
            let (yd, ud) = (Dual::seeded(y, &dy), Dual::seeded(&inputs, &du));
            let held = form.supply::<f64>();
            let supply = Supply {
                pressure: Dual::new(held.pressure, d_supply),
                pump_speed: Dual::new(held.pump_speed, d_speed),
            };
            let rate = state_rate_supplied(form, &yd, &ud, supply);
            let dkappa = if needs_kappa { condition_number_tangent(&form.stand, y, &dy) } else { 0.0 };
            (rate, PlatformOutputs::<Dual>::compute_supplied(form, &yd, Some(&ud), supply), dkappa)
        });
        for (value, u) in out.iter_mut().zip(unknowns) {
            let derivative = match BINDINGS.get(u.group) {
                _ if u.group == group::KAPPA => Some(dkappa),
                Some(Binding::Cached { .. }) => output_element(&outputs, *u).map(|d| d.eps),
                Some(Binding::Derivative) => INFO.derivative_state_index(*u).and_then(|i| rate.get(i)).map(|d| d.eps),
                _ => None,
            };
            *value = derivative
                .ok_or_else(|| format!("unknown {} is not an output, state or derivative", element_name(*u)))?;
        }
        Ok(())
    }

    /// The time derivative of an output (`fmi2GetRealOutputDerivatives`): its directional
    /// derivative along the state's own rate.
    pub(super) fn output_time_derivative(&mut self, var: VariableRef) -> f64 {
        let Some(sim) = self.sim() else { return 0.0 };
        let inputs = self.inputs();
        let dy = state_rate(&sim.form, &sim.state, &inputs);
        if var.group == group::KAPPA {
            return condition_number_tangent(sim.stand(), &sim.state, &dy);
        }
        let inputs = inputs.map(Dual::constant);
        let outputs = PlatformOutputs::<Dual>::compute(&sim.form, &Dual::seeded(&sim.state, &dy), Some(&inputs));
        output_element(&outputs, var).map_or(0.0, |d| d.eps)
    }
}

fn element_name(var: VariableRef) -> String {
    GROUPS.get(var.group).map_or(String::new(), |g| g.element_name(var.index))
}
