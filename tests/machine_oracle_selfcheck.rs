//! Self-checks of the independent machine oracle (tests/common/machine_oracle.rs): agreement
//! with the rigid-body Newton-Euler oracle for massless legs, energy conservation and the
//! energy balance with drives, statics, the equations of motion against Lagrange's equations
//! by finite differences of the energies, the joint forces against the platform's
//! Newton-Euler balance, the hydraulic servo legs of SPEC §10 (power balance per leg,
//! energy balance over a run, holding pressures), and SPEC §10b's oil with air and power unit
//! (section 10 to the bit without them, energy balances through a pump failure, no pressure
//! below zero absolute, the accumulator's discharge and the oil's mass balance).

use crate::common;

use common::machine_oracle::{
    ATMOSPHERIC_PRESSURE, EQUILIBRIUM_LEG_FORCE, NEUTRAL_R, OracleDrives, OracleFriction, OracleHydraulics,
    OracleInputs, OracleJoints, OracleMachine, OraclePowerUnit, OracleState, OracleStops, OracleWork,
    identity_rotation, rotation_from_angles,
};
use common::newton_euler::{NeState, NewtonEuler};
use common::rng::Rng;
use nalgebra::{Matrix3, UnitQuaternion, Vector3, Vector6};
use std::cell::Cell;
use stewart_fmu::physics::stand::Stand;

