//! The machine of docs/model.md §8 (legs as bodies, joint limits, cylinder friction) against
//! an independent formulation (`common::machine_oracle`: Kane's equations in minimal
//! coordinates, written from the specification alone), and its energy balance.

use crate::common;
use common::dyn_law;

use common::machine_oracle::{
    OracleFriction, OracleInputs, OracleJoints, OracleMachine, OracleState, identity_rotation,
};
use nalgebra::{Matrix3, Vector3};
use stewart_fmu::integration::{Method, SolverSettings};
use stewart_fmu::physics::actuators::HeldForces;
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::legs::bodies::LegBodies;
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::legs::friction::Friction;
use stewart_fmu::physics::legs::joint_limits::JointLimits;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::state::body;
use stewart_fmu::simulation::{PlatformOutputs, PlatformSimulation, Stabilisation};

/// Legs of a 3-tonne simulator's electric actuators: 40 kg cylinders, 15 kg rods.
fn heavy_legs() -> LegBodies {
    LegBodies {
        cylinder_mass: 40.0,
        rod_mass: 15.0,
        cylinder_com: 0.45,
        rod_com: 0.55,
        cylinder_inertia: 2.5,
        rod_inertia: 0.6,
        axial_mass: 0.0,
    }
}

fn oracle_of(legs: &LegBodies, friction: &Friction) -> OracleMachine {
    OracleMachine {
        cylinder_mass: legs.cylinder_mass,
        rod_mass: legs.rod_mass,
        cylinder_com: legs.cylinder_com,
        rod_com: legs.rod_com,
        cylinder_inertia: legs.cylinder_inertia,
        rod_inertia: legs.rod_inertia,
        friction: OracleFriction {
            coulomb: friction.coulomb,
            static_: friction.static_,
            stribeck_velocity: friction.stribeck_velocity,
            smoothing: friction.smoothing,
            viscous: friction.viscous,
        },
        ..OracleMachine::default_stand()
    }
}

/// Joint limits about the neutral pose, as the FMU builds them.
fn joint_limits(base_max: f64, platform_max: f64, stiffness: f64, damping: f64) -> JointLimits {
    let stand = Stand::truck_cabin();
    let r0 = Stand::truck_cabin_neutral_position();
    let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    JointLimits::new(base_max, platform_max, stiffness, damping, n0, &Matrix3::identity())
}

fn simulation(
    start: &BodyState,
    legs: LegBodies,
    friction: Friction,
    joints: Option<JointLimits>,
) -> PlatformSimulation {
    let settings = SolverSettings { method: Method::DormandPrince45, ..SolverSettings::tight() };
    PlatformSimulation::new(Stand::truck_cabin(), *start, settings, Stabilisation::Projection, 0.0)
        .and_then(|s| s.with_end_stops(None))
        .and_then(|s| s.with_machine(legs, friction, joints))
        .expect("valid machine")
}

fn oracle_state(s: &BodyState) -> OracleState {
    let rotation = s.rotation();
    let w = s.angular_velocity_body();
    OracleState {
        r: s.r.into(),
        rotation: std::array::from_fn(|a| std::array::from_fn(|b| rotation[(a, b)])),
        v: s.v.into(),
        w: w.into(),
        currents: [0.0; 6],
        pa: [0.0; 6],
        pb: [0.0; 6],
        spool: [0.0; 6],
        spool_rate: [0.0; 6],
        supply_pressure: 0.0,
        lowest_pressure: f64::INFINITY,
    }
}

/// The largest difference of pose and velocities between the FMU's state and the oracle's.
fn difference(s: &BodyState, o: &OracleState) -> f64 {
    let rotation = s.rotation();
    let w = s.angular_velocity_body();
    let mut worst: f64 = 0.0;
    for a in 0..3 {
        worst = worst.max((s.r[a] - o.r[a]).abs()).max((s.v[a] - o.v[a]).abs()).max((w[a] - o.w[a]).abs());
        for b in 0..3 {
            worst = worst.max((rotation[(a, b)] - o.rotation[a][b]).abs());
        }
    }
    worst
}

/// Leg forces from the legs' lengths and rates at a communication point: the static forces,
/// a leg-length feedback about the neutral legs that keeps the platform from tipping over, and
/// a ripple that keeps it moving.
type LegLaw<'a> = dyn Fn(f64, &[f64; 6], &[f64; 6]) -> [f64; 6] + 'a;

