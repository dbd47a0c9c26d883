//! Dense convex quadratic programmes of a fixed size, solved by Clarabel (the interior-point
//! solver of Goulart and Chen, Oxford; pure Rust):
//!
//! ```text
//! minimise  x^T H x / 2 + g^T x   subject to   A x <= b
//! ```
//!
//! with `H` symmetric positive semidefinite (`n x n`) and `A` (`m x n`) dense. The solver is set
//! up once for the sizes (its symbolic factorisation, every buffer), after which each
//! [`DenseQp::solve`] overwrites the data in place and solves: no set-up, no equilibration
//! computed from data (so a solve is a function of its data alone, whatever came before: a
//! restored FMU state continues with the same bits), no time limit (the budget is an
//! iteration count, the same on every machine).
//!
//! One allocation remains per solve, inside Clarabel: its timers clear a map of sub-timers
//! and fill it again (`clarabel::timers`, 0.11.1). It is counted in the cueing's benchmarks.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};

use super::real::Libm64;

/// How hard a solve tries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QpSettings {
    /// Interior-point iterations before the solve counts as failed.
    pub max_iterations: u32,
    /// Clarabel's gap and feasibility tolerances (absolute and relative).
    pub tolerance: f64,
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpOutcome {
    /// Solved to the tolerance (or to Clarabel's reduced accuracy).
    Solved { iterations: u32 },
    /// No usable solution: infeasible, out of iterations, or a numerical failure.
    Failed { iterations: u32, why: &'static str },
}

/// A dense QP of fixed sizes and its solver (see the module's documentation).
pub struct DenseQp {
    n: usize,
    m: usize,
    solver: DefaultSolver<Libm64>,
    /// `H`'s upper triangle, column by column (Clarabel's pattern of `P`).
    p_values: Vec<Libm64>,
    /// `A`, column by column.
    a_values: Vec<Libm64>,
    g: Vec<Libm64>,
    b: Vec<Libm64>,
}

impl std::fmt::Debug for DenseQp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DenseQp {{ n: {}, m: {} }}", self.n, self.m)
    }
}

/// A dense `rows x cols` pattern, column by column; `upper`: the upper triangle only.
fn dense_pattern(rows: usize, cols: usize, upper: bool, value: impl Fn(usize, usize) -> f64) -> CscMatrix<Libm64> {
    let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
    for j in 0..cols {
        for i in 0..if upper { j + 1 } else { rows } {
            rowval.push(i);
            nzval.push(Libm64(value(i, j)));
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(rows, cols, colptr, rowval, nzval)
}

impl DenseQp {
    /// The solver for `n` unknowns and `m` inequalities, set up on the pattern (allocates).
    pub fn new(n: usize, m: usize, settings: QpSettings) -> Result<DenseQp, String> {
        if n == 0 {
            return Err("a QP needs at least one unknown".into());
        }
        let p = dense_pattern(n, n, true, |i, j| if i == j { 1.0 } else { 0.0 });
        let a = dense_pattern(m, n, false, |_, _| 0.0);
        let (g, b) = (vec![Libm64(0.0); n], vec![Libm64(1.0); m]);
        let tol = Libm64(settings.tolerance);
        let clarabel_settings: DefaultSettings<Libm64> = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(settings.max_iterations)
            .presolve_enable(false)
            .input_sparse_dropzeros(false)
            .equilibrate_enable(false)
            .tol_gap_abs(tol)
            .tol_gap_rel(tol)
            .tol_feas(tol)
            .build()
            .map_err(|e| format!("QP solver settings: {e}"))?;
        let cones = [NonnegativeConeT(m)];
        let solver = DefaultSolver::new(&p, &g, &a, &b, &cones, clarabel_settings)
            .map_err(|e| format!("QP solver set-up: {e}"))?;
        Ok(DenseQp { n, m, p_values: p.nzval, a_values: a.nzval, g, b, solver })
    }

    pub fn unknowns(&self) -> usize {
        self.n
    }

    pub fn inequalities(&self) -> usize {
        self.m
    }

    /// Solves with `h` (row-major `n x n`, its upper triangle read), `g`, `a` (row-major
    /// `m x n`) and `b`; the solution goes to `x`. Allocates nothing of its own.
    pub fn solve(&mut self, h: &[f64], g: &[f64], a: &[f64], b: &[f64], x: &mut [f64]) -> QpOutcome {
        let (n, m) = (self.n, self.m);
        debug_assert!(h.len() == n * n && g.len() == n && a.len() == m * n && b.len() == m && x.len() == n);
        let mut at = 0;
        for j in 0..n {
            for i in 0..=j {
                self.p_values[at] = Libm64(h[i * n + j]);
                at += 1;
            }
        }
        for j in 0..n {
            for i in 0..m {
                self.a_values[j * m + i] = Libm64(a[i * n + j]);
            }
        }
        for (to, &from) in self.g.iter_mut().zip(g) {
            *to = Libm64(from);
        }
        for (to, &from) in self.b.iter_mut().zip(b) {
            *to = Libm64(from);
        }
        let updated = self
            .solver
            .update_P(&self.p_values)
            .and_then(|()| self.solver.update_A(&self.a_values))
            .and_then(|()| self.solver.update_q(&self.g))
            .and_then(|()| self.solver.update_b(&self.b));
        if updated.is_err() {
            return QpOutcome::Failed { iterations: 0, why: "the solver refused the data" };
        }
        self.solver.solve();
        let solution = &self.solver.solution;
        let iterations = solution.iterations;
        let why = match solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                if solution.x.iter().all(|v| v.0.is_finite()) {
                    for (to, from) in x.iter_mut().zip(&solution.x) {
                        *to = from.0;
                    }
                    return QpOutcome::Solved { iterations };
                }
                "a solution that is not finite"
            }
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => "infeasible",
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => "unbounded",
            SolverStatus::MaxIterations => "out of iterations",
            SolverStatus::MaxTime => "out of time",
            SolverStatus::NumericalError => "a numerical error",
            SolverStatus::InsufficientProgress => "no progress",
            _ => "unsolved",
        };
        QpOutcome::Failed { iterations, why }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small QP with a known answer: minimise (x1 - 1)^2 + (x2 - 2)^2 subject to
    /// x1 + x2 <= 2: the projection of (1, 2) onto the half-plane, (0.5, 1.5).
    #[test]
    fn a_projection_onto_a_half_plane() {
        let mut qp = DenseQp::new(2, 1, QpSettings { max_iterations: 50, tolerance: 1e-10 }).unwrap();
        let mut x = [0.0; 2];
        for _ in 0..3 {
            let outcome = qp.solve(&[2.0, 0.0, 0.0, 2.0], &[-2.0, -4.0], &[1.0, 1.0], &[2.0], &mut x);
            assert!(matches!(outcome, QpOutcome::Solved { .. }), "{outcome:?}");
            assert!((x[0] - 0.5).abs() < 1e-8 && (x[1] - 1.5).abs() < 1e-8, "{x:?}");
        }
        // An infeasible one: x1 <= -1 and -x1 <= -1.
        let mut qp = DenseQp::new(1, 2, QpSettings { max_iterations: 50, tolerance: 1e-10 }).unwrap();
        let mut x = [0.0];
        let outcome = qp.solve(&[1.0], &[0.0], &[1.0, -1.0], &[-1.0, -1.0], &mut x);
        assert!(matches!(outcome, QpOutcome::Failed { why: "infeasible", .. }), "{outcome:?}");
    }
}
