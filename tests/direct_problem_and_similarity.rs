//! The direct problem (paper section 3) round trip: forces computed from a programme motion,
//! applied to the forward simulation, reproduce the motion until the platform's instability
//! takes over; and mechanical similarity (textbook 1.4): an SI run and the same run in the
//! paper's non-dimensional units agree after scaling.

use crate::common;

use common::{dyn_law, simulation};
use nalgebra::Vector3;
use stewart_fmu::integration::SolverSettings;
use stewart_fmu::physics::body::kinematics::angles_from_rotation;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::direct_problem::solve_direct_problem;
use stewart_fmu::physics::legs::bodies::LegBodies;
use stewart_fmu::physics::legs::geometry::LegGeometry;
use stewart_fmu::physics::programme::{PoseProgramme, SoftStartSinusoid};
use stewart_fmu::physics::scaling::Scales;
use stewart_fmu::physics::stand::{PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use stewart_fmu::simulation::Stabilisation;

fn nondimensional() -> (Stand, Scales) {
    let stand = Stand::truck_cabin();
    let scales = Scales::paper(&stand);
    (scales.nondimensional_stand(&stand), scales)
}

fn programme_start(programme: &PoseProgramme) -> BodyState {
    let p = programme.point(0.0);
    BodyState::from_pose(p.r, p.v, &p.rotation, &p.w)
}

/// Runs the forward simulation with the direct problem's forces evaluated at every stage
/// time; returns (t, pose error) samples: position error plus angle error.
fn round_trip(stand: &Stand, programme: &PoseProgramme, t_end: f64, dt: f64) -> Vec<(f64, f64)> {
    let mut sim =
        simulation(stand.clone(), programme_start(programme), SolverSettings::tight(), Stabilisation::Projection);
    let law = |t: f64, _s: &BodyState, _l: &LegGeometry| {
        solve_direct_problem(stand, &LegBodies::default(), &programme.point(t)).expect("direct problem").forces
    };
    let mut samples = vec![];
    let n = (t_end / dt).round() as usize;
    for i in 1..=n {
        let t = i as f64 * dt;
        if sim.advance(dyn_law(&law), t).is_err() {
            break;
        }
        let s = sim.body_state();
        let p = programme.point(t);
        let err = (s.r - p.r).norm() + (angles_from_rotation(&s.rotation()) - angles_from_rotation(&p.rotation)).norm();
        samples.push((t, err));
    }
    samples
}

fn max_until(samples: &[(f64, f64)], t: f64) -> f64 {
    samples.iter().filter(|(ti, _)| *ti <= t + 1e-12).map(|s| s.1).fold(0.0, f64::max)
}

#[test]
fn heave_programme_forces_reproduce_the_heave_until_the_instability_grows() {
    let (stand, scales) = nondimensional();
    let centre = Stand::truck_cabin_neutral_position() / scales.length;
    let programme = PoseProgramme::heave(centre, 0.2, 1.0, 2.0);
    // All six forces are equal by symmetry and stay in the band of the paper's Fig. 4.
    let (mut lo, mut hi, mut spread) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for i in 0..=4000 {
        let u = solve_direct_problem(&stand, &LegBodies::default(), &programme.point(i as f64 * 0.01)).unwrap().forces;
        let (mn, mx) = u.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        lo = lo.min(mn);
        hi = hi.max(mx);
        spread = spread.max(mx - mn);
    }
    println!("heave programme forces over 0..40: min {lo:.5}, max {hi:.5}, largest spread between legs {spread:.1e}");
    assert!(lo > 0.152 && hi < 0.262 && lo < 0.16 && hi > 0.25, "force band [{lo}, {hi}]");
    assert!(spread < 1e-12);

    let samples = round_trip(&stand, &programme, 40.0, 0.25);
    let early = max_until(&samples, 8.0);
    let late = samples.last().map(|s| s.1).unwrap_or(f64::INFINITY);
    println!(
        "heave round trip: max pose error for t <= 8: {early:.2e}; at t = {:.2}: {late:.2e}",
        samples.last().map(|s| s.0).unwrap_or(0.0)
    );
    assert!(early <= 1e-9, "round trip error {early:e} for t <= 8");
    assert!(late > 1e3 * early, "the instability must show: late error {late:e}");
}

#[test]
fn six_dof_programme_round_trip() {
    let (stand, scales) = nondimensional();
    let c = Stand::truck_cabin_neutral_position() / scales.length;
    let s = |offset: f64, amplitude: f64, frequency: f64, phase: f64| SoftStartSinusoid {
        offset,
        amplitude,
        frequency,
        phase,
        time_constant: 2.0,
    };
    let programme = PoseProgramme {
        dof: [
            s(c.x, 0.04, 1.3, 0.0),
            s(c.y, -0.03, 0.7, 0.0),
            s(c.z, 0.1, 1.0, 0.0),
            s(0.0, 0.05, 0.9, 0.0),
            s(0.0, -0.04, 1.1, 0.0),
            s(0.0, 0.08, 0.5, 0.0),
        ],
    };
    let samples = round_trip(&stand, &programme, 6.0, 0.25);
    let err = max_until(&samples, 6.0);
    println!("six-dof programme round trip: max pose error for t <= 6: {err:.2e}");
    assert_eq!(samples.len(), 24, "the simulation must reach t = 6");
    assert!(err <= 1e-8, "round trip error {err:e}");
}

/// The same experiment in SI and in the paper's units: leg-length feedback around a moving
/// programme, from a tilted start. Positions and angles agree after scaling.
#[test]
fn si_and_nondimensional_runs_agree_after_scaling() {
    let si = Stand::truck_cabin();
    let (nd, scales) = nondimensional();
    let mg = si.mass * si.gravity;
    let l0 = 1.7550860729486566;
    let omega = 1.0 / scales.time;
    // Feedback law in SI: u = u0 + G (lp(t) - l) - D ldot.
    let (g_si, d_si) = (2.0e5, 2.0e4);
    let law_si = |t: f64, s: &BodyState, legs: &LegGeometry| {
        let rates = legs.length_rates(&si, s);
        let mut u = [0.0; 6];
        for k in 0..6 {
            let lp = l0 + 0.03 * (1.5 * omega * t + k as f64).sin();
            u[k] = PAPER_EQUILIBRIUM_LEG_FORCE * mg + g_si * (lp - legs.length[k]) - d_si * rates[k];
        }
        u
    };
    let (g_nd, d_nd) = (g_si * scales.length / mg, d_si * scales.velocity() / mg);
    let law_nd = |t: f64, s: &BodyState, legs: &LegGeometry| {
        let rates = legs.length_rates(&nd, s);
        let mut u = [0.0; 6];
        for k in 0..6 {
            let lp = (l0 + 0.03 * (1.5 * t + k as f64).sin()) / scales.length;
            u[k] = PAPER_EQUILIBRIUM_LEG_FORCE + g_nd * (lp - legs.length[k]) - d_nd * rates[k];
        }
        u
    };
    let rot = stewart_fmu::physics::body::kinematics::rotation_from_angles(&Vector3::new(0.05, -0.03, 0.1));
    let r0 = Stand::truck_cabin_neutral_position() + Vector3::new(0.02, 0.01, -0.03);
    let (v0, w0) = (Vector3::new(0.1, 0.0, -0.05), Vector3::new(0.2, -0.1, 0.3));
    let start_si = BodyState::from_pose(r0, v0, &rot, &w0);
    let start_nd = BodyState::from_pose(r0 / scales.length, v0 / scales.velocity(), &rot, &(w0 * scales.time));
    let mut a = simulation(si.clone(), start_si, SolverSettings::tight(), Stabilisation::Projection);
    let mut b = simulation(nd.clone(), start_nd, SolverSettings::tight(), Stabilisation::Projection);
    let mut worst: f64 = 0.0;
    for i in 1..=30 {
        let t_si = 0.1 * i as f64;
        a.advance(dyn_law(&law_si), t_si).unwrap();
        b.advance(dyn_law(&law_nd), t_si / scales.time).unwrap();
        let (sa, sb) = (a.body_state(), b.body_state());
        let dr = (sa.r / scales.length - sb.r).norm() / sb.r.norm();
        let dv = (sa.v / scales.velocity() - sb.v).norm() / sb.v.norm().max(1e-3);
        let drot = (sa.rotation() - sb.rotation()).abs().max();
        worst = worst.max(dr).max(dv).max(drot);
    }
    println!("SI vs non-dimensional over 3 s (7.7 time units): max relative difference {worst:.2e}");
    assert!(worst <= 1e-9, "similarity violated by {worst:e}");
}
