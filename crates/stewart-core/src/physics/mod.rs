//! The physics core: pure rigid-body mechanics of the loaded Stewart platform in the special
//! form of Zegzhda, Petrova and Yushkov (2020). No FFI, no integration, no I/O; every function
//! here is testable on its own.
//!
//! | module | what it holds |
//! |---|---|
//! | [`number`] | the number types: `Number` (`f64`, `Dual` for exact derivatives, six legs side by side) and `Real` (one value) |
//! | [`stand`] | mass, inertia, gravity, joint positions; the default truck-cabin stand; validation |
//! | [`body`] | the rigid body: its 24 redundant coordinates, the special form's accelerations, projection, angles, invariants |
//! | [`legs`] | the legs: geometry, end stops, the six legs side by side |
//! | [`actuators`] | what drives the legs: leg force laws, the electric drives |
//! | [`special_form`] | the platform's equations of motion: body, legs and stops together |
//! | [`direct_problem`] | leg forces for a prescribed motion (paper 2.2-2.7) |
//! | [`programme`] | programme motions (soft-start sinusoids) with exact derivatives |
//! | [`configuration`] | admissible configurations (legs, base plane, singularity) |
//! | [`scaling`] | the paper's non-dimensional units |
//! | [`error`] | parameter errors and physics faults |
//! | [`symmetric6`] | the extreme eigenvalues of a symmetric 6x6 matrix (for `kappa`) |

/// Number of legs (hydraulic cylinders) of a Stewart platform. Here, below every module,
/// so that the errors can name legs without importing the stand that reports them.
pub const LEG_COUNT: usize = 6;

pub mod actuators;
pub mod body;
pub mod configuration;
pub mod cueing;
pub mod direct_problem;
pub mod error;
pub mod full_pivot_lu;
pub mod legs;
pub mod number;
pub mod programme;
pub mod scaling;
pub mod special_form;
pub mod stand;
pub mod symmetric6;
