//! Self-checks of the independent machine oracle (tests/common/machine_oracle.rs): agreement
//! with the rigid-body Newton-Euler oracle for massless legs, energy conservation and the
//! energy balance with drives, statics, the equations of motion against Lagrange's equations
//! by finite differences of the energies, and the joint forces against the platform's
//! Newton-Euler balance.

mod common;

use common::machine_oracle::{
    EQUILIBRIUM_LEG_FORCE, NEUTRAL_R, OracleDrives, OracleFriction, OracleInputs, OracleJoints, OracleMachine,
    OracleState, OracleStops, identity_rotation, rotation_from_angles,
};
use common::newton_euler::{NeState, NewtonEuler};
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
        currents: [0.0; 6],
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
        currents: [0.0; 6],
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
