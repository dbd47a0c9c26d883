//! The `StewartController` variables. Stand parameters carry the same names as the
//! platform's, so one parameter set describes both.

use crate::models::declare::declare_variables;
use crate::models::machine;
use crate::models::variables::Dependency::{self, All, Each, SameIndex};
use crate::models::variables::VariableGroup as V;

/// The external programme's pose inputs (`pose.*`).
const POSE_INPUTS: &[Dependency] = &[
    All(group::POSE_R),
    All(group::POSE_V),
    All(group::POSE_A),
    All(group::POSE_ANGLES),
    All(group::POSE_ANGLE_RATES),
    All(group::POSE_ANGLE_ACCELERATIONS),
];
/// The measured legs, leg by leg.
const MEASURED_LEGS: &[Dependency] = &[SameIndex(group::L), SameIndex(group::LDOT)];
/// The force and voltage commands: the measured legs and the programme.
const FORCE_DEPENDENCIES: &[Dependency] = &[Each(MEASURED_LEGS), Each(POSE_INPUTS)];
/// The valve commands: the measured legs and pressures and the programme.
const HYDRAULIC_DEPENDENCIES: &[Dependency] = &[
    Each(MEASURED_LEGS),
    SameIndex(group::PA),
    SameIndex(group::PB),
    All(group::SUPPLY_PRESSURE),
    Each(POSE_INPUTS),
];
const LENGTH_DEPENDENCIES: &[Dependency] =
    &[All(group::POSE_R), All(group::POSE_V), All(group::POSE_ANGLES), All(group::POSE_ANGLE_RATES)];
/// The stand, as the platform's parameters of the same names.
const STAND: &[Dependency] = &[All(group::M), All(group::J), All(group::G_GRAVITY), All(group::B), All(group::A)];
/// The programmes' parameters.
const PROGRAMMES: &[Dependency] = &[
    All(group::PROGRAMME),
    All(group::HEAVE_CENTRE),
    All(group::HEAVE_AMPLITUDE),
    All(group::HEAVE_FREQUENCY),
    All(group::HEAVE_TIME_CONSTANT),
    All(group::SINE_OFFSET),
    All(group::SINE_ANGLE_OFFSET),
    All(group::SINE_AMPLITUDE),
    All(group::SINE_ANGLE_AMPLITUDE),
    All(group::SINE_FREQUENCY),
    All(group::SINE_PHASE),
    All(group::SINE_TIME_CONSTANT),
    All(group::DISTURBANCE_AMPLITUDE),
    All(group::DISTURBANCE_FREQUENCY),
    All(group::DISTURBANCE_TIME_CONSTANT),
    All(group::STARTUP_POSITION),
    All(group::STARTUP_DURATION),
    All(group::LANDING_SPEED),
    All(group::LANDING_FLOOR),
];
/// The legs as bodies, whose weight and inertia the programme forces carry.
const LEG_BODIES: &[Dependency] = machine::leg_body_knowns!();
/// The electric drives, whose static model gives the voltages.
const DRIVES: &[Dependency] = &[All(group::DRIVE), Each(machine::drive_law_knowns!()), All(group::UMAX)];
/// In Initialization Mode the outputs depend on (almost) every known; listing them all is
/// the honest answer.
const ALL_KNOWNS: &[Dependency] = &[
    All(group::L),
    All(group::LDOT),
    Each(POSE_INPUTS),
    Each(STAND),
    All(group::GAIN),
    All(group::DAMPING),
    All(group::FEEDFORWARD),
    Each(PROGRAMMES),
    All(group::FMIN),
    All(group::FMAX),
    Each(LEG_BODIES),
    Each(DRIVES),
];

