//! One FMU instance: the state machine, argument checks, time bookkeeping, FMU states and
//! logging around a model. Safe Rust: the exported functions ([`super::exports`]) turn C
//! pointers into slices and call these methods.
//!
//! Error policy:
//! - a call not allowed in the current state, a bad argument (NULL array, unknown or
//!   wrong-type value reference, non-finite value, variable not settable now, bad step
//!   size or communication point): `fmi2Error`, logged, and nothing changes (the host can
//!   correct the call and go on);
//! - a failed computation (parameters refused at `fmi2ExitInitializationMode`): `fmi2Error`
//!   and the instance enters the `error` state of the FMI tables;
//! - a step the physics or the integrator cannot complete: rolled back, `fmi2Discard`,
//!   state `stepFailed`, `fmi2Terminated` true;
//! - a panic: the instance is poisoned; every later call but `fmi2Reset` and
//!   `fmi2FreeInstance` is refused.

use super::logger::{LogCategory, Logger};
use super::state_machine::{Fmi2Function, InterfaceType, ModelState};
use super::types::*;
use crate::models::snapshot::{ByteReader, ByteWriter, SnapshotError, fnv1a64};
use crate::models::variables::{
    Causality, Initial, Variability, VariableGroup, VariableRef, VariableTable, VariableType,
};
use crate::models::{AnyModel, ModelKind};

/// First field of every instance; checked on every call to catch foreign or freed pointers.
const INSTANCE_MAGIC: u64 = 0x5354_4557_4152_5449; // "STEWARTI"
/// First field of every FMU state handle.
const FMU_STATE_MAGIC: u64 = 0x5354_4557_4152_5453; // "STEWARTS"
/// Serialized FMU states start with this.
const STATE_FORMAT_MAGIC: &[u8; 8] = b"STEWFMU\x00";
const STATE_FORMAT_VERSION: u32 = 1;

/// Relative tolerance on `currentCommunicationPoint`: masters that accumulate `t += h`
/// (FMPy's SSP loop) drift from the FMU's `t + h` by a few ulps per step.
pub const COMMUNICATION_POINT_TOLERANCE: f64 = 1e-9;

/// The FMI base type a get/set function works on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
}

impl BaseType {
    fn matches(self, t: VariableType) -> bool {
        match self {
            BaseType::Real => t.is_real(),
            BaseType::Integer => t.is_integer_like(),
            BaseType::Boolean => t.is_boolean(),
        }
    }

    fn name(self) -> &'static str {
        match self {
            BaseType::Real => "Real",
            BaseType::Integer => "Integer",
            BaseType::Boolean => "Boolean",
        }
    }
}

/// An FMU state (`fmi2FMUstate`): the serialized bytes of an instance.
pub struct FmuStateHandle {
    magic: u64,
    bytes: Vec<u8>,
}

impl FmuStateHandle {
    /// # Safety
    /// `p` must be NULL or a pointer the importer got from this library (magic checked).
    pub unsafe fn from_handle<'a>(p: fmi2FMUstate) -> Option<&'a mut FmuStateHandle> {
        let h = p as *mut FmuStateHandle;
        // SAFETY: non-NULL pointers handed out by this library point to a live FmuStateHandle
        // (the importer must not pass freed ones); the magic check catches foreign pointers.
        let h = unsafe { h.as_mut()? };
        (h.magic == FMU_STATE_MAGIC).then_some(h)
    }

    pub fn into_handle(self) -> fmi2FMUstate {
        Box::into_raw(Box::new(self)) as fmi2FMUstate
    }

