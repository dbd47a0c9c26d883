//! The FMI 3.0 calling-sequence state machine as a table: for each function, the set of
//! states in which it may be called (FMI 3.0, sections 3.2 and 4.2: the state machines of
//! Model Exchange and Co-Simulation). FMI 2's `stepComplete` column is FMI 3's Step Mode and
//! `stepFailed` is Step Discarded. A call outside its set returns `fmi3Error`, logs the
//! function and the state, and changes nothing. Scheduled Execution is not implemented (its
//! instantiation fails), and neither clocks nor structural parameters exist here: their
//! functions are allowed where the standard allows them and then answer with an error saying
//! so.

use crate::fmi::{FmiFunction, FmiVersion, InterfaceType, ModelState};

/// The FMI 3.0 functions that take an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fmi3Function {
    SetDebugLogging,
    FreeInstance,
    EnterInitializationMode,
    ExitInitializationMode,
    EnterEventMode,
    Terminate,
    Reset,
    GetFloat64,
    GetInt32,
    GetBoolean,
    /// Get functions of the types without variables here (Float32, Int8 ... UInt64 but Int32,
    /// String, Binary), with the C name.
    GetOther(&'static str),
    GetClock,
    SetFloat64,
    SetInt32,
    SetBoolean,
    SetOther(&'static str),
    SetClock,
    GetNumberOfVariableDependencies,
    GetVariableDependencies,
    GetFMUState,
    SetFMUState,
    FreeFMUState,
    SerializedFMUStateSize,
    SerializeFMUState,
    DeserializeFMUState,
    GetDirectionalDerivative,
    GetAdjointDerivative,
    EnterConfigurationMode,
    ExitConfigurationMode,
    /// `fmi3Get/SetInterval*`, `fmi3Get/SetShift*`, with the C name.
    ClockTiming(&'static str),
    EvaluateDiscreteStates,
    UpdateDiscreteStates,
    // Model Exchange
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetContinuousStateDerivatives,
    GetEventIndicators,
    GetContinuousStates,
    GetNominalsOfContinuousStates,
    GetNumberOfEventIndicators,
    GetNumberOfContinuousStates,
    // Co-Simulation
    EnterStepMode,
    GetOutputDerivatives,
    DoStep,
    ActivateModelPartition,
}

use ModelState as S;

const INST: u16 = S::Instantiated.bit();
const INIT: u16 = S::InitializationMode.bit();
const STEP: u16 = S::StepComplete.bit();
const DISCARDED: u16 = S::StepFailed.bit();
const TERMINATED: u16 = S::Terminated.bit();
const ERROR: u16 = S::Error.bit();
const EVENT: u16 = S::EventMode.bit();
const CONTINUOUS: u16 = S::ContinuousTimeMode.bit();
const INTERMEDIATE: u16 = S::IntermediateUpdateMode.bit();
const CONFIGURATION: u16 = S::ConfigurationMode.bit();
/// Every state but `Error`: after an error only freeing, resetting and restoring a saved
/// FMU state are meaningful (FMI 3.0, section 2.2.3, status `fmi3Error`).
const ANY: u16 = INST | INIT | STEP | DISCARDED | TERMINATED | EVENT | CONTINUOUS | INTERMEDIATE | CONFIGURATION;
const AFTER_ERROR: u16 = ANY | ERROR;

impl Fmi3Function {
    /// The C name, for log messages.
    pub fn name(self) -> &'static str {
        use Fmi3Function::*;
        match self {
            SetDebugLogging => "fmi3SetDebugLogging",
            FreeInstance => "fmi3FreeInstance",
            EnterInitializationMode => "fmi3EnterInitializationMode",
            ExitInitializationMode => "fmi3ExitInitializationMode",
            EnterEventMode => "fmi3EnterEventMode",
            Terminate => "fmi3Terminate",
            Reset => "fmi3Reset",
            GetFloat64 => "fmi3GetFloat64",
            GetInt32 => "fmi3GetInt32",
            GetBoolean => "fmi3GetBoolean",
            GetOther(name) | SetOther(name) | ClockTiming(name) => name,
            GetClock => "fmi3GetClock",
            SetFloat64 => "fmi3SetFloat64",
            SetInt32 => "fmi3SetInt32",
            SetBoolean => "fmi3SetBoolean",
            SetClock => "fmi3SetClock",
            GetNumberOfVariableDependencies => "fmi3GetNumberOfVariableDependencies",
            GetVariableDependencies => "fmi3GetVariableDependencies",
            GetFMUState => "fmi3GetFMUState",
            SetFMUState => "fmi3SetFMUState",
            FreeFMUState => "fmi3FreeFMUState",
            SerializedFMUStateSize => "fmi3SerializedFMUStateSize",
            SerializeFMUState => "fmi3SerializeFMUState",
            DeserializeFMUState => "fmi3DeserializeFMUState",
            GetDirectionalDerivative => "fmi3GetDirectionalDerivative",
            GetAdjointDerivative => "fmi3GetAdjointDerivative",
            EnterConfigurationMode => "fmi3EnterConfigurationMode",
            ExitConfigurationMode => "fmi3ExitConfigurationMode",
            EvaluateDiscreteStates => "fmi3EvaluateDiscreteStates",
            UpdateDiscreteStates => "fmi3UpdateDiscreteStates",
            EnterContinuousTimeMode => "fmi3EnterContinuousTimeMode",
            CompletedIntegratorStep => "fmi3CompletedIntegratorStep",
            SetTime => "fmi3SetTime",
            SetContinuousStates => "fmi3SetContinuousStates",
            GetContinuousStateDerivatives => "fmi3GetContinuousStateDerivatives",
            GetEventIndicators => "fmi3GetEventIndicators",
            GetContinuousStates => "fmi3GetContinuousStates",
            GetNominalsOfContinuousStates => "fmi3GetNominalsOfContinuousStates",
            GetNumberOfEventIndicators => "fmi3GetNumberOfEventIndicators",
            GetNumberOfContinuousStates => "fmi3GetNumberOfContinuousStates",
            EnterStepMode => "fmi3EnterStepMode",
            GetOutputDerivatives => "fmi3GetOutputDerivatives",
            DoStep => "fmi3DoStep",
            ActivateModelPartition => "fmi3ActivateModelPartition",
        }
    }

    /// The states in which the function may be called, as a bit set over [`ModelState`].
    /// Per-variable conditions (which variables may be set when) are checked separately.
    #[inline(always)]
    pub const fn allowed_states(self, interface: InterfaceType) -> u16 {
        use Fmi3Function::*;
        let me = matches!(interface, InterfaceType::ModelExchange);
        match self {
            SetDebugLogging | FreeInstance | Reset => AFTER_ERROR,
            EnterInitializationMode => INST,
            ExitInitializationMode => INIT,
            EnterEventMode => {
                if me {
                    CONTINUOUS
                } else {
                    STEP
                }
            }
            Terminate => EVENT | CONTINUOUS | STEP | DISCARDED,
            GetFloat64 | GetInt32 | GetBoolean | GetOther(_) => {
                INST | INIT | EVENT | CONTINUOUS | STEP | DISCARDED | INTERMEDIATE | TERMINATED | CONFIGURATION
            }
            SetFloat64 => INST | INIT | EVENT | CONTINUOUS | STEP | INTERMEDIATE | CONFIGURATION,
            SetInt32 | SetBoolean | SetOther(_) => INST | INIT | EVENT | STEP | CONFIGURATION,
            GetClock | SetClock | ClockTiming(_) => EVENT,
            GetNumberOfVariableDependencies | GetVariableDependencies => ANY,
            GetFMUState | SerializedFMUStateSize | SerializeFMUState => ANY,
            SetFMUState | FreeFMUState | DeserializeFMUState => AFTER_ERROR,
            GetDirectionalDerivative | GetAdjointDerivative => INIT | EVENT | CONTINUOUS | STEP | TERMINATED,
            EnterConfigurationMode => INST | EVENT | STEP,
            ExitConfigurationMode => CONFIGURATION,
            EvaluateDiscreteStates => EVENT | STEP,
            UpdateDiscreteStates => EVENT,
            EnterContinuousTimeMode if me => EVENT,
            CompletedIntegratorStep | SetContinuousStates if me => CONTINUOUS,
            SetTime if me => EVENT | CONTINUOUS,
            GetContinuousStateDerivatives
            | GetEventIndicators
            | GetContinuousStates
            | GetNominalsOfContinuousStates
                if me =>
            {
                INIT | EVENT | CONTINUOUS | TERMINATED
            }
            GetNumberOfEventIndicators | GetNumberOfContinuousStates => ANY,
            // Step Mode is entered from Event Mode; from Initialization Mode only through
            // fmi3ExitInitializationMode.
            EnterStepMode if !me => EVENT,
            GetOutputDerivatives if !me => STEP | DISCARDED | TERMINATED,
            DoStep if !me => STEP,
            _ => 0,
        }
    }
}

impl FmiFunction for Fmi3Function {
    const VERSION: FmiVersion = FmiVersion::Fmi3;

    fn name(self) -> &'static str {
        Fmi3Function::name(self)
    }

    // Inlined, so that each export's mask folds to a constant.
    #[inline(always)]
    fn allowed_states(self, interface: InterfaceType) -> u16 {
        Fmi3Function::allowed_states(self, interface)
    }
}
