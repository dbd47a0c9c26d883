//! # Stewart platform FMU
//!
//! Rigid-body dynamics of a loaded Stewart platform (hexapod) in the *special form* of
//! Zegzhda, Petrova and Yushkov (Vestnik SPbU 2020): redundant coordinates (centre of mass
//! plus the three body-axis unit vectors), packaged as an FMI 2.0 Co-Simulation FMU.
//!
//! The crate is layered; each layer only uses the ones above it:
//!
//! 1. [`physics`]: pure mechanics (stand, special form, direct problem, kinematics).
//! 2. [`integration`]: generic ODE integrators (Dormand-Prince 5(4), RK4).
//! 3. [`simulation`]: a stand in motion (integration + constraint projection + roll-back).
//! 4. [`control`]: the paper's programme-following feedback law (pure).
//! 5. [`models`]: the FMU models (variables, parameters, co-simulation steps), safe Rust.
//! 6. [`fmi2`]: the FMI 2.0 C boundary (`extern "C"` functions, state machine, logging).
//!
//! See `ARCHITECTURE.md` for the map of the repository.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod control;
pub mod fmi2;
pub mod integration;
pub mod models;
pub mod physics;
pub mod simulation;
