//! Numerical optimisation: dense convex quadratic programmes of a fixed size ([`qp`]), solved
//! by the Clarabel crate on [`real::Libm64`], an `f64` whose elementary functions are the
//! crate's own. Knows nothing of platforms, cueing or FMI; allocates at set-up only (but for
//! one allocation per solve inside Clarabel, [`qp`]).

pub mod qp;
pub mod real;
