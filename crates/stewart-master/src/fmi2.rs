//! The FMI 2.0 Co-Simulation C API as an importer sees it: the function pointers of one loaded
//! FMU binary (`Library`) and one instance of it (`Instance`), with the messages its logger
//! received.
//!
//! Declared here by hand (the standard's `fmi2Functions.h`, the dozen functions a
//! co-simulation master calls) rather than through the `fmi` crate, whose `fmi-sys` generates
//! its bindings with bindgen at build time and so needs libclang on every machine that builds
//! the Python package.

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::Path;
use std::sync::Arc;

pub type Component = *mut c_void;
pub type Status = c_int;
pub const OK: Status = 0;
pub const WARNING: Status = 1;
pub const DISCARD: Status = 2;
pub const ERROR: Status = 3;
const CO_SIMULATION: c_int = 1;
const TERMINATED: c_int = 3;

/// The FMU calls the logger as a C-variadic function `(env, instance, status, category,
/// message, ...)`. It is declared here without the `...`: on the platforms the master is built
/// for (x86-64 System V and Windows x64, aarch64 Linux's AAPCS64) the fixed arguments of a
/// variadic call are passed exactly as in a fixed call, and a message that
/// carries printf arguments is kept as its format (FMPy's logger does the same). The FMUs of
/// this repository pass their messages pre-formatted with `%` doubled.
type Logger = unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char);

#[repr(C)]
struct CallbackFunctions {
    logger: Option<Logger>,
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    component_environment: *mut c_void,
}

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const CallbackFunctions,
    c_int,
    c_int,
) -> Component;
type Free = unsafe extern "C" fn(Component);
type SetupExperiment = unsafe extern "C" fn(Component, c_int, f64, f64, c_int, f64) -> Status;
type Plain = unsafe extern "C" fn(Component) -> Status;
type SetReal = unsafe extern "C" fn(Component, *const u32, usize, *const f64) -> Status;
type GetReal = unsafe extern "C" fn(Component, *const u32, usize, *mut f64) -> Status;
type SetInt = unsafe extern "C" fn(Component, *const u32, usize, *const c_int) -> Status;
type GetInt = unsafe extern "C" fn(Component, *const u32, usize, *mut c_int) -> Status;
type DoStep = unsafe extern "C" fn(Component, f64, f64, c_int) -> Status;
type GetBooleanStatus = unsafe extern "C" fn(Component, c_int, *mut c_int) -> Status;

/// One FMU binary, loaded: the functions a co-simulation master calls.
pub struct Library {
    instantiate: Instantiate,
    free_instance: Free,
    setup_experiment: SetupExperiment,
    enter_initialization_mode: Plain,
    exit_initialization_mode: Plain,
    terminate: Plain,
    reset: Plain,
    set_real: SetReal,
    get_real: GetReal,
    set_integer: SetInt,
    get_integer: GetInt,
    set_boolean: SetInt,
    do_step: DoStep,
    get_boolean_status: GetBooleanStatus,
    // Last: the function pointers above point into it.
    _library: libloading::Library,
}

impl Library {
    /// Loads the shared library of an FMU and looks up its FMI 2 functions.
    pub fn load(path: &Path) -> Result<Library, String> {
        // SAFETY: loading runs the library's initialisers; an FMU's binary is trusted code
        // like any importer's (FMPy's ctypes.CDLL does the same).
        let library = unsafe { libloading::Library::new(path) }
            .map_err(|e| format!("cannot load the FMU's binary {}: {e}", path.display()))?;
        macro_rules! symbol {
            ($name:literal) => {{
                // SAFETY: the FMI 2 standard fixes the signature of each exported name; the
                // pointer is copied out and used only while `_library` is loaded.
                let s = unsafe { library.get::<_>(concat!($name, "\0").as_bytes()) }
                    .map_err(|e| format!("{} does not export {}: {e}", path.display(), $name))?;
                *s
            }};
        }
        Ok(Library {
            instantiate: symbol!("fmi2Instantiate"),
            free_instance: symbol!("fmi2FreeInstance"),
            setup_experiment: symbol!("fmi2SetupExperiment"),
            enter_initialization_mode: symbol!("fmi2EnterInitializationMode"),
            exit_initialization_mode: symbol!("fmi2ExitInitializationMode"),
            terminate: symbol!("fmi2Terminate"),
            reset: symbol!("fmi2Reset"),
            set_real: symbol!("fmi2SetReal"),
            get_real: symbol!("fmi2GetReal"),
            set_integer: symbol!("fmi2SetInteger"),
            get_integer: symbol!("fmi2GetInteger"),
            set_boolean: symbol!("fmi2SetBoolean"),
            do_step: symbol!("fmi2DoStep"),
            get_boolean_status: symbol!("fmi2GetBooleanStatus"),
            _library: library,
        })
    }
}