fn m3(a: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| a[i][j])
}
fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}
fn add3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Legs with mass (the brief's example numbers).
fn heavy(mut m: OracleMachine) -> OracleMachine {
    m.cylinder_mass = 40.0;
    m.rod_mass = 15.0;
    m.cylinder_com = 0.4;
    m.rod_com = 0.4;
    m.cylinder_inertia = 2.0;
    m.rod_inertia = 0.5;
    m
}

fn neutral_lengths(m: &OracleMachine) -> [f64; 6] {
    m.leg_lengths(&OracleState::at_rest(NEUTRAL_R, identity_rotation()))
}

fn tilted_moving() -> OracleState {
    OracleState {
        r: add3(NEUTRAL_R, [0.02, -0.03, 0.05]),
        rotation: rotation_from_angles([0.1, -0.05, 0.2]),
        v: [0.1, -0.05, 0.08],
        w: [0.05, 0.1, -0.12],
        ..OracleState::at_rest(NEUTRAL_R, identity_rotation())
    }
}

// ------------------------------------------------------------------------------------------
// 1. Massless legs: the rigid-body Newton-Euler oracle
// ------------------------------------------------------------------------------------------

#[test]
fn massless_legs_agree_with_newton_euler() {
    let oracle = OracleMachine::default_stand();
    let stand = Stand::truck_cabin();
    // The SPEC §2 transcription against the crate's default stand.
    assert_eq!(oracle.mass, stand.mass);
    assert_eq!(oracle.gravity, stand.gravity);
    assert!((v3(oracle.inertia) - Vector3::from(stand.inertia)).norm() < 1e-12);
    for k in 0..6 {
        let db = (v3(oracle.base_joints[k]) - stand.base_joints[k]).norm();
        let da = (v3(oracle.platform_joints[k]) - stand.platform_joints[k]).norm();
        assert!(db < 1e-14 && da < 1e-14, "leg {k}: joints differ by {db:e}, {da:e}");
    }

    let (h, steps) = (1e-3, 3000);
    let u0 = EQUILIBRIUM_LEG_FORCE * oracle.mass * oracle.gravity;
    let forces = move |t: f64| -> [f64; 6] { std::array::from_fn(|k| u0 * (1.0 + 0.01 * (2.0 * t + k as f64).sin())) };
    for (name, start) in [
        ("neutral at rest", OracleState::at_rest(NEUTRAL_R, identity_rotation())),
        ("tilted and moving", tilted_moving()),
    ] {
        let t0 = std::time::Instant::now();
        let run = oracle.simulate(&start, h, steps, &|t| OracleInputs::Forces(forces(t)));
        let elapsed = t0.elapsed().as_secs_f64();

        let held = Cell::new([0.0; 6]);
        let law = |_t: f64, _l: &[f64; 6], _ld: &[f64; 6]| held.get();
        let ne = NewtonEuler { stand: stand.clone(), law: &law };
        let q = UnitQuaternion::from_matrix(&m3(&start.rotation));
        let mut s = NeState { r: v3(start.r), v: v3(start.v), q: *q.quaternion(), w: v3(start.w) };
        let (mut dr, mut drot, mut dv, mut dw) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..steps {
            let t = i as f64 * h;
            held.set(forces(t));
            ne.integrate(&mut s, t, t + h, 100);
            let o = &run[i + 1];
            dr = dr.max((v3(o.r) - s.r).norm());
            drot = drot.max((m3(&o.rotation) - s.rotation()).abs().max());
            dv = dv.max((v3(o.v) - s.v).norm());
            dw = dw.max((v3(o.w) - s.w).norm());
        }
        let last = run.last().unwrap();
        println!(
            "[1] {name}: over 3 s max |dr| = {dr:.3e} m, max |dR| = {drot:.3e}, max |dv| = {dv:.3e} m/s, max |dw| = {dw:.3e} rad/s \
             (final r = {:?}; oracle {elapsed:.1} s)",
            last.r
        );
        assert!(dr < 1e-9 && drot < 1e-9 && dv < 1e-9 && dw < 1e-9, "{name}: oracle and Newton-Euler differ");
    }
}

// ------------------------------------------------------------------------------------------
// 2. Energy conservation: heavy legs, elastic stops and joint limits, springs
// ------------------------------------------------------------------------------------------

#[test]
fn energy_conserved_with_heavy_legs_stops_and_joint_limits() {
    let mut m = heavy(OracleMachine::default_stand());
    let l0 = neutral_lengths(&m);
    m.stops =
        Some(OracleStops { lmin: l0.map(|l| l - 0.03), lmax: l0.map(|l| l + 0.03), stiffness: 2e6, damping: 0.0 });
    m.joints = Some(OracleJoints {
        reference_r: NEUTRAL_R,
        reference_angles: [0.0; 3],
        base_max: 0.025,
        platform_max: 0.03,
        stiffness: 2e5,
        damping: 0.0,
    });
    // Springs in equilibrium at the neutral pose (with the legs' weight).
    let c = 2e5;
    let u_static = m.static_leg_forces(NEUTRAL_R, identity_rotation());
    let rest: [f64; 6] = std::array::from_fn(|k| l0[k] + u_static[k] / c);
    let springs = OracleInputs::Springs { stiffness: c, rest };
    let spring_energy = |s: &OracleState| -> f64 {
        let l = m.leg_lengths(s);
        (0..6).map(|k| 0.5 * c * (l[k] - rest[k]).powi(2)).sum()
    };
    let start = OracleState {
        r: NEUTRAL_R,
        rotation: identity_rotation(),
        v: [0.35, -0.25, 0.2],
        w: [0.25, -0.2, 0.3],
        ..OracleState::at_rest(NEUTRAL_R, identity_rotation())
    };
    let t0 = std::time::Instant::now();
    let run = m.simulate_with_work(&start, 1e-3, 3000, &|_| springs);
    let elapsed = t0.elapsed().as_secs_f64();
    let e0 = m.energy(&start) + spring_energy(&start);
    let k0 = m.kinetic_energy(start.r, start.rotation, start.v, start.w);
    let (mut worst, mut stop_steps, mut joint_steps) = (0.0f64, 0, 0);
    let (mut worst_w, mut max_pen, mut max_delta) = (0.0f64, 0.0f64, 0.0f64);
    let (s, j) = (m.stops.unwrap(), m.joints.unwrap());
    for (st, work) in &run {
        let e = m.energy(st) + spring_energy(st);
        worst = worst.max((e - e0).abs());
        // The springs' work is minus the change of their energy: E_machine(t) - E_machine(0) = W.
        worst_w = worst_w.max((m.energy(st) - m.energy(&start) - work.forces).abs());
        let l = m.leg_lengths(st);
        let pen = (0..6).map(|k| (s.lmin[k] - l[k]).max(l[k] - s.lmax[k])).fold(f64::MIN, f64::max);
        max_pen = max_pen.max(pen);
        if pen > 0.0 {
            stop_steps += 1;
        }
        let (tb, ta) = m.joint_angles(st);
        let d = (0..6).map(|k| (tb[k] - j.base_max).max(ta[k] - j.platform_max)).fold(f64::MIN, f64::max);
        max_delta = max_delta.max(d);
        if d > 0.0 {
            joint_steps += 1;
        }
        assert!(worst_w.is_finite());
    }
    println!(
        "[2] energy over 3 s: E0 = {e0:.6} J, K0 = {k0:.3} J, max |E - E0| = {worst:.3e} J = {:.3e} of E0 = {:.3e} of K0; \
         |dE_machine - W_springs| <= {worst_w:.3e} J; samples in stop contact {stop_steps}/3001 (max penetration {max_pen:.4} m), \
         beyond a joint limit {joint_steps}/3001 (max {max_delta:.4} rad); {elapsed:.1} s",
        worst / e0.abs(),
        worst / k0
    );
    assert!(stop_steps > 100 && joint_steps > 100, "the run must reach the stops and joint limits");
    assert!(worst / e0.abs() < 1e-9, "energy drift {worst:e} J");
    assert!(worst_w / e0.abs() < 1e-9);

    // The integration error: the same run with twice the RK4 substep (the contacts' kinks
    // located by the event location, so RK4's h^4 holds through the contacts).
    let mut coarse = m.clone();
    coarse.max_step = 2.0 * m.max_step;
    let run2 = coarse.simulate(&start, 1e-3, 3000, &|_| springs);
    let (mut dpose, mut dvel) = (0.0f64, 0.0f64);
    for ((a, _), b) in run.iter().zip(&run2) {
        dpose = dpose.max((v3(a.r) - v3(b.r)).norm()).max((m3(&a.rotation) - m3(&b.rotation)).abs().max());
        dvel = dvel.max((v3(a.v) - v3(b.v)).norm()).max((v3(a.w) - v3(b.w)).norm());
    }
    println!(
        "[2] substep {} s against {} s over 3 s: max pose difference {dpose:.3e}, velocity difference {dvel:.3e}",
        m.max_step, coarse.max_step
    );
    assert!(dpose < 1e-10 && dvel < 1e-9);
}

// ------------------------------------------------------------------------------------------
// 3. Energy balance with electric drives
// ------------------------------------------------------------------------------------------

fn driven_machine(kt: f64, ke: f64) -> OracleMachine {
    let mut m = heavy(OracleMachine::default_stand());
    let l0 = neutral_lengths(&m);
    m.stops =
        Some(OracleStops { lmin: l0.map(|l| l - 0.03), lmax: l0.map(|l| l + 0.03), stiffness: 2e6, damping: 2e4 });
    m.joints = Some(OracleJoints {
        reference_r: NEUTRAL_R,
        reference_angles: [0.0; 3],
        base_max: 0.01,
        platform_max: 0.012,
        stiffness: 2e5,
        damping: 2e3,
    });
    m.friction =
        OracleFriction { coulomb: 30.0, static_: 50.0, stribeck_velocity: 0.01, smoothing: 0.002, viscous: 200.0 };
    m.drives = Some(OracleDrives {
        resistance: 0.5,
        inductance: 5e-3,
        ke,
        kt,
        rotor_inertia: 2e-4,
        damping: 1e-4,
        gear_ratio: 1.0,
        screw_lead: 0.01,
    });
    m
}

fn drive_balance(kt: f64, ke: f64, steps: usize) -> (f64, f64, f64, usize, usize) {
    let m = driven_machine(kt, ke);
    let d = m.drives.unwrap();
    let n = d.n();
    let u = m.static_leg_forces(NEUTRAL_R, identity_rotation());
    let i0: [f64; 6] = std::array::from_fn(|k| u[k] / (n * d.kt));
    let u0: [f64; 6] = std::array::from_fn(|k| d.resistance * i0[k]);
    let start = OracleState { currents: i0, ..OracleState::at_rest(NEUTRAL_R, identity_rotation()) };
    // Holding voltage plus a different swing per leg.
    let profile = move |t: f64| {
        OracleInputs::Voltages(std::array::from_fn(|k| {
            u0[k] + 25.0 * (2.0 + 0.3 * k as f64).min(3.0) / 2.0 * (2.0 * t + k as f64).sin()
        }))
    };
    let run = m.simulate_with_work(&start, 1e-3, steps, &profile);
    let e0 = m.energy(&start);
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    let (mut stop_steps, mut joint_steps) = (0, 0);
    let (s, j) = (m.stops.unwrap(), m.joints.unwrap());
    for (st, w) in &run {
        let balance = m.energy(st) - e0 - (w.forces + w.electric - w.dissipated);
        worst = worst.max(balance.abs());
        scale = scale.max(w.electric.abs()).max(w.dissipated.abs());
        let l = m.leg_lengths(st);
        if (0..6).any(|k| l[k] < s.lmin[k] || l[k] > s.lmax[k]) {
            stop_steps += 1;
        }
        let (tb, ta) = m.joint_angles(st);
        if (0..6).any(|k| tb[k] > j.base_max || ta[k] > j.platform_max) {
            joint_steps += 1;
        }
    }
    let last = run.last().unwrap();
    println!(
        "[3] kt = {kt}, ke = {ke}, {:.1} s: E0 = {e0:.3} J, W_electric = {:.3} J, W_dissipated = {:.3} J, E - E0 = {:.3} J, \
         max |E - E0 - W_el + W_diss| = {worst:.3e} J = {:.3e} of E0 = {:.3e} of max work; in stop contact {stop_steps}, beyond joint limits {joint_steps} samples; final I = {:?}",
        steps as f64 * 1e-3,
        last.1.electric,
        last.1.dissipated,
        m.energy(&last.0) - e0,
        worst / e0.abs(),
        worst / scale,
        last.0.currents.map(|i| (i * 100.0).round() / 100.0)
    );
    (worst / e0.abs(), worst / scale, scale, stop_steps, joint_steps)
}

#[test]
fn energy_balance_with_drives() {
    let (rel_e0, rel_work, scale, stops, joints) = drive_balance(0.5, 0.5, 3000);
    assert!(scale > 100.0 && stops > 50 && joints > 50, "the run must do work and reach stops and joint limits");
    assert!(rel_e0 < 1e-8 && rel_work < 1e-8);
    // The conversion mismatch (ke - kt) omega I counted as dissipated keeps the balance.
    let (rel_e0, rel_work, _, _, _) = drive_balance(0.5, 0.55, 1000);
    assert!(rel_e0 < 1e-8 && rel_work < 1e-8);
}

// ------------------------------------------------------------------------------------------
// 4. Statics
// ------------------------------------------------------------------------------------------

#[test]
fn statics() {
    let m = OracleMachine::default_stand();
    let u = m.static_leg_forces(NEUTRAL_R, identity_rotation());
    let u0 = EQUILIBRIUM_LEG_FORCE * m.mass * m.gravity;
    let worst = u.iter().map(|x| (x / u0 - 1.0).abs()).fold(0.0, f64::max);
    println!("[4] massless legs, neutral pose: u = {u:?}, 0.2005 M g = {u0}, max relative error {worst:.3e}");
    assert!(worst < 1e-10);
    let l = neutral_lengths(&m);
    println!("[4] neutral leg lengths {l:?} (SPEC: 1.7550860729486566)");
    assert!(l.iter().all(|x| (x - 1.7550860729486566).abs() < 1e-13));

    let m = heavy(m);
    for (name, r, rot) in [
        ("neutral", NEUTRAL_R, identity_rotation()),
        ("offset and tilted", add3(NEUTRAL_R, [0.03, -0.02, 0.04]), rotation_from_angles([0.06, -0.04, 0.1])),
    ] {
        let u = m.static_leg_forces(r, rot);
        let start = OracleState::at_rest(r, rot);
        let (vd, wd) = m.accelerations(&start, &OracleInputs::Forces(u));
        let acc = v3(vd).norm().max(v3(wd).norm());
        let run = m.simulate(&start, 1e-3, 100, &|_| OracleInputs::Forces(u));
        let drift = run.iter().map(|s| (v3(s.r) - v3(r)).norm()).fold(0.0, f64::max);
        let drift_rot = run.iter().map(|s| (m3(&s.rotation) - m3(&rot)).abs().max()).fold(0.0, f64::max);
        println!(
            "[4] heavy legs, {name}: u = {u:?} (u/u0 - 1 = {:?}); |accelerations| at t = 0: {acc:.3e}; drift over 0.1 s: {drift:.3e} m, rotation {drift_rot:.3e}",
            u.map(|x| ((x / u0 - 1.0) * 1e6).round() / 1e6)
        );
        assert!(acc < 1e-9 && drift < 1e-8 && drift_rot < 1e-8);
    }
}

// ------------------------------------------------------------------------------------------
// 5. The equations of motion against Lagrange's equations (finite differences of T and V)
// ------------------------------------------------------------------------------------------

/// `exp([phi]x)` (Rodrigues) and the right Jacobian `J_r(phi)` (`R^T R' = [J_r phi']x`).
fn exp_and_jr(phi: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let th = phi.norm();
    let k = Matrix3::new(0.0, -phi.z, phi.y, phi.z, 0.0, -phi.x, -phi.y, phi.x, 0.0);
    let (a, b, c, d) = if th < 1e-3 {
        let t2 = th * th;
        (
            1.0 - t2 / 6.0 + t2 * t2 / 120.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0,
        )
    } else {
        (th.sin() / th, (1.0 - th.cos()) / (th * th), (1.0 - th.cos()) / (th * th), (th - th.sin()) / (th * th * th))
    };
    (Matrix3::identity() + k * a + k * k * b, Matrix3::identity() - k * c + k * k * d)
}

fn arr(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
}

/// Residual of Lagrange's equations in the chart `q = (r, phi)`, `R = R0 exp([phi]x)`, at
/// `phi = 0`, with the oracle's accelerations; relative to `M g`.
fn lagrange_residual(m: &OracleMachine, s: &OracleState, inputs: &OracleInputs) -> f64 {
    // Central differences at two steps, combined by Richardson extrapolation (the stiff
    // contact potentials make the h^2 term visible at 1e-9).
    let (r1, terms) = lagrange_residual_at(m, s, inputs, 2e-5);
    let (r2, _) = lagrange_residual_at(m, s, inputs, 1e-5);
    let r = (r2 * 4.0 - r1) / 3.0;
    let scale = m.mass * m.gravity;
    let fmt = |x: &Vector6<f64>| {
        x.map(|x| x / scale).as_slice().iter().map(|x| format!("{x:.1e}")).collect::<Vec<_>>().join(", ")
    };
    println!(
        "    {terms}\n    residual / (M g): eps 2e-5 [{}], eps 1e-5 [{}], extrapolated [{}]",
        fmt(&r1),
        fmt(&r2),
        fmt(&r)
    );
    r.amax() / scale
}

fn lagrange_residual_at(m: &OracleMachine, s: &OracleState, inputs: &OracleInputs, eps: f64) -> (Vector6<f64>, String) {
    let r0 = v3(s.r);
    let rot0 = m3(&s.rotation);
    let at = |q: &Vector6<f64>| -> ([f64; 3], [[f64; 3]; 3], Matrix3<f64>) {
        let (e, jr) = exp_and_jr(&Vector3::new(q[3], q[4], q[5]));
        ((r0 + Vector3::new(q[0], q[1], q[2])).into(), arr(&(rot0 * e)), jr)
    };
    let t = |q: &Vector6<f64>, qd: &Vector6<f64>| -> f64 {
        let (r, rot, jr) = at(q);
        let w = jr * Vector3::new(qd[3], qd[4], qd[5]);
        m.kinetic_energy(r, rot, [qd[0], qd[1], qd[2]], w.into())
    };
    let vpot = |q: &Vector6<f64>| -> f64 {
        let (r, rot, _) = at(q);
        m.potential_energy(r, rot)
    };
    let e = |i: usize| Vector6::from_fn(|j, _| if i == j { 1.0 } else { 0.0 });
    // (M(q) x)_i by polarisation of the quadratic form T(q, .).
    let m_times = |q: &Vector6<f64>, x: &Vector6<f64>| -> Vector6<f64> {
        Vector6::from_fn(|i, _| t(q, &(x + e(i))) - t(q, x) - t(q, &e(i)))
    };
    let q = Vector6::zeros();
    let qd = Vector6::new(s.v[0], s.v[1], s.v[2], s.w[0], s.w[1], s.w[2]);
    let (vd, wd) = m.accelerations(s, inputs);
    let qdd = Vector6::new(vd[0], vd[1], vd[2], wd[0], wd[1], wd[2]);
    let mdot_qd = (m_times(&(q + qd * eps), &qd) - m_times(&(q - qd * eps), &qd)) / (2.0 * eps);
    let dt_dq = Vector6::from_fn(|i, _| (t(&(q + e(i) * eps), &qd) - t(&(q - e(i) * eps), &qd)) / (2.0 * eps));
    let dv_dq = Vector6::from_fn(|i, _| (vpot(&(q + e(i) * eps)) - vpot(&(q - e(i) * eps))) / (2.0 * eps));
    // Non-conservative generalised forces: axial forces (actuator, friction, stop damping)
    // through dl/dq, joint-limit damping through dtheta/dq.
    let f = m.leg_forces(s, inputs);
    let lengths = |q: &Vector6<f64>| {
        let (r, rot, _) = at(q);
        m.leg_lengths(&OracleState::at_rest(r, rot))
    };
    let angles = |q: &Vector6<f64>| {
        let (r, rot, _) = at(q);
        m.joint_angles(&OracleState::at_rest(r, rot))
    };
    let mut q_nc = Vector6::zeros();
    for i in 0..6 {
        let (lp, lm) = (lengths(&(q + e(i) * eps)), lengths(&(q - e(i) * eps)));
        let ((bp, ap), (bm, am)) = (angles(&(q + e(i) * eps)), angles(&(q - e(i) * eps)));
        for k in 0..6 {
            let axial = f.actuator[k] + f.friction[k] + f.stop_damping[k];
            q_nc[i] += axial * (lp[k] - lm[k]) / (2.0 * eps);
            q_nc[i] -= f.base_damping[k] * (bp[k] - bm[k]) / (2.0 * eps)
                + f.platform_damping[k] * (ap[k] - am[k]) / (2.0 * eps);
        }
    }
    let residual = m_times(&q, &qdd) + mdot_qd - dt_dq + dv_dq - q_nc;
    let terms = format!(
        "terms: |M qdd| = {:.3e}, |Mdot qd| = {:.3e}, |dT/dq| = {:.3e}, |dV/dq| = {:.3e}, |Q_nc| = {:.3e}",
        m_times(&q, &qdd).norm(),
        mdot_qd.norm(),
        dt_dq.norm(),
        dv_dq.norm(),
        q_nc.norm()
    );
    (residual, terms)
}

/// A fast-moving tilted state with two stops and some joint limits in contact (all at least
/// 1e-3 from a contact's onset, so that the finite differences see smooth energies).
fn contact_state(mut m: OracleMachine) -> (OracleMachine, OracleState) {
    let s = OracleState {
        r: add3(NEUTRAL_R, [0.05, -0.04, 0.03]),
        rotation: rotation_from_angles([0.08, -0.06, 0.12]),
        v: [0.4, -0.3, 0.25],
        w: [0.3, -0.4, 0.5],
        currents: [10.0, -5.0, 20.0, 15.0, 0.0, 8.0],
        ..OracleState::at_rest(NEUTRAL_R, identity_rotation())
    };
    let l = m.leg_lengths(&s);
    let mut lmin = l.map(|x| x - 0.05);
    let mut lmax = l.map(|x| x + 0.05);
    lmin[0] = l[0] + 0.01; // below lmin
    lmax[3] = l[3] - 0.008; // above lmax
    m.stops = Some(OracleStops { lmin, lmax, stiffness: 2e6, damping: 3e4 });
    let mut j = OracleJoints {
        reference_r: NEUTRAL_R,
        reference_angles: [0.0; 3],
        base_max: 0.0,
        platform_max: 0.0,
        stiffness: 2e5,
        damping: 3e3,
    };
    m.joints = Some(j);
    let (tb, ta) = m.joint_angles(&s);
    // The maxima between the sorted angles, so that some legs are beyond and all clear.
    let mid = |x: [f64; 6]| {
        let mut y = x;
        y.sort_by(|a, b| a.partial_cmp(b).unwrap());
        (y[2] + y[3]) / 2.0
    };
    j.base_max = mid(tb);
    j.platform_max = mid(ta);
    m.joints = Some(j);
    let clear = (0..6).map(|k| (tb[k] - j.base_max).abs().min((ta[k] - j.platform_max).abs())).fold(f64::MAX, f64::min);
    println!(
        "    joint angles thetaB {tb:?}, thetaA {ta:?}; maxima {} {}; closest to an onset {clear:.2e} rad",
        j.base_max, j.platform_max
    );
    assert!(clear > 1e-3);
    m.friction =
        OracleFriction { coulomb: 30.0, static_: 50.0, stribeck_velocity: 0.01, smoothing: 0.002, viscous: 200.0 };
    (m, s)
}

#[test]
fn equations_of_motion_satisfy_lagrange() {
    let (m, s) = contact_state(heavy(OracleMachine::default_stand()));
    let u = [5000.0, 6000.0, 5500.0, 7000.0, 6500.0, 4000.0];
    println!("[5] heavy legs, stops, joint limits, friction, leg forces:");
    let res_forces = lagrange_residual(&m, &s, &OracleInputs::Forces(u));
    println!("[5] -> max |residual| / (M g) = {res_forces:.3e}");

    let mut md = m.clone();
    md.drives = driven_machine(0.5, 0.5).drives;
    println!("[5] the same with drives (rotor inertia), voltages:");
    let res_drives = lagrange_residual(&md, &s, &OracleInputs::Voltages([10.0, -20.0, 5.0, 30.0, 0.0, 12.0]));
    println!("[5] -> max |residual| / (M g) = {res_drives:.3e}");

    let mut ml = OracleMachine::default_stand();
    ml.cylinder_mass = 60.0;
    ml.rod_mass = 25.0;
    ml.cylinder_com = 0.7;
    ml.rod_com = 0.2;
    ml.cylinder_inertia = 8.0;
    ml.rod_inertia = 1.0;
    println!("[5] other leg parameters, fast (w = 2..4 rad/s), no contacts, springs:");
    let fast = OracleState { v: [1.0, -1.2, 0.7], w: [2.0, -3.0, 4.0], ..tilted_moving() };
    let res_other = lagrange_residual(&ml, &fast, &OracleInputs::Springs { stiffness: 1e5, rest: [1.8; 6] });
    println!("[5] -> max |residual| / (M g) = {res_other:.3e}");
    assert!(res_forces < 1e-9 && res_drives < 1e-9 && res_other < 1e-9);
}

// ------------------------------------------------------------------------------------------
// 6. Joint forces: the platform's own Newton-Euler balance
// ------------------------------------------------------------------------------------------

#[test]
fn joint_forces_balance_the_platform() {
    let check = |name: &str, m: &OracleMachine, s: &OracleState, inputs: &OracleInputs| -> f64 {
        let g = m.joint_forces(s, inputs);
        let mp = m.platform_joint_moments(s, inputs);
        let (vd, wd) = m.accelerations(s, inputs);
        let rot = m3(&s.rotation);
        let j = v3(m.inertia);
        let w = v3(s.w);
        let mut force = Vector3::new(0.0, 0.0, -m.mass * m.gravity);
        let mut moment = Vector3::zeros();
        for k in 0..6 {
            force += v3(g[k]);
            moment += (rot * v3(m.platform_joints[k])).cross(&v3(g[k])) + v3(mp[k]);
        }
        let lin = (force - v3(vd) * m.mass).norm();
        let ang = (rot.transpose() * moment - (j.component_mul(&v3(wd)) + w.cross(&j.component_mul(&w)))).norm();
        let rel = lin.max(ang) / (m.mass * m.gravity);
        let gmax = g.iter().map(|x| v3(*x).norm()).fold(0.0, f64::max);
        println!(
            "[6] {name}: |M v' - sum G + M g ez| = {lin:.3e} N, |J w' + w x J w - L| = {ang:.3e} N m (max |G_k| = {gmax:.1} N) -> {rel:.3e} of M g"
        );
        rel
    };
    let (m, s) = contact_state(heavy(OracleMachine::default_stand()));
    let u = OracleInputs::Forces([5000.0, 6000.0, 5500.0, 7000.0, 6500.0, 4000.0]);
    let r1 = check("heavy legs in contact, forces", &m, &s, &u);
    let mut md = m.clone();
    md.drives = driven_machine(0.5, 0.5).drives;
    let r2 =
        check("heavy legs in contact, drives", &md, &s, &OracleInputs::Voltages([10.0, -20.0, 5.0, 30.0, 0.0, 12.0]));
    // Massless legs: G_k = u_k n_k.
    let m0 = OracleMachine::default_stand();
    let s0 = tilted_moving();
    let u0 = [5000.0, 6000.0, 5500.0, 7000.0, 6500.0, 4000.0];
    let g0 = m0.joint_forces(&s0, &OracleInputs::Forces(u0));
    let l = m0.leg_lengths(&s0);
    let mut worst = 0.0f64;
    for k in 0..6 {
        let a = v3(s0.r) + m3(&s0.rotation) * v3(m0.platform_joints[k]);
        let n = (a - v3(m0.base_joints[k])) / l[k];
        worst = worst.max((v3(g0[k]) - n * u0[k]).norm());
    }
    println!("[6] massless legs: max |G_k - u_k n_k| = {worst:.3e} N");
    let r3 = check("massless legs", &m0, &s0, &OracleInputs::Forces(u0));
    assert!(r1 < 1e-10 && r2 < 1e-10 && r3 < 1e-12 && worst < 1e-9);
}

// ------------------------------------------------------------------------------------------
// 7. Hydraulic servo legs (SPEC §10)
// ------------------------------------------------------------------------------------------

const SUPPLY: f64 = 16e6;

/// The brief's realistic parameter set.
fn hydraulics() -> OracleHydraulics {
    OracleHydraulics {
        bore: 0.063,
        rod: 0.036,
        dead_volume_a: 0.5e-3,
        dead_volume_b: 0.5e-3,
        bulk_modulus: 1e9,
        tank_pressure: 0.0,
        rated_flow: 1.5e-3,
        rated_pressure_drop: 7e6,
        omega: 2.0 * std::f64::consts::PI * 100.0,
        damping: 0.7,
        pcr: 1e5,
        valve_leakage: 1e-12,
        internal_leakage: 1e-13,
        lmin: [1.45; 6],
        lmax: [2.05; 6],
        air_fraction: 0.0,
        air_polytropic: 1.0,
        power_unit: None,
    }
}

fn hydraulic_machine() -> OracleMachine {
    let mut m = heavy(OracleMachine::default_stand());
    m.hydraulics = Some(hydraulics());
    m
}

fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next() >> 11) as f64 / (1u64 << 53) as f64)
}

