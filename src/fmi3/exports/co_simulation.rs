//! Co-Simulation (FMI 3.0 chapter 4).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterStepMode, |inst| inst.enter_step_mode())
}

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
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
            "currentCommunicationPoint = {current_communication_point:?}, communicationStepSize = {communication_step_size:?}"
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
/// See the documentation of the `exports` module.
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
