//! The cueing model's states by name: the washout's (`washout.*`), the perception's lags
//! (`perception.*`) and the predictive method's between steps.

use crate::control::predictive_cueing::motion::{CHANNELS, CommandedMotion};
use crate::control::predictive_cueing::GRID_STEPS;
use crate::physics::cueing::perception::Perception;
use crate::physics::cueing::washout::{STATE_DIM, VehicleMotion, layout};

/// The washout's states by name (the FMU's state variables `washout.*`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CueingStates {
    pub q: [f64; 3],
    pub r: [f64; 3],
    pub v: [f64; 3],
    pub fl: [f64; 2],
    pub fl_rate: [f64; 2],
    pub tilt: [f64; 2],
    pub z: [f64; 3],
    pub angles: [f64; 3],
}

impl CueingStates {
    pub fn to_vector(&self) -> [f64; STATE_DIM] {
        let mut x = [0.0; STATE_DIM];
        x[layout::TRANSLATION_Q..][..3].copy_from_slice(&self.q);
        x[layout::HEAD_R..][..3].copy_from_slice(&self.r);
        x[layout::HEAD_V..][..3].copy_from_slice(&self.v);
        x[layout::TILT_F..][..2].copy_from_slice(&self.fl);
        x[layout::TILT_FDOT..][..2].copy_from_slice(&self.fl_rate);
        x[layout::TILT_ANGLES..][..2].copy_from_slice(&self.tilt);
        x[layout::ROTATION_Q..][..3].copy_from_slice(&self.z);
        x[layout::ROTATION_ANGLES..][..3].copy_from_slice(&self.angles);
        x
    }

    pub fn from_vector(x: &[f64; STATE_DIM]) -> Self {
        let take = |at: usize| -> [f64; 3] { [x[at], x[at + 1], x[at + 2]] };
        let pair = |at: usize| -> [f64; 2] { [x[at], x[at + 1]] };
        CueingStates {
            q: take(layout::TRANSLATION_Q),
            r: take(layout::HEAD_R),
            v: take(layout::HEAD_V),
            fl: pair(layout::TILT_F),
            fl_rate: pair(layout::TILT_FDOT),
            tilt: pair(layout::TILT_ANGLES),
            z: take(layout::ROTATION_Q),
            angles: take(layout::ROTATION_ANGLES),
        }
    }
}

/// The perception's 30 lags (the FMU's states `perception.*`): for the vehicle's motion and for
/// the simulator's, the otoliths' two lags per axis and the canals' three.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceptionStates {
    pub vehicle_otolith: [f64; 6],
    pub vehicle_canal: [f64; 9],
    pub simulator_otolith: [f64; 6],
    pub simulator_canal: [f64; 9],
}

/// Both perceptions at rest under gravity `g`.
pub(super) fn perception_at_rest(g: f64) -> PerceptionStates {
    let rest = Perception::at_rest([0.0, 0.0, g]);
    let mut p = PerceptionStates {
        vehicle_otolith: [0.0; 6],
        vehicle_canal: [0.0; 9],
        simulator_otolith: [0.0; 6],
        simulator_canal: [0.0; 9],
    };
    p.set(&rest, &rest);
    p
}

impl PerceptionStates {
    pub fn vehicle(&self) -> Perception {
        Self::perception(&self.vehicle_otolith, &self.vehicle_canal)
    }

    pub fn simulator(&self) -> Perception {
        Self::perception(&self.simulator_otolith, &self.simulator_canal)
    }

    fn perception(otolith: &[f64; 6], canal: &[f64; 9]) -> Perception {
        let mut x = [0.0; 15];
        x[..6].copy_from_slice(otolith);
        x[6..].copy_from_slice(canal);
        Perception::from_array(&x)
    }

    pub fn set(&mut self, vehicle: &Perception, simulator: &Perception) {
        let (v, s) = (vehicle.to_array(), simulator.to_array());
        self.vehicle_otolith.copy_from_slice(&v[..6]);
        self.vehicle_canal.copy_from_slice(&v[6..]);
        self.simulator_otolith.copy_from_slice(&s[..6]);
        self.simulator_canal.copy_from_slice(&s[6..]);
    }

    /// The 30 lags in the state vector's order.
    pub fn to_array(&self) -> [f64; 30] {
        let mut x = [0.0; 30];
        x[..6].copy_from_slice(&self.vehicle_otolith);
        x[6..15].copy_from_slice(&self.vehicle_canal);
        x[15..21].copy_from_slice(&self.simulator_otolith);
        x[21..].copy_from_slice(&self.simulator_canal);
        x
    }

    pub fn from_array(x: &[f64; 30]) -> Self {
        fn part<const N: usize>(x: &[f64; 30], at: usize) -> [f64; N] {
            std::array::from_fn(|i| x[at + i])
        }
        PerceptionStates {
            vehicle_otolith: part(x, 0),
            vehicle_canal: part(x, 6),
            simulator_otolith: part(x, 15),
            simulator_canal: part(x, 21),
        }
    }
}

/// The predictive method's state between steps (saved with the FMU state).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PredictiveState {
    /// The commanded head motion and attitude.
    pub motion: CommandedMotion,
    /// The last plan's jerks per grid step (what the next solve linearises about).
    pub plan: [[f64; CHANNELS]; GRID_STEPS],
    /// The jerks held until the next solve.
    pub jerk: [f64; CHANNELS],
    /// Solves done since the start: the next is at `start + solves mpc.period`.
    pub solves: u64,
    /// `mpc.iterations`: the last solve's.
    pub iterations: i32,
    /// `mpc.fallbacks`: failed solves since the start.
    pub fallbacks: i32,
    /// `mpc.acceptable`: solves since the start whose plan met only the acceptable level.
    pub acceptable: i32,
    /// Whether the current period is the classical washout's (the last solve failed).
    pub falling_back: bool,
    /// The vehicle's motion at the last solve (`None` before the first): the guess's rate of
    /// change is the inputs' over the period since (`mpc.trend`).
    pub last_vehicle: Option<VehicleMotion>,
}