/// A message the FMU logged: status, category, text.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub status: Status,
    pub category: String,
    pub text: String,
}

/// A failed FMI call: the function's name and the status it returned (an FMU that returns
/// Discard, Error, Fatal or Pending). Displays as FMPy's `FMICallException` does, so that a
/// row's message is the same whichever master ran it.
#[derive(Clone, Debug, PartialEq)]
pub struct CallError {
    pub function: &'static str,
    pub status: Status,
}

impl std::fmt::Display for CallError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let label = match self.status {
            0 => "ok",
            1 => "warning",
            2 => "discard",
            3 => "error",
            4 => "fatal",
            _ => "illegal return code",
        };
        write!(f, "{} failed with status {} ({label}).", self.function, self.status)
    }
}

fn check(function: &'static str, status: Status) -> Result<(), CallError> {
    if status > WARNING { Err(CallError { function, status }) } else { Ok(()) }
}

/// Where the logger puts the messages of one instance (its `componentEnvironment`).
struct Sink {
    messages: RefCell<Vec<Message>>,
}

unsafe extern "C" fn log_message(
    environment: *mut c_void,
    _instance: *const c_char,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    // No unwinding may leave this function: catch anything (a panic here would abort).
    let _ = std::panic::catch_unwind(|| {
        if environment.is_null() {
            return;
        }
        let text = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: the FMU passes NUL-terminated strings valid for the call.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        // SAFETY: `environment` is the `Sink` this instance was created with; it lives in a
        // Box owned by the `Instance`, which outlives every call into the FMU.
        let sink = unsafe { &*(environment as *const Sink) };
        if let Ok(mut messages) = sink.messages.try_borrow_mut() {
            messages.push(Message { status, category: text(category), text: text(message).replace("%%", "%") });
        }
    });
}

unsafe extern "C" fn allocate(n: usize, size: usize) -> *mut c_void {
    // SAFETY: calloc is the standard's own suggestion for this callback.
    unsafe { libc::calloc(n, size) }
}

unsafe extern "C" fn free(p: *mut c_void) {
    // SAFETY: p came from `allocate` (or is NULL).
    unsafe { libc::free(p) }
}

/// Variable values of the three settable types.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

/// One FMI 2 Co-Simulation instance. Freed (`fmi2Terminate` if initialised, then
/// `fmi2FreeInstance`) when dropped.
pub struct Instance {
    library: Arc<Library>,
    component: Component,
    sink: Box<Sink>,
    _callbacks: Box<CallbackFunctions>,
    initialised: bool,
}

// SAFETY: an FMI 2 instance may be called from any thread, one call at a time; `Instance`
// is not `Sync`, and its `&mut self` methods serialise the calls.
unsafe impl Send for Instance {}

impl Instance {
    /// `fmi2Instantiate` for Co-Simulation, logging off (the FMU still reports its
    /// problems), the messages kept.
    pub fn new(library: Arc<Library>, name: &str, guid: &str, resource_uri: &str) -> Result<Instance, String> {
        let sink = Box::new(Sink { messages: RefCell::new(Vec::new()) });
        let callbacks = Box::new(CallbackFunctions {
            logger: Some(log_message),
            allocate_memory: Some(allocate),
            free_memory: Some(free),
            step_finished: None,
            component_environment: &*sink as *const Sink as *mut c_void,
        });
        let c = |s: &str| CString::new(s).map_err(|_| format!("{s:?} contains a NUL character"));
        let (name_c, guid_c, uri_c) = (c(name)?, c(guid)?, c(resource_uri)?);
        // SAFETY: valid NUL-terminated strings and a callback structure that outlives the
        // instance (it is kept in the returned value).
        let component = unsafe {
            (library.instantiate)(name_c.as_ptr(), CO_SIMULATION, guid_c.as_ptr(), uri_c.as_ptr(), &*callbacks, 0, 0)
        };
        if component.is_null() {
            let messages = sink.messages.borrow();
            let why = messages.last().map(|m| format!(": {}", m.text)).unwrap_or_default();
            return Err(format!("fmi2Instantiate of {name} failed{why}"));
        }
        Ok(Instance { library, component, sink, _callbacks: callbacks, initialised: false })
    }

    /// The messages logged since `clear_messages`.
    pub fn messages(&self) -> Vec<Message> {
        self.sink.messages.borrow().clone()
    }

