//! The exported FMI 2.0 functions: a thin layer that turns C arguments into Rust values and
//! calls [`Instance`] methods through the boundary ([`crate::fmi::boundary::call`]), which
//! catches panics and enforces the state table. Signatures follow `fmi2FunctionTypes.h` exactly.
//!
//! # Safety (all functions)
//! The importer must follow the FMI 2.0 calling conventions for arrays and strings: array
//! arguments point to at least `n` elements (or are NULL when `n == 0`); strings are
//! NUL-terminated. NULL where a value is required is detected and answered with `fmi2Error`.
//! Instance and FMU-state handles may be anything: they are checked by value
//! ([`crate::fmi::registry`], the instance's own states) before any use, so freed, foreign and
//! other-version handles are refused without being read.

use std::ffi::{CStr, CString, c_char};

mod co_simulation;
mod model_exchange;

pub use co_simulation::*;
pub use model_exchange::*;

use super::state_machine::Fmi2Function as F;
use super::types::*;
use crate::fmi::boundary::{boundary, free_instance, no_instance, show, try_out, try_slice, try_slice_mut};
use crate::fmi::instance::Instance;
use crate::fmi::log::{Callback, Logger, log_without_instance};
use crate::fmi::{FmiVersion, InterfaceType, Status, library};

/// # Safety
/// `p` must be NULL or a NUL-terminated string.
unsafe fn c_str(p: fmi2String) -> Option<String> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and NUL-terminated per the contract.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    n_categories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    boundary!(c, F::SetDebugLogging, args("loggingOn = {logging_on}, nCategories = {n_categories}"), |inst| {
        let list = try_slice!(inst, categories, n_categories, "categories");
        // SAFETY: each entry is NULL or a NUL-terminated string.
        let names: Vec<Option<String>> = list.iter().map(|&p| unsafe { c_str(p) }).collect();
        inst.set_debug_logging(logging_on != fmi2False, &names)
    })
}