/// SPEC §10's valve and chamber flows, written out again line by line from the text:
/// `(Q_A, Q_B, Q_S, Q_T, valve losses)` (losses: `Q dp` of the open lands plus `C_v dp^2` of
/// all four leakage paths).
fn spec_valve(h: &OracleHydraulics, s: f64, pa: f64, pb: f64, ps: f64) -> (f64, f64, f64, f64, f64) {
    let pt = h.tank_pressure;
    let k = h.rated_flow / (h.rated_pressure_drop / 2.0).sqrt();
    let phi = |dp: f64| dp / (dp.powi(2) + h.pcr.powi(2)).powf(0.25);
    let cv = h.valve_leakage;
    let (mut qa, mut qb) = if s >= 0.0 {
        (k * s * phi(ps - pa), -k * s * phi(pb - pt))
    } else {
        (k * s * phi(pa - pt), -k * s * phi(ps - pb))
    };
    qa += cv * (ps - pa) - cv * (pa - pt);
    qb += cv * (ps - pb) - cv * (pb - pt);
    // Supply line: the land that connects P to a chamber, plus the P->A and P->B leakage; tank
    // line: the land that connects a chamber to T, plus the A->T and B->T leakage.
    let leak_s = cv * (ps - pa) + cv * (ps - pb);
    let leak_t = cv * (pa - pt) + cv * (pb - pt);
    let (q_s, q_t, throttling) = if s >= 0.0 {
        let (to_a, from_b) = (k * s * phi(ps - pa), k * s * phi(pb - pt));
        (to_a + leak_s, from_b + leak_t, to_a * (ps - pa) + from_b * (pb - pt))
    } else {
        let (to_b, from_a) = (k * s.abs() * phi(ps - pb), k * s.abs() * phi(pa - pt));
        (to_b + leak_s, from_a + leak_t, to_b * (ps - pb) + from_a * (pa - pt))
    };
    let leakage = cv * ((ps - pa).powi(2) + (pa - pt).powi(2) + (ps - pb).powi(2) + (pb - pt).powi(2));
    (qa, qb, q_s, q_t, throttling + leakage)
}

