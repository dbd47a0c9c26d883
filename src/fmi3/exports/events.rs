//! Configuration mode, clocks and discrete states (FMI 3.0 sections 2.2.8 and 3).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EnterConfigurationMode, |inst| {
        inst.error("this FMU has no structural parameters, so there is nothing to configure")
    })
}

/// # Safety
/// See the documentation of the `exports` module.
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
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    boundary!(instance, F::EvaluateDiscreteStates, |inst| {
        inst.error("not provided by this FMU (providesEvaluateDiscreteStates=\"false\"): it has no discrete states")
    })
}

/// # Safety
/// See the documentation of the `exports` module.
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
