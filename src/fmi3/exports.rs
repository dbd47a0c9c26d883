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
/// See the module documentation.
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
/// See the module documentation.
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
/// See the module documentation.
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
/// See the module documentation.
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
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    // SAFETY: the handle is looked up in the registry before any use.
    unsafe { free_instance(instance, F::FreeInstance) };
}

/// # Safety
/// See the module documentation.
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
            "toleranceDefined = {tolerance_defined}, tolerance = {tolerance}, startTime = {start_time}, stopTimeDefined = {stop_time_defined}, stopTime = {stop_time}"
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
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::ExitInitializationMode, |inst| inst.exit_initialization_mode())
}

/// # Safety
/// See the module documentation.
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
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::Terminate, |inst| inst.terminate())
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::Reset, |inst| inst.reset())
}

// ----- getting and setting variables ---------------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetFloat64,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice_mut!(inst, values, n_values, "values");
            inst.get_real(vrs, values)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::SetFloat64,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice!(inst, values, n_values, "values");
            inst.set_real(vrs, values)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetInt32,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice_mut!(inst, values, n_values, "values");
            inst.get_integer(vrs, values)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::SetInt32,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice!(inst, values, n_values, "values");
            inst.set_integer(vrs, values)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetBoolean,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice_mut!(inst, values, n_values, "values");
            inst.get_boolean(vrs, values, |f| f as fmi3Boolean)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::SetBoolean,
        args("valueReferences = {}, values = {}", show(vrs, n_vrs), show(values, n_values)),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let values = try_slice!(inst, values, n_values, "values");
            inst.set_boolean(vrs, values, |v| v != fmi3False)
        }
    )
}

/// Get and set functions of the types this FMU has no variables of: any value reference is
/// unknown (an error naming it); none is fine.
macro_rules! no_variables_of_type {
    ($get:ident, $set:ident, $t:ty, $name:expr) => {
        /// # Safety
        /// See the module documentation.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $get(
            instance: fmi3Instance,
            vrs: *const fmi3ValueReference,
            n_vrs: usize,
            values: *mut $t,
            n_values: usize,
        ) -> fmi3Status {
            boundary!(instance, F::GetOther(stringify!($get)), |inst| {
                let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
                let _ = try_slice_mut!(inst, values, n_values, "values");
                inst.no_variables_of_type(vrs, $name)
            })
        }

        /// # Safety
        /// See the module documentation.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $set(
            instance: fmi3Instance,
            vrs: *const fmi3ValueReference,
            n_vrs: usize,
            values: *const $t,
            n_values: usize,
        ) -> fmi3Status {
            boundary!(instance, F::SetOther(stringify!($set)), |inst| {
                let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
                let _ = try_slice!(inst, values, n_values, "values");
                inst.no_variables_of_type(vrs, $name)
            })
        }
    };
}

