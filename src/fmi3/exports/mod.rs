//! The exported FMI 3.0 functions: a thin layer that turns C arguments into Rust values and
//! calls the shared [`Instance`] through the boundary ([`crate::fmi::boundary::call`]), which
//! catches panics and enforces the FMI 3 state table. Signatures follow `fmi3FunctionTypes.h`.
//!
//! # Safety (all functions)
//! The importer must follow the FMI 3.0 calling conventions for arrays and strings: array
//! arguments point to at least as many elements as their count says (or are NULL when it is
//! 0); strings are NUL-terminated. NULL where a value is required is detected and answered
//! with `fmi3Error`. Instance and FMU-state handles may be anything: they are checked by
//! value ([`crate::fmi::registry`], the instance's own states) before any use, so freed,
//! foreign and other-version handles are refused without being read.

use std::ffi::{CStr, CString, c_char};

mod co_simulation;
mod derivatives;
mod events;
mod model_exchange;
mod states;
mod variables;

pub use co_simulation::*;
pub use derivatives::*;
pub use events::*;
pub use model_exchange::*;
pub use states::*;
pub use variables::*;

use super::state_machine::Fmi3Function as F;
use super::types::*;
use crate::fmi::boundary::{boundary, free_instance, no_instance, show, try_out, try_slice, try_slice_mut};
use crate::fmi::instance::{CoSimulationOptions, Instance};
use crate::fmi::log::{Callback, Logger, log_without_instance};
use crate::fmi::{FmiVersion, InterfaceType, Status, library};
use crate::models::variables::{Causality, Dependency};

/// # Safety
/// `p` must be NULL or a NUL-terminated string.
unsafe fn c_str(p: fmi3String) -> Option<String> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and NUL-terminated per the contract.
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    logging_on: fmi3Boolean,
    n_categories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    boundary!(instance, F::SetDebugLogging, args("loggingOn = {logging_on}, nCategories = {n_categories}"), |inst| {
        let list = try_slice!(inst, categories, n_categories, "categories");
        // SAFETY: each entry is NULL or a NUL-terminated string.
        let names: Vec<Option<String>> = list.iter().map(|&p| unsafe { c_str(p) }).collect();
        inst.set_debug_logging(logging_on != fmi3False, &names)
    })
}