#[test]
fn hydraulic_power_balance_per_leg_closes() {
    let mut rng = Rng(0x5eed_1234_abcd_0042);
    let (mut worst, mut worst_mass, mut worst_oracle, mut worst_flow, mut worst_spool) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut min_loss, mut largest) = (f64::MAX, 0.0f64);
    let cases = 2000;
    for case in 0..cases {
        let mut m = hydraulic_machine();
        let mut h = hydraulics();
        if case % 3 == 1 {
            h.tank_pressure = 3e5;
        }
        if case % 5 == 2 {
            h.lmin = std::array::from_fn(|_| uniform(&mut rng, 1.40, 1.5));
            h.lmax = std::array::from_fn(|_| uniform(&mut rng, 2.0, 2.1));
        }
        m.hydraulics = Some(h);
        m.friction =
            OracleFriction { coulomb: 30.0, static_: 50.0, stribeck_velocity: 0.01, smoothing: 0.002, viscous: 200.0 };
        let spool = std::array::from_fn(|_| match rng.below(6) {
            0 => 0.0,
            1 => -0.0,
            _ => uniform(&mut rng, -1.1, 1.1),
        });
        let s = OracleState {
            r: add3(NEUTRAL_R, std::array::from_fn(|_| uniform(&mut rng, -0.1, 0.1))),
            rotation: rotation_from_angles(std::array::from_fn(|_| uniform(&mut rng, -0.1, 0.1))),
            v: std::array::from_fn(|_| uniform(&mut rng, -0.6, 0.6)),
            w: std::array::from_fn(|_| uniform(&mut rng, -0.5, 0.5)),
            currents: [0.0; 6],
            pa: std::array::from_fn(|_| uniform(&mut rng, -2e6, 2.2e7)),
            pb: std::array::from_fn(|_| uniform(&mut rng, -2e6, 2.2e7)),
            spool,
            spool_rate: std::array::from_fn(|_| uniform(&mut rng, -200.0, 200.0)),
            supply_pressure: 0.0,
            lowest_pressure: f64::INFINITY,
        };
        let ps = match case % 4 {
            0 => SUPPLY,
            1 => 0.0,
            _ => uniform(&mut rng, 5e6, 2.1e7),
        };
        let valve = std::array::from_fn(|_| uniform(&mut rng, -1.5, 1.5));
        let inputs = OracleInputs::Valves { valve, supply_pressure: ps, pump_speed: 1.0 };

        // The oracle's pieces.
        let (pa_dot, pb_dot) = m.hydraulic_rates(&s, &inputs);
        let (va, vb) = m.chamber_volumes(&s);
        let ld = m.leg_rates(&s);
        let l = m.leg_lengths(&s);
        let powers = m.hydraulic_powers(&s, &inputs);
        let forces = m.leg_forces(&s, &inputs);
        let sdd = m.spool_accelerations(&s, &inputs);
        let (aa, ab) = (
            std::f64::consts::PI * 0.063f64.powi(2) / 4.0,
            std::f64::consts::PI * (0.063f64.powi(2) - 0.036f64.powi(2)) / 4.0,
        );
        let mut q_supply = 0.0;
        for k in 0..6 {
            let (pa, pb) = (s.pa[k], s.pb[k]);
            let (qa, qb, q_s, q_t, valve_losses) = spec_valve(&h, s.spool[k], pa, pb, ps);
            q_supply += q_s;
            // Left: the power drawn from the supply.
            let drawn = ps * q_s - h.tank_pressure * q_t;
            // Right: leg power + losses + compression power (the oracle's pressure rates).
            let u = pa * aa - pb * ab;
            let leg = u * ld[k];
            let internal = h.internal_leakage * (pa - pb).powi(2);
            let compression = pa * va[k] * pa_dot[k] / h.bulk_modulus + pb * vb[k] * pb_dot[k] / h.bulk_modulus;
            let scale = drawn.abs() + leg.abs() + valve_losses + internal + compression.abs();
            largest = largest.max(scale);
            worst = worst.max((drawn - (leg + valve_losses + internal + compression)).abs() / scale);
            min_loss = min_loss.min(valve_losses).min(internal);
            // Mass balance of the oil: Q_S - Q_T = Q_A + Q_B = the chambers' volume rates.
            let x = l[k] - h.lmin[k];
            let (va_own, vb_own) = (h.dead_volume_a + aa * x, h.dead_volume_b + ab * (h.lmax[k] - h.lmin[k] - x));
            // V_A' = A_A ldot, V_B' = -A_B ldot; the internal leakage leaves A and enters B.
            let (dva, dvb) = (aa * ld[k], -ab * ld[k]);
            let mass = (q_s - q_t) - (qa + qb);
            let chambers =
                (qa + qb) - (va_own * pa_dot[k] / h.bulk_modulus + dva + vb_own * pb_dot[k] / h.bulk_modulus + dvb);
            let qscale = q_s.abs() + q_t.abs() + qa.abs() + qb.abs() + dva.abs() + dvb.abs();
            worst_mass = worst_mass.max(mass.abs().max(chambers.abs()) / qscale);
            // The oracle's integrated powers and forces are these.
            let d = (powers.supply[k] - drawn).abs()
                + (powers.leg[k] - leg).abs()
                + (powers.losses[k] - valve_losses - internal).abs()
                + (powers.compression[k] - compression).abs()
                + (forces.actuator[k] - u).abs() * ld[k].abs();
            worst_oracle = worst_oracle.max(d / scale);
            let c = valve[k].clamp(-1.0, 1.0);
            let w = 2.0 * std::f64::consts::PI * 100.0;
            let spool_acc = w * w * (c - s.spool[k]) - 2.0 * 0.7 * w * s.spool_rate[k];
            worst_spool = worst_spool.max((sdd[k] - spool_acc).abs() / (w * w));
        }
        let qs_oracle = m.supply_flow(&s, &inputs);
        worst_flow = worst_flow.max((qs_oracle - q_supply).abs() / q_supply.abs().max(1e-9));
    }
    println!(
        "[7a] {cases} random states x 6 legs: max |p_S Q_S - p_T Q_T - (u ldot + losses + compression)| / sum|terms| = {worst:.3e} \
         (largest sum of terms {largest:.3e} W); oil mass balance {worst_mass:.3e}; oracle's powers against these {worst_oracle:.3e}; \
         Qsupply {worst_flow:.3e}; spool {worst_spool:.3e}; smallest loss {min_loss:.3e} W"
    );
    assert!(worst < 1e-13 && worst_mass < 1e-13 && worst_oracle < 1e-13 && worst_flow < 1e-12 && worst_spool < 1e-15);
    assert!(min_loss >= 0.0);
}