    /// # Safety
    /// `p` must have come from [`FmuStateHandle::into_handle`] and not have been freed.
    pub unsafe fn free(p: fmi2FMUstate) {
        // SAFETY: per the contract, `p` is a live Box<FmuStateHandle>.
        let mut b = unsafe { Box::from_raw(p as *mut FmuStateHandle) };
        b.magic = 0;
        drop(b);
    }

    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// A restorable picture of an instance, parsed and validated.
struct Snapshot {
    interface: InterfaceType,
    state: ModelState,
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    terminated: bool,
    last_successful_time: f64,
    model: AnyModel,
}

pub struct Instance {
    magic: u64,
    pub kind: ModelKind,
    pub interface: InterfaceType,
    pub state: ModelState,
    pub logger: Logger,
    pub model: AnyModel,
    pub table: VariableTable,
    /// Hash of the GUID, stamped into serialized states.
    token_hash: u64,
    pub start_time: f64,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    /// Current communication point.
    pub time: f64,
    /// `fmi2Terminated` status.
    pub terminated: bool,
    /// `fmi2LastSuccessfulTime` status.
    pub last_successful_time: f64,
    poisoned: Option<String>,
}

fn option_f64(w: &mut ByteWriter, x: Option<f64>) {
    w.bool(x.is_some());
    w.f64(x.unwrap_or(0.0));
}

fn read_option_f64(r: &mut ByteReader, what: &str) -> Result<Option<f64>, SnapshotError> {
    let present = r.bool()?;
    let x = r.f64()?;
    if present {
        if x.is_finite() { Ok(Some(x)) } else { Err(SnapshotError(format!("{what} is not finite"))) }
    } else {
        Ok(None)
    }
}

impl Instance {
    /// `guid` is the importer's GUID, already matched to `kind` by `ModelKind::from_guid`.
    pub fn new(kind: ModelKind, guid: &str, interface: InterfaceType, logger: Logger) -> Self {
        let info = kind.info();
        Instance {
            magic: INSTANCE_MAGIC,
            kind,
            interface,
            state: ModelState::Instantiated,
            logger,
            model: kind.instantiate(),
            table: VariableTable::new(info.groups),
            token_hash: fnv1a64(guid.as_bytes()),
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            time: 0.0,
            terminated: false,
            last_successful_time: 0.0,
            poisoned: None,
        }
    }

    /// # Safety
    /// `c` must be NULL or a pointer from `fmi2Instantiate` that has not been freed.
    pub unsafe fn from_handle<'a>(c: fmi2Component) -> Option<&'a mut Instance> {
        // SAFETY: see the function's contract; the magic number rejects foreign pointers.
        let inst = unsafe { (c as *mut Instance).as_mut()? };
        (inst.magic == INSTANCE_MAGIC).then_some(inst)
    }

    pub fn into_handle(self) -> fmi2Component {
        Box::into_raw(Box::new(self)) as fmi2Component
    }

    /// # Safety
    /// `c` must be a pointer from `fmi2Instantiate` that has not been freed.
    pub unsafe fn free(c: fmi2Component) {
        // SAFETY: per the contract `c` is a live Box<Instance>.
        let mut b = unsafe { Box::from_raw(c as *mut Instance) };
        b.magic = 0;
        drop(b);
    }

    // ----- logging and checks -------------------------------------------------------------

    pub fn log(&self, status: fmi2Status, message: &str) {
        self.logger.log(status, LogCategory::for_status(status), message);
    }

    /// Logs `"<function>: <message>"` as an error and returns `fmi2Error`.
    pub fn error(&self, func: Fmi2Function, message: &str) -> fmi2Status {
        self.log(fmi2Error, &format!("{}: {message}", func.name()));
        fmi2Error
    }

    pub fn check_call(&self, func: Fmi2Function) -> Result<(), fmi2Status> {
        if let Some(reason) = &self.poisoned {
            if !matches!(func, Fmi2Function::Reset | Fmi2Function::FreeInstance) {
                self.log(
                    fmi2Error,
                    &format!("{}: refused, the instance is poisoned by an internal error ({reason}); call fmi2Reset or fmi2FreeInstance", func.name()),
                );
                return Err(fmi2Error);
            }
            return Ok(());
        }
        if func.allowed_in(self.interface, self.state) {
            return Ok(());
        }
        let interface = match self.interface {
            InterfaceType::CoSimulation => "Co-Simulation",
            InterfaceType::ModelExchange => "Model Exchange",
        };
        self.log(
            fmi2Error,
            &format!(
                "{}: illegal call sequence, not allowed in state {} of a {interface} instance",
                func.name(),
                self.state.name()
            ),
        );
        Err(fmi2Error)
    }

    pub fn log_call(&self, func: Fmi2Function, status: fmi2Status) {
        if self.logger.is_enabled(LogCategory::Calls) {
            self.logger.log(
                fmi2OK,
                LogCategory::Calls,
                &format!("{} -> {} (state {}, t = {})", func.name(), status_name(status), self.state.name(), self.time),
            );
        }
    }

