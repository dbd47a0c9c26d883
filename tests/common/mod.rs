//! Shared helpers of the Rust integration tests.
#![allow(dead_code)]

pub mod figures;
pub mod fmi3_host;
pub mod fmi_host;
pub mod machine_oracle;
pub mod newton_euler;
pub mod rng;

use nalgebra::{Matrix3, Vector3};
use std::path::PathBuf;
use stewart_fmu::integration::SolverSettings;
use stewart_fmu::physics::actuators::LegForceLaw;
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::{PlatformSimulation, Stabilisation};

/// The repository's root (the tests' package is its `tests/` folder).
pub fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The default stand's neutral pose at rest.
pub fn neutral_state() -> BodyState {
    BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &Matrix3::identity(),
        &Vector3::zeros(),
    )
}

/// A pose offset from neutral by `dr`, rotated by 1-2-3 `angles`, moving with `v` and `w`.
pub fn pose(dr: Vector3<f64>, angles: Vector3<f64>, v: Vector3<f64>, w: Vector3<f64>) -> BodyState {
    BodyState::from_pose(Stand::truck_cabin_neutral_position() + dr, v, &rotation_from_angles(&angles), &w)
}

/// A force law as the tests hand it to the simulation: `sim.advance(dyn_law(&springs), t)`.
/// The simulation's steps are generic over the law, so that the FMU's laws compile into its
/// step; in this crate each law type handed in would compile the whole integrator again (both
/// state layouts and both vector paths: about 3.5 million lines of unoptimised LLVM IR, four
/// fifths of this crate's build time with six law types). Through `&dyn LegForceLaw` it
/// compiles once.
pub fn dyn_law(law: &impl LegForceLaw) -> &dyn LegForceLaw {
    law
}

pub fn simulation(
    stand: Stand,
    initial: BodyState,
    settings: SolverSettings,
    stab: Stabilisation,
) -> PlatformSimulation {
    PlatformSimulation::new(stand, initial, settings, stab, 0.0).expect("valid stand and initial state")
}

/// Largest absolute entry difference of two matrices.
pub fn max_abs_diff(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (a - b).abs().max()
}
