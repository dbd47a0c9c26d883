//! Co-Simulation (FMI 2.0 chapter 4).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    boundary!(
        c,
        F::SetRealInputDerivatives,
        args("vr = {}, order = {}, value = {}", show(vr, nvr), show(order, nvr), show(value, nvr)),
        |inst| {
            let vrs = try_slice!(inst, vr, nvr, "vr");
            let orders = try_slice!(inst, order, nvr, "order");
            let values = try_slice!(inst, value, nvr, "value");
            inst.set_real_input_derivatives(vrs, orders, values)
        }
    )
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    boundary!(
        c,
        F::GetRealOutputDerivatives,
        args("vr = {}, order = {}, value = {}", show(vr, nvr), show(order, nvr), show(value, nvr)),
        |inst| {
            let vrs = try_slice!(inst, vr, nvr, "vr");
            let orders = try_slice!(inst, order, nvr, "order");
            let values = try_slice_mut!(inst, value, nvr, "value");
            inst.get_output_derivatives(vrs, orders, values)
        }
    )
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    boundary!(
        c,
        F::DoStep,
        args(
            "currentCommunicationPoint = {current_communication_point:?}, communicationStepSize = {communication_step_size:?}"
        ),
        |inst| inst.do_step(current_communication_point, communication_step_size).0
    )
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    // Only allowed in stepInProgress, which this synchronous FMU never enters: the state
    // table refuses it.
    boundary!(c, F::CancelStep, |inst| inst.error("no asynchronous step to cancel"))
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status {
    boundary!(c, F::GetStatus, args("s = {kind}"), |inst| {
        let _ = try_out!(inst, value, "value");
        status_not_available(inst, kind)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    boundary!(c, F::GetRealStatus, args("s = {kind}"), |inst| {
        let out = try_out!(inst, value, "value");
        if kind != fmi2LastSuccessfulTime {
            return status_not_available(inst, kind);
        }
        *out = inst.last_successful_time;
        Status::Ok
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    boundary!(c, F::GetIntegerStatus, args("s = {kind}"), |inst| {
        let _ = try_out!(inst, value, "value");
        status_not_available(inst, kind)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    boundary!(c, F::GetBooleanStatus, args("s = {kind}"), |inst| {
        let out = try_out!(inst, value, "value");
        if kind != fmi2Terminated {
            return status_not_available(inst, kind);
        }
        *out = if inst.terminated { fmi2True } else { fmi2False };
        Status::Ok
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    boundary!(c, F::GetStringStatus, args("s = {kind}"), |inst| {
        let _ = try_out!(inst, value, "value");
        status_not_available(inst, kind)
    })
}

// ----- status queries (FMI 2 Co-Simulation) --------------------------------------------------

/// Status kinds this synchronous FMU cannot answer: logged, `fmi2Discard` (as the standard
/// prescribes).
fn status_not_available(inst: &Instance, kind: fmi2StatusKind) -> Status {
    inst.log(
        Status::Discard,
        &format!(
            "{}: status kind {kind} is not available (this FMU steps synchronously; it answers fmi2LastSuccessfulTime \
             with fmi2GetRealStatus and fmi2Terminated with fmi2GetBooleanStatus)",
            inst.function()
        ),
    );
    Status::Discard
}
