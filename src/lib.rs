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
//! 5. [`models`]: the FMU models (variables, parameters, co-simulation steps), safe Rust,
//!    knowing nothing of FMI versions.
//! 6. [`fmi`]: what both FMI versions share: the instance around a model, the panic
//!    boundary, logging, the model descriptions and instantiation tokens.
//! 7. [`fmi2`], [`fmi3`]: the two C boundaries (`extern "C"` functions, C types, state tables).
//!
//! See `ARCHITECTURE.md` for the map of the repository.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod control;
pub mod fmi;
pub mod fmi2;
pub mod fmi3;
pub mod integration;
pub mod models;
pub mod physics;
pub mod simulation;
