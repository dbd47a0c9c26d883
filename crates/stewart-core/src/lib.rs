//! # The Stewart platform's mechanics
//!
//! Rigid-body dynamics of a loaded Stewart platform (hexapod) in the *special form* of
//! Zegzhda, Petrova and Yushkov (Vestnik SPbU 2020): redundant coordinates (centre of mass
//! plus the three body-axis unit vectors), the machine around it (legs as bodies, end stops,
//! joint limits, friction, electric drives, hydraulic servo legs), the integrators that step
//! it and the paper's feedback law. Pure Rust: no FMI, no FFI, no I/O. The FMUs (the root
//! crate `stewart_fmu`) are a layer over this crate; nothing here knows of them.
//!
//! The crate is layered; each layer only uses the ones above it:
//!
//! 0. [`maths`]: the elementary functions (`sin`, `exp`, `pow`, ...), one implementation
//!    compiled into the FMU, so that every platform computes the same bits; [`simd`]: how
//!    per-leg and per-axis values sit side by side in vector registers, and whether the wide
//!    ones may be used.
//! 1. [`physics`]: pure mechanics (the body, the legs, the actuators, the special form, the
//!    direct problem, the washout's filters), each law written once over the number type
//!    (`f64`, dual numbers, six legs side by side).
//! 2. [`integration`]: generic ODE integrators (Dormand-Prince 5(4), RK4); [`optimisation`]:
//!    small dense quadratic programmes (an interior-point method).
//! 3. [`simulation`]: a stand in motion (integration + constraint projection + roll-back, the
//!    choice of vector registers).
//! 4. [`control`]: the paper's programme-following feedback law (pure).
//!
//! See `ARCHITECTURE.md` at the repository's root for the map.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod control;
pub mod integration;
pub mod maths;
pub mod optimisation;
pub mod physics;
pub mod simd;
pub mod simulation;
#[cfg(test)]
mod test_support;
