//! One FMU instance of either FMI version: the state machine, argument checks, time
//! bookkeeping, FMU states and logging around a model. Safe Rust: the exported functions
//! ([`crate::fmi2::exports`], [`crate::fmi3::exports`]) turn C pointers into slices and call
//! these methods. The boundary ([`super::boundary`]) sets the calling function's name as the
//! instance's context before each call, so every message names it.
//!
//! Error policy:
//! - a call not allowed in the current state, a bad argument (NULL array, unknown or
//!   wrong-type value reference, wrong number of values, non-finite value, variable not
//!   settable now, bad step size or communication point): error, logged, and nothing changes
//!   (the host can correct the call and go on);
//! - a failed computation (parameters refused at exit from Initialization Mode): error and
//!   the instance enters the `error` state of the FMI tables;
//! - a step the physics or the integrator cannot complete: rolled back, discard, state
//!   `stepFailed` (FMI 3: Step Discarded), terminated;
//! - a panic: the instance is poisoned; every later call but reset and free is refused.
//!
//! Value references: FMI 2 gives every scalar element its own (`F[1]` .. `F[6]` are 1 .. 6);
//! FMI 3 gives every variable one, that of its first element, and an array's values follow in
//! row-major order.

mod access;
mod exchange;
mod states;
mod stepping;
mod values;

pub use states::FmuState;

use std::ffi::c_void;

use crate::fmi::log::{LogCategory, Logger};
use crate::fmi::registry;
use crate::fmi::{FmiFunction, FmiVersion, InterfaceType, ModelState, Status};
use crate::models::snapshot::fnv1a64;
use crate::models::variables::{VariableGroup, VariableRef, VariableTable};
use crate::models::{AnyModel, ModelKind};
use access::*;

/// How far `currentCommunicationPoint` may be from the FMU's time, and a step's end past
/// `stopTime`: round-off only. The FMU's time after a step is the importer's `t + h`, so an
/// importer that adds up its steps meets it exactly and one that multiplies (`t = n h`) within
/// a few units in the last place; the bound is 16 of those at the time's magnitude plus 1e-9
/// of the step (for times near 0). A larger difference is a jump of the clock and refused.
pub fn communication_point_tolerance(t: f64, other: f64, h: f64) -> f64 {
    16.0 * f64::EPSILON * t.abs().max(other.abs()) + 1e-9 * h.abs()
}

/// FMI 3's intermediate update callback: `(instanceEnvironment, intermediateUpdateTime,
/// intermediateVariableSetRequested, intermediateVariableGetAllowed, intermediateStepFinished,
/// canReturnEarly, *earlyReturnRequested, *earlyReturnTime)`; booleans as C `bool` bytes.
pub type IntermediateUpdate = Option<unsafe extern "C" fn(*mut c_void, f64, u8, u8, u8, u8, *mut u8, *mut f64)>;

/// FMI 3 Co-Simulation options chosen at instantiation.
#[derive(Clone, Copy)]
pub struct CoSimulationOptions {
    /// `eventModeUsed`: steps report events (`eventHandlingNeeded`) and the importer handles
    /// them in Event Mode.
    pub event_mode_used: bool,
    /// `earlyReturnAllowed`: a step may end early at an event.
    pub early_return_allowed: bool,
    pub intermediate_update: IntermediateUpdate,
    pub environment: *mut c_void,
}

impl Default for CoSimulationOptions {
    fn default() -> Self {
        CoSimulationOptions {
            event_mode_used: false,
            early_return_allowed: false,
            intermediate_update: None,
            environment: std::ptr::null_mut(),
        }
    }
}

/// What `fmi3DoStep` reports besides its status.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DoStepOutcome {
    pub event_handling_needed: bool,
    pub terminate_simulation: bool,
    pub early_return: bool,
    pub last_successful_time: f64,
}

/// What an event update (`fmi2NewDiscreteStates`, `fmi3UpdateDiscreteStates`) reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventInfo {
    pub discrete_states_need_update: bool,
    pub terminate_simulation: bool,
    pub nominals_changed: bool,
    pub values_changed: bool,
    pub next_event_time: Option<f64>,
}

