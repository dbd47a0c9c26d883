//! The `StewartCueing` variables (SPEC §11-12, docs/cueing.md). The pose command carries the
//! controller's `pose.*` input names and the stand's geometry the platform's names, so an SSP
//! connects and binds them by name.

use crate::models::declare::declare_variables;
use crate::models::machine;
use crate::models::variables::Dependency::{self, All, SameIndex};
use crate::models::variables::VariableGroup as V;

const STATE_GROUPS: [Dependency; 8] = [
    All(group::Q),
    All(group::HEAD_R),
    All(group::HEAD_V),
    All(group::FL),
    All(group::DER_FL),
    All(group::TILT),
    All(group::Z),
    All(group::ROT_ANGLES),
];
/// The perceived vehicle's cues: its lags.
const PERCEIVED_VEHICLE: &[Dependency] = &[All(group::VEHICLE_OTOLITH), All(group::VEHICLE_CANAL)];
/// The perceived simulator's cues: its lags.
const PERCEIVED_SIMULATOR: &[Dependency] = &[All(group::SIMULATOR_OTOLITH), All(group::SIMULATOR_CANAL)];
/// The simulator's lags' rates: the command's cues (the washout's states and both inputs) and
/// the lags themselves.
const SIMULATOR_LAG_RATES: &[Dependency] = &[
    STATE_GROUPS[0],
    STATE_GROUPS[1],
    STATE_GROUPS[2],
    STATE_GROUPS[3],
    STATE_GROUPS[4],
    STATE_GROUPS[5],
    STATE_GROUPS[6],
    STATE_GROUPS[7],
    All(group::F),
    All(group::OMEGA),
    All(group::SIMULATOR_OTOLITH),
    All(group::SIMULATOR_CANAL),
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
    All(group::OMEGA),
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
    All(group::F),
    All(group::OMEGA),
];
/// In Initialization Mode the outputs depend on the inputs and every parameter.
const KNOWNS: &[Dependency] = &[
    All(group::F),
    All(group::OMEGA),
    All(group::G_GRAVITY),
    All(group::SCALE_F),
    All(group::SCALE_OMEGA),
    All(group::FMAX),
    All(group::OMEGAMAX),
    All(group::HP_F_OMEGA),
    All(group::HP_F_DAMPING),
    All(group::HP_F_BREAK),
    All(group::TILT_OMEGA),
    All(group::TILT_DAMPING),
    All(group::TILT_RATE_LIMIT),
    All(group::TILT_MAX),
    All(group::HP_W_OMEGA),
    All(group::HP_W_DAMPING),
    All(group::HEAD),
    All(group::MARGIN),
    All(group::ONSET),
    All(group::NEUTRAL),
    All(group::B),
    All(group::A),
    All(group::LMIN),
    All(group::LMAX),
    All(group::METHOD),
    All(group::MPC_PERIOD),
    All(group::MPC_HORIZON),
    All(group::MPC_TRUST),
    All(group::MPC_TREND),
    All(group::MPC_WEIGHT_F),
    All(group::MPC_WEIGHT_OMEGA),
    All(group::MPC_WEIGHT_NEUTRAL),
    All(group::MPC_WEIGHT_INPUT),
    All(group::MPC_LEG_SPEED),
    All(group::MPC_MAX_ITERATIONS),
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
        METHOD => V::parameter(
            "cueing.method", &[], 47, None,
            "0 = the classical washout (SPEC 11); 1 = predictive cueing (SPEC 12): an optimal control problem over \
             mpc.horizon every mpc.period, on the perception model, every leg within its stroke (Co-Simulation only)",
        )
        .integer(0, 1); integer(parameters.method),
        MPC_PERIOD => V::parameter(
            "mpc.period", &[], 140, Some("s"), "Predictive cueing: time between solves (the jerks are held in between)",
        ); real(parameters.predictive.period),
        MPC_HORIZON => V::parameter(
            "mpc.horizon", &[], 141, Some("s"),
            "Predictive cueing: prediction horizon (20 grid steps; the jerks in 4 blocks of 1, 2, 4 and 13 steps)",
        ); real(parameters.predictive.horizon),
        MPC_TRUST => V::parameter(
            "mpc.trust", &[], 142, Some("s"),
            "Predictive cueing: the perceived errors tau ahead weigh exp(-tau/trust) where the vehicle's future is \
             guessed (mpc.trend's guess, which grows worse with tau); within a preview file's rows they weigh 1",
        ); real(parameters.predictive.trust),
        MPC_TREND => V::parameter(
            "mpc.trend", &[], 154, Some("s"),
            "Predictive cueing: without a preview file the vehicle's future is guessed from its inputs now and their \
             rate of change over the last solve period: the horizontal specific force and the angular velocity go on \
             at that rate, fading over about this time (rate trend (1 - exp(-tau/trend)), within 8 m/s2 and 0.5 \
             rad/s); 0 holds the inputs",
        ); real(parameters.predictive.trend),
        MPC_WEIGHT_F => V::parameter(
            "mpc.weight.f", &[3], 143, Some("1"),
            "Predictive cueing: weight of the perceived specific-force error per cabin axis, per squared threshold \
             (0.17, 0.17, 0.28 m/s2)",
        ); real(parameters.predictive.weight_f),
        MPC_WEIGHT_OMEGA => V::parameter(
            "mpc.weight.omega", &[3], 146, Some("1"),
            "Predictive cueing: weight of the perceived angular-velocity error per cabin axis, per squared threshold \
             (3.0, 3.6, 2.6 deg/s)",
        ); real(parameters.predictive.weight_omega),
        MPC_WEIGHT_NEUTRAL => V::parameter(
            "mpc.weight.neutral", &[], 149, Some("1"),
            "Predictive cueing: weight of the head's displacement from neutral (per m2) and of the yaw (per rad2), \
             which return the stand to neutral",
        ); real(parameters.predictive.weight_neutral),
        MPC_WEIGHT_INPUT => V::parameter(
            "mpc.weight.input", &[], 150, Some("1"),
            "Predictive cueing: weight of the jerks (per (m/s3)2; the angular ones times g2), which keep the command \
             smooth; > 0",
        ); real(parameters.predictive.weight_input),
        MPC_LEG_SPEED => V::parameter(
            "mpc.legSpeed", &[], 151, Some("m/s"), "Predictive cueing: largest leg speed of the planned motion",
        ); real(parameters.predictive.leg_speed),
        MPC_MAX_ITERATIONS => V::parameter(
            "mpc.maxIterations", &[], 152, None,
            "Predictive cueing: the solver's iteration budget; a solve that does not converge within it takes its \
             last iterate within 1e-6, or without one hands its period to the classical washout (mpc.fallbacks)",
        )
        .integer(1, 1000); integer(parameters.iterations),
        PREVIEW_FILE => V::parameter(
            "preview.file", &[], 153, None,
            "Predictive cueing: a CSV file of the vehicle's future (header time, f[1], f[2], f[3], omega[1], omega[2], \
             omega[3]; s, m/s2, rad/s; simulation time), read at initialisation; empty: the inputs are guessed over \
             the horizon (mpc.trend)",
        )
        .string(); string(parameters.preview_file),
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
        PERCEIVED_F => V::output(
            "perceived.f", &[3], 160, Some("m/s2"),
            "The vehicle's specific force as the driver perceives it (the otoliths' model of SPEC 12 on f), cabin axes",
            KNOWNS,
        )
        .depends_on(PERCEIVED_VEHICLE); cached(outputs.perceived_f),
        PERCEIVED_OMEGA => V::output(
            "perceived.omega", &[3], 163, Some("rad/s"),
            "The vehicle's angular velocity as the driver perceives it (the canals' model on omega), cabin axes", KNOWNS,
        )
        .depends_on(PERCEIVED_VEHICLE); cached(outputs.perceived_omega),
        PERCEIVED_FSIM => V::output(
            "perceived.fsim", &[3], 166, Some("m/s2"),
            "The simulator's specific force as the driver perceives it (the otoliths' model on fsim)", KNOWNS,
        )
        .depends_on(PERCEIVED_SIMULATOR); cached(outputs.perceived_fsim),
        PERCEIVED_OMEGASIM => V::output(
            "perceived.omegasim", &[3], 169, Some("rad/s"),
            "The simulator's angular velocity as the driver perceives it (the canals' model on omegasim)", KNOWNS,
        )
        .depends_on(PERCEIVED_SIMULATOR); cached(outputs.perceived_omegasim),
        MPC_ITERATIONS => V::output(
            "mpc.iterations", &[], 172, None, "Predictive cueing: the solver's iterations in the last solve", KNOWNS,
        )
        .integer(0, 1000)
        .discrete(); computed,
        MPC_FALLBACKS => V::output(
            "mpc.fallbacks", &[], 173, None,
            "Predictive cueing: solves since the start that failed, with no iterate within the acceptable level \
             (each hands its period to the classical washout)",
            KNOWNS,
        )
        .integer(0, 2147483647)
        .discrete(); computed,
        MPC_ACCEPTABLE => V::output(
            "mpc.acceptable", &[], 174, None,
            "Predictive cueing: solves since the start whose plan met only the acceptable level (1e-6; out of \
             iterations or broken down) instead of the solver's tolerance (1e-8)",
            KNOWNS,
        )
        .integer(0, 2147483647)
        .discrete(); computed,
        // The continuous states (`STATES`) are the groups whose derivatives are declared, in
        // that order: `crate::physics::cueing::washout::layout`.
        Q => V::local("washout.q", &[3], 200, Some("m.s"), "Translational filter's first state per inertial axis: its derivative is washout.r", KNOWNS); real(state.q),
        HEAD_R => V::local(
            "washout.r", &[3], 203, Some("m"), "The washout's head displacement from neutral, inertial axes", KNOWNS,
        )
        .derivative_named("washout.q", &[SameIndex(group::HEAD_R)]); real(state.r),
        HEAD_V => V::local("washout.v", &[3], 206, Some("m/s"), "Its velocity", KNOWNS)
            .derivative_named("washout.r", &[SameIndex(group::HEAD_V)]); real(state.v),
        DER_HEAD_V => V::local("der(washout.v)", &[3], 209, Some("m/s2"), "The head's acceleration (W_t's output)", KNOWNS)
            .derivative("washout.v", "washout.v", 1, MOTION); derivative,
        FL => V::local("washout.fl", &[2], 212, Some("m/s2"), "Low-passed specific force f_l (x, y) of the tilt coordination", KNOWNS); real(state.fl),
        DER_FL => V::local("der(washout.fl)", &[2], 214, Some("m/s3"), "Its rate", KNOWNS)
            .derivative("washout.fl", "washout.fl", 1, &[SameIndex(group::DER_FL)]); real(state.fl_rate),
        DER2_FL => V::local("der2(washout.fl)", &[2], 216, Some("m/s4"), "Its second derivative", KNOWNS)
            .derivative("der(washout.fl)", "washout.fl", 2, MOTION); derivative,
        TILT => V::local("washout.tilt", &[2], 218, Some("rad"), "Tilt coordination's roll and pitch (rate-limited)", KNOWNS)
            .display("deg"); real(state.tilt),
        DER_TILT => V::local("der(washout.tilt)", &[2], 220, Some("rad/s"), "Their rates", KNOWNS)
            .derivative("washout.tilt", "washout.tilt", 1, MOTION); derivative,
        Z => V::local("washout.z", &[3], 222, Some("rad.s"), "Rotational filter's first state per angle: its derivative is washout.angles", KNOWNS); real(state.z),
        ROT_ANGLES => V::local("washout.angles", &[3], 225, Some("rad"), "The rotational channel's roll, pitch, yaw", KNOWNS)
            .display("deg")
            .derivative_named("washout.z", &[SameIndex(group::ROT_ANGLES)]); real(state.angles),
        DER_ROT_ANGLES => V::local("der(washout.angles)", &[3], 228, Some("rad/s"), "Their rates (W_r's output)", KNOWNS)
            .derivative("washout.angles", "washout.angles", 1, MOTION); derivative,
        // The perception's lags (docs/cueing.md): per cabin axis the cue lagged by each time
        // constant of the otoliths' (tau_oL, tau_oS) or the canals' (tau_1, tau_2, tau_a) filter.
        VEHICLE_OTOLITH => V::local(
            "perception.vehicle.otolith", &[3, 2], 240, Some("m/s2"),
            "The vehicle's specific force lagged by tau_oL = 5 s and tau_oS = 0.016 s, per axis (the otoliths' model)",
            KNOWNS,
        ); real(perception.vehicle_otolith),
        VEHICLE_CANAL => V::local(
            "perception.vehicle.canal", &[3, 3], 246, Some("rad/s"),
            "The vehicle's angular velocity lagged by tau_1 = 5.73 s, tau_2 = 0.005 s and tau_a = 80 s, per axis (the \
             canals' model)",
            KNOWNS,
        ); real(perception.vehicle_canal),
        SIMULATOR_OTOLITH => V::local(
            "perception.simulator.otolith", &[3, 2], 255, Some("m/s2"), "The same lags of fsim", KNOWNS,
        ); real(perception.simulator_otolith),
        SIMULATOR_CANAL => V::local(
            "perception.simulator.canal", &[3, 3], 261, Some("rad/s"), "The same lags of omegasim", KNOWNS,
        ); real(perception.simulator_canal),
        DER_VEHICLE_OTOLITH => V::local(
            "der(perception.vehicle.otolith)", &[3, 2], 270, Some("m/s3"), "Their rates", KNOWNS,
        )
        .derivative(
            "perception.vehicle.otolith", "perception.vehicle.otolith", 1,
            &[All(group::F), All(group::VEHICLE_OTOLITH)],
        ); derivative,
        DER_VEHICLE_CANAL => V::local(
            "der(perception.vehicle.canal)", &[3, 3], 276, Some("rad/s2"), "Their rates", KNOWNS,
        )
        .derivative(
            "perception.vehicle.canal", "perception.vehicle.canal", 1,
            &[All(group::OMEGA), All(group::VEHICLE_CANAL)],
        ); derivative,
        DER_SIMULATOR_OTOLITH => V::local(
            "der(perception.simulator.otolith)", &[3, 2], 285, Some("m/s3"), "Their rates", KNOWNS,
        )
        .derivative("perception.simulator.otolith", "perception.simulator.otolith", 1, SIMULATOR_LAG_RATES); derivative,
        DER_SIMULATOR_CANAL => V::local(
            "der(perception.simulator.canal)", &[3, 3], 291, Some("rad/s2"), "Their rates", KNOWNS,
        )
        .derivative("perception.simulator.canal", "perception.simulator.canal", 1, SIMULATOR_LAG_RATES); derivative,
        EVENT_INDICATORS => V::local(
            "eventIndicators", &[4], 300, Some("1"),
            "Event indicators (FMI 3 Model Exchange): the tilt limiter's switching functions of the roll and the pitch \
             (following: tilt.rateLimit - |target rate|, rad/s; slewing: the angle left to the target, rad), whose \
             crossing below zero is a switch of the ideal rate limiter; then sin(tilt.max) - |argument| of the roll's \
             and the pitch's target's arcsine, whose sign change is where the target's clip starts or stops",
            KNOWNS,
        )
        .fmi3_only(); computed,
    }
}