/// Runs both over `steps` communication steps of `h`, each side with the forces its own legs
/// give (`law(t, l, ldot)`, held over the step); returns the largest difference and the
/// platform's largest tilt, rad.
#[allow(clippy::too_many_arguments)]
fn compare(
    start: &BodyState,
    legs: LegBodies,
    friction: Friction,
    joints: Option<JointLimits>,
    oracle: &OracleMachine,
    law: &LegLaw,
    h: f64,
    steps: usize,
) -> (f64, f64) {
    let mut sim = simulation(start, legs, friction, joints);
    let mut reference = oracle_state(start);
    let (mut worst, mut tilt): (f64, f64) = (0.0, 0.0);
    for i in 0..steps {
        let t = i as f64 * h;
        let o = stewart_fmu::simulation::LegOutputs::compute(&sim.form, &sim.state);
        if let Err(e) = sim.advance(dyn_law(&HeldForces::constant(law(t, &o.l, &o.ldot))), t + h) {
            panic!("at t = {t}: {e} (tilt {tilt}, worst {worst:e})");
        }
        let u = law(t, &oracle.leg_lengths(&reference), &oracle.leg_rates(&reference));
        reference = oracle.simulate(&reference, h, 1, &|_| OracleInputs::Forces(u))[1];
        let s = sim.body_state();
        worst = worst.max(difference(&s, &reference));
        tilt = tilt.max(s.e[2].z.clamp(-1.0, 1.0).acos());
    }
    (worst, tilt)
}

/// The feedback of the default controller (`G = 2e5 N/m`, `D = 2e4 N s/m`) about the neutral
/// legs, on top of `held`, with a ripple of relative amplitude `ripple`.
fn feedback(held: [f64; 6], ripple: f64) -> impl Fn(f64, &[f64; 6], &[f64; 6]) -> [f64; 6] {
    let l0 = 1.7550860729486566;
    move |t, l, ldot| {
        std::array::from_fn(|k| {
            held[k] * (1.0 + ripple * (2.0 * t + k as f64).sin()) + 2.0e5 * (l0 - l[k]) - 2.0e4 * ldot[k]
        })
    }
}

fn static_forces(oracle: &OracleMachine) -> [f64; 6] {
    oracle.static_leg_forces(Stand::truck_cabin_neutral_position().into(), identity_rotation())
}

/// Heavy legs, no contact: the FMU's motion agrees with the oracle's to 1e-9 (m, m/s, rad/s,
/// rotation matrix entries) over 3 s, under leg forces held over 10 ms steps.
#[test]
fn heavy_legs_agree_with_the_independent_formulation() {
    let legs = heavy_legs();
    let oracle = oracle_of(&legs, &Friction::default());
    let law = feedback(static_forces(&oracle), 0.3);
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, 0.03),
        Vector3::new(0.05, 0.02, -0.1),
        &rotation_from_angles(&Vector3::new(0.02, -0.03, 0.05)),
        &Vector3::new(0.1, -0.05, 0.2),
    );
    let (worst, tilt) = compare(&start, legs, Friction::default(), None, &oracle, &law, 0.01, 300);
    let _figures = common::figures::print_figures(&format!(
        "heavy legs, 3 s: largest difference from the oracle {worst:.2e}, largest tilt {:.2} deg",
        tilt.to_degrees()
    ));
    assert!(worst < 1e-9, "{worst:e}");
    assert!(tilt > 0.01, "the platform moved ({tilt})");
}

/// The same with cylinder friction (smooth, so no event): agreement to 1e-9.
#[test]
fn heavy_legs_with_friction_agree_with_the_independent_formulation() {
    let legs = heavy_legs();
    let friction = Friction { coulomb: 150.0, static_: 250.0, viscous: 800.0, ..Friction::default() };
    let oracle = oracle_of(&legs, &friction);
    let law = feedback(static_forces(&oracle), 0.3);
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &Matrix3::identity(),
        &Vector3::zeros(),
    );
    let (worst, tilt) = compare(&start, legs, friction, None, &oracle, &law, 0.01, 300);
    let _figures = common::figures::print_figures(&format!(
        "heavy legs with friction, 3 s: largest difference {worst:.2e}, largest tilt {:.2} deg",
        tilt.to_degrees()
    ));
    assert!(worst < 1e-9, "{worst:e}");
}

