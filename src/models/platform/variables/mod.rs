//! The `StewartPlatform` variables (docs/model.md §5). Names, units and meanings are part of the
//! contract with hosts and tests: keep them.

use crate::models::declare::declare_variables;
use crate::models::machine;
use crate::models::variables::Dependency::{All, SameIndex};

mod dependencies;
mod hydraulics;
mod power_unit;
use dependencies::*;
use crate::models::variables::VariableGroup as V;
use crate::physics::actuators::PerActuator;
use crate::simulation::PlatformOutputs;
use crate::simulation::outputs::actuator_state;
use crate::simulation::state::{CURRENTS, hydraulic, quadrature};

declare_variables! {
    model: super::PlatformModel,
    outputs: PlatformOutputs,
    cache_blocks: [
        // What a controller reads every step, computed alone.
        leg_outputs,
        // The outputs of `PlatformOutputs` that depend on the state alone, by group, each
        // computed only when read: the pose (r, v, R, angles, w); what the legs' geometry gives
        // beyond their lengths (E, Fstop, thetaB, thetaA: the legs again, twelve acos); values
        // read off the state (constraintError, the work integrals, I).
        pose,
        leg_loads,
        state_values,
        // The actuators' and the joints' forces: they depend on the inputs too. (The declared
        // dependencies are those of both drive modes: F in mode 0, the currents in mode 1.)
        input_dependent_outputs,
        // The condition number `kappa` (an eigenvalue problem): read by studies every step,
        // by most hosts never.
        condition,
        // The actuators' states and integrals (the drives' currents, the hydraulic legs'
        // pressures and spools: what a hydraulic controller reads every step besides the legs),
        // copied from the state.
        actuators,
    ],
    variables: {
        TIME => V::time(0); computed,
        F => V::input(
            "F",
            &[6],
            1,
            Some("N"),
            "Axial leg force u_k acting on the platform at A_k along the leg (positive pushes the platform away from the \
             base). Held over each communication step, or interpolated to first order when fmi2SetRealInputDerivatives \
             gave its derivative",
        ); real(inputs.forces),
        M => machine::mass(10); real(parameters.stand.mass),
        J => machine::inertia(11); real(parameters.stand.inertia),
        G => machine::gravity(14); real(parameters.stand.gravity),
        B => machine::base_joints(20); real(parameters.stand.base_joints),
        A => machine::platform_joints(40); real(parameters.stand.platform_joints),
        R0 => V::parameter("r0", &[3], 60, Some("m"), "Initial position of the centre of mass"); real(parameters.r0),
        ANGLES0 => V::parameter("angles0", &[3], 63, Some("rad"), "Initial roll, pitch, yaw (1-2-3 sequence, R = Rx Ry Rz)")
            .display("deg"); real(parameters.angles0),
        V0 => V::parameter("v0", &[3], 66, Some("m/s"), "Initial velocity of the centre of mass"); real(parameters.v0),
        W0 => V::parameter("w0", &[3], 69, Some("rad/s"), "Initial angular velocity, body components"); real(parameters.w0),
        METHOD => V::parameter(
            "solver.method",
            &[],
            80,
            None,
            "Integrator: 1 = Dormand-Prince 5(4), adaptive with error control (solver.relTol, solver.absTol, \
             solver.maxStep); 2 = classical Runge-Kutta 4 with a fixed step (solver.fixedStep), a fixed cost per \
             communication step for real time",
        )
        .integer(1, 2); integer(parameters.settings.method),
        REL_TOL => V::parameter(
            "solver.relTol",
            &[],
            81,
            Some("1"),
            "Relative tolerance of the adaptive integrator's local error (replaced by the tolerance of \
             fmi2SetupExperiment when the importer defines one)",
        ); real(parameters.settings.rel_tol),
        ABS_TOL => V::parameter(
            "solver.absTol",
            &[],
            82,
            Some("1"),
            "Absolute tolerance of the adaptive integrator's local error, in the units of each state component \
             (m, m/s, unit-vector components and their rates)",
        ); real(parameters.settings.abs_tol),
        MAX_STEP => V::parameter(
            "solver.maxStep",
            &[],
            83,
            Some("s"),
            "Largest internal step of the adaptive integrator; 0 = limited only by the communication step",
        ); real(parameters.settings.max_step),
        FIXED_STEP => V::parameter(
            "solver.fixedStep",
            &[],
            84,
            Some("s"),
            "Internal step bound of RungeKutta4: each communication step is split into the fewest equal steps not \
             longer than this; 0 = one step per communication step",
        ); real(parameters.settings.fixed_step),
        STABILISATION => V::parameter(
            "solver.stabilisation",
            &[],
            85,
            None,
            "Constraint stabilisation: 2 = project onto the constraints e_a.e_b = delta_ab (orthonormal frame, \
             rigid-rotation velocities) after every internal step; 3 = Baumgarte terms in the derivatives \
             (solver.baumgarteRate), no projection; 1 = none, the residual drifts (for demonstration). Model Exchange \
             always uses Baumgarte terms unless this is 1",
        )
        .integer(1, 3); integer(parameters.stabilisation),
        R => V::output("r", &[3], 100, Some("m"), "Centre of mass S, inertial frame", &[SameIndex(group::R0)]); cached(pose.r),
        V => V::output("v", &[3], 103, Some("m/s"), "Velocity of the centre of mass", &[SameIndex(group::V0)])
            .derivative_named("r", &[SameIndex(group::V)]); cached(pose.v),
        // The continuous states (`STATES`) are the groups whose derivatives are declared, in
        // that order, which is `crate::simulation::state`'s layout: the special form's 24
        // `r, v, e1, e2, e3, e1', e2', e3'` (`e_b` is column `b` of `R`, hence column by
        // column), the work quadratures, the drives' currents and electric work, the
        // hydraulic states.
        ROT => V::output(
            "R",
            &[3, 3],
            106,
            Some("1"),
            "Rotation matrix body -> inertial: R[a,b] is component a of the body axis e_b",
            &[All(group::ANGLES0)],
        )
        .state_by_columns(); cached(pose.rotation),
        ANGLES => V::output("angles", &[3], 115, Some("rad"), "Roll, pitch, yaw (1-2-3 sequence, R = Rx Ry Rz)", &[All(group::ANGLES0)])
            .display("deg")
            .depends_on(&[All(group::ROT)]); cached(pose.angles),
        W => V::output("w", &[3], 118, Some("rad/s"), "Angular velocity, body components", &[SameIndex(group::W0)])
            .depends_on(&[All(group::ROT), All(group::DER_R)]); cached(pose.w),
        L => V::output(
            "l",
            &[6],
            121,
            Some("m"),
            "Leg length l_k = |a_k - B_k|",
            LEG_PARAMETERS,
        )
        .depends_on(POSE_STATES); cached(leg_outputs.l),
        LDOT => V::output(
            "ldot",
            &[6],
            127,
            Some("m/s"),
            "Leg length rate dl_k/dt",
            LEG_RATE_PARAMETERS,
        )
        .depends_on(BODY_STATES); cached(leg_outputs.ldot),
        E => V::output(
            "E",
            &[],
            133,
            Some("J"),
            "Energy: the platform's kinetic and gravitational potential energy M v^2/2 + w.J w/2 + M g z, the legs' \
             (and the drives' rotors') kinetic and potential energy, the end stops' and joint limits' potentials and the \
             drives' magnetic energy L I^2/2 (E(t) - E(0) = work.F + work.electric - work.dissipated)",
            ENERGY_PARAMETERS,
        )
        .depends_on(ENERGY_KNOWNS); cached(leg_loads.energy),
        CONSTRAINT_ERROR => V::output(
            "constraintError",
            &[],
            134,
            Some("1"),
            "Constraint residual max over a, b of |e_a.e_b - delta_ab|",
            &[All(group::ANGLES0)],
        )
        .depends_on(&[All(group::ROT)]); cached(state_values.constraint_error),
        BAUMGARTE_RATE => V::parameter(
            "solver.baumgarteRate",
            &[],
            86,
            Some("1/s"),
            "Rate alpha of the Baumgarte stabilisation (constraint residual decays like exp(-alpha t)): used by \
             Model Exchange, and by Co-Simulation with solver.stabilisation = 3",
        ); real(parameters.baumgarte_rate),
        DER_V => V::local(
            "der(v)",
            &[3],
            140,
            Some("m/s2"),
            "Acceleration of the centre of mass (Model Exchange derivative of v)",
            ALL_PARAMETERS,
        )
        .derivative("v", "v", 1, MOTION_KNOWNS); derivative,
        DER_R => V::local(
            "der(R)",
            &[3, 3],
            143,
            Some("1/s"),
            "Time derivative of the rotation matrix: column b is de_b/dt (Model Exchange state)",
            &[All(group::ANGLES0), All(group::W0)],
        )
        .state_by_columns()
        .derivative("R", "R", 1, &[SameIndex(group::DER_R)]); derivative,
        DER2_R => V::local(
            "der2(R)",
            &[3, 3],
            152,
            Some("1/s2"),
            "Second time derivative of the rotation matrix (the special form's e_b'', Model Exchange derivative of der(R))",
            ALL_PARAMETERS,
        )
        .derivative("der(R)", "R", 2, MOTION_KNOWNS); derivative,
        STOPS => V::parameter(
            "stops",
            &[],
            170,
            None,
            "End stops on: each leg is limited to its stroke lmin[k] <= l_k <= lmax[k] by a unilateral virtual potential \
             with contact damping (Fstop). false = the paper's idealised legs of unlimited stroke",
        )
        .boolean(); boolean(parameters.stops_enabled),
        LMIN => machine::stroke_lower(171); real(parameters.stops.lower),
        LMAX => machine::stroke_upper(177); real(parameters.stops.upper),
        STOP_STIFFNESS => V::parameter(
            "stops.stiffness",
            &[],
            183,
            Some("N/m"),
            "End-stop stiffness k_s: the stop force is k_s times the penetration (potential V = k_s delta^2 / 2)",
        ); real(parameters.stops.stiffness),
        STOP_DAMPING => V::parameter(
            "stops.damping",
            &[],
            184,
            Some("N.s/m"),
            "End-stop contact damping c_s: a damper force c_s d(delta)/dt in contact only, limited to the spring force \
             k_s delta so that the stop force is continuous at onset and never sticks (0 = elastic stops)",
        ); real(parameters.stops.damping),
        STOP_AT_SINGULARITY => V::parameter(
            "stopAtSingularity",
            &[],
            185,
            None,
            "Discard a step in which the legs pass through a singular arrangement (the force/moment matrix's \
             determinant changes sign), located inside the step. false = pass it and report it (logEvents)",
        )
        .boolean(); boolean(parameters.stop_at_singularity),
        FSTOP => V::output(
            "Fstop",
            &[6],
            200,
            Some("N"),
            "End-stop force along leg k (sign as F: positive pushes the platform away from the base); 0 inside the stroke",
            STOP_PARAMETERS,
        )
        .depends_on(BODY_STATES); cached(leg_loads.stop_force),
        KAPPA => V::output(
            "kappa",
            &[],
            206,
            Some("1"),
            "Condition number of the 6x6 leg force/moment matrix (moment rows divided by the stand's characteristic \
             length): large near a singular leg arrangement; at one (or where double precision cannot tell) it is \
             1/eps = 4.5e15, its largest value",
            LEG_PARAMETERS,
        )
        .depends_on(POSE_STATES); cached_apart(condition.kappa),
        WORK_F => V::output(
            "work.F",
            &[],
            207,
            Some("J"),
            "Work done by the leg forces F since the start, the integral of sum_k F_k ldot_k (Model Exchange state; \
             stays 0 with drive = 1, whose energy comes in as work.electric)",
            &[],
        ); cached(state_values.work_of_forces),
        WORK_DISSIPATED => V::output(
            "work.dissipated",
            &[],
            208,
            Some("J"),
            "Energy taken since the start by the end stops' and joint limits' damping, the cylinders' friction and the \
             drives' losses R I^2 + D omega^2 (+ (k_e - k_t) omega I) (>= 0; Model Exchange state)",
            &[],
        ); cached(state_values.dissipated_energy),
        DER_WORK_F => V::local(
            "der(work.F)",
            &[],
            210,
            Some("W"),
            "Power of the leg forces sum_k F_k ldot_k (Model Exchange derivative of work.F)",
            ALL_PARAMETERS,
        )
        .derivative("work.F", "work.F", 1, MOTION_KNOWNS); derivative,
        DER_WORK_DISSIPATED => V::local(
            "der(work.dissipated)",
            &[],
            211,
            Some("W"),
            "Power taken by the end stops' and joint limits' damping, by friction and by the drives' losses (Model \
             Exchange derivative of work.dissipated)",
            DISSIPATION_PARAMETERS,
        )
        .derivative("work.dissipated", "work.dissipated", 1, DISSIPATION_KNOWNS); derivative,
        EVENT_INDICATORS => V::local(
            "eventIndicators",
            &[crate::simulation::state::switching::EVENT_INDICATORS],
            220,
            Some("1"),
            "Event indicators (FMI 3 Model Exchange): l_k - lmin_k (k = 1..6, m), lmax_k - l_k (m), the determinant of \
             the leg force/moment matrix (moment rows divided by the stand's characteristic length), cos thetaB_k - \
             cos(joints.baseMaxAngle) and cos thetaA_k - cos(joints.platformMaxAngle); a sign change is a contact onset \
             or release, a passage through a singular leg arrangement, or a joint reaching or leaving its limit; then \
             supply.linePressure - (accumulator.precharge - 101325 Pa), a sign change the accumulator emptying or \
             charging again. Constant 1 for the stroke limits when the end stops are off, for the joints when the joint \
             limits are off, and for the accumulator without the power unit (hydraulic.supply = 0)",
            &[],
        )
        .fmi3_only(); computed,
        LEG_CYLINDER_MASS => V::parameter(
            "leg.cylinderMass", &[], 300, Some("kg"),
            "Mass m_c of each leg's cylinder (barrel), hinged at B_k; 0 with leg.rodMass and the inertias = the paper's \
             massless legs",
        ); real(parameters.legs.cylinder_mass),
        LEG_ROD_MASS => machine::rod_mass(301); real(parameters.legs.rod_mass),
        LEG_CYLINDER_COM => machine::cylinder_com(302); real(parameters.legs.cylinder_com),
        LEG_ROD_COM => machine::rod_com(303); real(parameters.legs.rod_com),
        LEG_CYLINDER_INERTIA => machine::cylinder_inertia(304); real(parameters.legs.cylinder_inertia),
        LEG_ROD_INERTIA => machine::rod_inertia(305); real(parameters.legs.rod_inertia),
        JOINTS => V::parameter(
            "joints", &[], 310, None,
            "Joint limits on: each base and platform joint angle (from the reference pose joints.r0, joints.angles0) is \
             limited by a unilateral virtual potential with contact damping. false = the paper's unlimited joints",
        )
        .boolean(); boolean(parameters.joints_enabled),
        JOINTS_BASE_MAX => V::parameter(
            "joints.baseMaxAngle", &[], 311, Some("rad"),
            "Largest angle thetaB of a base joint from its direction at the reference pose",
        )
        .display("deg"); real(parameters.joints.base_max),
        JOINTS_PLATFORM_MAX => V::parameter(
            "joints.platformMaxAngle", &[], 312, Some("rad"),
            "Largest angle thetaA of a platform joint from its direction (in the body frame) at the reference pose",
        )
        .display("deg"); real(parameters.joints.platform_max),
        JOINTS_STIFFNESS => V::parameter(
            "joints.stiffness", &[], 313, Some("N.m/rad"),
            "Joint-limit stiffness k_j: beyond its limit a joint's moment is k_j times the excess angle (potential \
             k_j delta^2 / 2)",
        ); real(parameters.joints.stiffness),
        JOINTS_DAMPING => V::parameter(
            "joints.damping", &[], 314, Some("N.m.s/rad"),
            "Joint-limit damping c_j: a damping moment c_j dtheta/dt in contact only, limited to the spring's k_j delta \
             so that it starts from zero at the onset and never pulls back into the limit (0 = elastic limits)",
        ); real(parameters.joints.damping),
        JOINTS_R0 => V::parameter(
            "joints.r0", &[3], 315, Some("m"),
            "Centre of mass of the reference pose the joint angles are measured from (default: the neutral pose)",
        ); real(parameters.joints.r0),
        JOINTS_ANGLES0 => V::parameter(
            "joints.angles0", &[3], 318, Some("rad"), "Roll, pitch, yaw of the joint angles' reference pose",
        )
        .display("deg"); real(parameters.joints.angles0),
        FRICTION_COULOMB => V::parameter(
            "friction.coulomb", &[], 330, Some("N"), "Coulomb friction force F_c of each cylinder (0 = no friction)",
        ); real(parameters.friction.coulomb),
        FRICTION_STATIC => V::parameter(
            "friction.static", &[], 331, Some("N"),
            "Static (breakaway) friction force F_s of each cylinder: the level at low speed, decaying to F_c (Stribeck)",
        ); real(parameters.friction.static_),
        FRICTION_STRIBECK => V::parameter(
            "friction.stribeckVelocity", &[], 332, Some("m/s"),
            "Stribeck velocity v_s: the friction level decays from F_s to F_c like exp(-(ldot/v_s)^2)",
        ); real(parameters.friction.stribeck_velocity),
        FRICTION_SMOOTHING => V::parameter(
            "friction.smoothing", &[], 333, Some("m/s"),
            "Smoothing velocity v_t of the friction's sign, tanh(ldot/v_t): the friction never sticks; smaller values \
             approach sticking and make the equations stiffer",
        ); real(parameters.friction.smoothing),
        FRICTION_VISCOUS => V::parameter(
            "friction.viscous", &[], 334, Some("N.s/m"), "Viscous friction coefficient sigma of each cylinder",
        ); real(parameters.friction.viscous),
        THETA_B => V::output(
            "thetaB", &[6], 340, Some("rad"),
            "Base joint angle thetaB_k: the angle between leg k and its direction at the joint limits' reference pose",
            JOINT_ANGLE_PARAMETERS,
        )
        .display("deg")
        .depends_on(POSE_STATES); cached(leg_loads.theta_b),
        THETA_A => V::output(
            "thetaA", &[6], 346, Some("rad"),
            "Platform joint angle thetaA_k: the angle between leg k and its direction at the reference pose, both in \
             the body frame",
            JOINT_ANGLE_PARAMETERS,
        )
        .display("deg")
        .depends_on(POSE_STATES); cached(leg_loads.theta_a),
        JOINT_FORCE => V::output(
            "jointForce", &[6, 3], 352, Some("N"),
            "Force of leg k on the platform at its joint A_k (row k: x, y, z, inertial frame): the actuator, friction, \
             end-stop and joint-limit forces and the leg's weight and inertia; what the joint must be sized for",
            ALL_PARAMETERS,
        )
        .depends_on(MOTION_KNOWNS); cached(input_dependent_outputs.joint_force),
        DRIVE => V::parameter(
            "drive", &[], 400, None,
            "Actuators: 0 = the leg forces F are the inputs (ideal force actuators); 1 = each leg is an electric drive \
             (a DC motor turning a ball screw) with the armature voltage U as its input, F ignored; 2 = each leg is a \
             hydraulic differential cylinder fed by a servo valve, the valve commands valve and the supply pressure pS \
             its inputs",
        )
        // Every code of the actuators' list (`ActuatorKind::ALL` in code order).
        .integer(0, crate::physics::actuators::ActuatorKind::ALL.len() as i32 - 1); integer(parameters.drive),
        MOTOR_R => machine::motor_resistance(401); real(parameters.actuators.electric.resistance),
        MOTOR_L => machine::motor_inductance(402); real(parameters.actuators.electric.inductance),
        MOTOR_KE => machine::motor_ke(403); real(parameters.actuators.electric.ke),
        MOTOR_KT => machine::motor_kt(404); real(parameters.actuators.electric.kt),
        MOTOR_J => machine::motor_inertia(405); real(parameters.actuators.electric.rotor_inertia),
        MOTOR_D => machine::motor_damping(406); real(parameters.actuators.electric.damping),
        GEAR_RATIO => machine::gear_ratio(407); real(parameters.actuators.electric.gear_ratio),
        SCREW_LEAD => machine::screw_lead(408); real(parameters.actuators.electric.screw_lead),
        I0 => V::parameter(
            "I0", &[6], 410, Some("A"),
            "Initial armature current of drive k (a run that starts holding the stand starts at the holding current)",
        ); real(parameters.actuators.electric.initial_currents),
        U => V::input(
            "U", &[6], 420, Some("V"),
            "Armature voltage U_k of drive k (used when drive = 1; 0 = the windings shorted: dynamic braking). Held \
             over each communication step, or interpolated to first order when fmi2SetRealInputDerivatives gave its \
             derivative",
        ); real(inputs.electric),
        I => V::output(
            "I", &[6], 430, Some("A"), "Armature current I_k of drive k (Model Exchange state; 0 when drive = 0)",
            &[All(group::DRIVE), SameIndex(group::I0)],
        ); cached_at(actuators.actuator_states, actuator_state(CURRENTS)),
        WORK_ELECTRIC => V::output(
            "work.electric", &[], 436, Some("J"),
            "Electric energy supplied to the drives since the start, the integral of sum_k U_k I_k (Model Exchange \
             state; E(t) - E(0) = work.F + work.electric - work.dissipated)",
            &[],
        ); cached_at(actuators.actuator_states, actuator_state(quadrature::WORK_ELECTRIC)),
        DER_I => V::local(
            "der(I)", &[6], 440, Some("A/s"),
            "Rate of the armature currents (U - R I - k_e N ldot) / L (Model Exchange derivative of I)",
            DRIVE_PARAMETERS,
        )
        .derivative("I", "I", 1, DRIVE_KNOWNS); derivative,
        DER_WORK_ELECTRIC => V::local(
            "der(work.electric)", &[], 446, Some("W"),
            "Electric power supplied to the drives sum_k U_k I_k (Model Exchange derivative of work.electric)",
            &[All(group::DRIVE), All(group::I0), All(group::U)],
        )
        .derivative("work.electric", "work.electric", 1, &[All(group::I), All(group::U)]); derivative,
        ACTUATOR_FORCE => V::output(
            "actuatorForce", &[6], 450, Some("N"),
            "Axial force of actuator k on leg k: the input F_k as last set (drive = 0), or the electric drive's N (k_t \
             I_k - D N ldot_k), independent of F (drive = 1); the end stops, friction and the leg's own inertia apart",
            ALL_PARAMETERS,
        )
        .depends_on(MOTION_KNOWNS); cached(input_dependent_outputs.actuator_force),
        VALVE => V::input(
            "valve", &[6], 460, Some("1"),
            "Servo valve command c_k of leg k (used when drive = 2), saturated to [-1, 1]: 1 opens the valve fully \
             towards extension (supply to the cap side), 0 centres the spool (the legs lock on their oil), -1 towards \
             retraction. Held over each communication step, or interpolated to first order when \
             fmi2SetRealInputDerivatives gave its derivative",
        ); real(inputs.hydraulic),
        PS => V::input(
            "pS", &[], 466, Some("Pa"),
            "Hydraulic supply pressure p_S (gauge; drive = 2). Drop it to 0 to model a pump failure: the supply port \
             then acts as a second tank (no check valve)",
        ); real(parameters.actuators.hydraulic.supply),
        TANK_PRESSURE => hydraulics::tank_pressure(470); real(parameters.actuators.hydraulic.legs.tank_pressure),
        BORE => machine::hydraulic_bore(471); real(parameters.actuators.hydraulic.legs.bore),
        ROD => machine::hydraulic_rod(472); real(parameters.actuators.hydraulic.legs.rod),
        DEAD_VOLUME_A => hydraulics::dead_volume_a(473); real(parameters.actuators.hydraulic.legs.dead_volume_a),
        DEAD_VOLUME_B => hydraulics::dead_volume_b(474); real(parameters.actuators.hydraulic.legs.dead_volume_b),
        BULK_MODULUS => hydraulics::bulk_modulus(475); real(parameters.actuators.hydraulic.legs.bulk_modulus),
        RATED_FLOW => machine::valve_rated_flow(476); real(parameters.actuators.hydraulic.legs.rated_flow),
        RATED_DROP => machine::valve_rated_pressure_drop(477); real(parameters.actuators.hydraulic.legs.rated_pressure_drop),
        VALVE_OMEGA => hydraulics::valve_omega(478); real(parameters.actuators.hydraulic.legs.valve_omega),
        VALVE_DAMPING => hydraulics::valve_damping(479); real(parameters.actuators.hydraulic.legs.valve_damping),
        VALVE_PCR => hydraulics::valve_pcr(480); real(parameters.actuators.hydraulic.legs.pcr),
        VALVE_LEAKAGE => hydraulics::valve_leakage(481); real(parameters.actuators.hydraulic.legs.valve_leakage),
        INTERNAL_LEAKAGE => hydraulics::internal_leakage(482); real(parameters.actuators.hydraulic.legs.internal_leakage),
        AIR_FRACTION => hydraulics::air_fraction(483); real(parameters.actuators.hydraulic.legs.air_fraction),
        AIR_POLYTROPIC => hydraulics::air_polytropic(484); real(parameters.actuators.hydraulic.legs.air_polytropic),
        PA0 => hydraulics::pa0(490); real(parameters.actuators.hydraulic.initial_pa),
        PB0 => hydraulics::pb0(496); real(parameters.actuators.hydraulic.initial_pb),
        PA => V::output(
            "pA", &[6], 510, Some("Pa"), "Cap-side chamber pressure p_A of leg k, gauge (Model Exchange state; 0 \
             unless drive = 2)", &[All(group::DRIVE), SameIndex(group::PA0)],
        ); cached_at(actuators.actuator_states, actuator_state(hydraulic::PA)),
        PB => V::output(
            "pB", &[6], 516, Some("Pa"), "Rod-side chamber pressure p_B of leg k, gauge (Model Exchange state; 0 \
             unless drive = 2)", &[All(group::DRIVE), SameIndex(group::PB0)],
        ); cached_at(actuators.actuator_states, actuator_state(hydraulic::PB)),
        SPOOL => V::output(
            "spool", &[6], 522, Some("1"), "Spool position s_k of leg k's valve, normalised (Model Exchange state; \
             starts centred)", &[],
        ); cached_at(actuators.actuator_states, actuator_state(hydraulic::SPOOL)),
        QSUPPLY => V::output(
            "Qsupply", &[], 528, Some("m3/s"),
            "Total flow drawn from the supply by the six valves, null leakage included (negative when the supply \
             pressure is below the chambers', e.g. after a pump failure)",
            HYDRAULIC_PARAMETERS,
        )
        .depends_on(HYDRAULIC_KNOWNS); cached(input_dependent_outputs.supply_flow),
        PMIN => V::output(
            "pmin", &[], 529, Some("Pa"),
            "Lowest chamber pressure of the hydraulic legs since the start (below -1 bar gauge the oil would \
             cavitate and the model is no longer valid: the FMU logs a warning once per run); 0 unless drive = 2",
            &[All(group::DRIVE), All(group::PA0), All(group::PB0)],
        ); computed,
        WORK_HYDRAULIC => V::output(
            "work.hydraulic", &[], 530, Some("J"),
            "Energy drawn from the hydraulic supply since the start, the integral of sum_k (p_S Q_S - p_T Q_T) \
             (Model Exchange state; E(t) - E(0) = work.F + work.electric + work.hydraulic - work.compression - \
             work.dissipated)",
            &[],
        ); cached_at(actuators.actuator_states, actuator_state(quadrature::WORK_HYDRAULIC)),
        WORK_COMPRESSION => V::output(
            "work.compression", &[], 531, Some("J"),
            "Energy stored by compressing the oil since the start, the integral of sum_k (p_A V_A p_A' + p_B V_B \
             p_B') / beta (Model Exchange state)",
            &[],
        ); cached_at(actuators.actuator_states, actuator_state(quadrature::WORK_COMPRESSION)),
        DER_PA => V::local(
            "der(pA)", &[6], 540, Some("Pa/s"), "Rate of the cap-side pressures (Model Exchange derivative of pA)",
            HYDRAULIC_PARAMETERS,
        )
        .derivative("pA", "pA", 1, HYDRAULIC_KNOWNS); derivative,
        DER_PB => V::local(
            "der(pB)", &[6], 546, Some("Pa/s"), "Rate of the rod-side pressures (Model Exchange derivative of pB)",
            HYDRAULIC_PARAMETERS,
        )
        .derivative("pB", "pB", 1, HYDRAULIC_KNOWNS); derivative,
        DER_SPOOL => V::local(
            "der(spool)", &[6], 552, Some("1/s"), "Spool rate s_k' (Model Exchange state; starts at rest)", &[],
        )
        .derivative("spool", "spool", 1, &[SameIndex(group::DER_SPOOL)]); derivative,
        DER2_SPOOL => V::local(
            "der2(spool)", &[6], 558, Some("1/s2"),
            "Spool acceleration w_v^2 (c_k - s_k) - 2 zeta_v w_v s_k' (Model Exchange derivative of der(spool))",
            SPOOL_PARAMETERS,
        )
        .derivative("der(spool)", "spool", 2, &[SameIndex(group::SPOOL), SameIndex(group::DER_SPOOL), SameIndex(group::VALVE)]); derivative,
        DER_WORK_HYDRAULIC => V::local(
            "der(work.hydraulic)", &[], 564, Some("W"),
            "Power drawn from the hydraulic supply (Model Exchange derivative of work.hydraulic)",
            HYDRAULIC_PARAMETERS,
        )
        .derivative("work.hydraulic", "work.hydraulic", 1, HYDRAULIC_KNOWNS); derivative,
        DER_WORK_COMPRESSION => V::local(
            "der(work.compression)", &[], 565, Some("W"),
            "Compression power of the oil (Model Exchange derivative of work.compression)",
            HYDRAULIC_PARAMETERS,
        )
        .derivative("work.compression", "work.compression", 1, HYDRAULIC_KNOWNS); derivative,
        // The power unit (§10b, hydraulic.supply = 1).
        SUPPLY_MODE => power_unit::supply_mode(570); integer(parameters.actuators.hydraulic.powered),
        PUMP_SPEED => power_unit::pump_speed(571); real(parameters.actuators.hydraulic.pump_speed),
        PUMP_MAX_FLOW => power_unit::max_flow(572); real(parameters.actuators.hydraulic.power_unit.max_flow),
        PUMP_SET_PRESSURE => power_unit::set_pressure(573); real(parameters.actuators.hydraulic.power_unit.set_pressure),
        PUMP_BAND => power_unit::compensator_band(574); real(parameters.actuators.hydraulic.power_unit.compensator_band),
        RELIEF_PRESSURE => power_unit::relief_pressure(575); real(parameters.actuators.hydraulic.power_unit.relief_pressure),
        RELIEF_GAIN => power_unit::relief_gain(576); real(parameters.actuators.hydraulic.power_unit.relief_gain),
        ACCUMULATOR_VOLUME => power_unit::accumulator_volume(577); real(parameters.actuators.hydraulic.power_unit.accumulator_volume),
        ACCUMULATOR_PRECHARGE => power_unit::precharge(578); real(parameters.actuators.hydraulic.power_unit.precharge),
        ACCUMULATOR_POLYTROPIC => power_unit::accumulator_polytropic(579); real(parameters.actuators.hydraulic.power_unit.accumulator_polytropic),
        SUPPLY_VOLUME => power_unit::supply_volume(580); real(parameters.actuators.hydraulic.power_unit.supply_volume),
        SUPPLY_PRESSURE => power_unit::supply_pressure(581, POWER_UNIT_PARAMETERS)
            .depends_on(SUPPLY_PRESSURE_KNOWNS); cached_at(input_dependent_outputs.power_unit, 0),
        PUMP_FLOW => power_unit::pump_flow(582, POWER_UNIT_PARAMETERS)
            .depends_on(PUMP_FLOW_KNOWNS); cached_at(input_dependent_outputs.power_unit, 1),
        RELIEF_FLOW => power_unit::relief_flow(583, POWER_UNIT_PARAMETERS)
            .depends_on(LINE_KNOWNS); cached_at(input_dependent_outputs.power_unit, 2),
        OIL_VOLUME => power_unit::oil_volume(584, POWER_UNIT_PARAMETERS)
            .depends_on(LINE_KNOWNS); cached_at(input_dependent_outputs.power_unit, 3),
        WORK_PUMP => power_unit::pump_work(585); cached_at(actuators.actuator_states, actuator_state(quadrature::WORK_PUMP)),
        LINE_PRESSURE => power_unit::line_pressure(586, POWER_UNIT_START); cached_at(actuators.actuator_states, actuator_state(hydraulic::SUPPLY_PRESSURE)),
        DER_LINE_PRESSURE => power_unit::line_pressure_rate(587, POWER_UNIT_PARAMETERS, POWER_UNIT_KNOWNS); derivative,
        DER_WORK_PUMP => power_unit::pump_power(588, POWER_UNIT_PARAMETERS, POWER_UNIT_KNOWNS); derivative,
    }
}

/// Each actuator's inputs (`drive`'s kind): the group a host sets every step.
pub const ACTUATOR_INPUTS: PerActuator<usize> =
    PerActuator { forces: group::F, electric: group::U, hydraulic: group::VALVE };