/// The stand with heavy legs, friction and end stops at the cylinders' stroke ends, starting
/// at rest `heave` above neutral on the holding pressures.
fn hydraulic_run_setup(heave: f64) -> (OracleMachine, OracleState) {
    let mut m = hydraulic_machine();
    let h = m.hydraulics.unwrap();
    m.stops = Some(OracleStops { lmin: h.lmin, lmax: h.lmax, stiffness: 1e7, damping: 5e4 });
    m.friction =
        OracleFriction { coulomb: 30.0, static_: 50.0, stribeck_velocity: 0.01, smoothing: 0.002, viscous: 200.0 };
    let r = add3(NEUTRAL_R, [0.0, 0.0, heave]);
    let (pa, pb) = m.holding_pressures(r, identity_rotation(), SUPPLY);
    (m, OracleState { pa, pb, ..OracleState::at_rest(r, identity_rotation()) })
}

/// Valves moving (a different swing per leg) and the supply dropped to 0 after 1.2 s.
fn hydraulic_profile(t: f64) -> OracleInputs {
    let valve = std::array::from_fn(|k| 0.6 * (2.0 * std::f64::consts::PI * t / 0.9 + 0.5 * k as f64).sin() + 0.1);
    OracleInputs::Valves { valve, supply_pressure: if t < 1.2 { SUPPLY } else { 0.0 }, pump_speed: 1.0 }
}