pub struct Instance {
    pub version: FmiVersion,
    pub kind: ModelKind,
    pub interface: InterfaceType,
    pub state: ModelState,
    pub logger: Logger,
    /// Private, so that every change invalidates the value cache: through
    /// [`Instance::model_mut`] or [`Instance::replace_model`], by [`Instance::stale_after_set`]
    /// for sets of Real and Boolean variables, or by clearing `fresh` where another field is
    /// borrowed alongside (`update_discrete_states`).
    model: AnyModel,
    /// Real values by value reference, for the cache blocks set in `fresh` (see
    /// [`crate::models::FmuModel::cache_block`]).
    value_cache: Vec<f64>,
    /// Bit `b`: block `b` of `value_cache` holds the model's current values.
    fresh: u32,
    /// Bit `b`: block `b` (when fresh) holds a NaN, as the model reported when it filled the
    /// block, so that a read checks its values for NaN only then.
    nan: u32,
    /// Bit `b`: block `b` was read since the last step. A step fills these blocks again as it
    /// ends, so that a host reading the same outputs every step gets them computed once per
    /// step and its read is a copy; a block no longer read drops out after one step.
    read_since_step: u32,
    /// Bit `b`: a set of an input made block `b` stale since the last step. The step's end
    /// does not fill such a block again: a host that sets the inputs before it reads the
    /// outputs that follow them (a controller's commands in a closed loop) would discard that
    /// fill unread; its read fills it.
    set_since_step: u32,
    /// By element value reference: the cache block of a Real element and the run of
    /// consecutive elements from it in that block, so that a get of consecutive elements is
    /// one copy.
    cached: Vec<CachedElement>,
    /// By value reference: the width of the variable it names (0 if none), for FMI 3's check
    /// of consecutive whole variables (4 bytes a reference against the access entries' 40).
    variable_width: Vec<u32>,
    /// The runs of the last read of several cache blocks (a host reads the same every step).
    read_plan: values::ReadPlan,
    pub table: VariableTable,
    /// Hash of the instantiation token, stamped into serialized states.
    token_hash: u64,
    pub start_time: f64,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    /// Current communication point (Co-Simulation) or time (Model Exchange).
    pub time: f64,
    /// The importer should end the simulation (`fmi2Terminated`).
    pub terminated: bool,
    /// End of the last completed step (`fmi2LastSuccessfulTime`).
    pub last_successful_time: f64,
    poisoned: Option<String>,
    /// The exported function being called: every message names it.
    current: &'static str,
    /// Model Exchange: for each continuous state in the order the importer sees, its index in
    /// the model's state vector (the identity in FMI 2; FMI 3 lists whole array variables).
    state_order: Vec<usize>,
    pub co_simulation: CoSimulationOptions,
    /// What each value reference addresses (built once per instance).
    access: Vec<Option<Access>>,
    /// The FMU states this instance made and the importer has not freed yet (freed with the
    /// instance at the latest). Boxed: a handle is a state's address, which must not move
    /// when the vector grows.
    #[allow(clippy::vec_box)]
    fmu_states: Vec<Box<FmuState>>,
    /// The Strings of the last get of Strings: the pointers the importer got point into them.
    strings: Vec<std::ffi::CString>,
}

