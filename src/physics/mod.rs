//! The physics core: pure rigid-body mechanics of the loaded Stewart platform in the special
//! form of Zegzhda, Petrova and Yushkov (2020). No FFI, no integration, no I/O; every function
//! here is testable on its own.
//!
//! | module | what it holds |
//! |---|---|
//! | [`stand`] | mass, inertia, gravity, joint positions; the default truck-cabin stand; validation |
//! | [`body_state`] | the 24 redundant coordinates `r, v, e_a, e_a'` |
//! | [`legs`] | leg arms, lengths, directions, rates and the resultant wrench |
//! | [`per_leg`] | a value per leg, the six legs side by side in vector registers |
//! | [`per_axis`] | a value per body axis, the three axes side by side (axis accelerations, power, projection) |
//! | [`end_stops`] | stroke limits as a unilateral virtual potential with contact damping |
//! | [`forces`] | leg force laws (held inputs, springs, closures) |
//! | [`special_form`] | the special-form equations of motion (paper 1.4-1.6) |
//! | [`direct_problem`] | leg forces for a prescribed motion (paper 2.2-2.7) |
//! | [`kinematics`] | 1-2-3 angles, angular rates, inverse kinematics |
//! | [`programme`] | programme motions (soft-start sinusoids) with exact derivatives |
//! | [`invariants`] | energy, momenta |
//! | [`projection`] | projection onto the constraints `e_a . e_b = delta_ab` |
//! | [`configuration`] | admissible configurations (legs, base plane, singularity) |
//! | [`scaling`] | the paper's non-dimensional units |
//! | [`error`] | parameter errors and physics faults |

pub mod body_state;
pub mod configuration;
pub mod direct_problem;
pub mod end_stops;
pub mod error;
pub mod forces;
pub mod invariants;
pub mod kinematics;
pub mod legs;
pub mod per_axis;
pub mod per_leg;
pub mod programme;
pub mod projection;
pub mod scaling;
pub mod special_form;
pub mod stand;
