//! Directional and adjoint derivatives (FMI 3.0 section 2.2.10).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
