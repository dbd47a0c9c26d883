//! Co-Simulation: a step with its events, FMI 3 early return, input and output derivatives.

use super::access::*;
use super::{DoStepOutcome, Instance, communication_point_tolerance};
use crate::fmi::log::LogCategory;
use crate::fmi::{FmiVersion, ModelState, Status};
use crate::models::StepReport;
use crate::models::variables::Causality;

impl Instance {
    /// A co-simulation step from `tc` to `tc + h` (or, with FMI 3 early return, to an event
    /// before it).
    pub fn do_step(&mut self, tc: f64, h: f64) -> (Status, DoStepOutcome) {
        let mut outcome = DoStepOutcome { last_successful_time: self.time, ..Default::default() };
        if !(h.is_finite() && h > 0.0) {
            return (self.error(&format!("communicationStepSize must be finite and > 0, got {h:?}")), outcome);
        }
        if !tc.is_finite() {
            return (self.error(&format!("currentCommunicationPoint must be finite, got {tc:?}")), outcome);
        }
        let tol = communication_point_tolerance(self.time, tc, h);
        if (tc - self.time).abs() > tol {
            let message = format!(
                "currentCommunicationPoint {tc:?} does not match the FMU's time {:?} (difference {:e}, more than the \
                 round-off tolerance {tol:e} s)",
                self.time,
                tc - self.time
            );
            return (self.error(&message), outcome);
        }
        let t_end = tc + h;
        if let Some(stop) = self.stop_time
            && t_end > stop + communication_point_tolerance(stop, t_end, h)
        {
            let message = format!("step to t = {t_end:?} goes past the stopTime {stop:?}");
            return (self.error(&message), outcome);
        }
        let events = self.version == FmiVersion::Fmi3 && self.kind.info().capabilities.event_indicators > 0;
        let early = events && self.co_simulation.early_return_allowed;
        let mut t = tc;
        loop {
            let result = self.model_mut().do_step(t, t_end - t, early);
            match result {
                Ok(StepReport { reached, event, warning }) => {
                    if let Some(w) = warning {
                        self.logger.log(Status::Warning, LogCategory::Warning, &w);
                    }
                    self.time = reached;
                    self.last_successful_time = reached;
                    outcome.last_successful_time = reached;
                    if self.logger.is_enabled(LogCategory::Events) {
                        let logger = &self.logger;
                        self.model.report_events(&mut |m| logger.log(Status::Ok, LogCategory::Events, m));
                    }
                    if event && events && self.co_simulation.event_mode_used {
                        outcome.event_handling_needed = true;
                    }
                    if reached >= t_end || !event {
                        self.time = if reached >= t_end { t_end } else { reached };
                        self.refresh_read_blocks();
                        return (Status::Ok, outcome);
                    }
                    // An event before the step's end: ask the importer whether to return now.
                    if self.return_early_at(reached) {
                        outcome.early_return = true;
                        self.refresh_read_blocks();
                        return (Status::Ok, outcome);
                    }
                    t = reached;
                }
                Err(e) => {
                    self.state = ModelState::StepFailed;
                    // Only the limit of internal steps stopped it: the importer can restore a
                    // state (or reset) and go on with shorter steps.
                    self.terminated = !e.retry_shorter;
                    outcome.terminate_simulation = !e.retry_shorter;
                    outcome.last_successful_time = self.time;
                    self.last_successful_time = self.time;
                    self.log(Status::Discard, &format!("{}: {}", self.current, e.message));
                    return (Status::Discard, outcome);
                }
            }
        }
    }

    /// At the end of a step: the cache blocks read since the last one, computed now (see
    /// `read_since_step`), but for those a set of an input made stale since the last one
    /// (see `set_since_step`).
    pub(super) fn refresh_read_blocks(&mut self) {
        let read = std::mem::take(&mut self.read_since_step);
        let set = std::mem::take(&mut self.set_since_step);
        self.refresh(read & !set);
    }

    /// At an event at `t` inside an FMI 3 step with early return allowed: the importer's
    /// intermediate update callback decides (`canReturnEarly`; getting and setting variables
    /// is not allowed during the callback); without a callback, a step that reports events
    /// returns at each, so that the importer can handle it in Event Mode.
    pub(super) fn return_early_at(&mut self, t: f64) -> bool {
        let options = self.co_simulation;
        match options.intermediate_update {
            Some(callback) => {
                let (mut requested, mut at) = (0u8, t);
                self.state = ModelState::IntermediateUpdateMode;
                // SAFETY: the importer gave us this callback for this instance; the out-pointers
                // are local variables valid for the call.
                unsafe { callback(options.environment, t, 0, 0, 0, 1, &mut requested, &mut at) };
                self.state = ModelState::StepComplete;
                requested != 0
            }
            None => options.event_mode_used,
        }
    }

    pub fn set_real_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        if !self.kind.info().capabilities.can_interpolate_inputs {
            return self.error("not supported by this model (canInterpolateInputs=\"false\")");
        }
        let mut refs = Vec::with_capacity(vrs.len());
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let (g, r) = match self.lookup(vr, BaseType::Real) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if g.causality != Causality::Input {
                return self.error(&format!("{} is not an input", g.element_name(r.index)));
            }
            if order != 1 {
                return self
                    .error(&format!("derivative order {order} of {} not supported (only 1)", g.element_name(r.index)));
            }
            if !x.is_finite() {
                return self.error(&format!(
                    "derivative of {} = {x:?} refused: values must be finite",
                    g.element_name(r.index)
                ));
            }
            refs.push(r);
        }
        for (r, &x) in refs.into_iter().zip(values) {
            self.model_mut().set_input_derivative(r, x);
        }
        Status::Ok
    }

    /// Output derivatives: FMI 2 one per reference, FMI 3 one per element of each referenced
    /// variable (`values` holds them all).
    pub fn get_output_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &mut [f64]) -> Status {
        let max_order = self.kind.info().capabilities.max_output_derivative_order;
        if max_order == 0 {
            return self.error("not supported by this model (maxOutputDerivativeOrder = 0)");
        }
        if let Err(s) = self.check_values(vrs, BaseType::Real, values.len(), false) {
            return s;
        }
        for (&vr, &order) in vrs.iter().zip(orders) {
            let Ok((g, r)) = self.lookup(vr, BaseType::Real) else { return Status::Error };
            if g.causality != Causality::Output {
                return self.error(&format!("{} is not an output", self.variable_name(g, r)));
            }
            if order < 1 || order as u32 > max_order {
                return self.error(&format!(
                    "derivative order {order} of {} not available (maxOutputDerivativeOrder = {max_order})",
                    self.variable_name(g, r)
                ));
            }
        }
        for (slot, r) in values.iter_mut().zip(elements(&self.access, vrs)) {
            *slot = self.model.output_derivative(r);
        }
        Status::Ok
    }
}
