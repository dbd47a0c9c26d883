//! The FMI 2.0 calling-sequence state machine as a table: for each function, the set of
//! states in which it may be called (FMI 2.0.5, sections 3.2.3 and 4.2.4). A call outside
//! its set returns `fmi2Error`, logs the function and the state, and changes nothing.
//!
//! Unlike Reference-FMUs this keeps an explicit `Error` state (the tables' "error" column):
//! after a failed computation only the calls allowed there work, until `fmi2Reset`,
//! `fmi2SetFMUstate` or `fmi2FreeInstance`.

use crate::fmi::{FmiFunction, FmiVersion, InterfaceType, ModelState};

/// The FMI 2.0 functions that take an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fmi2Function {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetReal,
    GetInteger,
    GetBoolean,
    GetString,
    SetReal,
    SetInteger,
    SetBoolean,
    SetString,
    GetFMUstate,
    SetFMUstate,
    FreeFMUstate,
    SerializedFMUstateSize,
    SerializeFMUstate,
    DeSerializeFMUstate,
    GetDirectionalDerivative,
    // Co-Simulation
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
    GetRealStatus,
    GetIntegerStatus,
    GetBooleanStatus,
    GetStringStatus,
    // Model Exchange
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetDerivatives,
    GetEventIndicators,
    GetContinuousStates,
    GetNominalsOfContinuousStates,
}

use ModelState as S;

const INST: u16 = S::Instantiated.bit();
const INIT: u16 = S::InitializationMode.bit();
const STEP_COMPLETE: u16 = S::StepComplete.bit();
const IN_PROGRESS: u16 = S::StepInProgress.bit();
const STEP_FAILED: u16 = S::StepFailed.bit();
const CANCELED: u16 = S::StepCanceled.bit();
const TERMINATED: u16 = S::Terminated.bit();
const ERROR: u16 = S::Error.bit();
const EVENT: u16 = S::EventMode.bit();
const CONTINUOUS: u16 = S::ContinuousTimeMode.bit();

impl FmiFunction for Fmi2Function {
    const VERSION: FmiVersion = FmiVersion::Fmi2;

    fn name(self) -> &'static str {
        Fmi2Function::name(self)
    }

    // Inlined, so that each export's mask folds to a constant.
    #[inline(always)]
    fn allowed_states(self, interface: InterfaceType) -> u16 {
        Fmi2Function::allowed_states(self, interface)
    }
}

impl Fmi2Function {
    pub const ALL: [Fmi2Function; 41] = {
        use Fmi2Function::*;
        [
            SetDebugLogging,
            FreeInstance,
            SetupExperiment,
            EnterInitializationMode,
            ExitInitializationMode,
            Terminate,
            Reset,
            GetReal,
            GetInteger,
            GetBoolean,
            GetString,
            SetReal,
            SetInteger,
            SetBoolean,
            SetString,
            GetFMUstate,
            SetFMUstate,
            FreeFMUstate,
            SerializedFMUstateSize,
            SerializeFMUstate,
            DeSerializeFMUstate,
            GetDirectionalDerivative,
            SetRealInputDerivatives,
            GetRealOutputDerivatives,
            DoStep,
            CancelStep,
            GetStatus,
            GetRealStatus,
            GetIntegerStatus,
            GetBooleanStatus,
            GetStringStatus,
            EnterEventMode,
            NewDiscreteStates,
            EnterContinuousTimeMode,
            CompletedIntegratorStep,
            SetTime,
            SetContinuousStates,
            GetDerivatives,
            GetEventIndicators,
            GetContinuousStates,
            GetNominalsOfContinuousStates,
        ]
    };

