//! Model Exchange (FMI 3.0 chapter 3).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterContinuousTimeMode, |inst| inst.enter_continuous_time_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    boundary!(instance, F::SetTime, args("time = {time:?}"), |inst| inst.set_time(time))
}

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
