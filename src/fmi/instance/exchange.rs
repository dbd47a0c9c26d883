//! Model Exchange and partial derivatives: states in the importer's order, derivatives,
//! event indicators and updates, directional and adjoint derivatives.

use super::access::*;
use super::{EventInfo, Instance};
use crate::fmi::log::LogCategory;
use crate::fmi::{InterfaceType, ModelState, Status};
use crate::models::EventUpdate;
use crate::models::variables::VariableRef;

impl Instance {
    // ----- directional and adjoint derivatives ---------------------------------------------

    /// Resolves the unknowns and knowns of a derivative call into element references.
    pub(super) fn derivative_refs(
        &self,
        unknowns: &[u32],
        knowns: &[u32],
    ) -> Result<(Vec<VariableRef>, Vec<VariableRef>), Status> {
        let resolve = |vrs: &[u32]| -> Result<Vec<VariableRef>, Status> {
            for &vr in vrs {
                self.access(vr, BaseType::Real)?;
            }
            Ok(elements(&self.access, vrs).collect())
        };
        let u = resolve(unknowns)?;
        let k = resolve(knowns)?;
        Ok((u, k))
    }

    /// The references of a directional (`adjoint` false: seeds per known, sensitivities per
    /// unknown) or adjoint derivative (the other way round), with the model's capability,
    /// every size and every seed checked.
    pub(super) fn derivative_arguments(
        &self,
        unknowns: &[u32],
        knowns: &[u32],
        seeds: &[f64],
        out: &[f64],
        adjoint: bool,
    ) -> Result<(Vec<VariableRef>, Vec<VariableRef>), Status> {
        let capabilities = self.kind.info().capabilities;
        if adjoint && !capabilities.adjoint_derivatives {
            return Err(self.error("not supported by this model (providesAdjointDerivatives=\"false\")"));
        }
        if !adjoint && !capabilities.directional_derivatives {
            return Err(self.error("not supported by this model (providesDirectionalDerivative=\"false\")"));
        }
        let (u, k) = self.derivative_refs(unknowns, knowns)?;
        let (from, to) = if adjoint {
            (("unknowns", u.len()), ("knowns", k.len()))
        } else {
            (("knowns", k.len()), ("unknowns", u.len()))
        };
        if seeds.len() != from.1 || out.len() != to.1 {
            return Err(self.error(&format!(
                "the {} address {} values and the {} {}, but nSeed = {} and nSensitivity = {}",
                from.0,
                from.1,
                to.0,
                to.1,
                seeds.len(),
                out.len()
            )));
        }
        if let Some(s) = seeds.iter().find(|s| !s.is_finite()) {
            return Err(self.error(&format!("seed {s} is not finite")));
        }
        Ok((u, k))
    }

    /// `sensitivity = J seed` for the Jacobian of `unknowns` with respect to `knowns`.
    pub fn get_directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Status {
        let (u, k) = match self.derivative_arguments(unknowns, knowns, seeds, out, false) {
            Ok(x) => x,
            Err(s) => return s,
        };
        match self.model.directional_derivative(&u, &k, seeds, out) {
            Ok(()) => Status::Ok,
            Err(m) => self.error(&m),
        }
    }

    /// `sensitivity = J^T seed` (FMI 3 adjoint derivative), exact: the Jacobian's columns come
    /// from one exact directional derivative per known.
    pub fn get_adjoint_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Status {
        let (u, k) = match self.derivative_arguments(unknowns, knowns, seeds, out, true) {
            Ok(x) => x,
            Err(s) => return s,
        };
        let mut column = vec![0.0; u.len()];
        for (j, known) in k.iter().enumerate() {
            if let Err(m) = self.model.directional_derivative(&u, std::slice::from_ref(known), &[1.0], &mut column) {
                return self.error(&m);
            }
            if let Some(slot) = out.get_mut(j) {
                *slot = column.iter().zip(seeds).map(|(c, s)| c * s).sum();
            }
        }
        Status::Ok
    }

    // ----- Model Exchange -------------------------------------------------------------------

    pub fn state_count(&self) -> usize {
        self.state_order.len()
    }

    pub fn event_indicator_count(&self) -> usize {
        self.kind.info().capabilities.event_indicators
    }

    pub(super) fn check_state_count(&self, n: usize) -> Result<(), Status> {
        if n == self.state_count() {
            Ok(())
        } else {
            Err(self.error(&format!("nx = {n}, but the model has {} continuous states", self.state_count())))
        }
    }

