//! What the platform says when a step fails or an event happens: the likely cause of a failed
//! RK4 step, the host's step against the stiffest law, a crossing in words.

use super::PlatformModel;
use crate::integration::Crossing;
use crate::physics::body::state::BodyState;
use crate::physics::direct_problem::singular_legs;
use crate::physics::error::leg_list;
use crate::physics::legs::geometry::LegGeometry;
use crate::simulation::PlatformSimulation;
use crate::simulation::outputs::LegLoadOutputs;
use crate::simulation::state::{SIMULATION_DIM, body, hydraulic, switching};

impl PlatformModel {
    /// Why a failed RK4 step is most likely the integrator's instability rather than the motion:
    /// its internal step (for a communication step `h`) against the stiffest law's stable step.
    pub(super) fn rk4_instability(&self, h: f64) -> Option<String> {
        let (sim, _) = self.simulation.as_ref()?;
        let settings = &sim.integrator.settings;
        if settings.method != crate::integration::Method::RungeKutta4 {
            return None;
        }
        let step = if settings.fixed_step > 0.0 { settings.fixed_step.min(h) } else { h };
        let law = self.parameters.stiffest_law()?;
        (step > law.rk4_stable_step).then(|| {
            format!(
                "; the likely cause is RK4's instability, not the motion: its internal step of {step:.3e} s is longer \
                 than the {:.3e} s it integrates stably, because {} is about {:.3e} s: set solver.fixedStep below {:.1e} s \
                 or use the adaptive method (solver.method = 1)",
                law.rk4_stable_step,
                law.what,
                law.time,
                law.rk4_stable_step / 5.0
            )
        })
    }

    /// Model Exchange: the host's integrator owns the step: its step (the last completed one,
    /// or the time since if longer) against the stiffest law, when it is too long for an
    /// explicit method.
    pub(super) fn host_step_hint(&self) -> Option<String> {
        let (sim, experiment) = self.simulation.as_ref()?;
        if !experiment.model_exchange {
            return None;
        }
        let since = self.host_step.max(sim.time - self.last_completed_step);
        let law = self.parameters.stiffest_law()?;
        (since > 0.1 * law.time).then(|| {
            format!(
                "the host's integrator steps {since:.3e} s, while {} is about {:.3e} s: an \
                 explicit integrator needs steps well below it (a tenth or less), an implicit or adaptive one (CVODE) \
                 finds them itself",
                law.what, law.time
            )
        })
    }

    /// What a crossing of switching function `c.index` means, in words.
    pub(super) fn describe_crossing(sim: &PlatformSimulation, c: &Crossing<SIMULATION_DIM>) -> String {
        let state = BodyState::from_vector(body(&c.y));
        let legs = LegGeometry::new(sim.stand(), &state);
        let rates = legs.length_rates(sim.stand(), &state);
        let what = if c.rising { "left" } else { "reached" };
        let (stop, k) = match c.index {
            i if i < switching::UPPER => ("lower", i - switching::LOWER),
            i if i < switching::DETERMINANT => ("upper", i - switching::UPPER),
            switching::DETERMINANT => {
                let involved = singular_legs(sim.stand(), &legs);
                return format!(
                    "t = {:?}: the legs passed through a singular arrangement (determinant of the force/moment matrix \
                     changed sign; legs {} form a force combination without resultant there)",
                    c.t,
                    leg_list(&involved)
                );
            }
            switching::ACCUMULATOR => {
                let pressure = c.y.get(hydraulic::SUPPLY_PRESSURE).copied().unwrap_or(f64::NAN);
                let what = if c.rising { "began to charge again" } else { "emptied" };
                return format!(
                    "t = {:?}: the accumulator {what}: the supply line passed its precharge (supply.pressure = {pressure:?} Pa \
                     gauge)",
                    c.t
                );
            }
            i => {
                let o = LegLoadOutputs::at(&sim.form, &c.y);
                let (joint, k, theta, max) = match sim.form.joint_limits() {
                    Some(j) if i < switching::PLATFORM_JOINT => {
                        let k = i - switching::BASE_JOINT;
                        ("base", k, o.theta_b.get(k).copied().unwrap_or(f64::NAN), j.base_max)
                    }
                    Some(j) => {
                        let k = i - switching::PLATFORM_JOINT;
                        ("platform", k, o.theta_a.get(k).copied().unwrap_or(f64::NAN), j.platform_max)
                    }
                    None => return String::new(),
                };
                return format!(
                    "t = {:?}: the {joint} joint of leg {} {what} its angle limit ({:.4} deg, limit {:.4} deg)",
                    c.t,
                    k + 1,
                    theta.to_degrees(),
                    max.to_degrees()
                );
            }
        };
        let (Some(l), Some(ldot)) = (legs.length.get(k), rates.get(k)) else { return String::new() };
        format!("t = {:?}: leg {} {what} its {stop} end stop (l = {l:?} m, ldot = {ldot:?} m/s)", c.t, k + 1)
    }
}