#[test]
fn hydraulic_energy_balance_over_a_run() {
    let (m, start) = hydraulic_run_setup(0.2);
    let (h, steps) = (1e-3, 1600);
    let t0 = std::time::Instant::now();
    let run = m.simulate_with_work(&start, h, steps, &hydraulic_profile);
    let elapsed = t0.elapsed().as_secs_f64();
    let e0 = m.energy(&start);
    let hyd = m.hydraulics.unwrap();
    let (mut worst, mut scale, mut stop_samples) = (0.0f64, 0.0f64, 0);
    let (mut lo, mut hi, mut pmin, mut pmax, mut smax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN, 0.0f64);
    for (st, w) in &run {
        assert_eq!(w.forces, 0.0);
        let balance = m.energy(st) - e0 - (w.hydraulic - w.compression - w.dissipated);
        worst = worst.max(balance.abs());
        scale = scale.max(w.hydraulic.abs()).max(w.compression.abs()).max(w.dissipated.abs());
        let l = m.leg_lengths(st);
        if (0..6).any(|k| l[k] < hyd.lmin[k] || l[k] > hyd.lmax[k]) {
            stop_samples += 1;
        }
        for k in 0..6 {
            lo = lo.min(l[k]);
            hi = hi.max(l[k]);
            pmin = pmin.min(st.pa[k]).min(st.pb[k]);
            pmax = pmax.max(st.pa[k]).max(st.pb[k]);
            smax = smax.max(st.spool[k].abs());
        }
    }
    let (last, lw) = run.last().unwrap();
    println!(
        "[7b] {:.1} s in {elapsed:.1} s: E0 = {e0:.1} J, E - E0 = {:.1} J, W_hydraulic = {:.1} J, W_compression = {:.1} J, \
         W_dissipated = {:.1} J; max |E - E0 - W_h + W_c + W_d| = {worst:.3e} J = {:.3e} of the largest work; \
         legs {lo:.4}..{hi:.4} m, {stop_samples} samples in stop contact; pressures {pmin:.3e}..{pmax:.3e} Pa; max |s| {smax:.3}; \
         final r = {:?}",
        steps as f64 * h,
        m.energy(last) - e0,
        lw.hydraulic,
        lw.compression,
        lw.dissipated,
        worst / scale,
        last.r
    );
    assert!(stop_samples > 20, "the run must reach the end stops");
    assert!(scale > 1e4);
    assert!(worst / scale < 1e-9, "energy balance {worst:e} J");

    // The balance's error is RK4's: twice the substep.
    let mut coarse = m.clone();
    coarse.max_step = 2.0 * m.max_step;
    let run2 = coarse.simulate_with_work(&start, h, steps, &hydraulic_profile);
    let (mut worst2, mut dpose, mut dp) = (0.0f64, 0.0f64, 0.0f64);
    for ((a, _), (b, w)) in run.iter().zip(&run2) {
        worst2 = worst2.max((coarse.energy(b) - e0 - (w.hydraulic - w.compression - w.dissipated)).abs());
        dpose = dpose.max((v3(a.r) - v3(b.r)).norm()).max((m3(&a.rotation) - m3(&b.rotation)).abs().max());
        for k in 0..6 {
            dp = dp.max((a.pa[k] - b.pa[k]).abs()).max((a.pb[k] - b.pb[k]).abs());
        }
    }
    println!(
        "[7b] substep {:e} s: balance {worst2:.3e} J ({:.1} x the {:e} s run's); pose difference {dpose:.3e}, pressure difference {dp:.3e} Pa",
        coarse.max_step,
        worst2 / worst,
        m.max_step
    );
    assert!(dpose < 1e-8 && dp < 10.0);

    // At coarse substeps the balance's residual is RK4's truncation error, h^4.
    let mut residuals = Vec::new();
    for step in [1e-4, 5e-5] {
        let mut c = m.clone();
        c.max_step = step;
        let r = c.simulate_with_work(&start, h, steps, &hydraulic_profile);
        let res = r
            .iter()
            .map(|(s, w)| (c.energy(s) - e0 - (w.hydraulic - w.compression - w.dissipated)).abs())
            .fold(0.0, f64::max);
        residuals.push(res);
    }
    let order = (residuals[0] / residuals[1]).log2();
    println!(
        "[7b] substeps 1e-4 s and 5e-5 s: balance {:.3e} J and {:.3e} J, observed order {order:.2}",
        residuals[0], residuals[1]
    );
    assert!(residuals[0] > 30.0 * worst && order > 3.5 && order < 4.5);
}

