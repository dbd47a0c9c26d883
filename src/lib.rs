//! # Stewart platform FMU
//!
//! Rigid-body dynamics of a loaded Stewart platform (hexapod) in the *special form* of
//! Zegzhda, Petrova and Yushkov (Vestnik SPbU 2020): redundant coordinates (centre of mass
//! plus the three body-axis unit vectors), packaged as FMI 2.0 and FMI 3.0 FMUs
//! (Co-Simulation and Model Exchange), with a controller FMU for the paper's feedback.
//!
//! The mechanics (the laws, the integrators, a stand in motion, the feedback law) are the
//! crate `stewart_core` (`crates/stewart-core`: no FMI, no FFI, no I/O), re-exported here
//! under their own names. This crate adds the layers above them; each uses only the ones
//! before it:
//!
//! 5. [`models`]: the FMU models (each variable declared once with where its value lives,
//!    parameters, steps), safe Rust, knowing nothing of FMI versions.
//! 6. [`fmi`]: what both FMI versions share: the instance around a model, the panic
//!    boundary, logging, the model descriptions and instantiation tokens.
//! 7. [`fmi2`], [`fmi3`]: the two C boundaries (`extern "C"` functions, C types, state tables).
//!
//! See `ARCHITECTURE.md` for the map of the repository.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod fmi;
pub mod fmi2;
pub mod fmi3;
pub mod models;

// Layers 0-4, under the paths the models, the tests and the benches name them by.
pub use stewart_core::{control, integration, maths, physics, simd, simulation};