    pub fn set_time(&mut self, t: f64) -> Status {
        if !t.is_finite() {
            return self.error(&format!("time must be finite, got {t:?}"));
        }
        self.time = t;
        self.model_mut().set_time(t);
        Status::Ok
    }

    pub fn set_continuous_states(&mut self, x: &[f64]) -> Status {
        if let Err(s) = self.check_state_count(x.len()) {
            return s;
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return self.error(&format!("state {i} = {:?} refused: states must be finite", x[i]));
        }
        let mut internal = vec![0.0; x.len()];
        for (&xi, &i) in x.iter().zip(&self.state_order) {
            if let Some(slot) = internal.get_mut(i) {
                *slot = xi;
            }
        }
        self.model_mut().set_continuous_states(&internal);
        Status::Ok
    }

    /// The model's state vector (or its derivative) in the importer's order.
    pub(super) fn in_importer_order(&self, internal: &[f64], out: &mut [f64]) {
        for (slot, &i) in out.iter_mut().zip(&self.state_order) {
            *slot = internal.get(i).copied().unwrap_or(f64::NAN);
        }
    }

    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> Status {
        if let Err(s) = self.check_state_count(x.len()) {
            return s;
        }
        let mut internal = vec![0.0; x.len()];
        self.model.continuous_states(&mut internal);
        self.in_importer_order(&internal, x);
        Status::Ok
    }

    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> Status {
        if let Err(s) = self.check_state_count(dx.len()) {
            return s;
        }
        let mut internal = vec![0.0; dx.len()];
        self.model.derivatives(&mut internal);
        self.in_importer_order(&internal, dx);
        if let Some(i) = dx.iter().position(|v| !v.is_finite()) {
            let hint = self.model.undefined_reason().map(|r| format!("; {r}")).unwrap_or_default();
            return self.error(&format!(
                "derivative {i} is not finite at t = {:?}: the state is not admissible{hint}",
                self.time
            ));
        }
        Status::Ok
    }

    pub fn get_nominals(&mut self, x: &mut [f64]) -> Status {
        if let Err(s) = self.check_state_count(x.len()) {
            return s;
        }
        // Positions in m, velocities in m/s, unit vectors and their rates: all of order one;
        // the work quadratures too in practice (the error control is relative).
        x.fill(1.0);
        Status::Ok
    }

    pub fn get_event_indicators(&mut self, z: &mut [f64]) -> Status {
        let count = self.event_indicator_count();
        if z.len() != count {
            return self.error(&format!("ni = {}, but the model has {count} event indicators", z.len()));
        }
        self.model.event_indicators(z);
        Status::Ok
    }

    pub fn enter_event_mode(&mut self) -> Status {
        self.state = ModelState::EventMode;
        Status::Ok
    }

    pub fn enter_continuous_time_mode(&mut self) -> Status {
        self.state = ModelState::ContinuousTimeMode;
        Status::Ok
    }

    /// FMI 3 Co-Simulation: from Initialization or Event Mode into Step Mode.
    pub fn enter_step_mode(&mut self) -> Status {
        self.state = ModelState::StepComplete;
        Status::Ok
    }

    /// An event update. No discrete states and no time events: the end-stop forces are
    /// continuous in the state and the events only mark their kinks (and singular
    /// arrangements passed), so one update settles every event and the continuous states
    /// are unchanged.
    pub fn update_discrete_states(&mut self) -> EventInfo {
        let mut info = EventInfo::default();
        let logger = &self.logger;
        self.fresh = 0;
        if self.interface == InterfaceType::CoSimulation {
            // FMI 3 Co-Simulation's Event Mode: the step located its events, logged them and
            // took the switching functions' sides past them. Reading the sides again from a
            // state that the landing step left a round-off short of its crossing would find
            // the crossing again, and the next step would land on it again.
            return info;
        }
        let update: EventUpdate = self.model.event_update(&mut |m| logger.log(Status::Ok, LogCategory::Events, m));
        if let Some(reason) = update.terminate {
            info.terminate_simulation = true;
            self.terminated = true;
            self.logger.log(Status::Warning, LogCategory::Discard, &format!("{}: {reason}", self.current));
        }
        info
    }

    /// Returns `(enterEventMode, terminateSimulation)`.
    pub fn completed_integrator_step(&mut self) -> (bool, bool) {
        // A check of the state, no change: the cached values stay.
        match self.model.completed_integrator_step() {
            Ok(()) => (false, false),
            Err(e) => {
                self.terminated = true;
                self.logger.log(Status::Warning, LogCategory::Discard, &format!("{}: {}", self.current, e.message));
                (false, true)
            }
        }
    }
}
