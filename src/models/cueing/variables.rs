//! The `StewartCueing` variables (SPEC §11, docs/cueing.md). The pose command carries the
//! controller's `pose.*` input names and the stand's geometry the platform's names, so an SSP
//! connects and binds them by name.

use crate::models::declare::declare_variables;
use crate::models::machine;
use crate::models::variables::Dependency::{self, AllNamed as All, SameIndexNamed as SameIndex};
use crate::models::variables::VariableGroup as V;

const STATE_GROUPS: [Dependency; 8] = [
    All("washout.q"),
    All("washout.r"),
    All("washout.v"),
    All("washout.fl"),
    All("der(washout.fl)"),
    All("washout.tilt"),
    All("washout.z"),
    All("washout.angles"),
];
/// Outputs of the pose alone: the washout's states (through the limiter, all of them).
const POSE: &[Dependency] = &STATE_GROUPS;
/// Outputs with the pose's rates: the states and the angular velocity, which the rotational
/// high-pass passes straight through.
const RATES: &[Dependency] = &[
    STATE_GROUPS[0],
    STATE_GROUPS[1],
    STATE_GROUPS[2],
    STATE_GROUPS[3],
    STATE_GROUPS[4],
    STATE_GROUPS[5],
    STATE_GROUPS[6],
    STATE_GROUPS[7],
    All("omega"),
];
/// Outputs with accelerations, and the derivatives: the states and both inputs.
const MOTION: &[Dependency] = &[
    STATE_GROUPS[0],
    STATE_GROUPS[1],
    STATE_GROUPS[2],
    STATE_GROUPS[3],
    STATE_GROUPS[4],
    STATE_GROUPS[5],
    STATE_GROUPS[6],
    STATE_GROUPS[7],
    All("f"),
    All("omega"),
];
/// In Initialization Mode the outputs depend on the inputs and every parameter.
const KNOWNS: &[Dependency] = &[
    All("f"),
    All("omega"),
    All("g"),
    All("scale.f"),
    All("scale.omega"),
    All("fmax"),
    All("omegamax"),
    All("hp.f.omega"),
    All("hp.f.damping"),
    All("hp.f.break"),
    All("tilt.omega"),
    All("tilt.damping"),
    All("tilt.rateLimit"),
    All("tilt.max"),
    All("hp.w.omega"),
    All("hp.w.damping"),
    All("head"),
    All("margin"),
    All("limiter.onset"),
    All("neutral"),
    All("B"),
    All("A"),
    All("lmin"),
    All("lmax"),
];

