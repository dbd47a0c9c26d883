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

use std::ffi::c_void;

use super::log::{LogCategory, Logger};
use super::registry;
use super::{FmiFunction, FmiVersion, InterfaceType, ModelState, Status};
use crate::models::snapshot::{self, ByteReader, ByteWriter, SnapshotError, fnv1a64};
use crate::models::variables::{
    Causality, Dependency, Initial, Variability, VariableGroup, VariableRef, VariableTable, VariableType,
};
use crate::models::{AnyModel, EventUpdate, ModelKind, StepReport};
use crate::physics::body::state::all_finite;

/// How far `currentCommunicationPoint` may be from the FMU's time, and a step's end past
/// `stopTime`: round-off only. The FMU's time after a step is the importer's `t + h`, so an
/// importer that adds up its steps meets it exactly and one that multiplies (`t = n h`) within
/// a few units in the last place; the bound is 16 of those at the time's magnitude plus 1e-9
/// of the step (for times near 0). A larger difference is a jump of the clock and refused.
pub fn communication_point_tolerance(t: f64, other: f64, h: f64) -> f64 {
    16.0 * f64::EPSILON * t.abs().max(other.abs()) + 1e-9 * h.abs()
}

/// The base type a get/set function works on (FMI 2 Real/Integer/Boolean, FMI 3
/// Float64/Int32/Boolean).
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

    fn name(self, version: FmiVersion) -> &'static str {
        match (self, version) {
            (BaseType::Real, FmiVersion::Fmi2) => "Real",
            (BaseType::Real, FmiVersion::Fmi3) => "Float64",
            (BaseType::Integer, FmiVersion::Fmi2) => "Integer",
            (BaseType::Integer, FmiVersion::Fmi3) => "Int32",
            (BaseType::Boolean, _) => "Boolean",
        }
    }
}

/// What a value reference addresses, precomputed per instance so that a get or set checks a
/// reference with one table read: the element (FMI 2) or the variable's first element and its
/// number of values (FMI 3), its base type, and the states in which it may be set.
#[derive(Clone, Copy, Debug)]
struct Access {
    group: usize,
    index: usize,
    width: usize,
    base: BaseType,
    /// Bit set over [`ModelState`]: where `fmi2Set*`/`fmi3Set*` may change it.
    settable_in: u16,
    /// The block of the value cache a Real variable is read through, or [`NO_CACHE`].
    cache: u8,
    /// How many elements of the group, from this one on, consecutive value references
    /// address (FMI 2: to the end of the array; FMI 3: the variable's own width): the
    /// longest run a set of consecutive references may store in one call to the model.
    run: usize,
    /// The cache blocks a set of this variable makes stale: for an input, those holding a
    /// value that depends on it (`<ModelStructure>`: the dependencies of outputs, initial
    /// unknowns and derivatives); for anything else every block (parameters change the whole
    /// model).
    stales: u32,
}

/// [`Access::cache`] of a variable read through the model element by element.
const NO_CACHE: u8 = u8::MAX;

fn base_type(t: VariableType) -> BaseType {
    if t.is_real() {
        BaseType::Real
    } else if t.is_boolean() {
        BaseType::Boolean
    } else {
        BaseType::Integer
    }
}

/// The access table of a model for one FMI version, indexed by value reference.
/// `cache_block` gives the model's cache block of each group ([`AnyModel::cache_block`]).
fn access_table(
    table: &VariableTable,
    version: FmiVersion,
    cache_block: impl Fn(usize) -> Option<u8>,
) -> Vec<Option<Access>> {
    let max_vr = table.groups.iter().map(|g| g.vr(g.len().saturating_sub(1))).max().unwrap_or(0);
    let blocks: Vec<Option<u8>> = (0..table.groups.len()).map(cache_block).collect();
    // The cache blocks holding a value that depends on an input group, by the model's
    // declared structure: outputs, initial unknowns and derivatives.
    let dependants = |input: &VariableGroup| {
        let on_input = |d: &Dependency| matches!(*d, Dependency::All(n) | Dependency::SameIndex(n) if n == input.name);
        table.groups.iter().zip(&blocks).fold(0u32, |mask, (g, block)| {
            let mut knowns =
                g.output_dependencies.iter().chain(g.initial_dependencies).chain(g.derivative_dependencies);
            match block {
                Some(b) if knowns.any(on_input) => mask | 1 << b,
                _ => mask,
            }
        })
    };
    // Per group: what a set of it makes stale.
    let stales: Vec<u32> =
        table.groups.iter().map(|g| if g.causality == Causality::Input { dependants(g) } else { u32::MAX }).collect();
    (0..=max_vr)
        .map(|vr| {
            let (g, r) = match version {
                FmiVersion::Fmi2 => table.lookup(vr).filter(|(g, _)| !g.fmi3_only)?,
                FmiVersion::Fmi3 => table.lookup_variable(vr)?,
            };
            let settable_in =
                ModelState::ALL.iter().filter(|&&s| settable_in_state(g, s)).fold(0u16, |m, s| m | s.bit());
            let width = match version {
                FmiVersion::Fmi2 => 1,
                FmiVersion::Fmi3 => g.len(),
            };
            let base = base_type(g.var_type);
            let cache = if base == BaseType::Real { blocks.get(r.group).copied().flatten() } else { None };
            let stales = stales.get(r.group).copied().unwrap_or(u32::MAX);
            Some(Access {
                group: r.group,
                index: r.index,
                width,
                base,
                settable_in,
                cache: cache.unwrap_or(NO_CACHE),
                run: g.len() - r.index,
                stales,
            })
        })
        .collect()
}