#[test]
fn holding_pressures_hold_the_stand() {
    let mut m = hydraulic_machine();
    let mut h = hydraulics();
    h.valve_leakage = 0.0;
    h.internal_leakage = 0.0;
    m.hydraulics = Some(h);
    let inputs = OracleInputs::Valves { valve: [0.0; 6], supply_pressure: SUPPLY, pump_speed: 1.0 };
    let mut worst = 0.0f64;
    for (name, r, rot) in [
        ("neutral", NEUTRAL_R, identity_rotation()),
        ("offset and tilted", add3(NEUTRAL_R, [0.03, -0.02, 0.04]), rotation_from_angles([0.06, -0.04, 0.1])),
    ] {
        let (pa, pb) = m.holding_pressures(r, rot, SUPPLY);
        let start = OracleState { pa, pb, ..OracleState::at_rest(r, rot) };
        let (vd, wd) = m.accelerations(&start, &inputs);
        let acc = v3(vd).norm().max(v3(wd).norm());
        let (pad, pbd) = m.hydraulic_rates(&start, &inputs);
        let rates = pad.iter().chain(&pbd).fold(0.0f64, |a, x| a.max(x.abs()));
        let u = m.leg_forces(&start, &inputs).actuator;
        let us = m.static_leg_forces(r, rot);
        let du = (0..6).map(|k| (u[k] - us[k]).abs()).fold(0.0, f64::max);
        let run = m.simulate(&start, 1e-3, 100, &|_| inputs);
        let drift = run.iter().map(|s| (v3(s.r) - v3(r)).norm()).fold(0.0, f64::max);
        let dp = run.iter().map(|s| (0..6).map(|k| (s.pa[k] - pa[k]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
        println!(
            "[7c] {name}: p_A = {:?} Pa, p_B = {:?} Pa; |u - u_static| = {du:.3e} N; |accelerations| = {acc:.3e}; \
             |p'| = {rates:.3e} Pa/s; over 0.1 s drift {drift:.3e} m, |p_A - p_A0| {dp:.3e} Pa",
            pa.map(|p| p.round()),
            pb[0]
        );
        worst = worst.max(acc);
        assert!(acc < 1e-9 && rates == 0.0 && du < 1e-8 && drift < 1e-9);
    }
    assert!(worst < 1e-9);
}

// ------------------------------------------------------------------------------------------
// 8. Oil with entrained air and the power unit (SPEC §10b)
// ------------------------------------------------------------------------------------------

/// The power unit of the brief: pump 1.5 l/s set to 16 MPa with a 0.5 MPa band, relief at
/// 17.5 MPa, a 10 l accumulator precharged to 9 MPa absolute, a 2 l supply line.
fn power_unit() -> OraclePowerUnit {
    OraclePowerUnit {
        max_flow: 1.5e-3,
        set_pressure: 16e6,
        compensator_band: 0.5e6,
        relief_pressure: 17.5e6,
        relief_gain: 1e-9,
        accumulator_volume: 10e-3,
        precharge: 9e6,
        accumulator_polytropic: 1.4,
        supply_volume: 2e-3,
    }
}

/// A typical servo oil: 0.5 % air, isothermal.
const AIR: f64 = 0.005;

/// `hydraulic_run_setup(0.2)` with air `alpha0` (`n = 1`) and, if given, the power unit.
fn air_run_setup(alpha0: f64, unit: Option<OraclePowerUnit>) -> (OracleMachine, OracleState) {
    let (mut m, start) = hydraulic_run_setup(0.2);
    let h = m.hydraulics.as_mut().unwrap();
    (h.air_fraction, h.air_polytropic, h.power_unit) = (alpha0, 1.0, unit);
    (m, start)
}

/// SPEC §10b's `beta_e`, written out again from the text (not the oracle's function).
fn spec_beta_e(beta: f64, alpha0: f64, n: f64, p: f64) -> f64 {
    let big_p = p + 101325.0;
    let theta = alpha0 / (1.0 - alpha0) * (101325.0 / big_p).powf(1.0 / n);
    beta * (1.0 + theta) / (1.0 + theta * beta / (n * big_p))
}

/// FNV-1a over the bits of every state and work accumulator that section 10 has, at every
/// communication point of a run.
fn section_10_digest(run: &[(OracleState, OracleWork)]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for b in x.to_bits().to_le_bytes() {
            hash ^= b as u64;
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for (s, w) in run {
        s.r.iter().chain(s.rotation.iter().flatten()).chain(&s.v).chain(&s.w).for_each(|&x| eat(x));
        s.currents.iter().chain(&s.pa).chain(&s.pb).chain(&s.spool).chain(&s.spool_rate).for_each(|&x| eat(x));
        [w.forces, w.electric, w.dissipated, w.hydraulic, w.compression].into_iter().for_each(&mut eat);
    }
    hash
}

/// The digest of section 7b's run (1.6 s, valves swinging, `pS` dropped to 0 at 1.2 s, end
/// stops reached, chambers down to -2.27 MPa), recorded from the oracle before §10b (commit
/// 3d70871).
const SECTION_10_DIGEST: u64 = 0x42ae_788d_0de5_5644;

#[test]
fn air_free_oil_without_the_power_unit_is_section_10_to_the_bit() {
    let t0 = std::time::Instant::now();
    let (m, start) = hydraulic_run_setup(0.2);
    let run = m.simulate_with_work(&start, 1e-3, 1600, &hydraulic_profile);
    let digest = section_10_digest(&run);
    // The §10b parameters and states that air-free oil and the input supply leave unused: a
    // polytropic exponent, a supply-line state and a stopped pump change nothing.
    let (mut m2, mut start2) = (m.clone(), start);
    m2.hydraulics.as_mut().unwrap().air_polytropic = 1.4;
    start2.supply_pressure = 3e6;
    let stopped = |t: f64| match hydraulic_profile(t) {
        OracleInputs::Valves { valve, supply_pressure, .. } => {
            OracleInputs::Valves { valve, supply_pressure, pump_speed: 0.0 }
        }
        other => other,
    };
    let run2 = m2.simulate_with_work(&start2, 1e-3, 1600, &stopped);
    let digest2 = section_10_digest(&run2);
    let (last, lw) = run2.last().unwrap();
    let lowest = run.iter().flat_map(|(s, _)| s.pa.iter().chain(&s.pb)).fold(f64::MAX, |a, &p| a.min(p));
    println!(
        "[8a] section 7b's run: digest {digest:#018x}, with n = 1.4, p_S state 3e6 Pa and pump.speed 0 {digest2:#018x} \
         (recorded before §10b {SECTION_10_DIGEST:#018x}); pmin {:.4e} Pa (lowest sample {lowest:.4e} Pa); {:.1} s",
        last.lowest_pressure,
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(digest, SECTION_10_DIGEST, "air-free oil must be section 10 to the bit");
    assert_eq!(digest2, SECTION_10_DIGEST);
    assert_eq!((lw.pump, last.supply_pressure), (0.0, 3e6), "the power unit's state and work stay untouched");
    let outputs = m2.power_unit_outputs(last, &stopped(1.5));
    assert_eq!((outputs.supply_pressure, outputs.pump_flow, outputs.oil_volume), (0.0, 0.0, 0.0));
    // pmin: at least as low as every sample, and no lower than the run's pressures allow.
    assert!(last.lowest_pressure <= lowest && last.lowest_pressure > lowest - 1e5);
}

/// `E(t) - E(0)` against the works of a run, the largest residual and the largest work.
fn balance(m: &OracleMachine, run: &[(OracleState, OracleWork)], with_pump: bool) -> (f64, f64) {
    let e0 = m.energy(&run[0].0);
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for (s, w) in run {
        let supplied = if with_pump { w.pump } else { w.hydraulic };
        let residual = m.energy(s) - e0 - (w.forces + w.electric + supplied - w.compression - w.dissipated);
        worst = worst.max(residual.abs());
        scale = scale.max(supplied.abs()).max(w.compression.abs()).max(w.dissipated.abs());
    }
    (worst, scale)
}

/// Section 7b's pump failure (`pS` to 0 at 1.2 s with the valves swinging) with air: section
/// 10 alone takes the chambers below -1 bar gauge; with 0.5 % air no chamber reaches zero
/// absolute, and section 10's energy balance (`work.hydraulic`) holds.
#[test]
fn air_keeps_every_chamber_above_zero_absolute() {
    // beta_e: the oracle's against the text's, beta without air, n P near vacuum.
    let h = air_run_setup(AIR, None).0.hydraulics.unwrap();
    let mut worst_beta = 0.0f64;
    for i in 0..=400 {
        let p = -ATMOSPHERIC_PRESSURE + 10f64.powf(-2.0 + 0.025 * i as f64);
        for n in [1.0, 1.4] {
            let hn = OracleHydraulics { air_polytropic: n, ..h };
            let spec = spec_beta_e(h.bulk_modulus, AIR, n, p);
            worst_beta = worst_beta.max((hn.effective_bulk_modulus(p) / spec - 1.0).abs());
        }
    }
    let near_vacuum = h.effective_bulk_modulus(-ATMOSPHERIC_PRESSURE + 1e-3) / 1e-3;
    let free = OracleHydraulics { air_fraction: 0.0, ..h };
    assert!(worst_beta < 1e-14, "beta_e {worst_beta:e}");
    assert!((near_vacuum - 1.0).abs() < 1e-5, "beta_e / P at 1 mPa absolute: {near_vacuum}");
    assert_eq!(free.effective_bulk_modulus(-5e6), free.bulk_modulus);

    let (steps, dt) = (2500, 1e-3);
    let mut lowest = vec![];
    for alpha0 in [0.0, AIR] {
        let (m, start) = air_run_setup(alpha0, None);
        let t0 = std::time::Instant::now();
        let run = m.simulate_with_work(&start, dt, steps, &hydraulic_profile);
        let elapsed = t0.elapsed().as_secs_f64();
        let (worst, scale) = balance(&m, &run, false);
        let (last, lw) = run.last().unwrap();
        let below = |limit: f64| run.iter().filter(|(s, _)| s.pa.iter().chain(&s.pb).any(|&p| p < limit)).count();
        let (below_bar, below_vacuum) = (below(-1e5), below(-ATMOSPHERIC_PRESSURE));
        // The substep against the decay rate near vacuum: h |p'| / P at every sample.
        let mut decay = 0.0f64;
        if alpha0 > 0.0 {
            for (i, (s, _)) in run.iter().enumerate() {
                let (pad, pbd) = m.hydraulic_rates(s, &hydraulic_profile(i as f64 * dt));
                for (p, pd) in s.pa.iter().chain(&s.pb).zip(pad.iter().chain(&pbd)) {
                    decay = decay.max(m.max_step * pd.abs() / (p + ATMOSPHERIC_PRESSURE));
                }
            }
        }
        println!(
            "[8c] alpha0 = {alpha0}: {:.1} s in {elapsed:.1} s; lowest chamber pressure {:.4e} Pa gauge = {:.4e} Pa \
             absolute; samples below -1 bar gauge {below_bar}, below zero absolute {below_vacuum}; largest h |p'| / P \
             {decay:.3e}; max |E - E0 - W_h + W_c + W_d| = {worst:.3e} J = {:.3e} of the largest work ({scale:.4e} J); \
             W_compression {:.1} J",
            steps as f64 * dt,
            last.lowest_pressure,
            last.lowest_pressure + ATMOSPHERIC_PRESSURE,
            worst / scale,
            lw.compression
        );
        assert!(worst / scale < 1e-12, "energy balance {worst:e} J");
        assert!(decay < 0.1, "h |p'| / P = {decay}");
        lowest.push((last.lowest_pressure, below_bar, below_vacuum));
        if alpha0 > 0.0 {
            // The substep's error near vacuum: half the substep.
            let mut fine = m.clone();
            fine.max_step = 0.5 * m.max_step;
            let run2 = fine.simulate_with_work(&start, dt, steps, &hydraulic_profile);
            let (mut dp, mut dlog, mut dpose) = (0.0f64, 0.0f64, 0.0f64);
            for ((a, _), (b, _)) in run.iter().zip(&run2) {
                dpose = dpose.max((v3(a.r) - v3(b.r)).norm());
                for (pa, pb) in a.pa.iter().chain(&a.pb).zip(b.pa.iter().chain(&b.pb)) {
                    dp = dp.max((pa - pb).abs());
                    let (qa, qb) = (pa + ATMOSPHERIC_PRESSURE, pb + ATMOSPHERIC_PRESSURE);
                    dlog = dlog.max((qa / qb).ln().abs());
                }
            }
            let (worst2, _) = balance(&fine, &run2, false);
            println!(
                "[8c] alpha0 = {alpha0}, substep {:e} s against {:e} s: pressures differ by {dp:.3e} Pa (relative, \
                 absolute pressures: {dlog:.3e}), pose {dpose:.3e} m; balance {worst2:.3e} J; lowest {:.4e} Pa absolute",
                fine.max_step,
                m.max_step,
                run2.last().unwrap().0.lowest_pressure + ATMOSPHERIC_PRESSURE
            );
            assert!(dp < 1.0 && dlog < 1e-6 && dpose < 1e-9);
        }
    }
    let ((dry, dry_bar, dry_vacuum), (airy, _, airy_vacuum)) = (lowest[0], lowest[1]);
    assert!(dry < -1e5 && dry_bar > 100 && dry_vacuum > 100, "section 10 alone goes below -1 bar gauge ({dry:e} Pa)");
    assert!(airy + ATMOSPHERIC_PRESSURE > 0.0 && airy_vacuum == 0, "with air: {airy:e} Pa gauge");
    assert!(airy + ATMOSPHERIC_PRESSURE < 1e4, "the chambers come near vacuum ({airy:e} Pa gauge)");
}

/// Valves swinging (section 7b's profile), the pump on until 1.2 s, then stopped.
fn pump_failure(t: f64) -> OracleInputs {
    match hydraulic_profile(t) {
        OracleInputs::Valves { valve, .. } => {
            OracleInputs::Valves { valve, supply_pressure: SUPPLY, pump_speed: if t < 1.2 { 1.0 } else { 0.0 } }
        }
        other => other,
    }
}

/// The power unit through a pump failure: `E(t) - E(0) = work.pump - work.compression -
/// work.dissipated` with `E_acc` in `E`, from a start above the relief pressure (relief open,
/// pump at no delivery), through the pump's regulation, the accumulator's discharge, its
/// emptying and the chambers' fall to vacuum; without and with air.
#[test]
fn power_unit_energy_balance_through_a_pump_failure() {
    let (steps, dt) = (4000, 1e-3);
    for alpha0 in [0.0, AIR] {
        let (m, mut start) = air_run_setup(alpha0, Some(power_unit()));
        start.supply_pressure = 18e6;
        let pu = power_unit();
        let t0 = std::time::Instant::now();
        let run = m.simulate_with_work(&start, dt, steps, &pump_failure);
        let elapsed = t0.elapsed().as_secs_f64();
        let (worst, scale) = balance(&m, &run, true);
        let (mut relief, mut pump_max, mut charged, mut empty, mut ps_lo, mut ps_hi) =
            (0.0f64, 0.0f64, 0, 0, f64::MAX, f64::MIN);
        for (i, (s, _)) in run.iter().enumerate() {
            let o = m.power_unit_outputs(s, &pump_failure(i as f64 * dt));
            assert_eq!(o.supply_pressure, s.supply_pressure);
            relief = relief.max(o.relief_flow);
            pump_max = pump_max.max(o.pump_flow);
            (ps_lo, ps_hi) = (ps_lo.min(s.supply_pressure), ps_hi.max(s.supply_pressure));
            if o.oil_volume > 0.0 {
                charged += 1;
            } else {
                empty += 1;
            }
        }
        let (last, lw) = run.last().unwrap();
        let e_acc0 = pu.gas_energy(start.supply_pressure);
        println!(
            "[8b] power unit, alpha0 = {alpha0}: {:.1} s in {elapsed:.1} s; max |E - E0 - W_pump + W_c + W_d| = \
             {worst:.3e} J = {:.3e} of the largest work ({scale:.4e} J); W_pump {:.1} J, W_hydraulic {:.1} J, \
             W_compression {:.1} J, W_dissipated {:.1} J, E_acc(0) {e_acc0:.1} J; p_S {ps_lo:.4e}..{ps_hi:.4e} Pa; \
             largest relief flow {relief:.3e} m3/s, pump flow {pump_max:.3e} m3/s; accumulator charged in {charged}, \
             empty in {empty} samples; lowest chamber pressure {:.4e} Pa gauge",
            steps as f64 * dt,
            worst / scale,
            lw.pump,
            lw.hydraulic,
            lw.compression,
            lw.dissipated,
            last.lowest_pressure
        );
        assert!(worst / scale < 1e-12, "energy balance {worst:e} J");
        assert!(relief > 1e-4 && pump_max == pu.max_flow, "the relief opened and the pump delivered full flow");
        assert!(charged > 100 && empty > 100, "the accumulator emptied ({charged}, {empty})");
        if alpha0 > 0.0 {
            assert!(last.lowest_pressure + ATMOSPHERIC_PRESSURE > 0.0);
            assert!(last.lowest_pressure + ATMOSPHERIC_PRESSURE < 1e4, "near vacuum");
            assert!(ps_lo + ATMOSPHERIC_PRESSURE > 0.0);
        } else {
            assert!(last.lowest_pressure < -1e5);
        }
    }
}

/// The accumulator with the pump stopped and the valves almost closed: its oil volume falls
/// as the valves draw on the supply, it is SPEC's `V_0 (1 - (P_0 / P_S)^(1/n_a))` of the state
/// (0 once `P_S <= P_0`), and the oil's mass balance of the supply side holds:
/// `V_oil(t) - V_oil(0) + V_s integral dp / beta_e(p) = -integral Q_S dt`.
#[test]
fn the_accumulator_discharges_as_the_supply_is_drawn() {
    let pu = power_unit();
    let (m, start) = air_run_setup(AIR, Some(pu));
    let h = m.hydraulics.unwrap();
    let closed_ish = |t: f64| OracleInputs::Valves {
        valve: std::array::from_fn(|k| 0.08 * (2.0 * std::f64::consts::PI * t / 0.5 + k as f64).sin()),
        supply_pressure: SUPPLY,
        pump_speed: 0.0,
    };
    let (steps, dt) = (3000, 1e-3);
    let t0 = std::time::Instant::now();
    let run = m.simulate_with_work(&start, dt, steps, &closed_ish);
    let elapsed = t0.elapsed().as_secs_f64();
    let spec_oil = |ps: f64| {
        let big_p = ps + 101325.0;
        if big_p > 9e6 { 10e-3 * (1.0 - (9e6 / big_p).powf(1.0 / 1.4)) } else { 0.0 }
    };
    // integral of V_s / beta_e from p0 to p1, composite Simpson.
    let line = |p0: f64, p1: f64| {
        let n = 2000;
        let dp = (p1 - p0) / n as f64;
        let f = |p: f64| 2e-3 / spec_beta_e(h.bulk_modulus, AIR, 1.0, p);
        (0..n).map(|i| p0 + i as f64 * dp).map(|a| dp / 6.0 * (f(a) + 4.0 * f(a + 0.5 * dp) + f(a + dp))).sum::<f64>()
    };
    let (v0, p0) = (spec_oil(start.supply_pressure), start.supply_pressure);
    let (mut formula, mut mass, mut rises, mut mass_scale) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut previous = v0;
    for (i, (s, w)) in run.iter().enumerate() {
        let o = m.power_unit_outputs(s, &closed_ish(i as f64 * dt));
        assert_eq!((o.pump_flow, o.relief_flow), (0.0, 0.0));
        formula = formula.max((o.oil_volume - spec_oil(s.supply_pressure)).abs());
        rises = rises.max(o.oil_volume - previous);
        previous = o.oil_volume;
        let stored = o.oil_volume - v0 + line(p0, s.supply_pressure);
        mass = mass.max((stored + w.supply_volume).abs());
        mass_scale = mass_scale.max(w.supply_volume.abs());
    }
    let (last, lw) = run.last().unwrap();
    let v_end = spec_oil(last.supply_pressure);
    let samples_empty = run.iter().filter(|(s, _)| spec_oil(s.supply_pressure) == 0.0).count();
    println!(
        "[8d] pump stopped, valves within 0.08: {:.1} s in {elapsed:.1} s; p_S {:.4e} -> {:.4e} Pa, oil volume \
         {v0:.4e} -> {v_end:.4e} m3 ({samples_empty} samples empty); drawn {:.4e} m3; largest rise between samples \
         {rises:.3e} m3; |V_oil - formula| <= {formula:.3e} m3; mass balance {mass:.3e} m3 = {:.3e} of the draw",
        steps as f64 * dt,
        p0,
        last.supply_pressure,
        lw.supply_volume,
        mass / mass_scale
    );
    assert!(v0 - v_end > 1e-3, "the accumulator discharged");
    assert!(rises <= 0.0, "the oil volume never rises with the pump stopped ({rises:e} m3)");
    assert!(formula == 0.0);
    assert!(mass < 1e-9 * mass_scale, "mass balance {mass:e} m3");
}
