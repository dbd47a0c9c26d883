//! What the platform's unknowns depend on (`<ModelStructure>`, FMI 3's variable dependencies):
//! each concern's knowns listed once here, by the declarations' `group::` indices, and the
//! lists of the unknowns composed from them. The order of each composed list is part of the
//! model's token (the digest hashes the knowns in order): a concern's list goes where its
//! knowns stood.

use super::group;
use crate::models::machine;
use crate::models::variables::Dependency::{self, All, Each};

/// The body's pose states.
pub const POSE_STATES: &[Dependency] = &[All(group::R), All(group::ROT)];
/// The body's states: pose and rates.
pub const BODY_STATES: &[Dependency] = &[All(group::R), All(group::V), All(group::ROT), All(group::DER_R)];
/// Where the legs are at the start: the joints and the initial pose.
const STAND_GEOMETRY: &[Dependency] = &[All(group::A), All(group::B)];
const INITIAL_MOTION: &[Dependency] = &[All(group::R0), All(group::ANGLES0), All(group::V0), All(group::W0)];
/// The end stops, their stiffness apart (the stops' potential) from their damping.
const STOPS_STROKE: &[Dependency] = &[All(group::STOPS), All(group::LMIN), All(group::LMAX), All(group::STOP_STIFFNESS)];
const STOPS: &[Dependency] = &[Each(STOPS_STROKE), All(group::STOP_DAMPING)];
/// The legs as bodies.
const LEG_BODIES: &[Dependency] = machine::leg_body_knowns!();
/// The joint limits: the limits and their reference pose, then the damping.
const JOINT_LIMITS: &[Dependency] =
    &[All(group::JOINTS), All(group::JOINTS_BASE_MAX), All(group::JOINTS_PLATFORM_MAX), All(group::JOINTS_STIFFNESS)];
const JOINTS_REFERENCE: &[Dependency] = &[All(group::JOINTS_R0), All(group::JOINTS_ANGLES0)];
const JOINTS: &[Dependency] =
    &[Each(JOINT_LIMITS), All(group::JOINTS_DAMPING), Each(JOINTS_REFERENCE)];
const FRICTION: &[Dependency] = &[
    All(group::FRICTION_COULOMB),
    All(group::FRICTION_STATIC),
    All(group::FRICTION_STRIBECK),
    All(group::FRICTION_SMOOTHING),
    All(group::FRICTION_VISCOUS),
];

/// The electric drives' law (`drive = 1`).
const DRIVE_LAW: &[Dependency] = machine::drive_law_knowns!();
/// The drives' parameters.
pub const DRIVE_PARAMETERS: &[Dependency] = &[All(group::DRIVE), Each(DRIVE_LAW)];
/// The knowns of the drives' currents' rates and losses: the leg rates, the currents, the
/// voltages.
pub const DRIVE_KNOWNS: &[Dependency] = &[Each(BODY_STATES), All(group::I), All(group::U)];

/// The hydraulic legs' law (`drive = 2`), their initial pressures and the supply pressure.
const HYDRAULIC_LAW: &[Dependency] = &[
    All(group::BORE),
    All(group::ROD),
    All(group::DEAD_VOLUME_A),
    All(group::DEAD_VOLUME_B),
    All(group::BULK_MODULUS),
    All(group::TANK_PRESSURE),
    All(group::RATED_FLOW),
    All(group::RATED_DROP),
    All(group::VALVE_PCR),
    All(group::VALVE_LEAKAGE),
    All(group::INTERNAL_LEAKAGE),
    All(group::AIR_FRACTION),
    All(group::AIR_POLYTROPIC),
    All(group::PA0),
    All(group::PB0),
    All(group::PS),
    All(group::SUPPLY_MODE),
    Each(POWER_UNIT_LAW),
];
/// The power unit's law (§10b).
const POWER_UNIT_LAW: &[Dependency] = &[
    All(group::PUMP_MAX_FLOW),
    All(group::PUMP_SET_PRESSURE),
    All(group::PUMP_BAND),
    All(group::RELIEF_PRESSURE),
    All(group::RELIEF_GAIN),
    All(group::ACCUMULATOR_VOLUME),
    All(group::ACCUMULATOR_PRECHARGE),
    All(group::ACCUMULATOR_POLYTROPIC),
    All(group::SUPPLY_VOLUME),
];
/// What the supply line's pressure starts at: the mode and `pS`'s start value.
pub const POWER_UNIT_START: &[Dependency] = &[All(group::DRIVE), All(group::SUPPLY_MODE), All(group::PS)];
/// The power unit's parameters (the hydraulic legs' with it: the valves drain the line).
pub const POWER_UNIT_PARAMETERS: &[Dependency] = HYDRAULIC_PARAMETERS;
/// The knowns of the power unit's rates: the legs' and the pump's speed.
pub const POWER_UNIT_KNOWNS: &[Dependency] = &[Each(HYDRAULIC_KNOWNS), All(group::PUMP_SPEED)];
/// The power unit's outputs, each on what it reads: the supply pressure the input `pS` or the
/// line's state; the pump's flow the line and the pump's speed; the relief and the accumulator
/// the line alone. (A master orders its components by these: `supply.pressure` does not feed
/// `pump.speed` through.)
pub const SUPPLY_PRESSURE_KNOWNS: &[Dependency] = &[All(group::PS), All(group::LINE_PRESSURE)];
pub const PUMP_FLOW_KNOWNS: &[Dependency] = &[All(group::LINE_PRESSURE), All(group::PUMP_SPEED)];
pub const LINE_KNOWNS: &[Dependency] = &[All(group::LINE_PRESSURE)];
/// The hydraulic legs' parameters (with the strokes their chambers span).
pub const HYDRAULIC_PARAMETERS: &[Dependency] =
    &[All(group::DRIVE), All(group::LMIN), All(group::LMAX), Each(HYDRAULIC_LAW)];
