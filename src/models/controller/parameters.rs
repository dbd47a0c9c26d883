//! The controller's parameters (docs/model.md §5, §9, §10; docs/control.md): the programmes,
//! the feedback and its limits, the legs and drives its direct problem carries, the hydraulic
//! loop, and their defaults.

use nalgebra::Vector3;

use crate::control::{Disturbance, LegFeedback};
use crate::models::declare::IntegerStorage;
use crate::models::machine::Drive;
use crate::physics::actuators::drives::ElectricDrives;
use crate::physics::actuators::hydraulics::{DEFAULT_SUPPLY_PRESSURE, HydraulicLegs};
use crate::physics::legs::bodies::LegBodies;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::stand::Stand;

/// Default feedback gain, N/m: with the default stand and a 1 ms communication step it keeps
/// every leg within a millimetre of its programme length on the default heave programme
/// (about 10 M g / R_b; tested).
pub const DEFAULT_GAIN: f64 = 2.0e5;
/// Default rate gain, N s/m: a damping ratio near 0.8 for the heave mode with
/// [`DEFAULT_GAIN`].
pub const DEFAULT_DAMPING: f64 = 2.0e4;
/// Default actuator saturation, N: each drive can push or pull the whole default platform's
/// weight (29.4 kN); the default heave programme needs at most 7.7 kN per leg.
pub const DEFAULT_FORCE_LIMIT: f64 = 3.0e4;
/// Default voltage limit `Umax`, V: the drives' 300 V supply (docs/model.md §9).
pub const DEFAULT_VOLTAGE_LIMIT: f64 = 300.0;
/// Default lift duration of the start-up programme, s.
pub const DEFAULT_STARTUP_DURATION: f64 = 3.0;
/// Default descent speed of the safe landing, m/s: 0.1, a sixth of the heave programme's
/// fastest leg, so that the valves draw under 40 L/min while the accumulator feeds them.
pub const DEFAULT_LANDING_SPEED: f64 = 0.1;
/// How far above its rest on the lower stops the safe landing ends, m: 5 mm, so that the
/// legs stop under control just before the stops take the weight.
pub const LANDING_CLEARANCE: f64 = 0.005;

/// Which programme motion the controller follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgrammeKind {
    Heave = 1,
    Sinusoid = 2,
    External = 3,
    StartUp = 4,
    Landing = 5,
}

impl ProgrammeKind {
    fn from_code(code: i32) -> Option<Self> {
        match code {
            1 => Some(ProgrammeKind::Heave),
            2 => Some(ProgrammeKind::Sinusoid),
            3 => Some(ProgrammeKind::External),
            4 => Some(ProgrammeKind::StartUp),
            5 => Some(ProgrammeKind::Landing),
            _ => None,
        }
    }
}

/// Everything set through parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerParameters {
    pub stand: Stand,
    pub feedback: LegFeedback,
    pub programme: ProgrammeKind,
    /// Programme 1: the heave about `heave_centre`.
    pub heave_centre: Vector3<f64>,
    pub heave: Heave,
    /// Programme 2: a soft-start sinusoid in each degree of freedom (x, y, z, roll, pitch,
    /// yaw).
    pub sine: Sinusoids,
    pub disturbance: Disturbance,
    /// Programme 4: parked centre of mass (m) and lift duration (s).
    pub startup_position: Vector3<f64>,
    pub startup_duration: f64,
    /// Actuator saturation `Fmin`, N.
    pub f_min: f64,
    /// Actuator saturation `Fmax`, N.
    pub f_max: f64,
    /// `leg.*`: the legs' masses, whose weight and inertia the programme forces carry.
    pub legs: LegBodies,
    /// `drive`: also output the drives' voltages `U` (and carry their rotors' inertia), or the
    /// hydraulic legs' valve commands.
    pub drive: Drive,
    /// `motor.*`, `gear.ratio`, `screw.lead`: the drives' parameters (as the platform's).
    pub drives: ElectricDrives,
    /// `Umax`, V: the voltage command is limited to `[-Umax, Umax]`.
    pub u_max: f64,
    /// The hydraulic loop (`drive = 2`).
    pub hydraulic: HydraulicLoop,
    /// The safe landing (programme 5, or on its triggers).
    pub landing: Landing,
}

/// The safe landing (`landing.*`): a vertical descent at `speed` to the height `floor`
/// ([`crate::physics::programme::SafeLanding`]), programme 5 from `heave.centre` at the start,
/// or from wherever any programme is when the input `landing.command` is 1 or the measured
/// `supply.pressure` falls below `pressure` (0: no threshold).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    /// `landing.speed`, m/s.
    pub speed: f64,
    /// `landing.floor`, m.
    pub floor: f64,
    /// `landing.pressure`, Pa.
    pub pressure: f64,
}

