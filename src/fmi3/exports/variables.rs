//! Getting and setting variables (FMI 3.0 section 2.2.6), and variable dependencies.

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3String,
    n_values: usize,
) -> fmi3Status {
    boundary!(instance, F::GetOther("fmi3GetString"), |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let values = try_slice_mut!(inst, values, n_values, "values");
        inst.get_string(vrs, n_values, |i, s| values[i] = s.as_ptr())
    })
}

/// # Safety
/// See the module documentation.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3String,
    n_values: usize,
) -> fmi3Status {
    boundary!(instance, F::SetOther("fmi3SetString"), |inst| {
        let vrs = try_slice!(inst, vrs, n_vrs, "valueReferences");
        let values = try_slice!(inst, values, n_values, "values");
        // SAFETY: each value is NULL or a NUL-terminated C string (the FMI calling convention).
        let texts: Vec<Option<&str>> = values.iter().map(|&p| unsafe { crate::fmi::boundary::c_text(p) }).collect();
        inst.set_string(vrs, &texts)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
    let knowns = Dependency::knowns(deps);
    for i in 0..g.len() {
        for &(known, same) in &knowns {
            let Some(known) = inst.table.groups.get(known) else { continue };
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