    /// The C name, for log messages.
    pub fn name(self) -> &'static str {
        use Fmi2Function::*;
        match self {
            SetDebugLogging => "fmi2SetDebugLogging",
            FreeInstance => "fmi2FreeInstance",
            SetupExperiment => "fmi2SetupExperiment",
            EnterInitializationMode => "fmi2EnterInitializationMode",
            ExitInitializationMode => "fmi2ExitInitializationMode",
            Terminate => "fmi2Terminate",
            Reset => "fmi2Reset",
            GetReal => "fmi2GetReal",
            GetInteger => "fmi2GetInteger",
            GetBoolean => "fmi2GetBoolean",
            GetString => "fmi2GetString",
            SetReal => "fmi2SetReal",
            SetInteger => "fmi2SetInteger",
            SetBoolean => "fmi2SetBoolean",
            SetString => "fmi2SetString",
            GetFMUstate => "fmi2GetFMUstate",
            SetFMUstate => "fmi2SetFMUstate",
            FreeFMUstate => "fmi2FreeFMUstate",
            SerializedFMUstateSize => "fmi2SerializedFMUstateSize",
            SerializeFMUstate => "fmi2SerializeFMUstate",
            DeSerializeFMUstate => "fmi2DeSerializeFMUstate",
            GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
            SetRealInputDerivatives => "fmi2SetRealInputDerivatives",
            GetRealOutputDerivatives => "fmi2GetRealOutputDerivatives",
            DoStep => "fmi2DoStep",
            CancelStep => "fmi2CancelStep",
            GetStatus => "fmi2GetStatus",
            GetRealStatus => "fmi2GetRealStatus",
            GetIntegerStatus => "fmi2GetIntegerStatus",
            GetBooleanStatus => "fmi2GetBooleanStatus",
            GetStringStatus => "fmi2GetStringStatus",
            EnterEventMode => "fmi2EnterEventMode",
            NewDiscreteStates => "fmi2NewDiscreteStates",
            EnterContinuousTimeMode => "fmi2EnterContinuousTimeMode",
            CompletedIntegratorStep => "fmi2CompletedIntegratorStep",
            SetTime => "fmi2SetTime",
            SetContinuousStates => "fmi2SetContinuousStates",
            GetDerivatives => "fmi2GetDerivatives",
            GetEventIndicators => "fmi2GetEventIndicators",
            GetContinuousStates => "fmi2GetContinuousStates",
            GetNominalsOfContinuousStates => "fmi2GetNominalsOfContinuousStates",
        }
    }

    /// The states in which the function may be called, as a bit set over [`ModelState`].
    /// Get functions marked "7"/"8" in the tables (values for debugging only) are allowed.
    /// Per-variable conditions (which variables may be set when) are checked separately.
    #[inline(always)]
    pub const fn allowed_states(self, interface: InterfaceType) -> u16 {
        use Fmi2Function::*;
        match interface {
            InterfaceType::CoSimulation => match self {
                SetDebugLogging => {
                    INST | INIT | STEP_COMPLETE | IN_PROGRESS | STEP_FAILED | CANCELED | TERMINATED | ERROR
                }
                FreeInstance | Reset => INST | INIT | STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR,
                SetupExperiment | EnterInitializationMode => INST,
                ExitInitializationMode => INIT,
                Terminate => STEP_COMPLETE | STEP_FAILED,
                GetReal | GetInteger | GetBoolean | GetString => {
                    INIT | STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR
                }
                SetReal | SetInteger | SetBoolean | SetString => INST | INIT | STEP_COMPLETE,
                GetFMUstate => INST | INIT | STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR,
                SetFMUstate | FreeFMUstate | SerializedFMUstateSize | SerializeFMUstate | DeSerializeFMUstate => {
                    INST | INIT | STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR
                }
                GetDirectionalDerivative => INIT | STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR,
                SetRealInputDerivatives => INST | INIT | STEP_COMPLETE,
                GetRealOutputDerivatives => STEP_COMPLETE | STEP_FAILED | CANCELED | TERMINATED | ERROR,
                DoStep => STEP_COMPLETE,
                CancelStep => IN_PROGRESS,
                GetStatus | GetRealStatus | GetIntegerStatus | GetBooleanStatus | GetStringStatus => {
                    STEP_COMPLETE | IN_PROGRESS | STEP_FAILED | TERMINATED
                }
                EnterEventMode
                | NewDiscreteStates
                | EnterContinuousTimeMode
                | CompletedIntegratorStep
                | SetTime
                | SetContinuousStates
                | GetDerivatives
                | GetEventIndicators
                | GetContinuousStates
                | GetNominalsOfContinuousStates => 0,
            },
            InterfaceType::ModelExchange => match self {
                SetDebugLogging | FreeInstance | Reset => INST | INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
                SetupExperiment | EnterInitializationMode => INST,
                ExitInitializationMode => INIT,
                Terminate => EVENT | CONTINUOUS,
                GetReal | GetInteger | GetBoolean | GetString => INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
                // Per-variable conditions 1, 3, 4, 5 of the ME table.
                SetReal => INST | INIT | EVENT | CONTINUOUS,
                SetInteger | SetBoolean | SetString => INST | INIT | EVENT,
                GetFMUstate
                | SetFMUstate
                | FreeFMUstate
                | SerializedFMUstateSize
                | SerializeFMUstate
                | DeSerializeFMUstate => INST | INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
                GetDirectionalDerivative => INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
                EnterEventMode => EVENT | CONTINUOUS,
                NewDiscreteStates | EnterContinuousTimeMode => EVENT,
                CompletedIntegratorStep | SetContinuousStates => CONTINUOUS,
                SetTime => EVENT | CONTINUOUS,
                GetDerivatives | GetEventIndicators | GetContinuousStates => {
                    INIT | EVENT | CONTINUOUS | TERMINATED | ERROR
                }
                GetNominalsOfContinuousStates => INST | EVENT | CONTINUOUS | TERMINATED | ERROR,
                SetRealInputDerivatives
                | GetRealOutputDerivatives
                | DoStep
                | CancelStep
                | GetStatus
                | GetRealStatus
                | GetIntegerStatus
                | GetBooleanStatus
                | GetStringStatus => 0,
            },
        }
    }

    pub fn allowed_in(self, interface: InterfaceType, state: ModelState) -> bool {
        self.allowed_states(interface) & state.bit() != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn do_step_only_in_step_complete_and_fatal_allows_nothing() {
        // Every state, FMI 3's own included (no FMI 2 function is allowed there).
        for state in ModelState::ALL {
            assert_eq!(
                Fmi2Function::DoStep.allowed_in(InterfaceType::CoSimulation, state),
                state == ModelState::StepComplete
            );
            for f in Fmi2Function::ALL {
                if state == ModelState::Fatal {
                    assert!(!f.allowed_in(InterfaceType::CoSimulation, state), "{f:?} in fatal");
                }
            }
        }
    }

    /// The table's functions are the exported list's (which `build-fmu` checks the binaries
    /// against), all but the three without an instance.
    #[test]
    fn the_table_names_the_exported_functions() {
        let names: Vec<&str> = Fmi2Function::ALL.iter().map(|f| f.name()).collect();
        let without_instance = ["fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2Instantiate"];
        let exported: Vec<&str> =
            crate::fmi2::FUNCTIONS.into_iter().filter(|f| !without_instance.contains(f)).collect();
        assert_eq!(names, exported);
    }
}