impl ControllerParameters {
    /// The legs the direct problem carries: with drives, their rotors move with the legs'
    /// lengths.
    pub fn leg_bodies(&self) -> LegBodies {
        let axial_mass = if self.drive == Drive::Electric { self.drives.reflected_mass() } else { 0.0 };
        LegBodies { axial_mass, ..self.legs }
    }
}

/// Default gain of the inner force loop, 1/N: a valve opening of 1 per 67 kN of force error.
/// The leg's force responds to the valve at `dF/ds = beta K sqrt(p_S/2) (A_A/V_A + A_B/V_B)`,
/// about 1.2e7 N/s per unit opening at mid-stroke with the default legs, so the loop's
/// crossover is near 180 rad/s: above the oil columns' modes (60-135 rad/s), whose
/// near-zero damping the loop supplies, and below the spool's 628 rad/s and the 1 ms sample.
pub const DEFAULT_FORCE_GAIN: f64 = 1.5e-5;

/// Default gain of the leg-length error in the flow feed-forward, 1/s: the valve is fed the
/// rate `ldot^p + Kl (l^p - l)`, an outer position loop through the flow with a 20 ms time
/// constant. The force loop alone leaves the flow feed-forward's error (a few per cent of the
/// opening, from the measured drops) as a force error of a few hundred newtons, which the
/// force law's `G` turns into millimetres; this term takes it out. Chosen on the default stand
/// and heave programme (docs/model.md §10, measured by tests/python/test_hydraulics.py): the
/// leg error falls as the gain grows to 100 1/s, and at 200 1/s the oil columns ring.
pub const DEFAULT_POSITION_GAIN: f64 = 50.0;

/// The controller's hydraulic loop (`drive = 2`): the force law's command as the reference of
/// an inner loop on the measured actuator force, with a flow feed-forward from the
/// programme's leg rates (docs/control.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HydraulicLoop {
    /// `hydraulic.bore`, `hydraulic.rod`, m: as the platform's.
    pub bore: f64,
    pub rod: f64,
    /// `valve.ratedFlow` (m³/s), `valve.ratedPressureDrop` (Pa): as the platform's.
    pub rated_flow: f64,
    pub rated_pressure_drop: f64,
    /// `pS`, Pa: the supply pressure the feed-forward assumes.
    pub supply: f64,
    /// `hydraulic.forceGain`, 1/N.
    pub force_gain: f64,
    /// `hydraulic.flowFeedforward`, 1: the share of the programme's flow fed forward.
    pub flow_feedforward: f64,
    /// `hydraulic.positionGain`, 1/s: the leg-length error's share of the rate fed forward.
    pub position_gain: f64,
}

impl Default for HydraulicLoop {
    fn default() -> Self {
        let legs = HydraulicLegs::default();
        HydraulicLoop {
            bore: legs.bore,
            rod: legs.rod,
            rated_flow: legs.rated_flow,
            rated_pressure_drop: legs.rated_pressure_drop,
            supply: DEFAULT_SUPPLY_PRESSURE,
            force_gain: DEFAULT_FORCE_GAIN,
            flow_feedforward: 1.0,
            position_gain: DEFAULT_POSITION_GAIN,
        }
    }
}

impl HydraulicLoop {
    /// The valve command for the force command `force` (N), the measured pressures `pa`, `pb`
    /// (Pa), the measured supply pressure `supply` (Pa) and the programme's leg rate `rate`
    /// (m/s): `c = kF (F - (p_A A_A - p_B A_B)) + ff`, `ff = A ldot^p / (K sqrt(dp))` with the
    /// area and the supply land's drop of the side the leg fills (`A_A`, `p_S - p_A` extending;
    /// `A_B`, `p_S - p_B` retracting; the drop at least the rated `pS / 20`), saturated to [-1, 1].
    pub fn valve(&self, force: f64, pa: f64, pb: f64, supply: f64, rate: f64, length_error: f64) -> f64 {
        let rate = rate + self.position_gain * length_error;
        let legs = HydraulicLegs {
            bore: self.bore,
            rod: self.rod,
            rated_flow: self.rated_flow,
            rated_pressure_drop: self.rated_pressure_drop,
            ..HydraulicLegs::default()
        };
        let (area_a, area_b) = legs.areas();
        let k = legs.flow_coefficient();
        let (area, drop) = if rate >= 0.0 { (area_a, supply - pa) } else { (area_b, supply - pb) };
        let feedforward = self.flow_feedforward * area * rate / (k * drop.max(0.05 * self.supply).sqrt());
        let measured = pa * area_a - pb * area_b;
        (self.force_gain * (force - measured) + feedforward).clamp(-1.0, 1.0)
    }

