//! Errors of the physics core. Each says what is wrong in the words of the model, and names
//! the FMI parameter or the leg concerned, so that the FMI layer can pass it on verbatim.

use std::fmt;

use super::LEG_COUNT;

/// "1, 3, 4": the 1-based numbers of the legs flagged in `legs`.
pub fn leg_list(legs: &[bool; LEG_COUNT]) -> String {
    let numbers: Vec<String> = (0..LEG_COUNT).filter(|&k| legs[k]).map(|k| (k + 1).to_string()).collect();
    numbers.join(", ")
}

/// A parameter set that does not describe a physical stand or a usable initial pose.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterError {
    /// The FMI variable name of the offending parameter, e.g. `J[3]` or `r0[3]`.
    pub parameter: String,
    /// What is wrong with it.
    pub message: String,
}

impl ParameterError {
    pub fn new(parameter: impl Into<String>, message: impl Into<String>) -> Self {
        ParameterError { parameter: parameter.into(), message: message.into() }
    }
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "parameter {}: {}", self.parameter, self.message)
    }
}

impl std::error::Error for ParameterError {}

/// A configuration the motion cannot continue through. Leg numbers are 1-based, as in the
/// FMI variable names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhysicsFault {
    /// A leg's length fell below the coincidence tolerance: its force direction is undefined.
    LegCollapsed { leg: usize, length: f64 },
    /// A platform joint reached or crossed the base plane `z = 0`.
    JointBelowBase { leg: usize, height: f64 },
    /// The state is no longer finite (the motion diverged).
    NonFiniteState,
    /// The motion passed through a singular leg arrangement (the force/moment matrix's
    /// determinant changed sign) and the simulation was asked to stop there
    /// (`stopAtSingularity`). `legs[k]`: leg k+1 takes part in the force combination that
    /// produces no force and no moment there.
    PassedSingularConfiguration { legs: [bool; LEG_COUNT] },
    /// A hydraulic leg's chamber volume reached zero: the leg went through its end stop by
    /// more than the dead volume allows.
    ChamberEmptied { leg: usize, length: f64 },
}

impl fmt::Display for PhysicsFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            PhysicsFault::LegCollapsed { leg, length } => {
                write!(f, "leg {leg} collapsed to length {length:e} (its force direction is undefined)")
            }
            PhysicsFault::JointBelowBase { leg, height } => {
                write!(f, "platform joint A[{leg}] passed through the base plane (z = {height:e})")
            }
            PhysicsFault::NonFiniteState => {
                write!(f, "the state is no longer finite (the motion diverged)")
            }
            PhysicsFault::ChamberEmptied { leg, length } => write!(
                f,
                "hydraulic leg {leg} at length {length:e} m left a chamber without volume (the piston went through its \
                 end stop by more than the dead volume allows: stiffer stops or larger dead volumes)"
            ),
            PhysicsFault::PassedSingularConfiguration { legs } => write!(
                f,
                "the legs passed through a singular arrangement (the force/moment matrix's determinant changed sign; \
                 legs {} form a force combination without resultant there), and stopAtSingularity is on",
                leg_list(&legs)
            ),
        }
    }
}

impl std::error::Error for PhysicsFault {}
