//! Numerical optimisation: dense convex quadratic programmes of a fixed size ([`dense`]: a
//! primal-dual interior-point method with one dense Cholesky factorisation per iteration).
//! Knows nothing of platforms, cueing or FMI; allocates when made, never in a solve.

pub mod dense;