declare_variables! {
    model: super::ControllerModel,
    cache_blocks: [commands, programme_outputs, programme_angles],
    variables: {
        TIME => V::time(0); computed,
        L => V::input("l", &[6], 1, Some("m"), "Measured leg length l_k (from the platform's output l)"); real(l),
        LDOT => V::input("ldot", &[6], 7, Some("m/s"), "Measured leg length rate (from the platform's output ldot)"); real(ldot),
        POSE_R => V::input("pose.r", &[3], 13, Some("m"), "Programme 3 (external): centre of mass"); real(pose.r),
        POSE_V => V::input("pose.v", &[3], 16, Some("m/s"), "Programme 3 (external): velocity of the centre of mass"); real(pose.v),
        POSE_A => V::input("pose.a", &[3], 19, Some("m/s2"), "Programme 3 (external): acceleration of the centre of mass"); real(pose.a),
        POSE_ANGLES => V::input("pose.angles", &[3], 22, Some("rad"), "Programme 3 (external): roll, pitch, yaw (1-2-3)").display("deg"); real(pose.angles),
        POSE_ANGLE_RATES => V::input("pose.angleRates", &[3], 25, Some("rad/s"), "Programme 3 (external): rates of roll, pitch, yaw"); real(pose.angle_rates),
        POSE_ANGLE_ACCELERATIONS => V::input(
            "pose.angleAccelerations",
            &[3],
            28,
            Some("rad/s2"),
            "Programme 3 (external): second derivatives of roll, pitch, yaw",
        ); real(pose.angle_accelerations),
        M => machine::mass(40); real(parameters.stand.mass),
        J => machine::inertia(41); real(parameters.stand.inertia),
        G_GRAVITY => machine::gravity(44); real(parameters.stand.gravity),
        B => machine::base_joints(50); real(parameters.stand.base_joints),
        A => machine::platform_joints(70); real(parameters.stand.platform_joints),
        GAIN => V::parameter("G", &[], 90, Some("N/m"), "Feedback gain on the leg-length error l^p - l (tunable)").tunable(); real(parameters.feedback.gain),
        DAMPING => V::parameter("D", &[], 91, Some("N.s/m"), "Feedback gain on the leg-rate error ldot^p - ldot (tunable)").tunable(); real(parameters.feedback.damping),
        FEEDFORWARD => V::parameter(
            "feedforward",
            &[],
            92,
            None,
            "1 = apply the programme forces F^p of the direct problem plus feedback; 0 = feedback only (F^p = 0)",
        )
        .integer(0, 1); integer(parameters.feedback.feedforward),
        PROGRAMME => V::parameter(
            "programme",
            &[],
            93,
            None,
            "Programme motion: 1 = the paper's heave z = z0 + a sin(Omega t)(1 - exp(-t/T))^2 above heave.centre; \
             2 = a sinusoid with soft start in each of the six degrees of freedom (sine.*); 3 = the pose and its \
             derivatives from the inputs pose.*; 4 = start-up: a rest-to-rest lift from startup.position to \
             heave.centre in startup.duration, then programme 1; 5 = safe landing from heave.centre at the start: \
             a vertical descent at landing.speed to landing.floor (the same landing any programme turns into when \
             landing.command is 1 or supply.pressure falls below landing.pressure)",
        )
        .integer(1, 5); integer(parameters.programme),
        HEAVE_CENTRE => V::parameter("heave.centre", &[3], 94, Some("m"), "Programme 1: centre of mass about which the platform heaves"); real(parameters.heave_centre),
        HEAVE_AMPLITUDE => V::parameter("heave.amplitude", &[], 97, Some("m"), "Programme 1: heave amplitude a"); real(parameters.heave.amplitude),
        HEAVE_FREQUENCY => V::parameter("heave.frequency", &[], 98, Some("rad/s"), "Programme 1: heave circular frequency Omega"); real(parameters.heave.frequency),
        HEAVE_TIME_CONSTANT => V::parameter("heave.timeConstant", &[], 99, Some("s"), "Programme 1: soft-start time constant T"); real(parameters.heave.time_constant),
        SINE_OFFSET => V::parameter("sine.offset", &[3], 100, Some("m"), "Programme 2: mean centre of mass x, y, z"); real(parameters.sine.offset),
        SINE_ANGLE_OFFSET => V::parameter("sine.angleOffset", &[3], 103, Some("rad"), "Programme 2: mean roll, pitch, yaw").display("deg"); real(parameters.sine.angle_offset),
        SINE_AMPLITUDE => V::parameter("sine.amplitude", &[3], 106, Some("m"), "Programme 2: amplitudes of x, y, z"); real(parameters.sine.amplitude),
        SINE_ANGLE_AMPLITUDE => V::parameter("sine.angleAmplitude", &[3], 109, Some("rad"), "Programme 2: amplitudes of roll, pitch, yaw")
            .display("deg"); real(parameters.sine.angle_amplitude),
        SINE_FREQUENCY => V::parameter(
            "sine.frequency",
            &[6],
            112,
            Some("rad/s"),
            "Programme 2: circular frequencies of x, y, z, roll, pitch, yaw",
        ); real(parameters.sine.frequency),
        SINE_PHASE => V::parameter("sine.phase", &[6], 118, Some("rad"), "Programme 2: phases of x, y, z, roll, pitch, yaw"); real(parameters.sine.phase),
        SINE_TIME_CONSTANT => V::parameter("sine.timeConstant", &[], 124, Some("s"), "Programme 2: soft-start time constant"); real(parameters.sine.time_constant),
        DISTURBANCE_AMPLITUDE => V::parameter(
            "disturbance.amplitude",
            &[],
            125,
            Some("N"),
            "Force disturbance added to every leg, amplitude sin(frequency t)(1 - exp(-t/timeConstant)): the \
             paper's perturbation is 0.0001 M g (tunable)",
        )
        .tunable(); real(parameters.disturbance.amplitude),
        DISTURBANCE_FREQUENCY => V::parameter("disturbance.frequency", &[], 126, Some("rad/s"), "Circular frequency of the disturbance"); real(parameters.disturbance.frequency),
        DISTURBANCE_TIME_CONSTANT => V::parameter("disturbance.timeConstant", &[], 127, Some("s"), "Soft-start time constant of the disturbance"); real(parameters.disturbance.time_constant),
        F => V::output(
            "F",
            &[6],
            150,
            Some("N"),
            "Leg force command F_k = F^p_k + G (l^p_k - l_k) + D (ldot^p_k - ldot_k) + disturbance (to the platform's F)",
            ALL_KNOWNS,
        )
        .depends_on(FORCE_DEPENDENCIES); cached(commands.f),
        FP => V::output("Fp", &[6], 156, Some("N"), "Programme leg forces F^p from the direct problem", ALL_KNOWNS)
            .depends_on(POSE_INPUTS); cached(programme_outputs.fp),
        LP => V::output("lp", &[6], 162, Some("m"), "Programme leg lengths l^p (inverse kinematics)", ALL_KNOWNS)
            .depends_on(LENGTH_DEPENDENCIES); cached(programme_outputs.lp),
        LDOTP => V::output("ldotp", &[6], 168, Some("m/s"), "Programme leg length rates", ALL_KNOWNS)
            .depends_on(LENGTH_DEPENDENCIES); cached(programme_outputs.ldotp),
        RP => V::output("rp", &[3], 174, Some("m"), "Programme centre of mass", ALL_KNOWNS).depends_on(&[All(group::POSE_R)]); cached(programme_outputs.rp),
        ANGLESP => V::output("anglesp", &[3], 177, Some("rad"), "Programme roll, pitch, yaw", ALL_KNOWNS)
            .display("deg")
            .depends_on(&[All(group::POSE_ANGLES)]); cached(programme_angles.anglesp),
        STARTUP_POSITION => V::parameter(
            "startup.position",
            &[3],
            128,
            Some("m"),
            "Programme 4: centre of mass of the parked platform at t = 0 (default: the default stand at rest on its \
             lower end stops)",
        ); real(parameters.startup_position),
        STARTUP_DURATION => V::parameter(
            "startup.duration",
            &[],
            131,
            Some("s"),
            "Programme 4: duration of the lift to heave.centre (quintic rest-to-rest profile); the heave programme \
             starts at its end",
        ); real(parameters.startup_duration),
        FMIN => V::parameter(
            "Fmin",
            &[],
            132,
            Some("N"),
            "Actuator saturation: the force command F_k is limited to [Fmin, Fmax] (real drives saturate)",
        ); real(parameters.f_min),
        FMAX => V::parameter("Fmax", &[], 133, Some("N"), "Actuator saturation: largest force command (see Fmin)"); real(parameters.f_max),
        LEG_CYLINDER_MASS => V::parameter(
            "leg.cylinderMass", &[], 190, Some("kg"),
            "Mass m_c of each leg's cylinder: the programme forces F^p carry the legs' weight and inertia (as the \
             platform's leg.* parameters)",
        ); real(parameters.legs.cylinder_mass),
        LEG_ROD_MASS => machine::rod_mass(191); real(parameters.legs.rod_mass),
        LEG_CYLINDER_COM => machine::cylinder_com(192); real(parameters.legs.cylinder_com),
        LEG_ROD_COM => machine::rod_com(193); real(parameters.legs.rod_com),
        LEG_CYLINDER_INERTIA => machine::cylinder_inertia(194); real(parameters.legs.cylinder_inertia),
        LEG_ROD_INERTIA => machine::rod_inertia(195); real(parameters.legs.rod_inertia),
        DRIVE => V::parameter(
            "drive", &[], 200, None,
            "0 = force commands F only (U = 0); 1 = the platform's legs are electric drives: also the voltage commands \
             U = R F / (N k_t) + k_e N ldot^p, the force command through the drive's static model (same motor.*, \
             gear.ratio, screw.lead as the platform), and the programme forces carry the rotors' inertia; 2 = the \
             platform's legs are hydraulic: also the valve commands, an inner loop on the measured actuator force \
             pA A_A - pB A_B towards F with a flow feed-forward from the programme's leg rates",
        )
        .integer(0, 2); integer(parameters.drive),
        MOTOR_R => machine::motor_resistance(201); real(parameters.drives.resistance),
        MOTOR_L => machine::motor_inductance(202); real(parameters.drives.inductance),
        MOTOR_KE => machine::motor_ke(203); real(parameters.drives.ke),
        MOTOR_KT => machine::motor_kt(204); real(parameters.drives.kt),
        MOTOR_J => machine::motor_inertia(205); real(parameters.drives.rotor_inertia),
        MOTOR_D => machine::motor_damping(206); real(parameters.drives.damping),
        GEAR_RATIO => machine::gear_ratio(207); real(parameters.drives.gear_ratio),
        SCREW_LEAD => machine::screw_lead(208); real(parameters.drives.screw_lead),
        UMAX => V::parameter(
            "Umax", &[], 209, Some("V"), "Voltage saturation: the voltage command U_k is limited to [-Umax, Umax] (the drives' supply)",
        ); real(parameters.u_max),
        U => V::output(
            "U", &[6], 210, Some("V"),
            "Voltage command U_k = R F_k / (N k_t) + k_e N ldot^p_k, limited to [-Umax, Umax] (to the platform's U; 0 \
             when drive = 0)",
            ALL_KNOWNS,
        )
        .depends_on(FORCE_DEPENDENCIES); cached(commands.u),
        PA => V::input(
            "pA", &[6], 220, Some("Pa"), "Measured cap-side pressure of leg k (from the platform's output pA; drive = 2)",
        ); real(pa),
        PB => V::input(
            "pB", &[6], 226, Some("Pa"), "Measured rod-side pressure of leg k (from the platform's output pB; drive = 2)",
        ); real(pb),
        BORE => machine::hydraulic_bore(232); real(parameters.hydraulic.bore),
        ROD => machine::hydraulic_rod(233); real(parameters.hydraulic.rod),
        RATED_FLOW => machine::valve_rated_flow(234); real(parameters.hydraulic.rated_flow),
        RATED_DROP => machine::valve_rated_pressure_drop(235); real(parameters.hydraulic.rated_pressure_drop),
        PS => V::parameter(
            "pS", &[], 236, Some("Pa"), "Supply pressure p_S the flow feed-forward assumes (the platform's pS input)",
        ); real(parameters.hydraulic.supply),
        FORCE_GAIN => V::parameter(
            "hydraulic.forceGain", &[], 237, Some("1/N"),
            "Gain kF of the inner force loop: valve = kF (F - (pA A_A - pB A_B)) + feed-forward (tunable)",
        )
        .tunable(); real(parameters.hydraulic.force_gain),
        FLOW_FEEDFORWARD => V::parameter(
            "hydraulic.flowFeedforward", &[], 238, Some("1"),
            "Share of the programme's flow A ldot^p / (K sqrt(dp)) fed forward to the valve (0 = none, 1 = all; tunable)",
        )
        .tunable(); real(parameters.hydraulic.flow_feedforward),
        POSITION_GAIN => V::parameter(
            "hydraulic.positionGain", &[], 239, Some("1/s"),
            "Gain of the leg-length error in the flow feed-forward: the valve is fed the rate ldot^p + Kl (l^p - l) \
             (tunable)",
        )
        .tunable(); real(parameters.hydraulic.position_gain),
        VALVE => V::output(
            "valve", &[6], 240, Some("1"),
            "Servo valve command of leg k (to the platform's valve; 0 unless drive = 2), saturated to [-1, 1]",
            ALL_KNOWNS,
        )
        .depends_on(HYDRAULIC_DEPENDENCIES); cached(commands.valve),
        SUPPLY_PRESSURE => V::input(
            "supply.pressure", &[], 246, Some("Pa"),
            "Measured supply pressure (from the platform's output supply.pressure; drive = 2): the flow feed-forward's \
             drops, and the safe landing's trigger (landing.pressure)",
        ); real(supply_pressure),
        LANDING_COMMAND => V::input(
            "landing.command", &[], 247, Some("1"),
            "1 (>= 0.5) starts the safe landing at the next step from wherever the programme is (latched: the landing \
             goes on whatever the input does after); 0 = no",
        ); real(landing_command),
        LANDING_PRESSURE => V::parameter(
            "landing.pressure", &[], 248, Some("Pa"),
            "The safe landing starts at the next step when supply.pressure is below this (drive = 2; 0 = never: only \
             landing.command or programme 5 start it)",
        ); real(parameters.landing.pressure),
        LANDING_SPEED => V::parameter(
            "landing.speed", &[], 249, Some("m/s"),
            "Descent speed of the safe landing (reached within 0.5 s from the programme's motion, quintic)",
        ); real(parameters.landing.speed),
        LANDING_FLOOR => V::parameter(
            "landing.floor", &[], 250, Some("m"),
            "Height of the centre of mass where the safe landing stops (0.5 s to rest); default 5 mm above the \
             default stand resting level on its lower stops",
        ); real(parameters.landing.floor),
    }
}