    pub fn poison(&mut self, func: Fmi2Function, message: &str) {
        let reason = format!("panic in {} at t = {}: {message}", func.name(), self.time);
        self.logger.log(fmi2Fatal, LogCategory::Fatal, &format!("{reason}; the instance is poisoned"));
        self.poisoned = Some(reason);
    }

    pub fn is_poisoned(&self) -> bool {
        self.poisoned.is_some()
    }

    fn lookup(
        &self,
        func: Fmi2Function,
        vr: u32,
        want: BaseType,
    ) -> Result<(&'static VariableGroup, VariableRef), fmi2Status> {
        match self.table.lookup(vr) {
            Some((g, r)) if want.matches(g.var_type) => Ok((g, r)),
            Some((g, r)) => Err(self.error(
                func,
                &format!(
                    "value reference {vr} is {} of type {:?}, not a {} variable",
                    g.element_name(r.index),
                    g.var_type,
                    want.name()
                ),
            )),
            None => Err(self.error(
                func,
                &format!("value reference {vr} is not a {} variable of {}", want.name(), self.kind.info().model_name),
            )),
        }
    }

    /// Whether a variable may be set in the current state (FMI 2.0 conditions 1, 3, 6 of the
    /// CS table; 1, 3, 4, 5 of the ME table).
    fn settable(&self, g: &VariableGroup) -> bool {
        if g.variability == Variability::Constant || g.causality == Causality::Independent {
            return false;
        }
        let exact_or_approx = matches!(g.initial, Some(Initial::Exact | Initial::Approx));
        match self.state {
            ModelState::Instantiated => exact_or_approx || g.causality == Causality::Input,
            ModelState::InitializationMode => g.initial == Some(Initial::Exact) || g.causality == Causality::Input,
            ModelState::StepComplete | ModelState::EventMode => {
                g.causality == Causality::Input
                    || (g.causality == Causality::Parameter && g.variability == Variability::Tunable)
            }
            ModelState::ContinuousTimeMode => {
                g.causality == Causality::Input && g.variability == Variability::Continuous
            }
            _ => false,
        }
    }

    fn check_settable(&self, func: Fmi2Function, g: &VariableGroup, r: VariableRef) -> Result<(), fmi2Status> {
        if self.settable(g) {
            return Ok(());
        }
        Err(self.error(
            func,
            &format!(
                "{} ({} {}) may not be set in state {}",
                g.element_name(r.index),
                g.variability.xml(),
                g.causality.xml(),
                self.state.name()
            ),
        ))
    }

    // ----- common functions -----------------------------------------------------------------

    pub fn set_debug_logging(&mut self, func: Fmi2Function, logging_on: bool, names: &[Option<String>]) -> fmi2Status {
        let mut categories = Vec::with_capacity(names.len());
        for name in names {
            match name.as_deref().map(|n| (n, LogCategory::from_name(n))) {
                Some((_, Some(c))) => categories.push(c),
                Some((n, None)) => {
                    let known: Vec<&str> = LogCategory::ALL.iter().map(|c| c.name()).collect();
                    return self.error(func, &format!("unknown log category \"{n}\" (known: {})", known.join(", ")));
                }
                None => return self.error(func, "a category name is NULL"),
            }
        }
        self.logger.set_debug_logging(logging_on, &categories);
        fmi2OK
    }