no_variables_of_type!(fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, "Float32");
no_variables_of_type!(fmi3GetInt8, fmi3SetInt8, fmi3Int8, "Int8");
no_variables_of_type!(fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, "UInt8");
no_variables_of_type!(fmi3GetInt16, fmi3SetInt16, fmi3Int16, "Int16");
no_variables_of_type!(fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, "UInt16");
no_variables_of_type!(fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, "UInt32");
no_variables_of_type!(fmi3GetInt64, fmi3SetInt64, fmi3Int64, "Int64");
no_variables_of_type!(fmi3GetUInt64, fmi3SetUInt64, fmi3UInt64, "UInt64");
no_variables_of_type!(fmi3GetString, fmi3SetString, fmi3String, "String");

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    value_sizes: *mut usize,
    values: *mut fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    boundary!(instance, F::GetOther("fmi3GetBinary"), |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let _ = try_slice_mut!(inst, value_sizes, n_values, "valueSizes");
        let _ = try_slice_mut!(inst, values, n_values, "values");
        inst.no_variables_of_type(vrs, "Binary")
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    value_sizes: *const usize,
    values: *const fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    boundary!(instance, F::SetOther("fmi3SetBinary"), |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let _ = try_slice!(inst, value_sizes, n_values, "valueSizes");
        let _ = try_slice!(inst, values, n_values, "values");
        inst.no_variables_of_type(vrs, "Binary")
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    boundary!(instance, F::GetClock, |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let _ = try_slice_mut!(inst, values, n_vrs, "values");
        inst.no_variables_of_type(vrs, "Clock")
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    boundary!(instance, F::SetClock, |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let _ = try_slice!(inst, values, n_vrs, "values");
        inst.no_variables_of_type(vrs, "Clock")
    })
}

// ----- variable dependencies ------------------------------------------------------------------

/// One dependency entry of `fmi3GetVariableDependencies`: element of the dependent (1-based, 0
/// for a scalar), independent variable, its element.
type DependencyEntry = (usize, u32, usize);

/// The element-level dependencies of variable `vr` in the current state: Initialization Mode's
/// (`InitialUnknown`) before initialisation ends, otherwise those of an output or a state
/// derivative.
fn dependencies_of(inst: &Instance, vr: u32) -> Result<Vec<DependencyEntry>, String> {
    let Some((g, _)) = inst.table.lookup_variable(vr) else {
        return Err(format!("value reference {vr} is not a variable of {}", inst.kind.info().model_name));
    };
    let initial =
        matches!(inst.state, crate::fmi::ModelState::Instantiated | crate::fmi::ModelState::InitializationMode);
    let deps: &[Dependency] = if initial && g.is_initial_unknown() {
        g.initial_dependencies
    } else if g.derivative_of.is_some() {
        g.derivative_dependencies
    } else if g.causality == Causality::Output {
        g.output_dependencies
    } else {
        return Err(format!(
            "{} is neither an output nor a state derivative: it has no dependency information",
            g.variable_name()
        ));
    };
    let index = |shape: &[usize], i: usize| if shape.is_empty() { 0 } else { i + 1 };
    let mut out = vec![];
    for i in 0..g.len() {
        for d in deps {
            let (name, same) = match d {
                Dependency::All(n) => (*n, false),
                Dependency::SameIndex(n) => (*n, true),
            };
            let Some((_, known)) = inst.table.group(name) else { continue };
            if same {
                out.push((index(g.shape, i), known.first_vr, index(known.shape, i)));
            } else {
                out.extend((0..known.len()).map(|j| (index(g.shape, i), known.first_vr, index(known.shape, j))));
            }
        }
    }
    Ok(out)
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    vr: fmi3ValueReference,
    n_dependencies: *mut usize,
) -> fmi3Status {
    boundary!(instance, F::GetNumberOfVariableDependencies, args("valueReference = {vr}"), |inst| {
        let out = try_out!(inst, n_dependencies, "nDependencies");
        match dependencies_of(inst, vr) {
            Ok(d) => {
                *out = d.len();
                Status::Ok
            }
            Err(m) => inst.error(&m),
        }
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    dependent: fmi3ValueReference,
    element_indices_of_dependent: *mut usize,
    independents: *mut fmi3ValueReference,
    element_indices_of_independents: *mut usize,
    dependency_kinds: *mut fmi3DependencyKind,
    n_dependencies: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetVariableDependencies,
        args("dependent = {dependent}, nDependencies = {n_dependencies}"),
        |inst| {
            let dependents =
                try_slice_mut!(inst, element_indices_of_dependent, n_dependencies, "elementIndicesOfDependent");
            let knowns = try_slice_mut!(inst, independents, n_dependencies, "independents");
            let known_elements =
                try_slice_mut!(inst, element_indices_of_independents, n_dependencies, "elementIndicesOfIndependents");
            let kinds = try_slice_mut!(inst, dependency_kinds, n_dependencies, "dependencyKinds");
            let entries = match dependencies_of(inst, dependent) {
                Ok(d) => d,
                Err(m) => return inst.error(&m),
            };
            if entries.len() != n_dependencies {
                return inst.error(&format!(
                    "variable {dependent} has {} dependencies (fmi3GetNumberOfVariableDependencies), nDependencies = \
                 {n_dependencies}",
                    entries.len()
                ));
            }
            for (i, (e, vr, k)) in entries.into_iter().enumerate() {
                dependents[i] = e;
                knowns[i] = vr;
                known_elements[i] = k;
                kinds[i] = fmi3Dependent;
            }
            Status::Ok
        }
    )
}

// ----- FMU states -----------------------------------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::GetFMUState, args("FMUState = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUState");
        inst.get_fmu_state(slot)
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(instance: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::SetFMUState, args("FMUState = {state:?}"), |inst| { inst.set_fmu_state(state) })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::FreeFMUState, args("FMUState = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUState");
        inst.free_fmu_state(slot)
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    state: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    boundary!(instance, F::SerializedFMUStateSize, args("FMUState = {state:?}"), |inst| {
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
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    state: fmi3FMUState,
    serialized: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    boundary!(instance, F::SerializeFMUState, args("FMUState = {state:?}, size = {size}"), |inst| {
        let out = try_slice_mut!(inst, serialized, size, "serializedState");
        inst.serialize_fmu_state(state, out)
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serialized: *const fmi3Byte,
    size: usize,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    boundary!(instance, F::DeserializeFMUState, args("size = {size}"), |inst| {
        let bytes = try_slice!(inst, serialized, size, "serializedState");
        let slot = try_out!(inst, state, "FMUState");
        inst.deserialize_fmu_state(bytes, slot)
    })
}

// ----- partial derivatives --------------------------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetDirectionalDerivative,
        args(
            "unknowns = {}, knowns = {}, seed = {}, sensitivity = {}",
            show(unknowns, n_unknowns),
            show(knowns, n_knowns),
            show(seed, n_seed),
            show(sensitivity, n_sensitivity)
        ),
        |inst| {
            let unknowns = try_slice!(inst, unknowns, n_unknowns, "unknowns");
            let knowns = try_slice!(inst, knowns, n_knowns, "knowns");
            let seeds = try_slice!(inst, seed, n_seed, "seed");
            let out = try_slice_mut!(inst, sensitivity, n_sensitivity, "sensitivity");
            inst.get_directional_derivative(unknowns, knowns, seeds, out)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetAdjointDerivative,
        args(
            "unknowns = {}, knowns = {}, seed = {}, sensitivity = {}",
            show(unknowns, n_unknowns),
            show(knowns, n_knowns),
            show(seed, n_seed),
            show(sensitivity, n_sensitivity)
        ),
        |inst| {
            let unknowns = try_slice!(inst, unknowns, n_unknowns, "unknowns");
            let knowns = try_slice!(inst, knowns, n_knowns, "knowns");
            let seeds = try_slice!(inst, seed, n_seed, "seed");
            let out = try_slice_mut!(inst, sensitivity, n_sensitivity, "sensitivity");
            inst.get_adjoint_derivative(unknowns, knowns, seeds, out)
        }
    )
}

// ----- configuration, clocks, discrete states -------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterConfigurationMode, |inst| {
        inst.error("this FMU has no structural parameters, so there is nothing to configure")
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::ExitConfigurationMode, |inst| inst.error("this FMU has no structural parameters"))
}

/// Clock timing functions: this FMU has no clocks.
macro_rules! no_clocks {
    ($name:ident ( $( $arg:ident : $t:ty ),* )) => {
        /// # Safety
        /// See the module documentation.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $( $arg: $t ),*) -> fmi3Status {
            let _ = ($( $arg ),*);
            boundary!(instance, F::ClockTiming(stringify!($name)), |inst| inst.error("this FMU has no clocks"))
        }
    };
}

no_clocks!(fmi3GetIntervalDecimal(vrs: *const fmi3ValueReference, n: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier));
no_clocks!(fmi3GetIntervalFraction(vrs: *const fmi3ValueReference, n: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier));
no_clocks!(fmi3GetShiftDecimal(vrs: *const fmi3ValueReference, n: usize, shifts: *mut fmi3Float64));
no_clocks!(fmi3GetShiftFraction(vrs: *const fmi3ValueReference, n: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64));
no_clocks!(fmi3SetIntervalDecimal(vrs: *const fmi3ValueReference, n: usize, intervals: *const fmi3Float64));
no_clocks!(fmi3SetIntervalFraction(vrs: *const fmi3ValueReference, n: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64));
no_clocks!(fmi3SetShiftDecimal(vrs: *const fmi3ValueReference, n: usize, shifts: *const fmi3Float64));
no_clocks!(fmi3SetShiftFraction(vrs: *const fmi3ValueReference, n: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64));

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EvaluateDiscreteStates, |inst| {
        inst.error("not provided by this FMU (providesEvaluateDiscreteStates=\"false\"): it has no discrete states")
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discrete_states_need_update: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    nominals_of_continuous_states_changed: *mut fmi3Boolean,
    values_of_continuous_states_changed: *mut fmi3Boolean,
    next_event_time_defined: *mut fmi3Boolean,
    next_event_time: *mut fmi3Float64,
) -> fmi3Status {
    boundary!(instance, F::UpdateDiscreteStates, |inst| {
        let need = try_out!(inst, discrete_states_need_update, "discreteStatesNeedUpdate");
        let terminate = try_out!(inst, terminate_simulation, "terminateSimulation");
        let nominals = try_out!(inst, nominals_of_continuous_states_changed, "nominalsOfContinuousStatesChanged");
        let values = try_out!(inst, values_of_continuous_states_changed, "valuesOfContinuousStatesChanged");
        let defined = try_out!(inst, next_event_time_defined, "nextEventTimeDefined");
        let next = try_out!(inst, next_event_time, "nextEventTime");
        let info = inst.update_discrete_states();
        *need = info.discrete_states_need_update as fmi3Boolean;
        *terminate = info.terminate_simulation as fmi3Boolean;
        *nominals = info.nominals_changed as fmi3Boolean;
        *values = info.values_changed as fmi3Boolean;
        *defined = info.next_event_time.is_some() as fmi3Boolean;
        *next = info.next_event_time.unwrap_or(0.0);
        Status::Ok
    })
}

// ----- Model Exchange -------------------------------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterContinuousTimeMode, |inst| inst.enter_continuous_time_mode())
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _no_set_fmu_state_prior_to_current_point: fmi3Boolean,
    enter_event_mode: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
) -> fmi3Status {
    boundary!(instance, F::CompletedIntegratorStep, |inst| {
        let enter = try_out!(inst, enter_event_mode, "enterEventMode");
        let terminate = try_out!(inst, terminate_simulation, "terminateSimulation");
        let (e, t) = inst.completed_integrator_step();
        (*enter, *terminate) = (e as fmi3Boolean, t as fmi3Boolean);
        Status::Ok
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    boundary!(instance, F::SetTime, args("time = {time}"), |inst| inst.set_time(time))
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuous_states: *const fmi3Float64,
    n_continuous_states: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::SetContinuousStates,
        args("continuousStates = {}", show(continuous_states, n_continuous_states)),
        |inst| {
            let x = try_slice!(inst, continuous_states, n_continuous_states, "continuousStates");
            inst.set_continuous_states(x)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    derivatives: *mut fmi3Float64,
    n_continuous_states: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetContinuousStateDerivatives,
        args("derivatives = {}", show(derivatives, n_continuous_states)),
        |inst| {
            let dx = try_slice_mut!(inst, derivatives, n_continuous_states, "derivatives");
            inst.get_derivatives(dx)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    event_indicators: *mut fmi3Float64,
    n_event_indicators: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetEventIndicators,
        args("eventIndicators = {}", show(event_indicators, n_event_indicators)),
        |inst| {
            let z = try_slice_mut!(inst, event_indicators, n_event_indicators, "eventIndicators");
            inst.get_event_indicators(z)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    continuous_states: *mut fmi3Float64,
    n_continuous_states: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetContinuousStates,
        args("continuousStates = {}", show(continuous_states, n_continuous_states)),
        |inst| {
            let x = try_slice_mut!(inst, continuous_states, n_continuous_states, "continuousStates");
            inst.get_continuous_states(x)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    n_continuous_states: usize,
) -> fmi3Status {
    boundary!(instance, F::GetNominalsOfContinuousStates, |inst| {
        let x = try_slice_mut!(inst, nominals, n_continuous_states, "nominals");
        inst.get_nominals(x)
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    n_event_indicators: *mut usize,
) -> fmi3Status {
    boundary!(instance, F::GetNumberOfEventIndicators, |inst| {
        let out = try_out!(inst, n_event_indicators, "nEventIndicators");
        *out = if inst.interface == InterfaceType::ModelExchange { inst.event_indicator_count() } else { 0 };
        Status::Ok
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    n_continuous_states: *mut usize,
) -> fmi3Status {
    boundary!(instance, F::GetNumberOfContinuousStates, |inst| {
        let out = try_out!(inst, n_continuous_states, "nContinuousStates");
        *out = if inst.interface == InterfaceType::ModelExchange { inst.state_count() } else { 0 };
        Status::Ok
    })
}

// ----- Co-Simulation --------------------------------------------------------------------------

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterStepMode, |inst| inst.enter_step_mode())
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    boundary!(
        instance,
        F::GetOutputDerivatives,
        args(
            "valueReferences = {}, orders = {}, values = {}",
            show(vrs, n_vrs),
            show(orders, n_vrs),
            show(values, n_values)
        ),
        |inst| {
            let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
            let orders = try_slice!(inst, orders, n_vrs, "orders");
            let values = try_slice_mut!(inst, values, n_values, "values");
            inst.get_output_derivatives(vrs, orders, values)
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    current_communication_point: fmi3Float64,
    communication_step_size: fmi3Float64,
    _no_set_fmu_state_prior_to_current_point: fmi3Boolean,
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
) -> fmi3Status {
    boundary!(
        instance,
        F::DoStep,
        args(
            "currentCommunicationPoint = {current_communication_point}, communicationStepSize = {communication_step_size}"
        ),
        |inst| {
            let event = try_out!(inst, event_handling_needed, "eventHandlingNeeded");
            let terminate = try_out!(inst, terminate_simulation, "terminateSimulation");
            let early = try_out!(inst, early_return, "earlyReturn");
            let last = try_out!(inst, last_successful_time, "lastSuccessfulTime");
            let (status, outcome) = inst.do_step(current_communication_point, communication_step_size);
            *event = outcome.event_handling_needed as fmi3Boolean;
            *terminate = outcome.terminate_simulation as fmi3Boolean;
            *early = outcome.early_return as fmi3Boolean;
            *last = outcome.last_successful_time;
            status
        }
    )
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    clock_reference: fmi3ValueReference,
    activation_time: fmi3Float64,
) -> fmi3Status {
    let _ = (clock_reference, activation_time);
    boundary!(instance, F::ActivateModelPartition, |inst| {
        inst.error("Scheduled Execution is not implemented by this FMU")
    })
}