/// Heavy legs tipping onto their joint limits (open-loop forces with a 5 % ripple per leg, the
/// default limits): the located contacts and the motion on the limits agree too.
#[test]
fn heavy_legs_on_their_joint_limits_agree_with_the_independent_formulation() {
    use stewart_fmu::physics::legs::joint_limits::{
        DEFAULT_BASE_MAX_ANGLE, DEFAULT_DAMPING, DEFAULT_PLATFORM_MAX_ANGLE, DEFAULT_STIFFNESS,
    };
    let legs = heavy_legs();
    let oracle = OracleMachine {
        joints: Some(OracleJoints {
            reference_r: Stand::truck_cabin_neutral_position().into(),
            reference_angles: [0.0; 3],
            base_max: DEFAULT_BASE_MAX_ANGLE,
            platform_max: DEFAULT_PLATFORM_MAX_ANGLE,
            stiffness: DEFAULT_STIFFNESS,
            damping: DEFAULT_DAMPING,
        }),
        ..oracle_of(&legs, &Friction::default())
    };
    let held = static_forces(&oracle);
    let law = move |t: f64, _: &[f64; 6], _: &[f64; 6]| -> [f64; 6] {
        std::array::from_fn(|k| held[k] * (1.0 + 0.05 * (2.0 * t + (k + 1) as f64).sin()))
    };
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &Matrix3::identity(),
        &Vector3::zeros(),
    );
    let limits = joint_limits(DEFAULT_BASE_MAX_ANGLE, DEFAULT_PLATFORM_MAX_ANGLE, DEFAULT_STIFFNESS, DEFAULT_DAMPING);
    let (worst, tilt) = compare(&start, legs, Friction::default(), Some(limits), &oracle, &law, 0.01, 300);
    let _figures = common::figures::print_figures(&format!(
        "heavy legs on their joint limits, 3 s: largest difference {worst:.2e}, largest tilt {:.2} deg",
        tilt.to_degrees()
    ));
    assert!(tilt > 0.4, "the platform reached its joint limits ({} deg)", tilt.to_degrees());
    assert!(worst < 1e-9, "{worst:e}");
}

/// The joints' forces on the platform and the legs' inertia: the FMU's `jointForce` against
/// the oracle's own leg balances, at states on and off the joint limits.
#[test]
fn joint_forces_agree_with_the_independent_formulation() {
    let legs = heavy_legs();
    let friction = Friction { coulomb: 100.0, static_: 200.0, viscous: 300.0, ..Friction::default() };
    let (base_max, platform_max) = (0.12, 0.15);
    let limits = joint_limits(base_max, platform_max, 1e6, 5e4);
    let oracle = OracleMachine {
        joints: Some(OracleJoints {
            reference_r: Stand::truck_cabin_neutral_position().into(),
            reference_angles: [0.0; 3],
            base_max,
            platform_max,
            stiffness: 1e6,
            damping: 5e4,
        }),
        ..oracle_of(&legs, &friction)
    };
    let u = [6100.0, 5800.0, 6400.0, 5500.0, 6000.0, 6300.0];
    let mut worst: f64 = 0.0;
    let mut contacts = 0;
    for (dz, angles, w) in [
        (0.0, Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.0)),
        (0.05, Vector3::new(0.05, -0.03, 0.1), Vector3::new(0.4, -0.3, 0.5)),
        (-0.1, Vector3::new(0.25, 0.1, -0.05), Vector3::new(-0.6, 0.2, 0.3)),
        (0.1, Vector3::new(-0.05, 0.3, 0.2), Vector3::new(0.2, 0.8, -0.4)),
    ] {
        let state = BodyState::from_pose(
            Stand::truck_cabin_neutral_position() + Vector3::new(0.02, -0.01, dz),
            Vector3::new(0.1, -0.2, 0.3),
            &rotation_from_angles(&angles),
            &w,
        );
        let sim = simulation(&state, legs, friction, Some(limits));
        let ours = sim.form.joint_forces(body(&sim.state), &u);
        let theirs = oracle.joint_forces(&oracle_state(&state), &OracleInputs::Forces(u));
        let outputs = PlatformOutputs::compute(&sim.form, &sim.state, Some(&u));
        let (tb, ta) = oracle.joint_angles(&oracle_state(&state));
        for k in 0..6 {
            contacts += usize::from(tb[k] > base_max) + usize::from(ta[k] > platform_max);
            worst = worst.max((outputs.theta_b[k] - tb[k]).abs() * 1e4).max((outputs.theta_a[k] - ta[k]).abs() * 1e4);
            for c in 0..3 {
                worst = worst.max((ours[k][c] - theirs[k][c]).abs() / 1e4);
                assert_eq!(outputs.joint_force[k][c], ours[k][c]);
            }
        }
    }
    let _figures = common::figures::print_figures(&format!(
        "joint forces and angles against the oracle: largest difference {worst:.2e} (of 1e4 N, 1e-4 rad); {contacts} joints beyond their limits"
    ));
    assert!(contacts >= 4, "the joint limits were exercised ({contacts})");
    assert!(worst < 1e-9, "{worst:e}");
}