/// By element value reference: the cache block each Real element is read through, or
/// [`NO_CACHE`].
fn element_blocks(access: &[Option<Access>]) -> Vec<u8> {
    let mut blocks = vec![NO_CACHE; access.len()];
    for (vr, a) in access.iter().enumerate() {
        if let Some(a) = a
            && a.base == BaseType::Real
            && let Some(elements) = blocks.get_mut(vr..vr + a.width)
        {
            elements.fill(a.cache);
        }
    }
    blocks
}

/// By element value reference: the length of the run of elements from it in the same cache
/// block (0 for an element not cached).
fn cache_runs(blocks: &[u8]) -> Vec<u16> {
    let mut runs = vec![0u16; blocks.len()];
    for vr in (0..blocks.len()).rev() {
        if blocks[vr] != NO_CACHE {
            let rest = if blocks.get(vr + 1) == Some(&blocks[vr]) { runs[vr + 1] } else { 0 };
            runs[vr] = rest.saturating_add(1);
        }
    }
    runs
}

/// What the fast paths of a get know of a Real element, by element value reference (FMI 2's
/// numbering, the value cache's index): one table, so that a read looks its first reference up
/// once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CachedElement {
    /// The element's cache block, or [`NO_CACHE`].
    block: u8,
    /// How many consecutive elements from this one lie in its cache block (0: not cached).
    run: u16,
}

fn cached_elements(access: &[Option<Access>]) -> Vec<CachedElement> {
    let blocks = element_blocks(access);
    let runs = cache_runs(&blocks);
    blocks.into_iter().zip(runs).map(|(block, run)| CachedElement { block, run }).collect()
}

/// `0, 1, 2, ...`: a run of consecutive value references is a slice of it.
static COUNTING: [u32; 1024] = {
    let mut c = [0; 1024];
    let mut i = 0;
    while i < c.len() {
        c[i] = i as u32;
        i += 1;
    }
    c
};

/// Whether value references are consecutive (`vrs[i] = vrs[0] + i`, wrapping): compared with
/// the run of [`COUNTING`] that starts at `vrs[0]`, beyond it with the counting itself.
/// (Counts built in registers instead of read from the table: the read of twelve leg values
/// 166 -> 177 instructions.)
#[inline(always)]
fn consecutive(vrs: &[u32]) -> bool {
    let Some(&first) = vrs.first() else { return false };
    match COUNTING.get(first as usize..first as usize + vrs.len()) {
        Some(run) => same_u32(run, vrs),
        None => vrs.iter().enumerate().fold(0, |diff, (i, &vr)| diff | (vr ^ first.wrapping_add(i as u32))) == 0,
    }
}

/// `a == b` for slices of one length. From 4 to 16 elements (a dozen references in a read
/// or set), two overlapping fixed-size comparisons of the ends, without early exit, as libc's
/// `memcmp` does inside but without its call.
#[inline(always)]
fn same_u32(a: &[u32], b: &[u32]) -> bool {
    match a.len() {
        8..=16 => ends_equal::<8>(a, b),
        4..=7 => ends_equal::<4>(a, b),
        _ => a == b,
    }
}

/// Whether the first and the last `K` elements of `a` and `b` (of one length, at least `K`)
/// agree.
#[inline(always)]
fn ends_equal<const K: usize>(a: &[u32], b: &[u32]) -> bool {
    match (a.first_chunk::<K>(), b.first_chunk::<K>(), a.last_chunk::<K>(), b.last_chunk::<K>()) {
        // `&`, not `&&`: both compared without a branch between them.
        (Some(a0), Some(b0), Some(a1), Some(b1)) => (a0 == b0) & (a1 == b1),
        _ => false,
    }
}

/// `to.copy_from_slice(from)`. From 2 to 16 values (a read of a dozen outputs), two
/// overlapping fixed-size copies of the ends, as libc's `memcpy` does inside but without its
/// call.
#[inline(always)]
fn copy_f64(to: &mut [f64], from: &[f64]) {
    match to.len() {
        8..=16 => copy_ends::<8>(to, from),
        4..=7 => copy_ends::<4>(to, from),
        2..=3 => copy_ends::<2>(to, from),
        _ => to.copy_from_slice(from),
    }
}

/// Copies the first and the last `K` values of `from` into `to` (of one length, at least `K`).
#[inline(always)]
fn copy_ends<const K: usize>(to: &mut [f64], from: &[f64]) {
    if let (Some(t), Some(f)) = (to.first_chunk_mut::<K>(), from.first_chunk::<K>()) {
        *t = *f;
    }
    if let (Some(t), Some(f)) = (to.last_chunk_mut::<K>(), from.last_chunk::<K>()) {
        *t = *f;
    }
}