/// The hydraulic legs' states and input besides the body's.
const HYDRAULIC_STATES: &[Dependency] =
    &[All(group::PA), All(group::PB), All(group::SPOOL), All(group::PS), All(group::LINE_PRESSURE)];
/// The knowns of the hydraulic legs' rates and powers: the body state (the legs' lengths and
/// rates), the pressures, the spools and the supply pressure.
pub const HYDRAULIC_KNOWNS: &[Dependency] = &[Each(BODY_STATES), Each(HYDRAULIC_STATES)];
/// The spools' law.
pub const SPOOL_PARAMETERS: &[Dependency] =
    &[All(group::DRIVE), All(group::VALVE_OMEGA), All(group::VALVE_DAMPING), All(group::VALVE)];

/// The knowns of the accelerations and powers: the end stops' forces depend on the leg rates,
/// so with stops every acceleration depends on the whole body state, and on the leg forces
/// (or with drives on the currents, with hydraulic legs on the pressures).
pub const MOTION_KNOWNS: &[Dependency] =
    &[Each(BODY_STATES), All(group::F), All(group::I), All(group::PA), All(group::PB)];
/// The knowns of the dissipated power: those of the drives' and of the hydraulic legs'.
pub const DISSIPATION_KNOWNS: &[Dependency] = &[Each(BODY_STATES), All(group::I), All(group::U), Each(HYDRAULIC_STATES)];
/// The knowns of the energy: the body state and the currents (magnetic energy).
pub const ENERGY_KNOWNS: &[Dependency] = &[Each(BODY_STATES), All(group::I)];

/// What the end stops' forces depend on in Initialization Mode.
pub const STOP_PARAMETERS: &[Dependency] = &[Each(STAND_GEOMETRY), Each(INITIAL_MOTION), Each(STOPS)];
/// What the motion depends on in Initialization Mode: every parameter and input of the stand,
/// the legs and the actuators.
pub const ALL_PARAMETERS: &[Dependency] = &[
    All(group::F),
    All(group::M),
    All(group::J),
    All(group::G),
    All(group::B),
    All(group::A),
    Each(INITIAL_MOTION),
    All(group::STABILISATION),
    All(group::BAUMGARTE_RATE),
    Each(STOPS),
    Each(LEG_BODIES),
    Each(JOINTS),
    Each(FRICTION),
    Each(DRIVE_PARAMETERS),
    All(group::I0),
    All(group::U),
    Each(HYDRAULIC_LAW),
    All(group::VALVE),
];
/// What the energy depends on in Initialization Mode: the stand, the initial state, the
/// potentials' parameters, the legs' masses, the drives' rotors and inductance.
pub const ENERGY_PARAMETERS: &[Dependency] = &[
    All(group::M),
    All(group::J),
    All(group::G),
    Each(STAND_GEOMETRY),
    Each(INITIAL_MOTION),
    Each(STOPS_STROKE),
    Each(LEG_BODIES),
    Each(JOINT_LIMITS),
    Each(JOINTS_REFERENCE),
    All(group::DRIVE),
    All(group::MOTOR_L),
    All(group::MOTOR_J),
    All(group::GEAR_RATIO),
    All(group::SCREW_LEAD),
    All(group::I0),
];
/// What the dissipated power depends on in Initialization Mode.
pub const DISSIPATION_PARAMETERS: &[Dependency] = &[
    Each(STAND_GEOMETRY),
    Each(INITIAL_MOTION),
    Each(STOPS),
    Each(JOINTS),
    Each(FRICTION),
    All(group::DRIVE),
    All(group::MOTOR_R),
    All(group::MOTOR_KE),
    All(group::MOTOR_KT),
    All(group::MOTOR_D),
    All(group::GEAR_RATIO),
    All(group::SCREW_LEAD),
    All(group::I0),
    All(group::U),
    Each(HYDRAULIC_LAW),
    All(group::VALVE),
];
/// What the joint angles depend on in Initialization Mode.
pub const JOINT_ANGLE_PARAMETERS: &[Dependency] =
    &[Each(STAND_GEOMETRY), All(group::R0), All(group::ANGLES0), All(group::JOINTS), Each(JOINTS_REFERENCE)];
/// What the legs' lengths depend on in Initialization Mode.
pub const LEG_PARAMETERS: &[Dependency] = &[Each(STAND_GEOMETRY), All(group::R0), All(group::ANGLES0)];
/// What the legs' rates depend on in Initialization Mode.
pub const LEG_RATE_PARAMETERS: &[Dependency] = &[Each(STAND_GEOMETRY), Each(INITIAL_MOTION)];
