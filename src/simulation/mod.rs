//! A simulated stand: the physics core driven by an integrator, with constraint
//! stabilisation, admissibility checks and roll-back of failed steps. This is what the FMU
//! steps, and what the Rust tests and benches use directly.
//!
//! | module | what it holds |
//! |---|---|
//! | [`platform`] | [`PlatformSimulation`]: state, time, integrator; `advance` with roll-back |
//! | [`outputs`] | the FMU outputs derived from a state, and their time derivatives |
//! | [`vector`] | which vector registers a step computes in (the door to the AVX2-compiled integrators) |

pub mod outputs;
pub mod platform;
pub mod vector;

pub use outputs::{LegOutputs, PlatformOutputs};
pub use platform::{PlatformDynamics, PlatformSimulation, SIMULATION_DIM, SimulationState, Stabilisation, StepFailure};
pub use vector::VectorPath;