/// Creates an instance of either interface, or logs why not and returns NULL.
///
/// # Safety
/// `instance_name` and `token` must be NULL or NUL-terminated strings.
unsafe fn instantiate(
    instance_name: fmi3String,
    token: fmi3String,
    interface: InterfaceType,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    co_simulation: CoSimulationOptions,
) -> fmi3Instance {
    let function = match interface {
        InterfaceType::ModelExchange => "fmi3InstantiateModelExchange",
        InterfaceType::CoSimulation => "fmi3InstantiateCoSimulation",
    };
    // SAFETY: NULL or NUL-terminated strings, per the contract.
    let name = unsafe { c_str(instance_name) }.unwrap_or_default();
    let fail = |message: &str| {
        let message = format!("{function}: {message}");
        log_without_instance(Callback::Fmi3(log_message), environment, &name, Status::Error, &message);
        std::ptr::null_mut()
    };
    if name.is_empty() {
        return fail("instanceName is NULL or empty");
    }
    // SAFETY: as above.
    let Some(token) = (unsafe { c_str(token) }) else {
        return fail("instantiationToken is NULL");
    };
    let kind = match library::model_for_token(&token, FmiVersion::Fmi3) {
        Ok(kind) => kind,
        Err(message) => return fail(&format!("instantiationToken {message}")),
    };
    if interface == InterfaceType::ModelExchange && !kind.info().capabilities.model_exchange {
        return fail(&format!("{} implements Co-Simulation only", kind.info().model_identifier));
    }
    let Ok(cname) = CString::new(name.clone()) else {
        return fail("instanceName contains NUL");
    };
    let logger = Logger::new(Callback::Fmi3(log_message), environment, cname, logging_on != fmi3False);
    let mut inst = Instance::new(kind, &token, FmiVersion::Fmi3, interface, logger);
    inst.co_simulation = co_simulation;
    inst.into_handle()
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instance_name: fmi3String,
    instantiation_token: fmi3String,
    resource_path: fmi3String,
    visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    instance_environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
) -> fmi3Instance {
    let _ = (resource_path, visible);
    no_instance(std::ptr::null_mut(), || {
        // SAFETY: strings per the contract.
        unsafe {
            instantiate(
                instance_name,
                instantiation_token,
                InterfaceType::ModelExchange,
                logging_on,
                instance_environment,
                log_message,
                CoSimulationOptions::default(),
            )
        }
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: fmi3String,
    instantiation_token: fmi3String,
    resource_path: fmi3String,
    visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    event_mode_used: fmi3Boolean,
    early_return_allowed: fmi3Boolean,
    required_intermediate_variables: *const fmi3ValueReference,
    n_required_intermediate_variables: usize,
    instance_environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    intermediate_update: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let _ = (resource_path, visible, required_intermediate_variables);
    no_instance(std::ptr::null_mut(), || {
        if n_required_intermediate_variables > 0 {
            // Variables are neither read nor written during an intermediate update here.
            let name = c"fmi3InstantiateCoSimulation: requiredIntermediateVariables are not supported (getting and \
                         setting variables during intermediate updates is not allowed by this FMU)";
            log_without_instance(
                Callback::Fmi3(log_message),
                instance_environment,
                "",
                Status::Error,
                &name.to_string_lossy(),
            );
            return std::ptr::null_mut();
        }
        let options = CoSimulationOptions {
            event_mode_used: event_mode_used != fmi3False,
            early_return_allowed: early_return_allowed != fmi3False,
            intermediate_update,
            environment: instance_environment,
        };
        // SAFETY: strings per the contract.
        unsafe {
            instantiate(
                instance_name,
                instantiation_token,
                InterfaceType::CoSimulation,
                logging_on,
                instance_environment,
                log_message,
                options,
            )
        }
    })
}

/// Scheduled Execution is not implemented: logs and returns NULL.
///
/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instance_name: fmi3String,
    instantiation_token: fmi3String,
    resource_path: fmi3String,
    visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    instance_environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    clock_update: fmi3ClockUpdateCallback,
    lock_preemption: fmi3LockPreemptionCallback,
    unlock_preemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let _ = (instantiation_token, resource_path, visible, logging_on, clock_update, lock_preemption, unlock_preemption);
    no_instance(std::ptr::null_mut(), || {
        // SAFETY: NULL or a NUL-terminated string.
        let name = unsafe { c_str(instance_name) }.unwrap_or_default();
        log_without_instance(
            Callback::Fmi3(log_message),
            instance_environment,
            &name,
            Status::Error,
            "fmi3InstantiateScheduledExecution: Scheduled Execution is not implemented (the model description \
             declares Co-Simulation and Model Exchange)",
        );
        std::ptr::null_mut()
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    // SAFETY: the handle is looked up in the registry before any use.
    unsafe { free_instance(instance, F::FreeInstance) };
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    tolerance_defined: fmi3Boolean,
    tolerance: fmi3Float64,
    start_time: fmi3Float64,
    stop_time_defined: fmi3Boolean,
    stop_time: fmi3Float64,
) -> fmi3Status {
    boundary!(
        instance,
        F::EnterInitializationMode,
        args(
            "toleranceDefined = {tolerance_defined}, tolerance = {tolerance:?}, startTime = {start_time:?}, stopTimeDefined = {stop_time_defined}, stopTime = {stop_time:?}"
        ),
        |inst| {
            let status = inst.setup_experiment(
                (tolerance_defined != fmi3False).then_some(tolerance),
                start_time,
                (stop_time_defined != fmi3False).then_some(stop_time),
            );
            if status != Status::Ok {
                return status;
            }
            inst.enter_initialization_mode()
        }
    )
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::ExitInitializationMode, |inst| inst.exit_initialization_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterEventMode, |inst| {
        if inst.interface == InterfaceType::CoSimulation && !inst.co_simulation.event_mode_used {
            return inst.error("Event Mode was not requested at instantiation (eventModeUsed = false)");
        }
        inst.enter_event_mode()
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::Terminate, |inst| inst.terminate())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::Reset, |inst| inst.reset())
}
