//! The whole workspace (issue 9): end stops as a unilateral virtual potential, measured.
//!
//! - power loss: the default platform falls onto its lower stops and rests where the static
//!   equilibrium on the stops, solved here independently, puts it;
//! - the energy balance `E(t) - E(0) = work.F - work.dissipated` in forced motion through
//!   contacts, for both integrators;
//! - elastic stops: bounces that conserve energy, and what locating the contacts buys.

use crate::common;

use common::{dyn_law, neutral_state, simulation};
use stewart_fmu::integration::{Method, SolverSettings};
use stewart_fmu::physics::actuators::HeldForces;
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::stand::{PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use stewart_fmu::simulation::state::switching;
use stewart_fmu::simulation::{PlatformOutputs, PlatformSimulation, Stabilisation};

const MASS: f64 = 3000.0;
const G: f64 = 9.81;

fn equilibrium_force() -> f64 {
    PAPER_EQUILIBRIUM_LEG_FORCE * MASS * G
}

fn with_stops(settings: SolverSettings, stops: EndStops) -> PlatformSimulation {
    simulation(Stand::truck_cabin(), neutral_state(), settings, Stabilisation::Projection)
        .with_end_stops(Some(stops))
        .expect("valid stops")
}

/// `E(t) - E(0) - (work.F - work.dissipated)`, J.
fn balance_residual(sim: &PlatformSimulation, e0: f64) -> f64 {
    let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
    o.energy - e0 - (o.work_of_forces - o.dissipated_energy)
}

/// Static rest pose of the default stand on its lower stops (pure heave by symmetry), solved
/// from the default stand's geometry (docs/model.md §3) alone: `6 k_s (lmin - l) (H / l) = M g`, `l = sqrt(d² + H²)`, with
/// the horizontal leg projection `d` and the joint plane height `H`. Returns the centre of
/// mass height.
fn static_rest_height(stiffness: f64, lmin: f64) -> f64 {
    let d = 0.9756365463855202; // docs/model.md §3
    let residual = |h: f64| {
        let l = (d * d + h * h).sqrt();
        6.0 * stiffness * (lmin - l) * (h / l) - MASS * G
    };
    // Bisection between "just touching" and "1 cm in".
    let touch = (lmin * lmin - d * d).sqrt();
    let (mut lo, mut hi) = ((0.0f64).max(touch - 0.05), touch);
    assert!(residual(lo) > 0.0 && residual(hi) < 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if residual(mid) > 0.0 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi) + 0.5 // + h_c: the centre of mass is 0.5 m above the joint plane
}

#[test]
fn power_loss_lands_the_platform_on_its_lower_stops_at_the_static_rest_pose() {
    let stops = EndStops::default();
    let mut sim = with_stops(SolverSettings::default(), stops);
    let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
    let (h, t_cut, t_end) = (1e-3, 0.5, 5.0);
    let (mut peak_deceleration, mut t_peak, mut max_penetration, mut first_contact) = (0.0f64, 0.0, 0.0f64, None);
    let mut worst_balance = 0.0f64;
    let mut t = 0.0;
    while t < t_end - 1e-12 {
        let f = if t < t_cut - 1e-12 { equilibrium_force() } else { 0.0 };
        sim.advance(dyn_law(&HeldForces::constant([f; 6])), t + h).expect("step");
        t += h;
        for c in sim.crossings.as_slice() {
            if c.index < switching::UPPER && !c.rising && first_contact.is_none() {
                first_contact = Some(c.t);
            }
        }
        let dy = sim.derivative(dyn_law(&HeldForces::constant([0.0; 6])));
        if dy[5] > peak_deceleration {
            (peak_deceleration, t_peak) = (dy[5], t);
        }
        let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
        max_penetration = max_penetration.max(o.l.iter().map(|l| stops.lower[0] - l).fold(0.0, f64::max));
        worst_balance = worst_balance.max(balance_residual(&sim, e0).abs());
    }
    let s = sim.body_state();
    let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
    let z_static = static_rest_height(stops.stiffness, stops.lower[0]);
    let rest_penetration = stops.lower[0] - o.l[0];
    println!(
        "power loss at {t_cut} s: first contact at t = {:.6} s, peak deceleration {peak_deceleration:.1} m/s2 ({:.1} g) \
         at t = {t_peak:.3} s, max penetration {:.2} mm; at {t_end} s: z = {:.9} m (static solution {z_static:.9} m, \
         difference {:.2e} m), penetration {:.4} mm, |v| = {:.1e} m/s, |w| = {:.1e} rad/s, Fstop = {:.1} N per leg; \
         energy balance residual max {worst_balance:.2e} J (of {:.0} J dissipated)",
        first_contact.unwrap_or(f64::NAN),
        peak_deceleration / G,
        max_penetration * 1e3,
        s.r.z,
        s.r.z - z_static,
        rest_penetration * 1e3,
        s.v.norm(),
        s.angular_velocity_body().norm(),
        o.stop_force[0],
        o.dissipated_energy,
    );
    // Free fall from 0.5 s: the joint plane drops from H0 to the touching height.
    let touch = (1.45f64 * 1.45 - 0.9756365463855202f64.powi(2)).sqrt();
    let fall = (2.0 * (1.4589244164161732 - touch) / G).sqrt();
    assert!(
        (first_contact.unwrap() - (t_cut + fall)).abs() < 1e-6,
        "first contact {first_contact:?}, free fall {fall}"
    );
    assert!((s.r.z - z_static).abs() < 1e-6, "rest height {} vs {z_static}", s.r.z);
    assert!(s.r.xy().norm() < 1e-9 && s.v.norm() < 1e-5, "at rest, centred: r {:?}, v {:?}", s.r, s.v);
    assert!(max_penetration < 0.03, "penetration {max_penetration}");
    // All six stops carry the weight equally.
    for f in o.stop_force {
        assert!((f - o.stop_force[0]).abs() < 1e-6 * f, "{:?}", o.stop_force);
    }
    assert!(peak_deceleration > G && peak_deceleration < 50.0 * G);
    assert!(worst_balance < 1e-5 * MASS * G, "energy balance residual {worst_balance} J");
}

/// Open-loop forces that drive the platform up and down between its lower and upper stops
/// (with a small per-leg ripple that rocks it), with damping; the energy balance holds to
/// the integration tolerance with both methods.
#[test]
fn energy_balance_holds_through_contacts_for_forced_motion() {
    // Long enough for both stops, short enough that the rocking (amplified at every landing)
    // does not tip the platform over.
    const DURATION: f64 = 2.5;
    let u = equilibrium_force();
    let law = move |t: f64| -> [f64; 6] {
        std::array::from_fn(|k| u * (1.0 + 0.5 * (2.5 * t).sin() + 0.002 * (7.0 * t + 1.1 * k as f64).sin()))
    };
    for (name, settings) in [
        ("adaptive, relTol 1e-8", SolverSettings::default()),
        ("adaptive, relTol 1e-11", SolverSettings { rel_tol: 1e-11, abs_tol: 1e-13, ..Default::default() }),
        ("RK4, 1 ms", SolverSettings { method: Method::RungeKutta4, fixed_step: 1e-3, ..Default::default() }),
        ("RK4, 0.1 ms", SolverSettings { method: Method::RungeKutta4, fixed_step: 1e-4, ..Default::default() }),
    ] {
        let mut sim = with_stops(settings, EndStops::default());
        let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
        let (mut worst, mut contacts, mut t) = (0.0f64, 0usize, 0.0);
        let h = 1e-3;
        while t < DURATION - 1e-12 {
            sim.advance(dyn_law(&HeldForces::constant(law(t))), t + h).expect("step");
            t += h;
            contacts +=
                sim.crossings.as_slice().iter().filter(|c| c.index < switching::DETERMINANT && !c.rising).count();
            worst = worst.max(balance_residual(&sim, e0).abs());
        }
        let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
        println!(
            "{name:>22}: {contacts} contact onsets in {DURATION} s, work.F {:.1} J, work.dissipated {:.1} J, max |E - E0 - \
             (W_F - W_d)| = {worst:.2e} J ({:.1e} of M g R_b)",
            o.work_of_forces,
            o.dissipated_energy,
            worst / (MASS * G * 1.5)
        );
        assert!(contacts >= 4, "{name}: the platform must hit its stops ({contacts})");
        assert!(o.dissipated_energy > 100.0);
        let bound = if settings.method == Method::RungeKutta4 { 1e-4 } else { 1e-7 } * MASS * G * 1.5;
        assert!(worst < bound, "{name}: residual {worst} J");
    }
}

/// Elastic stops, zero leg forces from the neutral pose: the platform bounces on its lower
/// stops and rises back to where it started. Returns the heave every 10 ms, the largest
/// relative energy drift, the number of bounces and the angular velocity at each landing.
fn bounce(settings: SolverSettings, t_end: f64) -> (Vec<f64>, f64, usize, Vec<f64>) {
    let stops = EndStops { damping: 0.0, ..Default::default() };
    let mut sim = with_stops(settings, stops);
    let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
    let (mut z, mut worst, mut landings, mut t) = (vec![], 0.0f64, vec![], 0.0);
    let h = 1e-2;
    while t < t_end - 1e-9 {
        sim.advance(dyn_law(&HeldForces::constant([0.0; 6])), t + h).expect("step");
        t += h;
        for c in sim.crossings.as_slice().iter().filter(|c| c.index == switching::LOWER && !c.rising) {
            let s =
                stewart_fmu::physics::body::state::BodyState::from_vector(stewart_fmu::simulation::state::body(&c.y));
            landings.push(s.angular_velocity_body().norm());
        }
        z.push(sim.body_state().r.z);
        worst = worst.max(((PlatformOutputs::compute(&sim.form, &sim.state, None).energy - e0) / e0).abs());
    }
    (z, worst, landings.len(), landings)
}

#[test]
fn elastic_stops_conserve_energy_and_located_contacts_keep_the_tolerance() {
    let tight = SolverSettings { rel_tol: 1e-12, abs_tol: 1e-14, ..Default::default() };
    let loose = SolverSettings { rel_tol: 1e-10, abs_tol: 1e-12, ..Default::default() };
    // Ten bounces: the energy.
    let (_, drift, bounces, spin) = bounce(tight, 6.0);
    println!(
        "elastic stops, {bounces} bounces in 6 s at relTol 1e-12: max relative energy drift {drift:.2e}; angular \
         velocity at each landing (round-off-seeded tilt, amplified by every landing): {:?} rad/s",
        spin.iter().map(|w| format!("{w:.0e}")).collect::<Vec<_>>()
    );
    assert!(bounces >= 10);
    assert!(drift < 1e-9, "energy drift {drift:e}");
    // Accuracy through the contacts: five bounces (3 s), while the tilt seeded by round-off
    // is still far below anything the heave can see (it grows about 30x per landing: the
    // bouncing platform is unstable in tilt, so beyond some eight landings two runs differ
    // by their round-off whatever their tolerance).
    let (z_ref, _, _, _) = bounce(tight, 3.0);
    let (z_loose, _, _, _) = bounce(loose, 3.0);
    let (z_plain_tight, _, _, _) = bounce(SolverSettings { locate_events: false, ..tight }, 3.0);
    let diff = |a: &[f64]| a.iter().zip(&z_ref).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    println!(
        "elastic stops, 5 bounces: max |z(relTol 1e-10) - z(relTol 1e-12)| = {:.2e} m with contact location \
         (relTol 1e-12 without location: {:.2e} m off)",
        diff(&z_loose),
        diff(&z_plain_tight)
    );
    assert!(diff(&z_loose) < 1e-8, "{:e}", diff(&z_loose));
    // Location buys accuracy: with it the error follows the tolerance (about 9 relTol in z);
    // without it the steps over each contact's onset leave an error that does not, larger at
    // every tolerance by a factor that depends on where the steps happen to fall (3x to 500x
    // here; one tolerance's factor is luck, the bounce amplifies it), so the factor is judged
    // over four tolerances.
    let mut log_ratio = 0.0;
    for rel_tol in [1e-8, 1e-9, 1e-10, 1e-11] {
        let settings = SolverSettings { rel_tol, abs_tol: rel_tol * 1e-2, ..Default::default() };
        let (located, _, _, _) = bounce(settings, 3.0);
        let (plain, _, _, _) = bounce(SolverSettings { locate_events: false, ..settings }, 3.0);
        let (located, plain) = (diff(&located), diff(&plain));
        println!("  relTol {rel_tol:.0e}: max z error {located:.2e} m with location, {plain:.2e} m without");
        assert!(located < 1e2 * rel_tol, "located contacts must keep the tolerance: {located:e} at relTol {rel_tol:e}");
        assert!(plain > located, "location must buy accuracy at relTol {rel_tol:e}: {plain:e} <= {located:e}");
        log_ratio += (plain / located).ln() / 4.0;
    }
    println!("  without location the error is {:.0}x larger (geometric mean)", log_ratio.exp());
    assert!(log_ratio.exp() > 10.0, "location must buy accuracy: {:.1}x", log_ratio.exp());
}

/// Scenario 5: no end stops, open-loop forces; the platform tumbles through singular leg
/// arrangements for 3 s, through the exported FMI functions, with the forces held over each
/// 10 ms communication step; an independent Newton-Euler integration with the same held
/// forces agrees to 1e-9, and every passage is reported.
#[test]
fn tumbling_through_singular_arrangements_matches_newton_euler() {
    use common::fmi_host::Host;
    use common::newton_euler::{NeState, NewtonEuler};
    use nalgebra::{Matrix3, Quaternion, Vector3};
    use stewart_fmu::fmi2::exports::fmi2SetDebugLogging;
    use stewart_fmu::fmi2::types::*;

    let u = equilibrium_force();
    let forces =
        move |t: f64| -> [f64; 6] { std::array::from_fn(|k| u * (1.05 + 0.5 * (2.0 * t + 1.1 * k as f64).sin())) };
    let mut fmu = Host::platform("tumble");
    let category = std::ffi::CString::new("logEvents").unwrap();
    assert_eq!(unsafe { fmi2SetDebugLogging(fmu.c, fmi2True, 1, &category.as_ptr()) }, fmi2OK);
    assert_eq!(
        fmu.initialise(&[("stops", 0.0), ("joints", 0.0), ("solver.relTol", 1e-12), ("solver.absTol", 1e-14)]),
        fmi2OK
    );
    let held = std::cell::Cell::new([0.0; 6]);
    let law = |_t: f64, _l: &[f64; 6], _ld: &[f64; 6]| held.get();
    let ne = NewtonEuler { stand: Stand::truck_cabin(), law: &law };
    let mut ne_state = NeState {
        r: Stand::truck_cabin_neutral_position(),
        v: Vector3::zeros(),
        q: Quaternion::new(1.0, 0.0, 0.0, 0.0),
        w: Vector3::zeros(),
    };
    let h = 0.01;
    let (mut worst_r, mut worst_rot) = (0.0f64, 0.0f64);
    for i in 0..300 {
        let t = i as f64 * h;
        let f = forces(t);
        held.set(f);
        assert_eq!(fmu.set_forces(f), fmi2OK);
        assert_eq!(fmu.step(h), fmi2OK, "step at t = {t}: {}", fmu.last_message());
        ne.integrate(&mut ne_state, t, t + h, 400);
        let r = Vector3::new(fmu.get("r[1]"), fmu.get("r[2]"), fmu.get("r[3]"));
        let rot = Matrix3::from_fn(|a, b| fmu.get(&format!("R[{},{}]", a + 1, b + 1)));
        worst_r = worst_r.max((r - ne_state.r).norm());
        worst_rot = worst_rot.max((rot - ne_state.rotation()).abs().max());
    }
    let passages: Vec<String> = fmu
        .messages()
        .iter()
        .filter(|l| l.message.contains("singular arrangement"))
        .map(|l| l.message.clone())
        .collect();
    println!(
        "tumble, 3 s at 10 ms, no end stops: {} singular arrangements passed, max |r - r_NE| = {worst_r:.2e} m, \
         max |R - R_NE| = {worst_rot:.2e}; first: {}",
        passages.len(),
        passages.first().map_or("", |s| s.as_str())
    );
    assert!(passages.len() >= 3, "{passages:?}");
    assert!(fmu.get("r[3]") > 2.5, "the platform rose while tumbling");
    assert!(worst_r < 1e-9 && worst_rot < 1e-9, "{worst_r:e} {worst_rot:e}");
}

/// `stopAtSingularity`: the passage is located inside the step, so the discard reports the
/// same time whether the host steps 10 ms at a time or asks for 3 s in one call.
#[test]
fn stop_at_singularity_finds_the_passage_inside_the_step() {
    use common::fmi_host::Host;
    use stewart_fmu::fmi2::types::*;

    let u = equilibrium_force();
    let forces: [f64; 6] = std::array::from_fn(|k| u * (1.05 + 0.5 * (1.1 * k as f64).sin()));
    let located = |h: f64| -> (f64, String) {
        let mut fmu = Host::platform("stop at singularity");
        assert_eq!(fmu.initialise(&[("stops", 0.0), ("joints", 0.0), ("stopAtSingularity", 1.0)]), fmi2OK);
        assert_eq!(fmu.set_forces(forces), fmi2OK);
        while fmu.time < 3.0 {
            match fmu.step(h) {
                s if s == fmi2OK => {}
                s => {
                    assert_eq!(s, fmi2Discard);
                    let message = fmu.last_message();
                    let t: f64 = message
                        .split("at t = ")
                        .nth(1)
                        .and_then(|rest| rest.split(':').next())
                        .and_then(|x| x.parse().ok())
                        .expect("time in the message");
                    return (t, message);
                }
            }
        }
        panic!("no singular arrangement within 3 s")
    };
    let (t_small, message) = located(0.01);
    let (t_large, _) = located(3.0);
    println!("stopAtSingularity: passage at t = {t_small} (10 ms steps), {t_large} (one 3 s step): {message}");
    assert!((t_small - t_large).abs() < 1e-6, "{t_small} vs {t_large}");
    assert!(message.contains("stopAtSingularity is on") && message.contains("rolled back"));
}

/// Passages through singular arrangements only get reported, so they are tracked only while
/// they can be (`logEvents` reaches the importer, or `stopAtSingularity`): the motion is the
/// same to the bit with or without tracking, and tracking switched on mid-run reports exactly
/// the passages after that moment, none spurious at the switch.
#[test]
fn singular_passages_are_tracked_only_while_reported_and_the_motion_is_the_same() {
    use common::fmi_host::Host;
    use stewart_fmu::fmi2::exports::fmi2SetDebugLogging;
    use stewart_fmu::fmi2::types::*;

    let u = equilibrium_force();
    let forces =
        move |t: f64| -> [f64; 6] { std::array::from_fn(|k| u * (1.05 + 0.5 * (2.0 * t + 1.1 * k as f64).sin())) };
    let category = std::ffi::CString::new("logEvents").unwrap();
    // Returns the position bits of every step and the passage messages with their step index.
    let run = |log_from_step: usize| -> (Vec<[u64; 3]>, Vec<(usize, String)>) {
        let mut fmu = Host::platform("tracking");
        let off = unsafe { fmi2SetDebugLogging(fmu.c, fmi2False, 1, &category.as_ptr()) };
        assert_eq!(off, fmi2OK);
        assert_eq!(fmu.initialise(&[("stops", 0.0), ("joints", 0.0)]), fmi2OK);
        let (mut positions, mut passages) = (vec![], vec![]);
        for i in 0..300 {
            if i == log_from_step {
                let on = unsafe { fmi2SetDebugLogging(fmu.c, fmi2True, 1, &category.as_ptr()) };
                assert_eq!(on, fmi2OK);
            }
            let seen = fmu.messages().len();
            assert_eq!(fmu.set_forces(forces(i as f64 * 0.01)), fmi2OK);
            assert_eq!(fmu.step(0.01), fmi2OK, "{}", fmu.last_message());
            let r = [fmu.get("r[1]"), fmu.get("r[2]"), fmu.get("r[3]")];
            positions.push(r.map(f64::to_bits));
            passages.extend(
                fmu.messages()[seen..]
                    .iter()
                    .filter(|l| l.message.contains("singular arrangement"))
                    .map(|l| (i, l.message.clone())),
            );
        }
        (positions, passages)
    };
    let (always, all_passages) = run(0);
    let (later, later_passages) = run(150);
    let (never, no_passages) = run(usize::MAX);
    let expected: Vec<_> = all_passages.iter().filter(|(i, _)| *i >= 150).cloned().collect();
    println!(
        "singular passages: {} with logEvents on throughout, {} of them after step 150, {} reported when switched on \
         at step 150, {} with it off",
        all_passages.len(),
        expected.len(),
        later_passages.len(),
        no_passages.len()
    );
    assert!(all_passages.len() >= 3 && !expected.is_empty() && expected.len() < all_passages.len());
    assert_eq!(later_passages, expected, "passages after the switch, and none at it");
    assert!(no_passages.is_empty());
    assert_eq!(always, later, "the motion does not depend on the tracking");
    assert_eq!(always, never, "the motion does not depend on the tracking");
}
