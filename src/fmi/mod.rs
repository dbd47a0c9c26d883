//! What the FMI 2.0 and FMI 3.0 boundaries share: an instance around a model (state,
//! argument checks, time, FMU states, logging), the panic boundary, the log categories and
//! the model descriptions of both versions. Safe Rust except the pointer helpers of
//! [`boundary`]; the two C boundaries ([`crate::fmi2`], [`crate::fmi3`]) only turn C
//! arguments into Rust values and call into this.
//!
//! | module | what it holds |
//! |---|---|
//! | [`boundary`] | panic boundary, instance-handle and pointer checks, the calling function as context |
//! | [`instance`] | an instance: state machine, argument checks, time bookkeeping, FMU states, around a model |
//! | [`log`] | log categories and messages to the importer's FMI 2 or FMI 3 logger |
//! | [`description`] | `modelDescription.xml` of both versions, the instantiation tokens, the documentation page |
//! | [`library`] | which model a token selects in this binary |
//! | [`registry`] | the live instance handles: a handle is its slot in a static table (stale, foreign, busy handles refused unread) |

pub mod boundary;
pub mod description;
pub mod instance;
pub mod library;
pub mod log;
pub mod registry;

use std::ffi::c_int;

/// The status of an FMI call; FMI 2 and FMI 3 number them alike (`fmi2OK` = `fmi3OK` = 0 ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

impl Status {
    pub fn code(self) -> c_int {
        self as c_int
    }

    /// The status's name in the given FMI version, for log messages.
    pub fn name(self, version: FmiVersion) -> &'static str {
        match (version, self) {
            (FmiVersion::Fmi2, Status::Ok) => "fmi2OK",
            (FmiVersion::Fmi2, Status::Warning) => "fmi2Warning",
            (FmiVersion::Fmi2, Status::Discard) => "fmi2Discard",
            (FmiVersion::Fmi2, Status::Error) => "fmi2Error",
            (FmiVersion::Fmi2, Status::Fatal) => "fmi2Fatal",
            (FmiVersion::Fmi3, Status::Ok) => "fmi3OK",
            (FmiVersion::Fmi3, Status::Warning) => "fmi3Warning",
            (FmiVersion::Fmi3, Status::Discard) => "fmi3Discard",
            (FmiVersion::Fmi3, Status::Error) => "fmi3Error",
            (FmiVersion::Fmi3, Status::Fatal) => "fmi3Fatal",
        }
    }
}

/// The FMI version a binary boundary implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FmiVersion {
    Fmi2,
    Fmi3,
}

/// Interface type of an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InterfaceType {
    ModelExchange,
    CoSimulation,
}

impl InterfaceType {
    pub fn name(self) -> &'static str {
        match self {
            InterfaceType::CoSimulation => "Co-Simulation",
            InterfaceType::ModelExchange => "Model Exchange",
        }
    }
}

/// States of an instance: the columns of the FMI 2 and FMI 3 calling-sequence tables. FMI 2's
/// `stepComplete` is FMI 3's Step Mode; FMI 2's `stepFailed` is FMI 3's Step Discarded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum ModelState {
    Instantiated = 0,
    InitializationMode = 1,
    StepComplete = 2,
    StepInProgress = 3,
    StepFailed = 4,
    StepCanceled = 5,
    Terminated = 6,
    Error = 7,
    Fatal = 8,
    EventMode = 9,
    ContinuousTimeMode = 10,
    IntermediateUpdateMode = 11,
    ConfigurationMode = 12,
}

impl ModelState {
    pub const ALL: [ModelState; 13] = [
        ModelState::Instantiated,
        ModelState::InitializationMode,
        ModelState::StepComplete,
        ModelState::StepInProgress,
        ModelState::StepFailed,
        ModelState::StepCanceled,
        ModelState::Terminated,
        ModelState::Error,
        ModelState::Fatal,
        ModelState::EventMode,
        ModelState::ContinuousTimeMode,
        ModelState::IntermediateUpdateMode,
        ModelState::ConfigurationMode,
    ];

    pub const fn bit(self) -> u16 {
        1 << self as u8
    }

    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.iter().copied().find(|s| *s as u8 == code)
    }

    /// The state's name in the standard of the given version.
    pub fn name(self, version: FmiVersion) -> &'static str {
        match (self, version) {
            (ModelState::Instantiated, _) => "instantiated",
            (ModelState::InitializationMode, _) => "initializationMode",
            (ModelState::StepComplete, FmiVersion::Fmi2) => "stepComplete",
            (ModelState::StepComplete, FmiVersion::Fmi3) => "stepMode",
            (ModelState::StepInProgress, _) => "stepInProgress",
            (ModelState::StepFailed, FmiVersion::Fmi2) => "stepFailed",
            (ModelState::StepFailed, FmiVersion::Fmi3) => "stepDiscarded",
            (ModelState::StepCanceled, _) => "stepCanceled",
            (ModelState::Terminated, _) => "terminated",
            (ModelState::Error, _) => "error",
            (ModelState::Fatal, _) => "fatal",
            (ModelState::EventMode, _) => "eventMode",
            (ModelState::ContinuousTimeMode, _) => "continuousTimeMode",
            (ModelState::IntermediateUpdateMode, _) => "intermediateUpdateMode",
            (ModelState::ConfigurationMode, _) => "configurationMode",
        }
    }
}

/// An exported function: its C name and the states in which it may be called (its column
/// mask in the standard's table). The boundary checks the mask before the body runs and
/// names the function in every message (the context Reference-FMUs' `BEGIN_FUNCTION` sets).
pub trait FmiFunction: Copy {
    const VERSION: FmiVersion;
    fn name(self) -> &'static str;
    /// Bit set over [`ModelState::bit`].
    fn allowed_states(self, interface: InterfaceType) -> u16;
    #[inline(always)]
    fn allowed_in(self, interface: InterfaceType, state: ModelState) -> bool {
        self.allowed_states(interface) & state.bit() != 0
    }
}