/// Heavier legs need larger forces: the equilibrium forces at the neutral pose of the
/// controller's direct problem (legs with mass) against the oracle's independent statics, and
/// the platform released at rest under them stays put.
#[test]
fn heavier_legs_need_larger_forces_and_the_static_forces_hold_the_platform() {
    use stewart_fmu::physics::body::kinematics::PoseTrajectoryPoint;
    use stewart_fmu::physics::direct_problem::solve_direct_problem;
    let legs = heavy_legs();
    let oracle = oracle_of(&legs, &Friction::default());
    let theirs = static_forces(&oracle);
    let point = PoseTrajectoryPoint::at_rest(Stand::truck_cabin_neutral_position(), Matrix3::identity());
    let ours = solve_direct_problem(&Stand::truck_cabin(), &legs, &point).expect("regular").forces;
    let massless = solve_direct_problem(&Stand::truck_cabin(), &LegBodies::default(), &point).expect("regular").forces;
    for k in 0..6 {
        println!(
            "leg {}: {:.6} N with massless legs, {:.6} N with heavy legs (oracle {:.6} N)",
            k + 1,
            massless[k],
            ours[k],
            theirs[k]
        );
        assert!((ours[k] - theirs[k]).abs() < 1e-9 * theirs[k], "{} vs {}", ours[k], theirs[k]);
        assert!(ours[k] > massless[k] + 100.0);
    }
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &Matrix3::identity(),
        &Vector3::zeros(),
    );
    let mut sim = simulation(&start, legs, Friction::default(), None);
    sim.advance(dyn_law(&HeldForces::constant(ours)), 0.1).expect("steps");
    let drift = (sim.body_state().r - start.r).norm();
    println!("released at rest under the static forces: drift {drift:.2e} m in 0.1 s");
    assert!(drift < 1e-9, "{drift:e}");
}

/// The energy of the whole machine (platform, legs, stops, joint limits): conserved through
/// contacts with elastic stops and joint limits and no friction; with damping and friction,
/// `E(t) - E(0) = work.F - work.dissipated`.
#[test]
fn the_machines_energy_balance_holds_through_contacts() {
    for damped in [false, true] {
        let legs = heavy_legs();
        let (friction, stops, joints) = if damped {
            (
                Friction { coulomb: 200.0, static_: 300.0, viscous: 500.0, ..Friction::default() },
                EndStops::default(),
                joint_limits(0.2, 0.3, 1e6, 5e4),
            )
        } else {
            (Friction::default(), EndStops { damping: 0.0, ..EndStops::default() }, joint_limits(0.2, 0.3, 1e6, 0.0))
        };
        let start = BodyState::from_pose(
            Stand::truck_cabin_neutral_position() + Vector3::new(0.0, 0.0, -0.05),
            Vector3::new(0.3, 0.0, -0.5),
            &rotation_from_angles(&Vector3::new(0.15, -0.1, 0.0)),
            &Vector3::new(0.8, -0.5, 0.3),
        );
        let settings = SolverSettings { rel_tol: 1e-11, abs_tol: 1e-13, ..SolverSettings::default() };
        let mut sim = PlatformSimulation::new(Stand::truck_cabin(), start, settings, Stabilisation::Projection, 0.0)
            .and_then(|s| s.with_end_stops(Some(stops)))
            .and_then(|s| s.with_machine(legs, friction, Some(joints)))
            .expect("valid");
        let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
        let (mut worst, mut contacts, mut dissipated) = (0.0f64, 0, 0.0);
        for i in 0..300 {
            let t = i as f64 * 0.01;
            let u = if damped { [2000.0 * (t * 3.0).sin(); 6] } else { [0.0; 6] };
            sim.advance(dyn_law(&HeldForces::constant(u)), t + 0.01).expect("the motion goes on");
            contacts += sim.crossings.as_slice().len();
            let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
            let balance = o.energy - e0 - (o.work_of_forces - o.dissipated_energy);
            worst = worst.max(balance.abs() / e0);
            dissipated = o.dissipated_energy;
        }
        let _figures = common::figures::print_figures(&format!(
            "damped {damped}: largest |E - E0 - (work.F - work.dissipated)| / E0 = {worst:.2e} over 3 s, {contacts} \
             contacts located, {dissipated:.1} J dissipated"
        ));
        assert!(contacts >= 4, "contacts with stops or joint limits ({contacts})");
        assert!(worst < 1e-8, "{worst:e}");
        assert_eq!(dissipated > 1.0, damped);
    }
}
