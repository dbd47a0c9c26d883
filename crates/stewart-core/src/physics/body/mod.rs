//! The rigid body (the loaded platform) in the special form's redundant coordinates.
//!
//! | module | what it holds |
//! |---|---|
//! | [`state`] | the 24 coordinates `r, v, e_a, e_a'` |
//! | [`accelerations`] | the special form's accelerations for a given force and moment (paper 1.4-1.6) |
//! | [`per_axis`] | a value per body axis, the three axes side by side in vector registers |
//! | [`projection`] | projection onto the constraints `e_a . e_b = delta_ab` |
//! | [`kinematics`] | 1-2-3 angles, angular rates, inverse kinematics |
//! | [`invariants`] | energy, momenta |

pub mod accelerations;
pub mod invariants;
pub mod kinematics;
pub mod per_axis;
pub mod projection;
pub mod state;
