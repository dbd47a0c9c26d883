//! The FMI 2.0 C boundary: C types, the FMI 2 calling-sequence table and the exported
//! `fmi2*` functions, a thin layer over [`crate::fmi`] (instance, panic boundary, logging).
//!
//! | module | what it holds |
//! |---|---|
//! | [`types`] | C types from the FMI 2 headers; callbacks as `Option<fn>` |
//! | [`state_machine`] | the FMI 2 calling-sequence tables: allowed states per function |
//! | [`exports`] | the exported `fmi2*` functions (thin) |
//!
//! FMI names (`fmi2OK`, `componentEnvironment`) are kept as the standard spells them.

#![allow(non_upper_case_globals, non_snake_case)]

pub mod exports;
pub mod state_machine;
pub mod types;

/// Every FMI 2.0 function this library exports (common, Co-Simulation and Model Exchange): the
/// one list `build-fmu` checks each binary's exports against (these and nothing else) and the
/// tests walk.
pub const FUNCTIONS: [&str; 44] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];