    pub fn setup_experiment(
        &mut self,
        func: Fmi2Function,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> fmi2Status {
        if !start_time.is_finite() {
            return self.error(func, &format!("startTime must be finite, got {start_time}"));
        }
        if let Some(tol) = tolerance
            && !(tol > 0.0 && tol < 1.0)
        {
            return self.error(func, &format!("tolerance must be in (0, 1), got {tol}"));
        }
        if let Some(stop) = stop_time
            && (!stop.is_finite() || stop < start_time)
        {
            return self.error(func, &format!("stopTime {stop} must be finite and not before startTime {start_time}"));
        }
        self.tolerance = tolerance;
        self.start_time = start_time;
        self.stop_time = stop_time;
        self.time = start_time;
        self.last_successful_time = start_time;
        fmi2OK
    }

    pub fn enter_initialization_mode(&mut self) -> fmi2Status {
        self.time = self.start_time;
        self.last_successful_time = self.start_time;
        self.state = ModelState::InitializationMode;
        fmi2OK
    }

    pub fn exit_initialization_mode(&mut self, func: Fmi2Function) -> fmi2Status {
        let model_exchange = self.interface == InterfaceType::ModelExchange;
        match self.model.exit_initialization(self.start_time, self.tolerance, model_exchange) {
            Ok(summary) => {
                self.logger.log(fmi2OK, LogCategory::Events, &summary);
                self.state = match self.interface {
                    InterfaceType::CoSimulation => ModelState::StepComplete,
                    InterfaceType::ModelExchange => ModelState::EventMode,
                };
                fmi2OK
            }
            Err(message) => {
                self.state = ModelState::Error;
                self.error(func, &format!("{message}; the instance is in the error state (fmi2Reset to start again)"))
            }
        }
    }

    pub fn terminate(&mut self) -> fmi2Status {
        self.state = ModelState::Terminated;
        fmi2OK
    }

    pub fn reset(&mut self) -> fmi2Status {
        self.model = self.kind.instantiate();
        self.state = ModelState::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.tolerance = None;
        self.time = 0.0;
        self.terminated = false;
        self.last_successful_time = 0.0;
        self.poisoned = None;
        self.logger.log(fmi2OK, LogCategory::Events, "reset to the start values");
        fmi2OK
    }

    // ----- get/set ------------------------------------------------------------------------

    pub fn get_real(&mut self, func: Fmi2Function, vrs: &[u32], values: &mut [f64]) -> fmi2Status {
        // Two passes, no allocation: validate every reference, then read (all or nothing).
        for &vr in vrs {
            if let Err(s) = self.lookup(func, vr, BaseType::Real) {
                return s;
            }
        }
        for (value, &vr) in values.iter_mut().zip(vrs) {
            let Some((g, r)) = self.table.lookup(vr) else { return fmi2Error };
            let x = self.model.get_real(r);
            if x.is_nan() {
                return self
                    .error(func, &format!("{} is not a number with the current parameters", g.element_name(r.index)));
            }
            *value = x;
        }
        fmi2OK
    }

    pub fn set_real(&mut self, func: Fmi2Function, vrs: &[u32], values: &[f64]) -> fmi2Status {
        // Two passes, no allocation: validate every reference and value, then store.
        for (&vr, &x) in vrs.iter().zip(values) {
            let (g, r) = match self.lookup(func, vr, BaseType::Real) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if let Err(s) = self.check_settable(func, g, r) {
                return s;
            }
            if !x.is_finite() {
                return self.error(func, &format!("{} = {x} refused: values must be finite", g.element_name(r.index)));
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            let Some((_, r)) = self.table.lookup(vr) else { return fmi2Error };
            if let Err(m) = self.model.set_real(r, x) {
                return self.error(func, &m);
            }
        }
        fmi2OK
    }

    pub fn get_integer(&mut self, func: Fmi2Function, vrs: &[u32], values: &mut [i32]) -> fmi2Status {
        let mut refs = Vec::with_capacity(vrs.len());
        for &vr in vrs {
            match self.lookup(func, vr, BaseType::Integer) {
                Ok((_, r)) => refs.push(r),
                Err(s) => return s,
            }
        }
        for (i, r) in refs.into_iter().enumerate() {
            values[i] = self.model.get_integer(r);
        }
        fmi2OK
    }

    pub fn set_integer(&mut self, func: Fmi2Function, vrs: &[u32], values: &[i32]) -> fmi2Status {
        let mut refs = Vec::with_capacity(vrs.len());
        for &vr in vrs {
            let (g, r) = match self.lookup(func, vr, BaseType::Integer) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if let Err(s) = self.check_settable(func, g, r) {
                return s;
            }
            refs.push(r);
        }
        // Validate every value on a copy first: all or nothing.
        let mut trial = self.snapshot_model();
        for (r, &x) in refs.iter().zip(values) {
            if let Err(m) = trial.set_integer(*r, x) {
                let g = &self.table.groups[r.group];
                return self.error(func, &format!("{} = {x} refused: {m}", g.element_name(r.index)));
            }
        }
        self.model = trial;
        fmi2OK
    }

    pub fn get_boolean(&mut self, func: Fmi2Function, vrs: &[u32], values: &mut [fmi2Boolean]) -> fmi2Status {
        for &vr in vrs {
            if let Err(s) = self.lookup(func, vr, BaseType::Boolean) {
                return s;
            }
        }
        for (value, &vr) in values.iter_mut().zip(vrs) {
            let Some((_, r)) = self.table.lookup(vr) else { return fmi2Error };
            *value = if self.model.get_boolean(r) { fmi2True } else { fmi2False };
        }
        fmi2OK
    }

    pub fn set_boolean(&mut self, func: Fmi2Function, vrs: &[u32], values: &[fmi2Boolean]) -> fmi2Status {
        for &vr in vrs {
            let (g, r) = match self.lookup(func, vr, BaseType::Boolean) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if let Err(s) = self.check_settable(func, g, r) {
                return s;
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            let Some((_, r)) = self.table.lookup(vr) else { return fmi2Error };
            if let Err(m) = self.model.set_boolean(r, x != fmi2False) {
                return self.error(func, &m);
            }
        }
        fmi2OK
    }

    /// A deep copy of the model through its own serialization (models are not `Clone`
    /// through `AnyModel`).
    fn snapshot_model(&self) -> AnyModel {
        let mut w = ByteWriter::default();
        self.model.save(&mut w);
        let mut r = ByteReader::new(&w.bytes);
        AnyModel::restore(self.kind, &mut r).unwrap_or_else(|_| self.kind.instantiate())
    }

    pub fn no_variables_of_type(&self, func: Fmi2Function, vrs: &[u32], type_name: &str) -> fmi2Status {
        match vrs.first() {
            None => fmi2OK,
            Some(vr) => self.error(
                func,
                &format!("value reference {vr}: {} has no {type_name} variables", self.kind.info().model_name),
            ),
        }
    }

    // ----- co-simulation ---------------------------------------------------------------------

    pub fn do_step(&mut self, func: Fmi2Function, tc: f64, h: f64) -> fmi2Status {
        if !(h.is_finite() && h > 0.0) {
            return self.error(func, &format!("communicationStepSize must be finite and > 0, got {h}"));
        }
        if !tc.is_finite() {
            return self.error(func, &format!("currentCommunicationPoint must be finite, got {tc}"));
        }
        let tol = COMMUNICATION_POINT_TOLERANCE * self.time.abs().max(1.0);
        if (tc - self.time).abs() > tol {
            return self.error(
                func,
                &format!(
                    "currentCommunicationPoint {tc} does not match the FMU's time {} (difference {:e})",
                    self.time,
                    tc - self.time
                ),
            );
        }
        let t_end = tc + h;
        if let Some(stop) = self.stop_time
            && t_end > stop + COMMUNICATION_POINT_TOLERANCE * stop.abs().max(1.0)
        {
            return self
                .error(func, &format!("step to t = {t_end} goes past the stopTime {stop} set in fmi2SetupExperiment"));
        }
        match self.model.do_step(tc, h) {
            Ok(()) => {
                self.time = t_end;
                self.last_successful_time = t_end;
                if self.logger.is_enabled(LogCategory::Events) {
                    let logger = &self.logger;
                    self.model.report_events(&mut |m| logger.log(fmi2OK, LogCategory::Events, m));
                }
                fmi2OK
            }
            Err(e) => {
                self.state = ModelState::StepFailed;
                self.terminated = true;
                self.last_successful_time = self.time;
                self.log(fmi2Discard, &format!("fmi2DoStep: {}", e.message));
                fmi2Discard
            }
        }
    }

    pub fn set_real_input_derivatives(
        &mut self,
        func: Fmi2Function,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> fmi2Status {
        let mut refs = Vec::with_capacity(vrs.len());
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let (g, r) = match self.lookup(func, vr, BaseType::Real) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if g.causality != Causality::Input {
                return self.error(func, &format!("{} is not an input", g.element_name(r.index)));
            }
            if order != 1 {
                return self.error(
                    func,
                    &format!("derivative order {order} of {} not supported (only 1)", g.element_name(r.index)),
                );
            }
            if !x.is_finite() {
                return self.error(
                    func,
                    &format!("derivative of {} = {x} refused: values must be finite", g.element_name(r.index)),
                );
            }
            refs.push(r);
        }
        for (r, &x) in refs.into_iter().zip(values) {
            self.model.set_input_derivative(r, x);
        }
        fmi2OK
    }

    pub fn get_real_output_derivatives(
        &mut self,
        func: Fmi2Function,
        vrs: &[u32],
        orders: &[i32],
        values: &mut [f64],
    ) -> fmi2Status {
        let mut refs = Vec::with_capacity(vrs.len());
        for (&vr, &order) in vrs.iter().zip(orders) {
            let (g, r) = match self.lookup(func, vr, BaseType::Real) {
                Ok(f) => f,
                Err(s) => return s,
            };
            if g.causality != Causality::Output {
                return self.error(func, &format!("{} is not an output", g.element_name(r.index)));
            }
            if order != 1 {
                return self.error(
                    func,
                    &format!(
                        "derivative order {order} of {} not available (maxOutputDerivativeOrder = 1)",
                        g.element_name(r.index)
                    ),
                );
            }
            refs.push(r);
        }
        for (i, r) in refs.into_iter().enumerate() {
            values[i] = self.model.output_derivative(r);
        }
        fmi2OK
    }

    pub fn get_real_status(&self, func: Fmi2Function, kind: fmi2StatusKind, value: &mut f64) -> fmi2Status {
        if kind == fmi2LastSuccessfulTime {
            *value = self.last_successful_time;
            fmi2OK
        } else {
            self.status_not_available(func, kind)
        }
    }

    pub fn get_boolean_status(&self, func: Fmi2Function, kind: fmi2StatusKind, value: &mut fmi2Boolean) -> fmi2Status {
        if kind == fmi2Terminated {
            *value = if self.terminated { fmi2True } else { fmi2False };
            fmi2OK
        } else {
            self.status_not_available(func, kind)
        }
    }

    pub fn status_not_available(&self, func: Fmi2Function, kind: fmi2StatusKind) -> fmi2Status {
        self.log(
            fmi2Discard,
            &format!(
                "{}: status kind {kind} is not available (this FMU steps synchronously; it answers fmi2LastSuccessfulTime \
                 with fmi2GetRealStatus and fmi2Terminated with fmi2GetBooleanStatus)",
                func.name()
            ),
        );
        fmi2Discard
    }

    // ----- directional derivatives --------------------------------------------------------

    pub fn get_directional_derivative(
        &mut self,
        func: Fmi2Function,
        unknowns: &[u32],
        knowns: &[u32],
        seeds: &[f64],
        out: &mut [f64],
    ) -> fmi2Status {
        if !self.kind.info().directional_derivatives {
            return self.error(func, "not supported by this model (providesDirectionalDerivative=\"false\")");
        }
        let mut u_refs = [VariableRef { group: 0, index: 0 }; 64];
        let mut k_refs = [VariableRef { group: 0, index: 0 }; 64];
        if unknowns.len() > u_refs.len() || knowns.len() > k_refs.len() {
            return self.error(func, "at most 64 unknowns and 64 knowns per call");
        }
        for (slot, &vr) in u_refs.iter_mut().zip(unknowns) {
            match self.lookup(func, vr, BaseType::Real) {
                Ok((_, r)) => *slot = r,
                Err(s) => return s,
            }
        }
        for ((slot, &vr), &seed) in k_refs.iter_mut().zip(knowns).zip(seeds) {
            match self.lookup(func, vr, BaseType::Real) {
                Ok((_, r)) => *slot = r,
                Err(s) => return s,
            }
            if !seed.is_finite() {
                return self.error(func, &format!("seed {seed} for value reference {vr} is not finite"));
            }
        }
        match self.model.directional_derivative(&u_refs[..unknowns.len()], &k_refs[..knowns.len()], seeds, out) {
            Ok(()) => fmi2OK,
            Err(m) => self.error(func, &m),
        }
    }

    // ----- Model Exchange -------------------------------------------------------------------

    fn state_count(&self) -> usize {
        self.kind.info().states.len()
    }

    fn check_state_count(&self, func: Fmi2Function, n: usize) -> Result<(), fmi2Status> {
        if n == self.state_count() {
            Ok(())
        } else {
            Err(self.error(func, &format!("nx = {n}, but the model has {} continuous states", self.state_count())))
        }
    }

    pub fn set_time(&mut self, func: Fmi2Function, t: f64) -> fmi2Status {
        if !t.is_finite() {
            return self.error(func, &format!("time must be finite, got {t}"));
        }
        self.time = t;
        self.model.set_time(t);
        fmi2OK
    }

    pub fn set_continuous_states(&mut self, func: Fmi2Function, x: &[f64]) -> fmi2Status {
        if let Err(s) = self.check_state_count(func, x.len()) {
            return s;
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return self.error(func, &format!("state {i} = {} refused: states must be finite", x[i]));
        }
        self.model.set_continuous_states(x);
        fmi2OK
    }

    pub fn get_continuous_states(&mut self, func: Fmi2Function, x: &mut [f64]) -> fmi2Status {
        if let Err(s) = self.check_state_count(func, x.len()) {
            return s;
        }
        self.model.continuous_states(x);
        fmi2OK
    }

    pub fn get_derivatives(&mut self, func: Fmi2Function, dx: &mut [f64]) -> fmi2Status {
        if let Err(s) = self.check_state_count(func, dx.len()) {
            return s;
        }
        self.model.derivatives(dx);
        if let Some(i) = dx.iter().position(|v| !v.is_finite()) {
            return self.error(
                func,
                &format!("derivative {i} is not finite at t = {}: the state is not admissible", self.time),
            );
        }
        fmi2OK
    }

    pub fn get_nominals(&mut self, func: Fmi2Function, x: &mut [f64]) -> fmi2Status {
        if let Err(s) = self.check_state_count(func, x.len()) {
            return s;
        }
        // Positions in m, velocities in m/s, unit vectors and their rates: all of order one.
        x.fill(1.0);
        fmi2OK
    }

    pub fn get_event_indicators(&mut self, func: Fmi2Function, z: &mut [f64]) -> fmi2Status {
        let count = self.kind.info().event_indicators;
        if z.len() != count {
            return self.error(func, &format!("ni = {}, but the model has {count} event indicators", z.len()));
        }
        self.model.event_indicators(z);
        fmi2OK
    }

    pub fn enter_event_mode(&mut self) -> fmi2Status {
        self.state = ModelState::EventMode;
        fmi2OK
    }

    pub fn enter_continuous_time_mode(&mut self) -> fmi2Status {
        self.state = ModelState::ContinuousTimeMode;
        fmi2OK
    }

    pub fn new_discrete_states(&mut self, info: &mut fmi2EventInfo) -> fmi2Status {
        // No discrete states and no time events: the end-stop forces are continuous in the
        // state, the events only mark their kinks (and singular arrangements passed), so one
        // update settles every event and the continuous states are unchanged.
        *info = fmi2EventInfo::default();
        let logger = &self.logger;
        let update = self.model.event_update(&mut |m| logger.log(fmi2OK, LogCategory::Events, m));
        if let Some(reason) = update.terminate {
            info.terminateSimulation = fmi2True;
            self.terminated = true;
            self.logger.log(fmi2Warning, LogCategory::Discard, &format!("fmi2NewDiscreteStates: {reason}"));
        }
        fmi2OK
    }

    pub fn completed_integrator_step(
        &mut self,
        enter_event_mode: &mut fmi2Boolean,
        terminate: &mut fmi2Boolean,
    ) -> fmi2Status {
        *enter_event_mode = fmi2False;
        match self.model.completed_integrator_step() {
            Ok(()) => {
                *terminate = fmi2False;
                fmi2OK
            }
            Err(e) => {
                *terminate = fmi2True;
                self.terminated = true;
                self.logger.log(
                    fmi2Warning,
                    LogCategory::Discard,
                    &format!("fmi2CompletedIntegratorStep: {}", e.message),
                );
                fmi2OK
            }
        }
    }

    // ----- FMU state ----------------------------------------------------------------------

    /// The instance as pointer-free bytes: header, instance fields, model, checksum.
    pub fn serialize(&self) -> Vec<u8> {
        let mut payload = ByteWriter::default();
        payload.u8(match self.interface {
            InterfaceType::ModelExchange => 0,
            InterfaceType::CoSimulation => 1,
        });
        payload.u8(self.state as u8);
        payload.f64(self.time);
        payload.f64(self.start_time);
        option_f64(&mut payload, self.stop_time);
        option_f64(&mut payload, self.tolerance);
        payload.bool(self.terminated);
        payload.f64(self.last_successful_time);
        self.model.save(&mut payload);

        let mut w = ByteWriter::default();
        w.raw(STATE_FORMAT_MAGIC);
        w.u32(STATE_FORMAT_VERSION);
        w.u8(self.kind.code());
        w.u64(self.token_hash);
        w.u64(payload.bytes.len() as u64);
        w.raw(&payload.bytes);
        let checksum = fnv1a64(&w.bytes);
        w.u64(checksum);
        w.bytes
    }

    fn parse(&self, bytes: &[u8]) -> Result<Snapshot, SnapshotError> {
        let mut r = ByteReader::new(bytes);
        if r.take(8)? != STATE_FORMAT_MAGIC {
            return Err(SnapshotError("not a state of this FMU (wrong magic bytes)".into()));
        }
        let version = r.u32()?;
        if version != STATE_FORMAT_VERSION {
            return Err(SnapshotError(format!(
                "state format version {version}, this binary reads {STATE_FORMAT_VERSION}"
            )));
        }
        let kind_code = r.u8()?;
        if kind_code != self.kind.code() {
            return Err(SnapshotError(format!("state of model kind {kind_code}, this instance is {:?}", self.kind)));
        }
        if r.u64()? != self.token_hash {
            return Err(SnapshotError("state of a different version of this model (GUID differs)".into()));
        }
        let len = r.u64()?;
        let payload_len = usize::try_from(len).map_err(|_| SnapshotError("payload length overflows".into()))?;
        let payload = r.take(payload_len)?;
        let header_and_payload = bytes.len() - r.remaining();
        let checksum = r.u64()?;
        if r.remaining() != 0 {
            return Err(SnapshotError(format!("{} unexpected bytes after the checksum", r.remaining())));
        }
        if fnv1a64(&bytes[..header_and_payload]) != checksum {
            return Err(SnapshotError("checksum mismatch: the state is corrupted".into()));
        }
        let mut p = ByteReader::new(payload);
        let interface = match p.u8()? {
            0 => InterfaceType::ModelExchange,
            1 => InterfaceType::CoSimulation,
            x => return Err(SnapshotError(format!("invalid interface type {x}"))),
        };
        if interface != self.interface {
            return Err(SnapshotError(format!("state of a {interface:?} instance, this one is {:?}", self.interface)));
        }
        let code = p.u8()?;
        let state = ModelState::from_code(code).ok_or_else(|| SnapshotError(format!("invalid model state {code}")))?;
        let time = p.finite("time")?;
        let start_time = p.finite("start time")?;
        let stop_time = read_option_f64(&mut p, "stop time")?;
        let tolerance = read_option_f64(&mut p, "tolerance")?;
        let terminated = p.bool()?;
        let last_successful_time = p.finite("last successful time")?;
        let model = AnyModel::restore(self.kind, &mut p)?;
        if p.remaining() != 0 {
            return Err(SnapshotError(format!("{} unexpected bytes at the end of the model data", p.remaining())));
        }
        Ok(Snapshot {
            interface,
            state,
            time,
            start_time,
            stop_time,
            tolerance,
            terminated,
            last_successful_time,
            model,
        })
    }

    /// Checks bytes without restoring them (`fmi2DeSerializeFMUstate`).
    pub fn validate_state_bytes(&self, bytes: &[u8]) -> Result<(), SnapshotError> {
        self.parse(bytes).map(|_| ())
    }

    /// Restores the instance from bytes, all or nothing.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let s = self.parse(bytes)?;
        self.interface = s.interface;
        self.state = s.state;
        self.time = s.time;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.tolerance = s.tolerance;
        self.terminated = s.terminated;
        self.last_successful_time = s.last_successful_time;
        self.model = s.model;
        self.logger.log(
            fmi2OK,
            LogCategory::Events,
            &format!("FMU state restored: t = {}, state {}", self.time, self.state.name()),
        );
        Ok(())
    }

    pub fn new_state_handle(bytes: Vec<u8>) -> FmuStateHandle {
        FmuStateHandle { magic: FMU_STATE_MAGIC, bytes }
    }
}

impl FmuStateHandle {
    pub fn replace_bytes(&mut self, bytes: Vec<u8>) {
        self.bytes = bytes;
    }
}