impl Instance {
    /// `token` is the importer's instantiation token, already matched to `kind`.
    pub fn new(kind: ModelKind, token: &str, version: FmiVersion, interface: InterfaceType, logger: Logger) -> Self {
        let info = kind.info();
        let table = VariableTable::new(info.groups);
        let model = kind.instantiate();
        let access = access_table(&table, version, |g| model.cache_block(g));
        let state_order = match version {
            FmiVersion::Fmi2 => (0..info.states.len()).collect(),
            FmiVersion::Fmi3 => super::description::fmi3_state_order(info),
        };
        let mut instance = Instance {
            version,
            kind,
            interface,
            state: ModelState::Instantiated,
            logger,
            value_cache: vec![0.0; access.len()],
            fresh: 0,
            nan: 0,
            read_since_step: 0,
            set_since_step: 0,
            cached: cached_elements(&access),
            variable_width: access.iter().map(|a| a.map_or(0, |a| u32::try_from(a.width).unwrap_or(0))).collect(),
            read_plan: values::ReadPlan::NONE,
            model,
            table,
            token_hash: fnv1a64(token.as_bytes()),
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            time: 0.0,
            terminated: false,
            last_successful_time: 0.0,
            poisoned: None,
            current: "",
            state_order,
            co_simulation: CoSimulationOptions::default(),
            fmu_states: Vec::new(),
            strings: Vec::new(),
            access,
        };
        instance.apply_event_reporting();
        instance
    }

    /// The instance as the importer's handle, registered as live; NULL (logged) if the
    /// registry is full.
    pub fn into_handle(self) -> *mut c_void {
        let version = self.version;
        let address = Box::into_raw(Box::new(self)) as *mut c_void;
        if let Some(handle) = registry::register(address, version) {
            return handle;
        }
        // SAFETY: just made from a Box and never handed out.
        let inst = unsafe { Box::from_raw(address as *mut Instance) };
        inst.error(&format!("more than {} instances are live in this process; free some first", registry::CAPACITY));
        std::ptr::null_mut()
    }

    /// # Safety
    /// `address` must be an instance's address from [`Instance::into_handle`] that the
    /// registry handed over for dropping ([`registry::request_free`] or
    /// [`registry::release`]), so that no other reference to it exists.
    pub unsafe fn drop_instance(address: *mut c_void) {
        // SAFETY: per the contract, a live Box<Instance> that nothing else refers to.
        drop(unsafe { Box::from_raw(address as *mut Instance) });
    }

    // ----- context, logging and checks -----------------------------------------------------

    /// Sets the calling function (done by the boundary before each call).
    pub fn begin(&mut self, function: &'static str) {
        self.current = function;
    }