/// Whether a variable may be set in a state (FMI 2.0 conditions 1, 3, 6 of the CS table; 1, 3,
/// 4, 5 of the ME table; the same rules in FMI 3).
fn settable_in_state(g: &VariableGroup, state: ModelState) -> bool {
    if g.variability == Variability::Constant || g.causality == Causality::Independent {
        return false;
    }
    let exact_or_approx = matches!(g.initial, Some(Initial::Exact | Initial::Approx));
    match state {
        ModelState::Instantiated => exact_or_approx || g.causality == Causality::Input,
        ModelState::InitializationMode => g.initial == Some(Initial::Exact) || g.causality == Causality::Input,
        ModelState::StepComplete | ModelState::EventMode => {
            g.causality == Causality::Input
                || (g.causality == Causality::Parameter && g.variability == Variability::Tunable)
        }
        ModelState::ContinuousTimeMode => g.causality == Causality::Input && g.variability == Variability::Continuous,
        _ => false,
    }
}

/// The elements addressed by `vrs` in order: one per reference in FMI 2, every element of
/// each referenced variable in FMI 3. Unknown references are skipped (callers check first).
fn elements<'a>(access: &'a [Option<Access>], vrs: &'a [u32]) -> impl Iterator<Item = VariableRef> + 'a {
    // A plain state machine rather than `flat_map`: this runs on every get and set.
    let mut refs = vrs.iter();
    let mut current: Option<(Access, usize)> = None;
    std::iter::from_fn(move || {
        loop {
            if let Some((a, i)) = current.as_mut()
                && *i < a.width
            {
                *i += 1;
                return Some(VariableRef { group: a.group, index: a.index + *i - 1 });
            }
            current = access.get(*refs.next()? as usize).copied().flatten().map(|a| (a, 0));
        }
    })
}

