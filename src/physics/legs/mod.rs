//! The six legs between base and platform.
//!
//! | module | what it holds |
//! |---|---|
//! | [`geometry`] | leg arms, lengths, directions and rates of a state |
//! | [`end_stops`] | stroke limits as a unilateral virtual potential with contact damping |
//! | [`per_leg`] | a value per leg, the six legs side by side in vector registers |

pub mod end_stops;
pub mod geometry;
pub mod per_leg;
