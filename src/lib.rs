//! # Stewart platform FMU
//!
//! Rigid-body dynamics of a loaded Stewart platform (hexapod) in the *special form* of
//! Zegzhda, Petrova and Yushkov (Vestnik SPbU 2020): redundant coordinates (centre of mass
//! plus the three body-axis unit vectors), packaged as FMI 2.0 and FMI 3.0 FMUs
//! (Co-Simulation and Model Exchange), with a controller FMU for the paper's feedback.
//!
//! The crate is layered; each layer only uses the ones above it:
//!
//! 0. [`maths`]: the elementary functions (`sin`, `exp`, `pow`, ...), one implementation
//!    compiled into the FMU, so that every platform computes the same bits; [`simd`]: how
//!    per-leg and per-axis values sit side by side in vector registers, and whether the wide
//!    ones may be used.
//! 1. [`physics`]: pure mechanics (the body, the legs, the actuators, the special form, the
//!    direct problem), each law written once over the number type (`f64`, dual numbers, six
//!    legs side by side).
//! 2. [`integration`]: generic ODE integrators (Dormand-Prince 5(4), RK4).
//! 3. [`simulation`]: a stand in motion (integration + constraint projection + roll-back, the
//!    choice of vector registers).
//! 4. [`control`]: the paper's programme-following feedback law (pure).
//! 5. [`models`]: the FMU models (each variable declared once with where its value lives,
//!    parameters, steps), safe Rust, knowing nothing of FMI versions.
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
pub mod maths;
pub mod models;
pub mod physics;
pub mod simd;
pub mod simulation;