/// An FMU state (`fmi2FMUstate`, `fmi3FMUState`): the serialized bytes of an instance. The
/// instance that made it owns it; the importer's handle is its address, recognised by
/// comparison with the instance's own states, never by reading through it.
pub struct FmuState {
    bytes: Vec<u8>,
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

/// A restorable picture of an instance, parsed and validated.
struct Snapshot {
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
    /// By element value reference: the cache block of a Real element and the run of
    /// consecutive elements from it in that block, so that a get of consecutive elements is
    /// one copy.
    cached: Vec<CachedElement>,
    /// By value reference: the width of the variable it names (0 if none), for FMI 3's check
    /// of consecutive whole variables (4 bytes a reference against the access entries' 40).
    variable_width: Vec<u32>,
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
            cached: cached_elements(&access),
            variable_width: access.iter().map(|a| a.map_or(0, |a| u32::try_from(a.width).unwrap_or(0))).collect(),
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
                "{}({args}) -> {} (state {}, t = {})",
                self.current,
                status.name(self.version),
                self.state_name(),
                self.time
            ),
        );
    }

    pub fn poison(&mut self, message: &str) {
        let reason = format!("panic in {} at t = {}: {message}", self.current, self.time);
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
            return self.error(&format!("startTime must be finite, got {start_time}"));
        }
        if let Some(tol) = tolerance
            && !(tol > 0.0 && tol < 1.0)
        {
            return self.error(&format!("tolerance must be in (0, 1), got {tol}"));
        }
        if let Some(stop) = stop_time
            && (!stop.is_finite() || stop < start_time)
        {
            return self.error(&format!("stopTime {stop} must be finite and not before startTime {start_time}"));
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

    #[inline(always)]
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        // The fast path once per version, so that each has only its own run check inline.
        let fast = match self.version {
            FmiVersion::Fmi2 => self.get_fresh_run(FmiVersion::Fmi2, vrs, values),
            FmiVersion::Fmi3 => self.get_fresh_run(FmiVersion::Fmi3, vrs, values),
        };
        match fast {
            Some(status) => status,
            None => self.get_real_elementwise(vrs, values),
        }
    }

    /// The fast path of [`Instance::get_real`]: consecutive elements of one cache block (the
    /// legs' lengths and rates) that the step has computed already, one copy. `None`: the
    /// general path (which fills a stale block first). A get that fails leaves its values
    /// undefined (FMI 2.0 section 2.1.3, FMI 3.0 section 2.2.6), so nothing needs validating
    /// before the first is written.
    #[inline(always)]
    fn get_fresh_run(&mut self, version: FmiVersion, vrs: &[u32], values: &mut [f64]) -> Option<Status> {
        let (first, block) = self.cached_run(version, vrs, values.len())?;
        let bit = 1u32 << block;
        if self.fresh & bit == 0 {
            return None;
        }
        self.read_since_step |= bit;
        copy_f64(values, self.value_cache.get(first..first + values.len())?);
        Some(if self.nan & bit == 0 { Status::Ok } else { self.check_nan(vrs, values) })
    }

    /// Fills the cache blocks in `blocks` from the model and notes which hold a NaN.
    #[inline(never)]
    fn refresh(&mut self, blocks: u32) {
        let mut rest = blocks;
        while rest != 0 {
            let block = rest.trailing_zeros();
            let nan = self.model.fill_cache(block as u8, &mut self.value_cache);
            debug_assert_eq!(nan, self.block_holds_nan(block), "fill_cache's NaN report, block {block}");
            self.nan = (self.nan & !(1 << block)) | (u32::from(nan) << block);
            rest &= rest - 1;
        }
        self.fresh |= blocks;
    }

    /// Whether an element of cache block `block` is NaN (the check of the models' reports).
    fn block_holds_nan(&self, block: u32) -> bool {
        let values = self.value_cache.iter().zip(&self.cached);
        values.filter(|&(_, c)| u32::from(c.block) == block).any(|(x, _)| x.is_nan())
    }

    /// The end of a get whose block holds a NaN somewhere: an error if one was read.
    #[cold]
    fn check_nan(&self, vrs: &[u32], values: &[f64]) -> Status {
        if values.iter().any(|x| x.is_nan()) { self.nan_error(vrs, values) } else { Status::Ok }
    }

    /// [`Instance::get_real`] reference by reference (and any read of a stale block). Out of
    /// line, so that the fast path above keeps few registers.
    #[inline(never)]
    fn get_real_elementwise(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        if self.version == FmiVersion::Fmi2 && vrs.len() == values.len() {
            // One element per reference: the cache block of each comes from one table. Loops
            // without calls (so the tables stay in registers): which blocks the references
            // need, fill the stale ones, copy. A reference outside the cache (or unknown)
            // takes the element-by-element path.
            let cached = &self.cached;
            let mut needed = 0u32;
            for &vr in vrs {
                let block = cached.get(vr as usize).map_or(NO_CACHE, |c| c.block);
                needed |= 1u32.wrapping_shl(block.into());
            }
            let mut nan = false;
            if needed & 1u32.wrapping_shl(NO_CACHE.into()) == 0 {
                self.refresh(needed & !self.fresh);
                self.read_since_step |= needed;
                let cache = &self.value_cache;
                for (slot, &vr) in values.iter_mut().zip(vrs) {
                    *slot = cache.get(vr as usize).copied().unwrap_or(f64::NAN);
                    nan |= slot.is_nan();
                }
            } else {
                for (slot, &vr) in values.iter_mut().zip(vrs) {
                    if let Err(s) = self.read_real(vrs, vr, std::slice::from_mut(slot), 0) {
                        return s;
                    }
                    nan |= slot.is_nan();
                }
            }
            return if nan { self.nan_error(vrs, values) } else { Status::Ok };
        }
        let mut filled = 0;
        for &vr in vrs {
            match self.read_real(vrs, vr, values, filled) {
                Ok(width) => filled += width,
                Err(s) => return s,
            }
        }
        if filled != values.len() {
            return self.count_error(vrs, BaseType::Real, values.len());
        }
        if values.iter().any(|x| x.is_nan()) {
            return self.nan_error(vrs, values);
        }
        Status::Ok
    }

    /// When `vrs` address `n` consecutive elements of one cache block (FMI 2: consecutive
    /// references; FMI 3: consecutive variables), the first element's value reference (its
    /// place in the value cache) and the block. `version` is the instance's, passed as a
    /// constant where the caller knows it.
    #[inline(always)]
    fn cached_run(&self, version: FmiVersion, vrs: &[u32], n: usize) -> Option<(usize, u8)> {
        let first = *vrs.first()? as usize;
        let CachedElement { block, run } = *self.cached.get(first)?;
        // `&`, not `&&`: one branch for the usual case (a run outside the cache has run 0).
        let fits = (n != 0) & (n <= usize::from(run));
        let whole = match version {
            FmiVersion::Fmi2 => (vrs.len() == n) & consecutive(vrs),
            FmiVersion::Fmi3 => fits && self.consecutive_variables(vrs, n),
        };
        (fits & whole).then_some((first, block))
    }

    /// FMI 3: whether `vrs` are whole variables, each right after the last, `n` elements in
    /// all.
    #[inline(always)]
    fn consecutive_variables(&self, vrs: &[u32], n: usize) -> bool {
        let Some(&first) = vrs.first() else { return false };
        let mut next = first as usize;
        for &vr in vrs {
            // 0 for an element inside a variable or an unknown reference: the general path.
            let width = self.variable_width.get(vr as usize).map_or(0, |&w| w as usize);
            if (vr as usize != next) | (width == 0) {
                return false;
            }
            next += width;
        }
        next == first as usize + n
    }

    /// Reads the values of one reference into `values[filled..]`: from the value cache
    /// (filling its block if stale) or through the model. Returns the number of values read.
    /// Out of line, so that the loops of [`Instance::get_real_elementwise`] keep their
    /// registers.
    #[inline(never)]
    fn read_real(&mut self, vrs: &[u32], vr: u32, values: &mut [f64], filled: usize) -> Result<usize, Status> {
        let a = self.access(vr, BaseType::Real)?;
        let Some(out) = values.get_mut(filled..filled + a.width) else {
            return Err(self.count_error(vrs, BaseType::Real, values.len()));
        };
        if a.cache == NO_CACHE {
            for (i, slot) in out.iter_mut().enumerate() {
                *slot = self.model.get_real(VariableRef { group: a.group, index: a.index + i });
            }
            return Ok(a.width);
        }
        let bit = 1u32 << a.cache;
        if self.fresh & bit == 0 {
            self.refresh(bit);
        }
        self.read_since_step |= bit;
        let first = vr as usize;
        match self.value_cache.get(first..first + out.len()) {
            // Element by element: a handful of values, no memcpy call.
            Some(cached) => {
                for (slot, &x) in out.iter_mut().zip(cached) {
                    *slot = x;
                }
            }
            None => out.fill(f64::NAN),
        }
        Ok(a.width)
    }

    /// The error of a get whose references address more or fewer values than given.
    #[cold]
    fn count_error(&self, vrs: &[u32], want: BaseType, n_values: usize) -> Status {
        match self.check_values(vrs, want, n_values, false) {
            Err(s) => s,
            Ok(()) => self.error("the value references and nValues disagree"),
        }
    }

    /// The error of a get that read a NaN (an output undefined with the current parameters).
    #[cold]
    fn nan_error(&self, vrs: &[u32], values: &[f64]) -> Status {
        let i = values.iter().position(|x| x.is_nan()).unwrap_or(0);
        let r = elements(&self.access, vrs).nth(i).unwrap_or(VariableRef { group: usize::MAX, index: 0 });
        self.error(&format!("{} is not a number with the current parameters", self.element_name(r)))
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        // The run check once per version, so that each has only its own inline.
        let run = match self.version {
            FmiVersion::Fmi2 => self.settable_run(FmiVersion::Fmi2, vrs, values),
            FmiVersion::Fmi3 => self.settable_run(FmiVersion::Fmi3, vrs, values),
        };
        if let Some(a) = run {
            // Consecutive elements of one array (the leg forces): checked in one pass, stored
            // in one call; only the cached values that depend on the input go stale (all the
            // elements share the entry's `stales`, as `stale_after_set` would find).
            self.fresh &= !a.stales;
            return match self.model.set_real_run(VariableRef { group: a.group, index: a.index }, values) {
                Ok(()) => Status::Ok,
                Err(m) => self.error(&m),
            };
        }
        self.set_real_elementwise(vrs, values)
    }

    /// [`Instance::set_real`] reference by reference, out of line as for gets.
    #[inline(never)]
    fn set_real_elementwise(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        // Two passes, no allocation: validate every reference and value, then store (all or
        // nothing).
        if let Err(s) = self.check_set_real(vrs, values) {
            return s;
        }
        self.stale_after_set(vrs);
        let access = &self.access;
        let result = if self.version == FmiVersion::Fmi2 {
            // One element per reference (checked above).
            let element = |(&vr, &x): (&u32, &f64)| {
                let a = access.get(vr as usize).copied().flatten()?;
                Some((VariableRef { group: a.group, index: a.index }, x))
            };
            self.model.set_reals(vrs.iter().zip(values).map_while(element))
        } else {
            self.model.set_reals(elements(access, vrs).zip(values.iter().copied()))
        };
        match result {
            Ok(()) => Status::Ok,
            Err(m) => self.error(&m),
        }
    }

    /// Marks stale the cached values a set of `vrs` changes ([`Access::stales`]); an unknown
    /// reference (refused before anything is set) counts as changing everything.
    fn stale_after_set(&mut self, vrs: &[u32]) {
        let stale = vrs.iter().fold(0u32, |mask, &vr| {
            mask | self.access.get(vr as usize).copied().flatten().map_or(u32::MAX, |a| a.stales)
        });
        self.fresh &= !stale;
    }

    /// When `vrs` address consecutive elements of one settable Real group (FMI 2:
    /// consecutive references; FMI 3: one variable) and every value is finite, the first
    /// element's access entry. `version` is the instance's, as in [`Instance::cached_run`].
    #[inline(always)]
    fn settable_run(&self, version: FmiVersion, vrs: &[u32], values: &[f64]) -> Option<Access> {
        let a = (*self.access.get(*vrs.first()? as usize)?)?;
        let addressed = match version {
            FmiVersion::Fmi2 => vrs.len() == values.len() && values.len() <= a.run && consecutive(vrs),
            FmiVersion::Fmi3 => vrs.len() == 1 && values.len() == a.width,
        };
        let finite = all_finite(values);
        (addressed && finite && a.base == BaseType::Real && a.settable_in & self.state.bit() != 0).then_some(a)
    }

    /// The first pass of [`Instance::set_real`]: references, states and values. FMI 2's
    /// one element per reference is checked in one tight loop; anything else, or a failure,
    /// takes the general check that names the problem.
    #[inline]
    fn check_set_real(&self, vrs: &[u32], values: &[f64]) -> Result<(), Status> {
        let state = self.state.bit();
        let plain = self.version == FmiVersion::Fmi2
            && vrs.len() == values.len()
            && vrs.iter().zip(values).all(|(&vr, x)| {
                matches!(self.access.get(vr as usize), Some(Some(a))
                    if a.base == BaseType::Real && a.settable_in & state != 0 && x.is_finite())
            });
        if plain { Ok(()) } else { self.check_set_real_slowly(vrs, values) }
    }

    #[cold]
    fn check_set_real_slowly(&self, vrs: &[u32], values: &[f64]) -> Result<(), Status> {
        self.check_values(vrs, BaseType::Real, values.len(), true)?;
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            let r = elements(&self.access, vrs).nth(i).unwrap_or(VariableRef { group: usize::MAX, index: 0 });
            return Err(self.error(&format!(
                "{} = {} refused: values must be finite",
                self.element_name(r),
                values[i]
            )));
        }
        Ok(())
    }

    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Status {
        self.get_elements(vrs, values, BaseType::Integer, |model, r| model.get_integer(r))
    }

    /// A get of Integer or Boolean values, each read through the model and written as the C
    /// type of the calling FMI version.
    fn get_elements<T>(
        &mut self,
        vrs: &[u32],
        values: &mut [T],
        base: BaseType,
        read: impl Fn(&mut AnyModel, VariableRef) -> T,
    ) -> Status {
        if let Err(s) = self.check_values(vrs, base, values.len(), false) {
            return s;
        }
        for (slot, r) in values.iter_mut().zip(elements(&self.access, vrs)) {
            *slot = read(&mut self.model, r);
        }
        Status::Ok
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::Integer, values.len(), true) {
            return s;
        }
        // Validate every value on a copy first: all or nothing.
        let mut trial = self.copy_model();
        for (r, &x) in elements(&self.access, vrs).zip(values) {
            if let Err(m) = trial.set_integer(r, x) {
                return self.error(&format!("{} = {x} refused: {m}", self.element_name(r)));
            }
        }
        self.replace_model(trial);
        Status::Ok
    }

    /// Booleans as the calling version's C type `T`: `encode` turns a value into it.
    pub fn get_boolean<T>(&mut self, vrs: &[u32], values: &mut [T], encode: impl Fn(bool) -> T) -> Status {
        self.get_elements(vrs, values, BaseType::Boolean, |model, r| encode(model.get_boolean(r)))
    }

    /// Booleans given as the calling version's C type `T`: `decode` reads one.
    pub fn set_boolean<T: Copy>(&mut self, vrs: &[u32], values: &[T], decode: impl Fn(T) -> bool) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::Boolean, values.len(), true) {
            return s;
        }
        self.stale_after_set(vrs);
        for (r, &x) in elements(&self.access, vrs).zip(values) {
            if let Err(m) = self.model.set_boolean(r, decode(x)) {
                return self.error(&m);
            }
        }
        Status::Ok
    }

    /// A deep copy of the model through its own serialization (models are not `Clone`
    /// through `AnyModel`).
    fn copy_model(&self) -> AnyModel {
        let mut w = ByteWriter::default();
        self.model.save(&mut w);
        let mut r = ByteReader::new(&w.bytes);
        AnyModel::restore(self.kind, &mut r).unwrap_or_else(|_| self.kind.instantiate())
    }

    /// A get or set of a type the model has no variables of: every reference is unknown.
    pub fn no_variables_of_type(&self, vrs: &[u32], type_name: &str) -> Status {
        match vrs.first() {
            None => Status::Ok,
            Some(vr) => self
                .error(&format!("value reference {vr}: {} has no {type_name} variables", self.kind.info().model_name)),
        }
    }

    // ----- co-simulation ---------------------------------------------------------------------

    /// A co-simulation step from `tc` to `tc + h` (or, with FMI 3 early return, to an event
    /// before it).
    pub fn do_step(&mut self, tc: f64, h: f64) -> (Status, DoStepOutcome) {
        let mut outcome = DoStepOutcome { last_successful_time: self.time, ..Default::default() };
        if !(h.is_finite() && h > 0.0) {
            return (self.error(&format!("communicationStepSize must be finite and > 0, got {h}")), outcome);
        }
        if !tc.is_finite() {
            return (self.error(&format!("currentCommunicationPoint must be finite, got {tc}")), outcome);
        }
        let tol = communication_point_tolerance(self.time, tc, h);
        if (tc - self.time).abs() > tol {
            let message = format!(
                "currentCommunicationPoint {tc} does not match the FMU's time {} (difference {:e}, more than the \
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
            let message = format!("step to t = {t_end} goes past the stopTime {stop}");
            return (self.error(&message), outcome);
        }
        let events = self.version == FmiVersion::Fmi3 && self.kind.info().capabilities.event_indicators > 0;
        let early = events && self.co_simulation.early_return_allowed;
        let mut t = tc;
        loop {
            let result = self.model_mut().do_step(t, t_end - t, early);
            match result {
                Ok(StepReport { reached, event }) => {
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
    /// `read_since_step`).
    fn refresh_read_blocks(&mut self) {
        let read = std::mem::take(&mut self.read_since_step);
        self.refresh(read);
    }

    /// At an event at `t` inside an FMI 3 step with early return allowed: the importer's
    /// intermediate update callback decides (`canReturnEarly`; getting and setting variables
    /// is not allowed during the callback); without a callback, a step that reports events
    /// returns at each, so that the importer can handle it in Event Mode.
    fn return_early_at(&mut self, t: f64) -> bool {
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
                return self
                    .error(&format!("derivative of {} = {x} refused: values must be finite", g.element_name(r.index)));
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

    // ----- directional and adjoint derivatives ---------------------------------------------

    /// Resolves the unknowns and knowns of a derivative call into element references.
    fn derivative_refs(
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
    fn derivative_arguments(
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

    fn check_state_count(&self, n: usize) -> Result<(), Status> {
        if n == self.state_count() {
            Ok(())
        } else {
            Err(self.error(&format!("nx = {n}, but the model has {} continuous states", self.state_count())))
        }
    }

    pub fn set_time(&mut self, t: f64) -> Status {
        if !t.is_finite() {
            return self.error(&format!("time must be finite, got {t}"));
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
            return self.error(&format!("state {i} = {} refused: states must be finite", x[i]));
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
    fn in_importer_order(&self, internal: &[f64], out: &mut [f64]) {
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
            return self
                .error(&format!("derivative {i} is not finite at t = {}: the state is not admissible", self.time));
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

    // ----- FMU state ----------------------------------------------------------------------

    /// The instance as pointer-free bytes (format: [`crate::models::snapshot`]).
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
        snapshot::seal(self.kind.code(), self.token_hash, &payload.bytes)
    }

    fn parse(&self, bytes: &[u8]) -> Result<Snapshot, SnapshotError> {
        let payload = snapshot::open(bytes, self.kind.code(), self.token_hash)?;
        let mut p = ByteReader::new(payload);
        let interface = match p.u8()? {
            0 => InterfaceType::ModelExchange,
            1 => InterfaceType::CoSimulation,
            x => return Err(SnapshotError(format!("invalid interface type {x}"))),
        };
        if interface != self.interface {
            return Err(SnapshotError(format!(
                "state of a {} instance, this one is {}",
                interface.name(),
                self.interface.name()
            )));
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
        Ok(Snapshot { state, time, start_time, stop_time, tolerance, terminated, last_successful_time, model })
    }

    /// Checks bytes without restoring them (deserialization).
    pub fn validate_state_bytes(&self, bytes: &[u8]) -> Result<(), SnapshotError> {
        self.parse(bytes).map(|_| ())
    }

    /// Restores the instance from bytes, all or nothing.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let s = self.parse(bytes)?;
        self.state = s.state;
        self.time = s.time;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.tolerance = s.tolerance;
        self.terminated = s.terminated;
        self.last_successful_time = s.last_successful_time;
        self.replace_model(s.model);
        self.logger.log(
            Status::Ok,
            LogCategory::Events,
            &format!("FMU state restored: t = {}, state {}", self.time, self.state_name()),
        );
        Ok(())
    }

    /// Index of the state behind an importer's handle among this instance's own states.
    fn own_state(&self, handle: *mut c_void) -> Option<usize> {
        self.fmu_states.iter().position(|s| std::ptr::eq(&**s, handle as *const FmuState))
    }

    fn state_refused(&self, handle: *mut c_void, what: &str) -> Status {
        if handle.is_null() {
            self.error(&format!("{what} is NULL"))
        } else {
            self.error(&format!(
                "{what} {handle:?} is not a live FMU state of this instance (freed already, made by another \
                 instance, or not an FMU state; to move a state between instances, serialize it)"
            ))
        }
    }

    /// `fmi2GetFMUstate`/`fmi3GetFMUState`: a new state in `*slot` if it is NULL, else the
    /// instance's state `*slot` overwritten.
    pub fn get_fmu_state(&mut self, slot: &mut *mut c_void) -> Status {
        let bytes = self.serialize();
        self.store_fmu_state(slot, bytes)
    }

    fn store_fmu_state(&mut self, slot: &mut *mut c_void, bytes: Vec<u8>) -> Status {
        if slot.is_null() {
            let state = Box::new(FmuState { bytes });
            *slot = &*state as *const FmuState as *mut c_void;
            self.fmu_states.push(state);
            return Status::Ok;
        }
        match self.own_state(*slot) {
            Some(i) => {
                if let Some(s) = self.fmu_states.get_mut(i) {
                    s.bytes = bytes;
                }
                Status::Ok
            }
            None => self.state_refused(*slot, "*FMUstate"),
        }
    }

    /// `fmi2SetFMUstate`/`fmi3SetFMUState`.
    pub fn set_fmu_state(&mut self, handle: *mut c_void) -> Status {
        let Some(i) = self.own_state(handle) else { return self.state_refused(handle, "FMUstate") };
        // Taken out while the instance restores from it (no copy), then put back.
        let bytes = self.fmu_states.get_mut(i).map(|s| std::mem::take(&mut s.bytes)).unwrap_or_default();
        let result = self.restore(&bytes);
        if let Some(s) = self.fmu_states.get_mut(i) {
            s.bytes = bytes;
        }
        match result {
            Ok(()) => Status::Ok,
            Err(e) => self.error(&format!("state refused: {e}")),
        }
    }

    /// `fmi2FreeFMUstate`/`fmi3FreeFMUState`: NULL is fine; only this instance's own states.
    pub fn free_fmu_state(&mut self, slot: &mut *mut c_void) -> Status {
        if slot.is_null() {
            return Status::Ok;
        }
        match self.own_state(*slot) {
            Some(i) => {
                self.fmu_states.swap_remove(i);
                *slot = std::ptr::null_mut();
                Status::Ok
            }
            None => self.state_refused(*slot, "*FMUstate"),
        }
    }

    /// `fmi2SerializeFMUstate`/`fmi3SerializeFMUState`: a state's bytes into the importer's
    /// buffer (`out`, all the bytes it gave), which must be large enough.
    pub fn serialize_fmu_state(&self, handle: *mut c_void, out: &mut [u8]) -> Status {
        let bytes = match self.fmu_state_bytes(handle) {
            Ok(bytes) => bytes,
            Err(status) => return status,
        };
        match out.get_mut(..bytes.len()) {
            Some(slots) => {
                slots.copy_from_slice(bytes);
                Status::Ok
            }
            None => self.error(&format!("buffer of {} bytes is too small, the state needs {}", out.len(), bytes.len())),
        }
    }

    /// The bytes of one of this instance's states.
    pub fn fmu_state_bytes(&self, handle: *mut c_void) -> Result<&[u8], Status> {
        match self.own_state(handle).and_then(|i| self.fmu_states.get(i)) {
            Some(s) => Ok(&s.bytes),
            None => Err(self.state_refused(handle, "FMUstate")),
        }
    }

    /// `fmi2DeSerializeFMUstate`/`fmi3DeserializeFMUState`: checked bytes into a new state
    /// (`*slot` NULL) or into one of this instance's states.
    pub fn deserialize_fmu_state(&mut self, bytes: &[u8], slot: &mut *mut c_void) -> Status {
        if let Err(e) = self.validate_state_bytes(bytes) {
            return self.error(&format!("serialized state refused: {e}"));
        }
        self.store_fmu_state(slot, bytes.to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cache blocks a set of the named group's first element makes stale, for a model
    /// whose groups `cached` (by name) sit in the given blocks.
    fn stales(kind: ModelKind, cached: &[(&str, u8)], set: &str) -> u32 {
        let table = VariableTable::new(kind.info().groups);
        let block = |g: usize| cached.iter().find(|(name, _)| table.groups[g].name == *name).map(|&(_, b)| b);
        let access = access_table(&table, FmiVersion::Fmi2, block);
        let (_, g) = table.group(set).expect("group");
        access[g.first_vr as usize].expect("access").stales
    }

    #[test]
    fn a_set_makes_stale_exactly_the_cached_values_that_depend_on_it() {
        // The platform's leg lengths and rates depend on the state only; its accelerations
        // (Model Exchange derivatives) on the leg forces too; a parameter changes everything.
        let platform = [("l", 0), ("ldot", 0), ("der(v)", 3)];
        assert_eq!(stales(ModelKind::Platform, &platform, "F"), 1 << 3);
        assert_eq!(stales(ModelKind::Platform, &platform[..2], "F"), 0);
        assert_eq!(stales(ModelKind::Platform, &platform, "M"), u32::MAX);
        // The controller's force command feeds its inputs through.
        assert_eq!(stales(ModelKind::Controller, &[("F", 0)], "l"), 1 << 0);
        assert_eq!(stales(ModelKind::Controller, &[("F", 0), ("rp", 1)], "pose.r"), (1 << 0) | (1 << 1));
    }

    #[test]
    fn copies_of_every_length_copy_every_value() {
        for n in 0..=20 {
            let from: Vec<f64> = (0..n).map(|i| i as f64 + 0.5).collect();
            let mut to = vec![f64::NAN; n];
            copy_f64(&mut to, &from);
            assert_eq!(to, from, "{n} values");
        }
    }

    #[test]
    fn runs_of_cached_elements_and_consecutive_references() {
        assert_eq!(cache_runs(&[NO_CACHE, 0, 0, 1, NO_CACHE, 1]), vec![0, 2, 1, 1, 0, 1]);
        assert!(consecutive(&[7, 8, 9, 10, 11, 12, 13, 14, 15, 16]));
        assert!(!consecutive(&[7, 8, 9, 10, 11, 12, 13, 14, 16, 15]));
        assert!(!consecutive(&[]));
        // Past the counting table's end: the element-by-element pass.
        assert!(consecutive(&[1020, 1021, 1022, 1023, 1024, 1025]));
        assert!(!consecutive(&[1020, 1021, 1022, 1023, 1024, 1024]));
        assert!(consecutive(&[u32::MAX, 0, 1]));
        assert!(!consecutive(&[u32::MAX, 1]));
        // Every length up to 20 (the fixed-size halves from 4 to 16, overlapping from 9), and
        // one wrong reference at every place.
        for n in 1..=20u32 {
            for start in [0, 1020, u32::MAX - 5] {
                let run: Vec<u32> = (0..n).map(|i| start.wrapping_add(i)).collect();
                assert!(consecutive(&run), "{run:?}");
                for k in 1..n as usize {
                    let mut wrong = run.clone();
                    wrong[k] = wrong[k].wrapping_add(1);
                    assert!(!consecutive(&wrong), "{wrong:?}");
                }
            }
        }
    }
}