    pub(super) fn validate(&self) -> Result<(), String> {
        for (name, value) in [
            ("hydraulic.bore", self.bore),
            ("valve.ratedFlow", self.rated_flow),
            ("valve.ratedPressureDrop", self.rated_pressure_drop),
            ("pS", self.supply),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(format!("parameter {name}: must be a positive number, got {value:e}"));
            }
        }
        if !(self.rod >= 0.0 && self.rod < self.bore) {
            return Err(format!("parameter hydraulic.rod: must be in [0, hydraulic.bore), got {:e} m", self.rod));
        }
        for (name, value) in [
            ("hydraulic.forceGain", self.force_gain),
            ("hydraulic.flowFeedforward", self.flow_feedforward),
            ("hydraulic.positionGain", self.position_gain),
        ] {
            if !(value >= 0.0 && value.is_finite()) {
                return Err(format!("parameter {name}: must be >= 0, got {value:e}"));
            }
        }
        Ok(())
    }
}

/// Programme 1: `z = z0 + a sin(Omega t)(1 - exp(-t/T))^2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heave {
    /// `a`, m.
    pub amplitude: f64,
    /// `Omega`, rad/s.
    pub frequency: f64,
    /// `T`, s.
    pub time_constant: f64,
}

/// Programme 2: offsets, amplitudes (positions, then angles), frequencies and phases of the
/// six degrees of freedom, and one soft-start time constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sinusoids {
    pub offset: [f64; 3],
    pub angle_offset: [f64; 3],
    pub amplitude: [f64; 3],
    pub angle_amplitude: [f64; 3],
    pub frequency: [f64; 6],
    pub phase: [f64; 6],
    pub time_constant: f64,
}

impl Default for ControllerParameters {
    /// The paper's heave programme scaled to the default stand: `a = 0.2 R_b`,
    /// `Omega = sqrt(g / R_b)`, `T = 2 / Omega`.
    fn default() -> Self {
        let stand = Stand::truck_cabin();
        let centre = Stand::truck_cabin_neutral_position();
        let r_b = stand.base_radius();
        let omega = (stand.gravity / r_b).sqrt();
        ControllerParameters {
            feedback: LegFeedback { gain: DEFAULT_GAIN, damping: DEFAULT_DAMPING, feedforward: true },
            programme: ProgrammeKind::Heave,
            heave_centre: centre,
            heave: Heave { amplitude: 0.2 * r_b, frequency: omega, time_constant: 2.0 / omega },
            sine: Sinusoids {
                offset: [centre.x, centre.y, centre.z],
                angle_offset: [0.0; 3],
                amplitude: [0.0; 3],
                angle_amplitude: [0.0; 3],
                frequency: [omega; 6],
                phase: [0.0; 6],
                time_constant: 2.0 / omega,
            },
            disturbance: Disturbance { amplitude: 0.0, frequency: 2.0 * omega, time_constant: 2.0 / omega },
            startup_position: Vector3::new(
                centre.x,
                centre.y,
                EndStops::default().level_rest_height(&stand).unwrap_or(centre.z),
            ),
            startup_duration: DEFAULT_STARTUP_DURATION,
            f_min: -DEFAULT_FORCE_LIMIT,
            f_max: DEFAULT_FORCE_LIMIT,
            legs: LegBodies::default(),
            drive: Drive::Forces,
            drives: ElectricDrives::default(),
            u_max: DEFAULT_VOLTAGE_LIMIT,
            hydraulic: HydraulicLoop::default(),
            landing: Landing {
                speed: DEFAULT_LANDING_SPEED,
                floor: EndStops::default().level_rest_height(&stand).unwrap_or(centre.z) + LANDING_CLEARANCE,
                pressure: 0.0,
            },
            stand,
        }
    }
}

/// The pose of programme 3 (external), from the inputs `pose.*`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExternalPose {
    pub r: [f64; 3],
    pub v: [f64; 3],
    pub a: [f64; 3],
    pub angles: [f64; 3],
    pub angle_rates: [f64; 3],
    pub angle_accelerations: [f64; 3],
}

impl IntegerStorage for ProgrammeKind {
    fn code(&self) -> i32 {
        *self as i32
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        *self = ProgrammeKind::from_code(code).ok_or_else(|| {
            format!("{code} is not a programme (1 = heave, 2 = sinusoid, 3 = external, 4 = start-up, 5 = safe landing)")
        })?;
        Ok(())
    }
}