    pub fn clear_messages(&self) {
        self.sink.messages.borrow_mut().clear();
    }

    /// The last discard, error or fatal message since `clear_messages`, or "".
    pub fn last_problem(&self) -> String {
        self.sink
            .messages
            .borrow()
            .iter()
            .rev()
            .find(|m| m.status >= DISCARD)
            .map(|m| m.text.clone())
            .unwrap_or_default()
    }

    pub fn reset(&mut self) -> Result<(), CallError> {
        self.initialised = false;
        // SAFETY: a live instance of this library.
        check("fmi2Reset", unsafe { (self.library.reset)(self.component) })
    }

    pub fn setup_experiment(&mut self, start_time: f64) -> Result<(), CallError> {
        // SAFETY: as above; no tolerance and no stop time defined (FMPy's defaults).
        check("fmi2SetupExperiment", unsafe {
            (self.library.setup_experiment)(self.component, 0, 0.0, start_time, 0, 0.0)
        })
    }

    pub fn enter_initialization_mode(&mut self) -> Result<(), CallError> {
        // SAFETY: as above.
        check("fmi2EnterInitializationMode", unsafe { (self.library.enter_initialization_mode)(self.component) })
    }

    pub fn exit_initialization_mode(&mut self) -> Result<(), CallError> {
        // SAFETY: as above.
        let status = unsafe { (self.library.exit_initialization_mode)(self.component) };
        self.initialised = status <= WARNING;
        check("fmi2ExitInitializationMode", status)
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), CallError> {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: two arrays of the length passed.
        check("fmi2SetReal", unsafe {
            (self.library.set_real)(self.component, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), CallError> {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: two arrays of the length passed.
        check("fmi2GetReal", unsafe {
            (self.library.get_real)(self.component, vrs.as_ptr(), vrs.len(), values.as_mut_ptr())
        })
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), CallError> {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: two arrays of the length passed.
        check("fmi2SetInteger", unsafe {
            (self.library.set_integer)(self.component, vrs.as_ptr(), vrs.len(), values.as_ptr())
        })
    }

    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<(), CallError> {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: two arrays of the length passed.
        check("fmi2GetInteger", unsafe {
            (self.library.get_integer)(self.component, vrs.as_ptr(), vrs.len(), values.as_mut_ptr())
        })
    }

    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<(), CallError> {
        assert_eq!(vrs.len(), values.len());
        let ints: Vec<c_int> = values.iter().map(|&b| b as c_int).collect();
        // SAFETY: two arrays of the length passed.
        check("fmi2SetBoolean", unsafe {
            (self.library.set_boolean)(self.component, vrs.as_ptr(), vrs.len(), ints.as_ptr())
        })
    }

    /// Sets values of any type, grouped as FMPy's `set_values` does: the Reals in one call,
    /// then the Integers, then the Booleans, each in the order given.
    pub fn set_values(&mut self, values: &[(u32, Value)]) -> Result<(), CallError> {
        let (mut rv, mut rx, mut iv, mut ix, mut bv, mut bx) = (vec![], vec![], vec![], vec![], vec![], vec![]);
        for (vr, value) in values {
            match *value {
                Value::Real(x) => (rv.push(*vr), rx.push(x)),
                Value::Integer(x) => (iv.push(*vr), ix.push(x)),
                Value::Boolean(x) => (bv.push(*vr), bx.push(x)),
            };
        }
        if !rv.is_empty() {
            self.set_real(&rv, &rx)?;
        }
        if !iv.is_empty() {
            self.set_integer(&iv, &ix)?;
        }
        if !bv.is_empty() {
            self.set_boolean(&bv, &bx)?;
        }
        Ok(())
    }

    pub fn do_step(&mut self, time: f64, step: f64) -> Result<(), CallError> {
        // SAFETY: a live instance; noSetFMUStatePriorToCurrentPoint = true as FMPy passes it.
        check("fmi2DoStep", unsafe { (self.library.do_step)(self.component, time, step, 1) })
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: whether the FMU ended the simulation (`None`
    /// if it cannot say).
    pub fn terminated(&mut self) -> Option<bool> {
        let mut value: c_int = 0;
        // SAFETY: a live instance and a valid out pointer.
        let status = unsafe { (self.library.get_boolean_status)(self.component, TERMINATED, &mut value) };
        (status <= WARNING).then_some(value != 0)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: a live instance, freed exactly once.
        unsafe {
            if self.initialised {
                (self.library.terminate)(self.component);
            }
            (self.library.free_instance)(self.component);
        }
    }
}
