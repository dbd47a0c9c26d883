//! A simulated stand: the physics core driven by an integrator, with constraint
//! stabilisation, admissibility checks and roll-back of failed steps. This is what the FMU
//! steps, and what the Rust tests and benches use directly.
//!
//! | module | what it holds |
//! |---|---|
//! | [`state`] | the simulation state's layout, its rate for every actuator, the switching functions |
//! | [`dynamics`] | [`PlatformDynamics`]: the equations with a force law as an ODE system; [`LegOutputs`] |
//! | [`platform`] | [`PlatformSimulation`]: state, time, integrator; `advance` with roll-back |
//! | [`outputs`] | the FMU outputs derived from a state, and their time derivatives |
//! | [`vector`] | which vector registers a step computes in (the door to the AVX2-compiled integrators) |

pub mod dynamics;
pub mod outputs;
pub mod platform;
pub mod state;
pub mod vector;

pub use dynamics::{LegOutputs, PlatformDynamics, Stabilisation};
pub use outputs::PlatformOutputs;
pub use platform::{PlatformSimulation, StepFailure};
pub use state::{SIMULATION_DIM, SimulationState};
pub use vector::VectorPath;
