//! The six legs between base and platform.
//!
//! | module | what it holds |
//! |---|---|
//! | [`geometry`] | leg arms, lengths, directions and rates of a state |
//! | [`bodies`] | the legs as two bodies: their inertia and gravity seen at the platform joints |
//! | [`end_stops`] | stroke limits as a unilateral virtual potential with contact damping |
//! | [`joint_limits`] | joint angle limits as unilateral virtual potentials with contact damping |
//! | [`friction`] | cylinder friction (Stribeck, regularised) |
//! | [`per_leg`] | a value per leg, the six legs side by side in vector registers |

pub mod bodies;
pub mod end_stops;
pub mod friction;
pub mod geometry;
pub mod joint_limits;
pub mod per_leg;
