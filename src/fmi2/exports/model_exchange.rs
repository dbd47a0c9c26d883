//! Model Exchange (FMI 2.0 chapter 3).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::EnterEventMode, |inst| inst.enter_event_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: fmi2Component, event_info: *mut fmi2EventInfo) -> fmi2Status {
    boundary!(c, F::NewDiscreteStates, |inst| {
        let info = try_out!(inst, event_info, "fmi2EventInfo");
        let update = inst.update_discrete_states();
        *info = fmi2EventInfo {
            newDiscreteStatesNeeded: update.discrete_states_need_update as fmi2Boolean,
            terminateSimulation: update.terminate_simulation as fmi2Boolean,
            nominalsOfContinuousStatesChanged: update.nominals_changed as fmi2Boolean,
            valuesOfContinuousStatesChanged: update.values_changed as fmi2Boolean,
            nextEventTimeDefined: update.next_event_time.is_some() as fmi2Boolean,
            nextEventTime: update.next_event_time.unwrap_or(0.0),
        };
        Status::Ok
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    boundary!(c, F::EnterContinuousTimeMode, |inst| inst.enter_continuous_time_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _no_set_fmu_state_prior: fmi2Boolean,
    enter_event_mode: *mut fmi2Boolean,
    terminate_simulation: *mut fmi2Boolean,
) -> fmi2Status {
    boundary!(c, F::CompletedIntegratorStep, |inst| {
        let enter = try_out!(inst, enter_event_mode, "enterEventMode");
        let terminate = try_out!(inst, terminate_simulation, "terminateSimulation");
        let (e, t) = inst.completed_integrator_step();
        (*enter, *terminate) = (e as fmi2Boolean, t as fmi2Boolean);
        Status::Ok
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    boundary!(c, F::SetTime, args("time = {time:?}"), |inst| inst.set_time(time))
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status {
    boundary!(c, F::SetContinuousStates, args("x = {}", show(x, nx)), |inst| {
        let states = try_slice!(inst, x, nx, "x");
        inst.set_continuous_states(states)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(c: fmi2Component, derivatives: *mut fmi2Real, nx: usize) -> fmi2Status {
    boundary!(c, F::GetDerivatives, args("derivatives = {}", show(derivatives, nx)), |inst| {
        let dx = try_slice_mut!(inst, derivatives, nx, "derivatives");
        inst.get_derivatives(dx)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(c: fmi2Component, indicators: *mut fmi2Real, ni: usize) -> fmi2Status {
    boundary!(c, F::GetEventIndicators, args("eventIndicators = {}", show(indicators, ni)), |inst| {
        let z = try_slice_mut!(inst, indicators, ni, "eventIndicators");
        inst.get_event_indicators(z)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status {
    boundary!(c, F::GetContinuousStates, args("x = {}", show(x, nx)), |inst| {
        let states = try_slice_mut!(inst, x, nx, "x");
        inst.get_continuous_states(states)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    boundary!(c, F::GetNominalsOfContinuousStates, |inst| {
        let nominals = try_slice_mut!(inst, x_nominal, nx, "x_nominal");
        inst.get_nominals(nominals)
    })
}
