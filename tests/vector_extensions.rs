//! The steps' AVX2 path (`VectorPath::Avx2`, chosen at run time where the processor has it
//! and the build has the `avx2` feature) computes the same numbers as the baseline path, to
//! the bit: the same operations in the same order, only wider registers. Checked on motions
//! that take every branch of a step: contacts with both stops (located and stepped across),
//! singular arrangements passed, and both methods.

use crate::common;

use common::{dyn_law, pose, simulation};
use nalgebra::Vector3;
use stewart_fmu::integration::{Method, SolverSettings};
use stewart_fmu::physics::actuators::HeldForces;
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::stand::{PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use stewart_fmu::simulation::{PlatformSimulation, Stabilisation, VectorPath};

/// 2 s of 1 ms communication steps under forces that drive the platform through both stops
/// and a tilt; returns every state and crossing time.
fn run(
    method: Method,
    stops: bool,
    path: VectorPath,
) -> (Vec<[u64; stewart_fmu::simulation::SIMULATION_DIM]>, Vec<u64>) {
    let settings = SolverSettings { method, fixed_step: 1e-3, ..Default::default() };
    let start = pose(
        Vector3::new(0.01, -0.02, 0.0),
        Vector3::new(0.05, -0.03, 0.1),
        Vector3::zeros(),
        Vector3::new(0.2, -0.1, 0.3),
    );
    let mut sim: PlatformSimulation = simulation(Stand::truck_cabin(), start, settings, Stabilisation::Projection)
        .with_end_stops(stops.then(EndStops::default))
        .expect("valid stops");
    sim.set_vector_path(path);
    assert_eq!(sim.vector_path(), path);
    let f0 = PAPER_EQUILIBRIUM_LEG_FORCE * 3000.0 * 9.81;
    // Hard into both stops with them, a milder sway without (nothing stops a tip-over then).
    let amplitude = if stops { 0.6 } else { 0.2 };
    let (mut states, mut crossings) = (vec![], vec![]);
    for i in 0..2000 {
        let t = i as f64 * 1e-3;
        let phase: [f64; 6] = std::array::from_fn(|k| (2.0 * std::f64::consts::PI * (1.5 * t + 0.01 * k as f64)).sin());
        let value = std::array::from_fn(|k| f0 * (1.0 + amplitude * phase[k]));
        let law = HeldForces { value, slope: [0.0; 6], t0: t };
        sim.advance(dyn_law(&law), t + 1e-3).expect("the motion goes on");
        states.push(sim.state.map(f64::to_bits));
        crossings.extend(sim.crossings.as_slice().iter().map(|c| c.t.to_bits()));
    }
    (states, crossings)
}

#[test]
fn avx2_and_baseline_code_give_the_same_bits() {
    let fastest = VectorPath::fastest();
    // Fails on an x86-64 processor without AVX2 and FMA unless STEWART_FMU_NO_WIDE=1 says so:
    // there both runs would take the baseline code and compare nothing.
    if !stewart_fmu::simd::wide_testable() {
        println!("this build or processor has no AVX2 path: both runs take the baseline code");
    }
    let default = common::simulation(
        Stand::truck_cabin(),
        pose(Vector3::zeros(), Vector3::zeros(), Vector3::zeros(), Vector3::zeros()),
        SolverSettings::default(),
        Stabilisation::Projection,
    );
    assert_eq!(default.vector_path(), fastest, "a simulation takes the fastest path by default");
    for method in [Method::RungeKutta4, Method::DormandPrince45] {
        for stops in [true, false] {
            let (fast, fast_crossings) = run(method, stops, fastest);
            let (base, base_crossings) = run(method, stops, VectorPath::Baseline);
            println!("{method:?}, stops {stops}: {} states, {} crossings compared", fast.len(), fast_crossings.len());
            assert!(!stops || !fast_crossings.is_empty(), "the motion meets the stops");
            assert_eq!(fast_crossings, base_crossings, "{method:?}, stops {stops}");
            let first = fast.iter().zip(&base).position(|(a, b)| a != b);
            assert_eq!(first, None, "{method:?}, stops {stops}: states differ from step {first:?} on");
        }
    }
}
