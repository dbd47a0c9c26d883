//! What the cueing FMU reports at one instant: the pose command (through the workspace
//! limiter) with its exact first and second derivatives, the motion felt at the head, and
//! what the driver perceives of the vehicle's motion and of the simulator's.

use nalgebra::Vector3;

use super::parameters::{CueingParameters, Method};
use crate::physics::cueing::jet::Jet;
use crate::physics::cueing::perception::Perception;
use crate::physics::cueing::washout::{WashoutPose, body_rates, rotation};

/// The outputs at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CueingOutputs {
    pub r: [f64; 3],
    pub v: [f64; 3],
    pub a: [f64; 3],
    pub angles: [f64; 3],
    pub angle_rates: [f64; 3],
    pub angle_accelerations: [f64; 3],
    pub fsim: [f64; 3],
    pub omegasim: [f64; 3],
    pub usage: f64,
    pub scale: f64,
    pub limited: bool,
    pub perceived_f: [f64; 3],
    pub perceived_omega: [f64; 3],
    pub perceived_fsim: [f64; 3],
    pub perceived_omegasim: [f64; 3],
}

/// The command and the motion felt, of a method's pose (the head's displacement from its
/// neutral position and the attitude, each with two derivatives, before the limiter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command {
    pub r: [Jet; 3],
    pub angles: [Jet; 3],
    pub fsim: [f64; 3],
    pub omegasim: [f64; 3],
    pub usage: f64,
    pub scale: f64,
}

impl Command {
    pub fn of(p: &CueingParameters, pose: &WashoutPose) -> Command {
        let head = Vector3::from(p.head);
        // The centre of mass's deviation from neutral: the head's displacement and the
        // rotation about the head, r - neutral = P + head - R head.
        let arm = rotated(&rotation(&pose.angles), &head);
        let dr: [Jet; 3] = std::array::from_fn(|i| pose.head[i] - arm[i] + head[i]);
        let limited = match p.method {
            Method::Classical => p.workspace().limit(&dr, &pose.angles),
            Method::Predictive => p.workspace().net(&dr, &pose.angles),
        };
        let (r, angles) = (limited.r, limited.angles);
        let rot = rotation(&angles);
        let arm = rotated(&rot, &head);
        let head_acceleration = Vector3::from_fn(|i, _| r[i].d2 + arm[i].d2);
        let felt = rot.map(|x| x.v).transpose() * (head_acceleration + Vector3::new(0.0, 0.0, p.washout.gravity));
        let omegasim = body_rates(&angles.map(|a| a.v), &angles.map(|a| a.d1));
        Command { r, angles, fsim: felt.into(), omegasim: omegasim.into(), usage: limited.usage, scale: limited.scale }
    }
}

impl CueingOutputs {
    /// The outputs of a command and the perception's lags.
    pub fn of(c: &Command, vehicle: &Perception, simulator: &Perception) -> CueingOutputs {
        let (perceived_f, perceived_omega) = vehicle.perceived();
        let (perceived_fsim, perceived_omegasim) = simulator.perceived();
        CueingOutputs {
            r: c.r.map(|x| x.v),
            v: c.r.map(|x| x.d1),
            a: c.r.map(|x| x.d2),
            angles: c.angles.map(|x| x.v),
            angle_rates: c.angles.map(|x| x.d1),
            angle_accelerations: c.angles.map(|x| x.d2),
            fsim: c.fsim,
            omegasim: c.omegasim,
            usage: c.usage,
            scale: c.scale,
            limited: c.scale < 1.0,
            perceived_f,
            perceived_omega,
            perceived_fsim,
            perceived_omegasim,
        }
    }
}

fn rotated(rot: &nalgebra::Matrix3<Jet>, v: &Vector3<f64>) -> [Jet; 3] {
    std::array::from_fn(|i| rot[(i, 0)] * v.x + rot[(i, 1)] * v.y + rot[(i, 2)] * v.z)
}