declare_variables! {
    model: super::CueingModel,
    cache_blocks: [outputs],
    variables: {
        TIME => V::time(0); computed,
        F => V::input(
            "f", &[3], 1, Some("m/s2"),
            "Vehicle's specific force a - g_vec at the head, cabin axes (x forward, y left, z up): (0, 0, g) at rest",
        ); real(vehicle.f),
        OMEGA => V::input("omega", &[3], 4, Some("rad/s"), "Vehicle's angular velocity, cabin axes"); real(vehicle.omega),
        G_GRAVITY => V::parameter("g", &[], 10, Some("m/s2"), "Gravitational acceleration (g_vec = (0, 0, -g))"); real(parameters.washout.gravity),
        SCALE_F => V::parameter(
            "scale.f", &[3], 11, Some("1"),
            "Gain K_f on the specific force's deviation from rest, per cabin axis",
        ); real(parameters.washout.scale_f),
        SCALE_OMEGA => V::parameter("scale.omega", &[3], 14, Some("1"), "Gain K_w on the angular velocity, per cabin axis"); real(parameters.washout.scale_omega),
        FMAX => V::parameter(
            "fmax", &[], 17, Some("m/s2"), "Limit of each component of the scaled specific force's deviation from rest",
        ); real(parameters.washout.f_max),
        OMEGAMAX => V::parameter("omegamax", &[], 18, Some("rad/s"), "Limit of each component of the scaled angular velocity")
            .display("deg/s"); real(parameters.washout.omega_max),
        HP_F_OMEGA => V::parameter(
            "hp.f.omega", &[3], 19, Some("rad/s"),
            "w_t: natural frequency of the translational high-pass s^3/((s^2 + 2 zeta_t w_t s + w_t^2)(s + w_b)), per inertial axis",
        ); real(parameters.washout.hp_f_omega),
        HP_F_DAMPING => V::parameter("hp.f.damping", &[3], 22, Some("1"), "zeta_t: damping of the translational high-pass"); real(parameters.washout.hp_f_damping),
        HP_F_BREAK => V::parameter(
            "hp.f.break", &[3], 25, Some("rad/s"),
            "w_b: break frequency of the translational high-pass's first-order part (it returns the head to neutral)",
        ); real(parameters.washout.hp_f_break),
        TILT_OMEGA => V::parameter(
            "tilt.omega", &[], 28, Some("rad/s"),
            "w_l: natural frequency of the tilt coordination's low-pass w_l^2/(s^2 + 2 zeta_l w_l s + w_l^2)",
        ); real(parameters.washout.tilt_omega),
        TILT_DAMPING => V::parameter("tilt.damping", &[], 29, Some("1"), "zeta_l: damping of the tilt low-pass"); real(parameters.washout.tilt_damping),
        TILT_RATE_LIMIT => V::parameter(
            "tilt.rateLimit", &[], 30, Some("rad/s"),
            "Rate limit of the tilt angles (below the vestibular threshold: the driver feels the tilt as a force, not \
             a rotation)",
        )
        .display("deg/s"); real(parameters.washout.tilt_rate_limit),
        TILT_MAX => V::parameter("tilt.max", &[], 31, Some("rad"), "Largest tilt angle").display("deg"); real(parameters.washout.tilt_max),
        HP_W_OMEGA => V::parameter(
            "hp.w.omega", &[3], 32, Some("rad/s"),
            "w_r: natural frequency of the rotational high-pass s^2/(s^2 + 2 zeta_r w_r s + w_r^2), per angle",
        ); real(parameters.washout.hp_w_omega),
        HP_W_DAMPING => V::parameter("hp.w.damping", &[3], 35, Some("1"), "zeta_r: damping of the rotational high-pass"); real(parameters.washout.hp_w_damping),
        HEAD => V::parameter(
            "head", &[3], 38, Some("m"),
            "Head point (the driver's vestibular system) in the platform body frame, from the centre of mass: the \
             cabin rotates about it",
        ); real(parameters.head),
        MARGIN => V::parameter(
            "margin", &[], 41, Some("m"),
            "Stroke kept free at each end: the limiter keeps every leg in [lmin + margin, lmax - margin] (the \
             controller's following error and the stops' reach)",
        ); real(parameters.margin),
        ONSET => V::parameter(
            "limiter.onset", &[], 42, Some("1"),
            "Workspace usage (1 = a leg at its margin) from which the limiter pulls the command back towards neutral, \
             smoothly; below it the command is the washout's",
        ); real(parameters.onset),
        NEUTRAL => V::parameter(
            "neutral", &[3], 43, Some("m"),
            "Neutral centre of mass (no rotation), inertial frame: where the washout returns the cabin",
        ); real(parameters.neutral),
        MAX_STEP => V::parameter(
            "solver.maxStep", &[], 46, Some("s"),
            "Largest internal step of the Co-Simulation's fixed-step RK4 (the communication step is divided evenly)",
        ); real(parameters.max_step),
        B => machine::base_joints(50); real(parameters.base_joints),
        A => machine::platform_joints(70); real(parameters.platform_joints),
        LMIN => machine::stroke_lower(90); real(parameters.lmin),
        LMAX => machine::stroke_upper(96); real(parameters.lmax),
        POSE_R => V::output("pose.r", &[3], 110, Some("m"), "Commanded centre of mass (to the controller's pose.r)", KNOWNS)
            .depends_on(POSE); cached(outputs.r),
        POSE_V => V::output("pose.v", &[3], 113, Some("m/s"), "Its velocity (exact, from the filters' states)", KNOWNS)
            .depends_on(RATES); cached(outputs.v),
        POSE_A => V::output("pose.a", &[3], 116, Some("m/s2"), "Its acceleration (exact)", KNOWNS).depends_on(MOTION); cached(outputs.a),
        POSE_ANGLES => V::output("pose.angles", &[3], 119, Some("rad"), "Commanded roll, pitch, yaw (1-2-3)", KNOWNS)
            .display("deg")
            .depends_on(POSE); cached(outputs.angles),
        POSE_ANGLE_RATES => V::output("pose.angleRates", &[3], 122, Some("rad/s"), "Their rates (exact)", KNOWNS)
            .depends_on(RATES); cached(outputs.angle_rates),
        POSE_ANGLE_ACCELERATIONS => V::output(
            "pose.angleAccelerations", &[3], 125, Some("rad/s2"),
            "Their second derivatives, the inputs held (exact)", KNOWNS,
        )
        .depends_on(MOTION); cached(outputs.angle_accelerations),
        FSIM => V::output(
            "fsim", &[3], 128, Some("m/s2"),
            "Specific force of the commanded motion at the head, cabin axes: what the driver feels (compare with f)",
            KNOWNS,
        )
        .depends_on(MOTION); cached(outputs.fsim),
        OMEGASIM => V::output(
            "omegasim", &[3], 131, Some("rad/s"),
            "Angular velocity of the commanded motion, cabin axes (compare with omega)", KNOWNS,
        )
        .depends_on(RATES); cached(outputs.omegasim),
        USAGE => V::output(
            "workspace.usage", &[], 134, Some("1"),
            "Workspace usage of the washout's pose: 1 = a leg would reach lmin + margin or lmax - margin", KNOWNS,
        )
        .depends_on(POSE); cached(outputs.usage),
        SCALE => V::output(
            "workspace.scale", &[], 135, Some("1"),
            "Share of the washout's deviation from neutral that is commanded (1 = all; below 1 the limiter acts)", KNOWNS,
        )
        .depends_on(POSE); cached(outputs.scale),
        LIMITED => V::output("limited", &[], 136, None, "The workspace limiter is acting (workspace.scale < 1)", KNOWNS)
            .boolean()
            .discrete()
            .depends_on(POSE); computed,
        // The continuous states (`STATES`) are the groups whose derivatives are declared, in
        // that order: `crate::physics::cueing::washout::layout`.
        Q => V::local("washout.q", &[3], 200, Some("m.s"), "Translational filter's first state per inertial axis: its derivative is washout.r", KNOWNS); real(state.q),
        HEAD_R => V::local(
            "washout.r", &[3], 203, Some("m"), "The washout's head displacement from neutral, inertial axes", KNOWNS,
        )
        .derivative_named("washout.q", &[SameIndex("washout.r")]); real(state.r),
        HEAD_V => V::local("washout.v", &[3], 206, Some("m/s"), "Its velocity", KNOWNS)
            .derivative_named("washout.r", &[SameIndex("washout.v")]); real(state.v),
        DER_HEAD_V => V::local("der(washout.v)", &[3], 209, Some("m/s2"), "The head's acceleration (W_t's output)", KNOWNS)
            .derivative("washout.v", "washout.v", 1, MOTION); derivative,
        FL => V::local("washout.fl", &[2], 212, Some("m/s2"), "Low-passed specific force f_l (x, y) of the tilt coordination", KNOWNS); real(state.fl),
        DER_FL => V::local("der(washout.fl)", &[2], 214, Some("m/s3"), "Its rate", KNOWNS)
            .derivative("washout.fl", "washout.fl", 1, &[SameIndex("der(washout.fl)")]); real(state.fl_rate),
        DER2_FL => V::local("der2(washout.fl)", &[2], 216, Some("m/s4"), "Its second derivative", KNOWNS)
            .derivative("der(washout.fl)", "washout.fl", 2, MOTION); derivative,
        TILT => V::local("washout.tilt", &[2], 218, Some("rad"), "Tilt coordination's roll and pitch (rate-limited)", KNOWNS)
            .display("deg"); real(state.tilt),
        DER_TILT => V::local("der(washout.tilt)", &[2], 220, Some("rad/s"), "Their rates", KNOWNS)
            .derivative("washout.tilt", "washout.tilt", 1, MOTION); derivative,
        Z => V::local("washout.z", &[3], 222, Some("rad.s"), "Rotational filter's first state per angle: its derivative is washout.angles", KNOWNS); real(state.z),
        ROT_ANGLES => V::local("washout.angles", &[3], 225, Some("rad"), "The rotational channel's roll, pitch, yaw", KNOWNS)
            .display("deg")
            .derivative_named("washout.z", &[SameIndex("washout.angles")]); real(state.angles),
        DER_ROT_ANGLES => V::local("der(washout.angles)", &[3], 228, Some("rad/s"), "Their rates (W_r's output)", KNOWNS)
            .derivative("washout.angles", "washout.angles", 1, MOTION); derivative,
    }
}
