//! The textbook's checks of a model's correctness (section 1.3, docs/model.md §7): energy with spring
//! legs, linear and angular momentum of a free tumbling body (and the Euler top's unstable
//! intermediate axis), and the constraint residual with and without projection.

use crate::common;

use common::{dyn_law, simulation};
use nalgebra::{Matrix3, Vector3};
use stewart_fmu::integration::SolverSettings;
use stewart_fmu::physics::actuators::{HeldForces, SpringLegs};
use stewart_fmu::physics::body::invariants::{angular_momentum, linear_momentum, mechanical_energy};
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::legs::geometry::LegGeometry;
use stewart_fmu::physics::scaling::Scales;
use stewart_fmu::physics::stand::{PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use stewart_fmu::simulation::{PlatformSimulation, Stabilisation};

/// The default stand in the paper's non-dimensional units.
fn nondimensional_stand() -> Stand {
    let stand = Stand::truck_cabin();
    Scales::paper(&stand).nondimensional_stand(&stand)
}

/// Spring legs (non-dimensional stiffness `c`) whose rest lengths hold the neutral pose with
/// the paper's equilibrium force, and a perturbed, moving start.
fn spring_setup(c: f64) -> (Stand, SpringLegs, BodyState) {
    let stand = nondimensional_stand();
    let scale = Scales::paper(&Stand::truck_cabin());
    let neutral = Stand::truck_cabin_neutral_position() / scale.length;
    let l_neutral = 1.7550860729486566 / scale.length;
    let springs = SpringLegs { stiffness: c, rest_length: [l_neutral + PAPER_EQUILIBRIUM_LEG_FORCE / c; 6] };
    let start = BodyState::from_pose(
        neutral + Vector3::new(0.01, -0.02, 0.03),
        Vector3::new(0.02, 0.01, -0.01),
        &rotation_from_angles(&Vector3::new(0.03, -0.02, 0.05)),
        &Vector3::new(0.05, -0.03, 0.1),
    );
    (stand, springs, start)
}

fn total_energy(sim: &PlatformSimulation, springs: &SpringLegs) -> f64 {
    let s = sim.body_state();
    mechanical_energy(sim.stand(), &s) + springs.potential_energy(&LegGeometry::new(sim.stand(), &s))
}

#[test]
fn energy_is_conserved_with_spring_legs() {
    let (stand, springs, start) = spring_setup(5.0);
    let mut sim = simulation(stand, start, SolverSettings::tight(), Stabilisation::Projection);
    let e0 = total_energy(&sim, &springs);
    let mut worst: f64 = 0.0;
    for i in 1..=1000 {
        sim.advance(dyn_law(&springs), 0.1 * i as f64).expect("step");
        worst = worst.max(((total_energy(&sim, &springs) - e0) / e0).abs());
    }
    let s = sim.body_state();
    let _figures = common::figures::print_figures(&format!(
        "spring legs, 100 time units, tight tolerance: max relative energy drift {worst:.2e} ({} steps, {} rhs), \
         final z = {:.4}",
        sim.integrator.stats.accepted_steps, sim.integrator.stats.rhs_evaluations, s.r.z
    ));
    assert!(worst <= 1e-10, "relative energy drift {worst:e}");
    // The motion is a real oscillation, not a body at rest.
    assert!(sim.integrator.stats.accepted_steps > 1000);
}

/// With `g = 0` and no leg forces the body is free: momentum and angular momentum about the
/// origin are constant while it tumbles.
#[test]
fn momenta_are_conserved_for_a_free_tumbling_body() {
    let mut stand = Stand::truck_cabin();
    stand.gravity = 0.0;
    stand.inertia = [1500.0, 2000.0, 2600.0];
    // High above the base, so the legs (which carry no force) stay long.
    let start = BodyState::from_pose(
        Vector3::new(0.3, -0.2, 50.0),
        Vector3::new(0.1, -0.2, 0.3),
        &rotation_from_angles(&Vector3::new(0.3, 0.2, -0.1)),
        &Vector3::new(0.7, -0.4, 1.1),
    );
    // The unloaded legs pass singular arrangements as the body tumbles; irrelevant here.
    let mut sim = simulation(stand.clone(), start, SolverSettings::tight(), Stabilisation::Projection);
    let (p0, h0, e0) =
        (linear_momentum(&stand, &start), angular_momentum(&stand, &start), mechanical_energy(&stand, &start));
    let free = HeldForces::constant([0.0; 6]);
    let (mut dp, mut dh, mut de) = (0.0f64, 0.0f64, 0.0f64);
    for i in 1..=200 {
        sim.advance(dyn_law(&free), 0.1 * i as f64).expect("step");
        let s = sim.body_state();
        dp = dp.max((linear_momentum(&stand, &s) - p0).norm() / p0.norm());
        dh = dh.max((angular_momentum(&stand, &s) - h0).norm() / h0.norm());
        de = de.max(((mechanical_energy(&stand, &s) - e0) / e0).abs());
    }
    let _figures = common::figures::print_figures(&format!(
        "free tumbling body, 20 s: relative drift of momentum {dp:.2e}, angular momentum {dh:.2e}, energy {de:.2e}"
    ));
    assert!(dp <= 1e-12, "momentum drift {dp:e}");
    assert!(dh <= 1e-10, "angular momentum drift {dh:e}");
    assert!(de <= 1e-10, "energy drift {de:e}");
}

/// Rotation about the axis of the intermediate moment is unstable (the Euler top,
/// "tennis-racket" flip); about the largest and smallest it is stable.
#[test]
fn euler_top_intermediate_axis_is_unstable() {
    let mut stand = Stand::truck_cabin();
    stand.gravity = 0.0;
    stand.inertia = [1500.0, 2000.0, 2600.0];
    let spin = |w: Vector3<f64>| -> (f64, f64) {
        let start = BodyState::from_pose(Vector3::new(0.0, 0.0, 50.0), Vector3::zeros(), &Matrix3::identity(), &w);
        let mut sim = simulation(stand.clone(), start, SolverSettings::tight(), Stabilisation::Projection);
        let free = HeldForces::constant([0.0; 6]);
        let axis = w.iamax();
        let (mut min_ratio, mut max_ratio) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 1..=300 {
            sim.advance(dyn_law(&free), 0.1 * i as f64).expect("step");
            let ratio = sim.body_state().angular_velocity_body()[axis] / w[axis];
            min_ratio = min_ratio.min(ratio);
            max_ratio = max_ratio.max(ratio);
        }
        (min_ratio, max_ratio)
    };
    let eps = 1e-3;
    let (min1, _) = spin(Vector3::new(2.0, eps, eps));
    let (min2, _) = spin(Vector3::new(eps, 2.0, eps));
    let (min3, _) = spin(Vector3::new(eps, eps, 2.0));
    let _figures = common::figures::print_figures(&format!(
        "spin about axis 1 (smallest J): min w1/w1(0) = {min1:.4}; axis 2 (intermediate): {min2:.4}; axis 3 (largest): {min3:.4}"
    ));
    assert!(min1 > 0.99 && min3 > 0.99, "rotation about the extreme axes must stay put");
    assert!(min2 < -0.9, "rotation about the intermediate axis must flip over, got min ratio {min2}");
}

/// With projection the constraint residual stays at round-off; without, it drifts with the
/// integration error and grows.
#[test]
fn constraint_residual_with_and_without_projection() {
    let (stand, springs, start) = spring_setup(5.0);
    let settings = SolverSettings::default();
    let mut projected = simulation(stand.clone(), start, settings, Stabilisation::Projection);
    let mut free = simulation(stand, start, settings, Stabilisation::None);
    let mut worst_projected: f64 = 0.0;
    let mut free_at = vec![];
    for i in 1..=1000 {
        let t = 0.1 * i as f64;
        projected.advance(dyn_law(&springs), t).expect("step");
        free.advance(dyn_law(&springs), t).expect("step");
        worst_projected = worst_projected.max(projected.body_state().constraint_residual());
        if i % 250 == 0 {
            free_at.push(free.body_state().constraint_residual());
        }
    }
    let _figures = common::figures::print_figures(&format!(
        "constraint residual over 100 time units at default tolerance: with projection max {worst_projected:.2e}; \
         without projection at t = 25, 50, 75, 100: {:.2e} {:.2e} {:.2e} {:.2e}",
        free_at[0], free_at[1], free_at[2], free_at[3]
    ));
    assert!(worst_projected <= 1e-13, "projected residual {worst_projected:e}");
    assert!(free_at[3] > 1e3 * worst_projected.max(1e-16), "no visible drift without projection");
    assert!(free_at[3] > 2.0 * free_at[0], "residual without projection must grow: {free_at:?}");
}
