//! What the controller reports: the commands, the programme and its angles, each a cache
//! block of its own (NaN where the programme cannot be produced).

use nalgebra::Vector3;

use crate::physics::body::kinematics::PoseTrajectoryPoint;
use crate::physics::direct_problem::DirectProblemSolution;
use crate::physics::stand::LEG_COUNT;

/// Everything the controller reports at one instant (but the programme's angles).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerOutputs {
    pub commands: Commands,
    pub programme: ProgrammeOutputs,
}

/// The commands, which follow the measured legs: a cache block of their own, so that the
/// programme's outputs a closed loop reads after a step do not compute them with the legs it
/// is about to set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Commands {
    /// Leg forces, N.
    pub f: [f64; LEG_COUNT],
    /// The drives' voltage command, V (0 without drives).
    pub u: [f64; LEG_COUNT],
    /// The servo valves' command (0 without hydraulic legs).
    pub valve: [f64; LEG_COUNT],
}

/// The programme at the current time: forces (N), leg lengths (m) and rates (m/s) of the
/// direct problem, centre of mass (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgrammeOutputs {
    pub fp: [f64; LEG_COUNT],
    pub lp: [f64; LEG_COUNT],
    pub ldotp: [f64; LEG_COUNT],
    pub rp: Vector3<f64>,
}

/// The programme's roll, pitch and yaw: a cache block of their own, computed only when read
/// (three inverse trigonometric functions a closed loop does not need).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgrammeAngles {
    pub anglesp: Vector3<f64>,
}

// Where the programme cannot be produced the outputs are not numbers (the FMI layer refuses to
// return them, naming the variable).
const NAN3: Vector3<f64> = Vector3::new(f64::NAN, f64::NAN, f64::NAN);

impl Commands {
    pub(super) const UNDEFINED: Commands =
        Commands { f: [f64::NAN; LEG_COUNT], u: [f64::NAN; LEG_COUNT], valve: [f64::NAN; LEG_COUNT] };
}

impl ProgrammeOutputs {
    pub(super) const UNDEFINED: ProgrammeOutputs = ProgrammeOutputs {
        fp: [f64::NAN; LEG_COUNT],
        lp: [f64::NAN; LEG_COUNT],
        ldotp: [f64::NAN; LEG_COUNT],
        rp: NAN3,
    };

    pub(super) fn of(point: &PoseTrajectoryPoint, solution: &DirectProblemSolution) -> Self {
        ProgrammeOutputs { fp: solution.forces, lp: solution.lengths, ldotp: solution.rates, rp: point.r }
    }
}

impl ProgrammeAngles {
    pub(super) const UNDEFINED: ProgrammeAngles = ProgrammeAngles { anglesp: NAN3 };
}