    /// The exported function being called.
    pub fn function(&self) -> &'static str {
        self.current
    }

    pub fn log(&self, status: Status, message: &str) {
        self.logger.log(status, LogCategory::for_status(status), message);
    }

    /// Logs `"<function>: <message>"` as an error and returns the error status.
    pub fn error(&self, message: &str) -> Status {
        self.log(Status::Error, &format!("{}: {message}", self.current));
        Status::Error
    }

    fn state_name(&self) -> &'static str {
        self.state.name(self.version)
    }

    #[inline]
    pub fn check_call<F: FmiFunction>(&self, func: F) -> Result<(), Status> {
        if self.poisoned.is_none() && func.allowed_in(self.interface, self.state) {
            return Ok(());
        }
        self.refuse_call(func)
    }

    /// [`Instance::check_call`] of a call that is not plainly allowed: poisoned instance or a
    /// state the function is not allowed in.
    #[cold]
    fn refuse_call<F: FmiFunction>(&self, func: F) -> Result<(), Status> {
        if let Some(reason) = &self.poisoned {
            if !func.name().ends_with("Reset") && !func.name().ends_with("FreeInstance") {
                self.error(&format!(
                    "refused, the instance is poisoned by an internal error ({reason}); reset or free it"
                ));
                return Err(Status::Error);
            }
            return Ok(());
        }
        if func.allowed_in(self.interface, self.state) {
            return Ok(());
        }
        self.error(&format!(
            "illegal call sequence, not allowed in state {} of a {} instance",
            self.state_name(),
            self.interface.name()
        ));
        Err(Status::Error)
    }

    /// The `logCalls` line of a finished call; `args` formats its arguments (only called when
    /// the category is on: no formatting in the hot path otherwise).
    #[inline]
    pub fn log_call(&self, status: Status, args: impl FnOnce() -> String) {
        if self.logger.is_enabled(LogCategory::Calls) {
            self.write_call(status, args());
        }
    }

    #[cold]
    fn write_call(&self, status: Status, args: String) {
        self.logger.log(
            Status::Ok,
            LogCategory::Calls,
            &format!(
                "{}({args}) -> {} (state {}, t = {:?})",
                self.current,
                status.name(self.version),
                self.state_name(),
                self.time
            ),
        );
    }

    pub fn poison(&mut self, message: &str) {
        let reason = format!("panic in {} at t = {:?}: {message}", self.current, self.time);
        self.logger.log(Status::Fatal, LogCategory::Fatal, &format!("{reason}; the instance is poisoned"));
        self.poisoned = Some(reason);
    }

    pub fn is_poisoned(&self) -> bool {
        self.poisoned.is_some()
    }

    /// Resolves a value reference to the elements it addresses: one for FMI 2, every element
    /// of the variable for FMI 3.
    fn lookup(&self, vr: u32, want: BaseType) -> Result<(&'static VariableGroup, VariableRef), Status> {
        let found = match self.version {
            FmiVersion::Fmi2 => self.table.lookup(vr).filter(|(g, _)| !g.fmi3_only),
            FmiVersion::Fmi3 => self.table.lookup_variable(vr),
        };
        match found {
            Some((g, r)) if want.matches(g.var_type) => Ok((g, r)),
            Some((g, r)) => Err(self.error(&format!(
                "value reference {vr} is {} of type {:?}, not a {} variable",
                self.variable_name(g, r),
                g.var_type,
                want.name(self.version)
            ))),
            None => Err(self.error(&format!(
                "value reference {vr} is not a {} variable of {}",
                want.name(self.version),
                self.kind.info().model_name
            ))),
        }
    }

    /// The name of what a reference addresses: the element (FMI 2) or the variable (FMI 3).
    fn variable_name(&self, g: &VariableGroup, r: VariableRef) -> String {
        match self.version {
            FmiVersion::Fmi2 => g.element_name(r.index),
            FmiVersion::Fmi3 => g.variable_name(),
        }
    }

    /// Checks `vrs` against a base type (and, when `setting`, the current state) and counts
    /// the values they address, which must be `n_values`; the first pass of every get/set
    /// (nothing is read or written before all is known to be valid).
    fn check_values(&self, vrs: &[u32], want: BaseType, n_values: usize, setting: bool) -> Result<(), Status> {
        let mut count = 0usize;
        for &vr in vrs {
            let a = self.access(vr, want)?;
            if setting && a.settable_in & self.state.bit() == 0 {
                return Err(self.not_settable(a));
            }
            count += a.width;
        }
        if count != n_values {
            return Err(self.error(&format!("the value references address {count} values, but nValues = {n_values}")));
        }
        Ok(())
    }

    fn element_name(&self, r: VariableRef) -> String {
        self.table.groups.get(r.group).map_or_else(String::new, |g| g.element_name(r.index))
    }

    /// A reference's access entry if it has the wanted base type; else the error, logged.
    #[inline]
    fn access(&self, vr: u32, want: BaseType) -> Result<Access, Status> {
        match self.access.get(vr as usize).copied().flatten() {
            Some(a) if a.base == want => Ok(a),
            _ => Err(self.lookup_error(vr, want)),
        }
    }

    #[cold]
    fn lookup_error(&self, vr: u32, want: BaseType) -> Status {
        match self.lookup(vr, want) {
            Err(status) => status,
            Ok(_) => self.error(&format!("value reference {vr} cannot be accessed")),
        }
    }

    #[cold]
    fn not_settable(&self, a: Access) -> Status {
        let Some(g) = self.table.groups.get(a.group) else { return Status::Error };
        self.error(&format!(
            "{} ({} {}) may not be set in state {}",
            self.variable_name(g, VariableRef { group: a.group, index: a.index }),
            g.variability.xml(),
            g.causality.xml(),
            self.state_name()
        ))
    }

    // ----- common functions -----------------------------------------------------------------

    pub fn set_debug_logging(&mut self, logging_on: bool, names: &[Option<String>]) -> Status {
        let mut categories = Vec::with_capacity(names.len());
        for name in names {
            match name.as_deref().map(|n| (n, LogCategory::from_name(n))) {
                Some((_, Some(c))) => categories.push(c),
                Some((n, None)) => {
                    let known: Vec<&str> = LogCategory::ALL.iter().map(|c| c.name()).collect();
                    return self.error(&format!("unknown log category \"{n}\" (known: {})", known.join(", ")));
                }
                None => return self.error("a category name is NULL"),
            }
        }
        self.logger.set_debug_logging(logging_on, &categories);
        self.apply_event_reporting();
        Status::Ok
    }

    /// The experiment: `fmi2SetupExperiment`, and the arguments of `fmi3EnterInitializationMode`.
    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start_time: f64, stop_time: Option<f64>) -> Status {
        if !start_time.is_finite() {
            return self.error(&format!("startTime must be finite, got {start_time:?}"));
        }
        if let Some(tol) = tolerance
            && !(tol > 0.0 && tol < 1.0)
        {
            return self.error(&format!("tolerance must be in (0, 1), got {tol:?}"));
        }
        if let Some(stop) = stop_time
            && (!stop.is_finite() || stop < start_time)
        {
            return self.error(&format!("stopTime {stop:?} must be finite and not before startTime {start_time:?}"));
        }
        self.tolerance = tolerance;
        self.start_time = start_time;
        self.stop_time = stop_time;
        self.time = start_time;
        self.last_successful_time = start_time;
        Status::Ok
    }

    pub fn enter_initialization_mode(&mut self) -> Status {
        self.time = self.start_time;
        self.last_successful_time = self.start_time;
        self.state = ModelState::InitializationMode;
        Status::Ok
    }

    pub fn exit_initialization_mode(&mut self) -> Status {
        let model_exchange = self.interface == InterfaceType::ModelExchange;
        let (start_time, tolerance) = (self.start_time, self.tolerance);
        match self.model_mut().exit_initialization(start_time, tolerance, model_exchange) {
            Ok(done) => {
                self.logger.log(Status::Ok, LogCategory::Events, &done.summary);
                self.state = match (self.interface, self.version) {
                    (InterfaceType::CoSimulation, FmiVersion::Fmi3) if self.co_simulation.event_mode_used => {
                        ModelState::EventMode
                    }
                    (InterfaceType::CoSimulation, _) => ModelState::StepComplete,
                    (InterfaceType::ModelExchange, _) => ModelState::EventMode,
                };
                match done.warning {
                    Some(warning) => {
                        self.log(Status::Warning, &format!("{}: {warning}", self.current));
                        Status::Warning
                    }
                    None => Status::Ok,
                }
            }
            Err(message) => {
                self.state = ModelState::Error;
                self.error(&format!("{message}; the instance is in the error state (reset to start again)"))
            }
        }
    }

    pub fn terminate(&mut self) -> Status {
        self.state = ModelState::Terminated;
        Status::Ok
    }

    pub fn reset(&mut self) -> Status {
        self.replace_model(self.kind.instantiate());
        self.state = ModelState::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.tolerance = None;
        self.time = 0.0;
        self.terminated = false;
        self.last_successful_time = 0.0;
        self.poisoned = None;
        self.logger.log(Status::Ok, LogCategory::Events, "reset to the start values");
        Status::Ok
    }

    // ----- get/set ------------------------------------------------------------------------

    /// Tells the model whether reported-only events are wanted: when `logEvents` messages can
    /// reach the importer, and always in Model Exchange (event indicators).
    fn apply_event_reporting(&mut self) {
        let on = self.interface == InterfaceType::ModelExchange || self.logger.is_enabled(LogCategory::Events);
        self.model.set_event_reporting(on);
    }

    /// A new model in place of the current one (reset, restored state, validated copy), told
    /// what the instance reports.
    fn replace_model(&mut self, model: AnyModel) {
        *self.model_mut() = model;
        self.apply_event_reporting();
    }

    /// The model, for a change: the value cache no longer holds its values.
    fn model_mut(&mut self) -> &mut AnyModel {
        self.fresh = 0;
        &mut self.model
    }
}