/// # Safety
/// See the module documentation. `functions` must be NULL or point to a valid
/// `fmi2CallbackFunctions`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    fmu_guid: fmi2String,
    fmu_resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let _ = (fmu_resource_location, visible);
    no_instance(std::ptr::null_mut(), || {
        // SAFETY: NULL or a valid struct, per the contract; copied, not kept.
        let functions = unsafe { functions.as_ref() }.copied();
        // SAFETY: NULL or NUL-terminated strings.
        let name = unsafe { c_str(instance_name) }.unwrap_or_default();
        let fail = |message: &str| {
            if let Some(f) = functions.as_ref() {
                let message = format!("fmi2Instantiate: {message}");
                log_without_instance(Callback::Fmi2(f.logger), f.componentEnvironment, &name, Status::Error, &message);
            }
            std::ptr::null_mut()
        };
        let Some(f) = functions else {
            return std::ptr::null_mut();
        };
        if name.is_empty() {
            return fail("instanceName is NULL or empty");
        }
        // SAFETY: as above.
        let Some(guid) = (unsafe { c_str(fmu_guid) }) else {
            return fail("fmuGUID is NULL");
        };
        let kind = match library::model_for_token(&guid, FmiVersion::Fmi2) {
            Ok(kind) => kind,
            Err(message) => return fail(&format!("fmuGUID {message}")),
        };
        let interface = match fmu_type {
            fmi2CoSimulation => InterfaceType::CoSimulation,
            fmi2ModelExchange if kind.info().capabilities.model_exchange => InterfaceType::ModelExchange,
            fmi2ModelExchange => {
                return fail(&format!(
                    "fmuType fmi2ModelExchange: {} implements Co-Simulation only",
                    kind.info().model_identifier
                ));
            }
            other => return fail(&format!("invalid fmuType {other}")),
        };
        let Ok(cname) = CString::new(name.clone()) else {
            return fail("instanceName contains NUL");
        };
        let logger = Logger::new(Callback::Fmi2(f.logger), f.componentEnvironment, cname, logging_on != fmi2False);
        Instance::new(kind, &guid, FmiVersion::Fmi2, interface, logger).into_handle()
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    // SAFETY: the handle is looked up in the registry before any use.
    unsafe { free_instance(c, F::FreeInstance) };
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    boundary!(
        c,
        F::SetupExperiment,
        args(
            "toleranceDefined = {tolerance_defined}, tolerance = {tolerance:?}, startTime = {start_time:?}, stopTimeDefined = {stop_time_defined}, stopTime = {stop_time:?}"
        ),
        |inst| {
            inst.setup_experiment(
                (tolerance_defined != fmi2False).then_some(tolerance),
                start_time,
                (stop_time_defined != fmi2False).then_some(stop_time),
            )
        }
    )
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::EnterInitializationMode, |inst| inst.enter_initialization_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::ExitInitializationMode, |inst| inst.exit_initialization_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::Terminate, |inst| inst.terminate())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::Reset, |inst| inst.reset())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    boundary!(c, F::GetReal, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice_mut!(inst, value, nvr, "value");
        inst.get_real(vrs, values)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    boundary!(c, F::GetInteger, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice_mut!(inst, value, nvr, "value");
        inst.get_integer(vrs, values)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    boundary!(c, F::GetBoolean, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice_mut!(inst, value, nvr, "value");
        inst.get_boolean(vrs, values, |f| if f { fmi2True } else { fmi2False })
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    boundary!(c, F::GetString, args("vr = {}", show(vr, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice_mut!(inst, value, nvr, "value");
        inst.get_string(vrs, nvr, |i, s| values[i] = s.as_ptr())
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    boundary!(c, F::SetReal, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice!(inst, value, nvr, "value");
        inst.set_real(vrs, values)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    boundary!(c, F::SetInteger, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice!(inst, value, nvr, "value");
        inst.set_integer(vrs, values)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    boundary!(c, F::SetBoolean, args("vr = {}, value = {}", show(vr, nvr), show(value, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice!(inst, value, nvr, "value");
        inst.set_boolean(vrs, values, |v| v != fmi2False)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    boundary!(c, F::SetString, args("vr = {}", show(vr, nvr)), |inst| {
        let vrs = try_slice!(inst, vr, nvr, "vr");
        let values = try_slice!(inst, value, nvr, "value");
        // SAFETY: each value is NULL or a NUL-terminated C string (the FMI calling convention).
        let texts: Vec<Option<&str>> = values.iter().map(|&p| unsafe { crate::fmi::boundary::c_text(p) }).collect();
        inst.set_string(vrs, &texts)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    boundary!(c, F::GetFMUstate, args("FMUstate = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUstate");
        inst.get_fmu_state(slot)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    boundary!(c, F::SetFMUstate, args("FMUstate = {state:?}"), |inst| { inst.set_fmu_state(state) })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    boundary!(c, F::FreeFMUstate, args("FMUstate = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUstate");
        inst.free_fmu_state(slot)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    boundary!(c, F::SerializedFMUstateSize, args("FMUstate = {state:?}"), |inst| {
        let out = try_out!(inst, size, "size");
        match inst.fmu_state_bytes(state) {
            Ok(bytes) => {
                *out = bytes.len();
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    serialized: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    boundary!(c, F::SerializeFMUstate, args("FMUstate = {state:?}, size = {size}"), |inst| {
        let out = try_slice_mut!(inst, serialized as *mut u8, size, "serializedState");
        inst.serialize_fmu_state(state, out)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serialized: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    boundary!(c, F::DeSerializeFMUstate, args("size = {size}"), |inst| {
        let bytes = try_slice!(inst, serialized as *const u8, size, "serializedState");
        let slot = try_out!(inst, state, "FMUstate");
        inst.deserialize_fmu_state(bytes, slot)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    unknown: *const fmi2ValueReference,
    n_unknown: usize,
    known: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    boundary!(
        c,
        F::GetDirectionalDerivative,
        args(
            "vUnknown_ref = {}, vKnown_ref = {}, dvKnown = {}, dvUnknown = {}",
            show(unknown, n_unknown),
            show(known, n_known),
            show(dv_known, n_known),
            show(dv_unknown, n_unknown)
        ),
        |inst| {
            let unknowns = try_slice!(inst, unknown, n_unknown, "vUnknown_ref");
            let knowns = try_slice!(inst, known, n_known, "vKnown_ref");
            let seeds = try_slice!(inst, dv_known, n_known, "dvKnown");
            let out = try_slice_mut!(inst, dv_unknown, n_unknown, "dvUnknown");
            inst.get_directional_derivative(unknowns, knowns, seeds, out)
        }
    )
}
