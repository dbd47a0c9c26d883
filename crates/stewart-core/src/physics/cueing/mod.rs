//! Motion cueing (SPEC §11, docs/cueing.md): the classical washout that turns a vehicle's
//! specific force and angular velocity at the driver's head into a pose command for the stand,
//! and the workspace limiter that keeps that command inside the legs' strokes. Pure functions
//! on plain data; the `StewartCueing` FMU (`stewart_fmu::models::cueing`, a layer above this crate) steps them.
//!
//! | module | what it holds |
//! |---|---|
//! | [`jet`] | `Jet`: a value with two time derivatives (the pose command's exact rates) |
//! | [`washout`] | the filters, their states and rate, the washout's pose |
//! | [`limiter`] | the workspace limiter |

pub mod jet;
pub mod limiter;
pub mod perception;
pub mod washout;
