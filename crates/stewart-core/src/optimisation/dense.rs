//! A dense primal-dual interior-point method for small convex QPs,
//!
//! ```text
//! minimise  x^T H x / 2 + g^T x   subject to   A x <= b
//! ```
//!
//! with `H` symmetric positive definite (`n x n`, a few dozen) and `A` dense (`m x n`, a few
//! hundred rows): the predictive cueing's problem. Mehrotra's predictor-corrector on the
//! slack form `A x + s = b`, `s, z >= 0`, each Newton system reduced to the normal equations
//! `(H + A^T (Z/S) A) dx = r` and solved by one dense Cholesky factorisation per iteration
//! (used for the predictor and the corrector). Its work per iteration is about `m n^2 / 2 +
//! n^3 / 6` multiply-adds to form and factor the normal matrix (fewer where `A`'s columns
//! start late) and a few `m n` for the products with `A` and `A^T`: a fraction of a sparse
//! LDL's on the same dense KKT system (Clarabel's, which the tests hold it against:
//! docs/cueing.md gives the measurements). `A` is kept by columns, each from its first row
//! other than 0: the normal matrix's entries and the products with `A` and `A^T` run over long
//! stretches of rows and skip each column's leading zeros (the cueing's later unknowns reach
//! only its later rows), and the dot products keep four partial sums (short dependency
//! chains).
//!
//! Plain `f64` arithmetic in one fixed order and `sqrt` (exactly rounded): the same bits on
//! every platform. Buffers are made with the solver; a solve allocates nothing.

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpOutcome {
    /// Solved: the residuals and the duality gap within the tolerance.
    Solved { iterations: u32 },
    /// Out of iterations, or broken down, after an iterate within the acceptable tolerance:
    /// that iterate (the last such).
    Acceptable { iterations: u32 },
    /// No usable solution: out of iterations (infeasible, or too hard for the budget), or a
    /// factorisation that broke down.
    Failed { iterations: u32, why: &'static str },
}

/// How hard a solve tries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QpSettings {
    /// Iterations before the solve counts as failed.
    pub max_iterations: u32,
    /// Relative tolerance of the residuals and of the complementarity gap.
    pub tolerance: f64,
    /// A looser one: a solve that ends without reaching `tolerance` (out of iterations, a
    /// factorisation that breaks down, iterates that are not finite) returns its last iterate
    /// within this (IPOPT's "acceptable level"; Clarabel's "almost solved").
    pub acceptable_tolerance: f64,
}

/// A dense QP of fixed sizes and the solver's buffers.
#[derive(Clone, Debug)]
pub struct DenseQp {
    n: usize,
    m: usize,
    settings: QpSettings,
    x: Vec<f64>,
    /// The last iterate within the acceptable tolerance, if one was.
    x_acceptable: Vec<f64>,
    acceptable: bool,
    s: Vec<f64>,
    z: Vec<f64>,
    /// `A` by columns.
    columns: Columns,
    /// Per row: `Z/S` while the normal matrix is formed, then in each direction the row's
    /// weight in the right-hand side, `S^-1 (Z r_p - r_c)`.
    row_weight: Vec<f64>,
    /// A column of `A` times `Z/S`.
    weighted_column: Vec<f64>,
    /// The normal matrix and its Cholesky factor (lower, row-major).
    normal: Vec<f64>,
    /// The factor's diagonal's reciprocals: the solves multiply, a division's latency off
    /// their dependency chains.
    inverse_diagonal: Vec<f64>,
    /// Residuals and directions.
    r_dual: Vec<f64>,
    r_primal: Vec<f64>,
    rhs: Vec<f64>,
    dx: Vec<f64>,
    ds: Vec<f64>,
    dz: Vec<f64>,
    ds_affine: Vec<f64>,
    dz_affine: Vec<f64>,
    r_centre: Vec<f64>,
    ax: Vec<f64>,
}

impl DenseQp {
    /// The solver for `n` unknowns and `m` inequalities (allocates).
    pub fn new(n: usize, m: usize, settings: QpSettings) -> Result<DenseQp, String> {
        if n == 0 {
            return Err("a QP needs at least one unknown".into());
        }
        if !(settings.tolerance > 0.0 && settings.max_iterations > 0) {
            return Err("a QP solver needs a positive tolerance and at least one iteration".into());
        }
        if !(settings.acceptable_tolerance >= settings.tolerance) {
            return Err("a QP solver's acceptable tolerance must be at least its tolerance".into());
        }
        let v = |k: usize| vec![0.0; k];
        Ok(DenseQp {
            n,
            m,
            settings,
            x: v(n),
            x_acceptable: v(n),
            acceptable: false,
            s: v(m),
            z: v(m),
            columns: Columns { m, values: v(n * m), first_row: vec![0; n] },
            row_weight: v(m),
            weighted_column: v(m),
            normal: v(n * n),
            inverse_diagonal: v(n),
            r_dual: v(n),
            r_primal: v(m),
            rhs: v(n),
            dx: v(n),
            ds: v(m),
            dz: v(m),
            ds_affine: v(m),
            dz_affine: v(m),
            r_centre: v(m),
            ax: v(m),
        })
    }

    pub fn unknowns(&self) -> usize {
        self.n
    }

    pub fn inequalities(&self) -> usize {
        self.m
    }

    /// Solves with `h` (row-major `n x n`, symmetric), `g`, `a` (row-major `m x n`) and `b`;
    /// the solution goes to `x` (unchanged on failure).
    pub fn solve(&mut self, h: &[f64], g: &[f64], a: &[f64], b: &[f64], x: &mut [f64]) -> QpOutcome {
        let (n, m) = (self.n, self.m);
        debug_assert!(h.len() == n * n && g.len() == n && a.len() == m * n && b.len() == m && x.len() == n);
        let tol = self.settings.tolerance;
        let scale_d = 1.0 + max_abs(g);
        let scale_p = 1.0 + max_abs(b);
        // Start: x = 0, each slack its bound's value but at least 1 (an infeasible start is
        // fine: the primal residual closes along the way), each dual 1.
        self.x.fill(0.0);
        self.acceptable = false;
        for i in 0..m {
            self.s[i] = b[i].max(1.0);
            self.z[i] = 1.0;
        }
        self.columns.set(a);
        // One pass more than the budget: the last step's iterate is checked too.
        for iteration in 1..=self.settings.max_iterations + 1 {
            // Residuals: r_d = H x + g + A^T z, r_p = A x + s - b.
            for (j, h_row) in h.chunks_exact(n).enumerate() {
                self.r_dual[j] = g[j] + dot(h_row, &self.x) + self.columns.dot(j, &self.z);
            }
            self.columns.times(&self.x, &mut self.ax);
            for i in 0..m {
                self.r_primal[i] = self.ax[i] + self.s[i] - b[i];
            }
            let gap = dot(&self.s, &self.z);
            if !gap.is_finite() {
                // A slack or dual overflowed: no later iterate can be within the tolerance.
                return self.give_up(x, iteration, "the iterates are not finite");
            }
            let mu = if m > 0 { gap / m as f64 } else { 0.0 };
            // The objective's size, for a relative gap: x^T H x / 2 + g^T x (r_d - A^T z = H x + g).
            let mut objective = 0.0;
            for k in 0..n {
                objective += self.x[k] * (0.5 * (self.r_dual[k] - g[k]) + g[k]);
            }
            let mut atz_x = 0.0;
            for i in 0..m {
                atz_x += self.z[i] * self.ax[i];
            }
            objective -= 0.5 * atz_x;
            let (dual, primal) = (max_abs(&self.r_dual), max_abs(&self.r_primal));
            let within =
                |tol: f64| dual <= tol * scale_d && primal <= tol * scale_p && gap <= tol * objective.abs().max(1.0);
            if within(tol) {
                x.copy_from_slice(&self.x);
                return QpOutcome::Solved { iterations: iteration - 1 };
            }
            if within(self.settings.acceptable_tolerance) {
                self.x_acceptable.copy_from_slice(&self.x);
                self.acceptable = true;
            }
            if iteration > self.settings.max_iterations {
                break;
            }
            if !self.factor(h) {
                return self.give_up(x, iteration, "the normal equations are not positive definite");
            }
            // Predictor: the affine direction (r_c = s z).
            for i in 0..m {
                self.r_centre[i] = self.s[i] * self.z[i];
            }
            self.direction();
            let alpha_affine = self.step_to_boundary(1.0);
            let mut mu_affine = 0.0;
            for i in 0..m {
                mu_affine += (self.s[i] + alpha_affine * self.ds[i]) * (self.z[i] + alpha_affine * self.dz[i]);
            }
            mu_affine /= m.max(1) as f64;
            let ratio = if mu > 0.0 { mu_affine / mu } else { 0.0 };
            let sigma = ratio * ratio * ratio;
            // Corrector: r_c = s z + ds_aff dz_aff - sigma mu.
            self.ds_affine.copy_from_slice(&self.ds);
            self.dz_affine.copy_from_slice(&self.dz);
            for i in 0..m {
                self.r_centre[i] = self.s[i] * self.z[i] + self.ds_affine[i] * self.dz_affine[i] - sigma * mu;
            }
            self.direction();
            let alpha = self.step_to_boundary(0.99);
            for k in 0..n {
                self.x[k] += alpha * self.dx[k];
            }
            for i in 0..m {
                self.s[i] += alpha * self.ds[i];
                self.z[i] += alpha * self.dz[i];
            }
            if !self.x.iter().all(|v| v.is_finite()) {
                return self.give_up(x, iteration, "the iterates are not finite");
            }
        }
        self.give_up(x, self.settings.max_iterations, "out of iterations")
    }

    /// The end of a solve that did not reach the tolerance: its last acceptable iterate to
    /// `x`, or a failure (`x` unchanged).
    fn give_up(&self, x: &mut [f64], iterations: u32, why: &'static str) -> QpOutcome {
        if self.acceptable {
            x.copy_from_slice(&self.x_acceptable);
            QpOutcome::Acceptable { iterations }
        } else {
            QpOutcome::Failed { iterations, why }
        }
    }

    /// The normal matrix `H + A^T (Z/S) A` and its Cholesky factor in `normal` (lower
    /// triangle; the upper is not read), the factor's diagonal's reciprocals in
    /// `inverse_diagonal`; `false` if it is not positive definite.
    fn factor(&mut self, h: &[f64]) -> bool {
        let (n, m) = (self.n, self.m);
        for i in 0..m {
            self.row_weight[i] = self.z[i] / self.s[i];
        }
        // The lower triangle, `H_jk + sum_i (d_i a_ij) a_ik` over the rows where both columns
        // may be other than 0.
        for j in 0..n {
            let (from_j, column_j) = self.columns.column(j);
            for i in from_j..m {
                self.weighted_column[i] = self.row_weight[i] * column_j[i];
            }
            for k in 0..=j {
                let from = from_j.max(self.columns.first_row[k]);
                let column_k = self.columns.column(k).1;
                self.normal[j * n + k] = h[j * n + k] + dot(&self.weighted_column[from..], &column_k[from..]);
            }
        }
        // Cholesky, row by row: L L^T = normal. Near the solution Z/S grows without bound on
        // the active constraints and the matrix's condition with it: a pivot lost to round-off
        // (below 1e-13 of its diagonal) is replaced by a huge one, so that its direction takes
        // no step (Wright's modified Cholesky for interior-point methods).
        for j in 0..n {
            let diagonal = self.normal[j * n + j];
            for k in 0..=j {
                let (above, from_j) = self.normal.split_at(j * n);
                let row_j = &from_j[..n];
                let row_k = if k < j { &above[k * n..k * n + n] } else { row_j };
                let sum = row_j[k] - dot(&row_j[..k], &row_k[..k]);
                if k == j {
                    if !(diagonal > 0.0 && diagonal.is_finite()) || sum.is_nan() {
                        return false;
                    }
                    let pivot = if sum > 1e-13 * diagonal { sum } else { 1e128 };
                    let root = pivot.sqrt();
                    self.normal[j * n + j] = root;
                    self.inverse_diagonal[j] = 1.0 / root;
                } else {
                    self.normal[j * n + k] = sum * self.inverse_diagonal[k];
                }
            }
        }
        true
    }

    /// The Newton direction for the centring residual `r_centre`: `dx` from the normal
    /// equations `(H + A^T (Z/S) A) dx = -r_d - A^T S^-1 (Z r_p - r_c)`, then
    /// `ds = -r_p - A dx` and `dz = S^-1 (-r_c - Z ds)`.
    fn direction(&mut self) {
        let (n, m) = (self.n, self.m);
        for i in 0..m {
            self.row_weight[i] = (self.z[i] * self.r_primal[i] - self.r_centre[i]) / self.s[i];
        }
        for k in 0..n {
            self.rhs[k] = -self.r_dual[k] - self.columns.dot(k, &self.row_weight);
        }
        // L y = rhs, then L^T dx = y: the latter by rows of L (each solved unknown taken out of
        // the ones above it at once), which keeps one dependency chain per unknown short.
        for j in 0..n {
            let row = &self.normal[j * n..j * n + n];
            self.dx[j] = (self.rhs[j] - dot(&row[..j], &self.dx[..j])) * self.inverse_diagonal[j];
        }
        for j in (0..n).rev() {
            let dx_j = self.dx[j] * self.inverse_diagonal[j];
            self.dx[j] = dx_j;
            axpy(-dx_j, &self.normal[j * n..j * n + j], &mut self.dx[..j]);
        }
        // `A dx` into `ds`, then `ds = -r_p - A dx`.
        self.columns.times(&self.dx, &mut self.ds);
        for i in 0..m {
            self.ds[i] = -self.r_primal[i] - self.ds[i];
            self.dz[i] = (-self.r_centre[i] - self.z[i] * self.ds[i]) / self.s[i];
        }
    }

    /// The largest step up to 1 that keeps `s` and `z` positive, times `fraction`.
    fn step_to_boundary(&self, fraction: f64) -> f64 {
        let mut alpha = 1.0f64;
        for i in 0..self.m {
            if self.ds[i] < 0.0 {
                alpha = alpha.min(-self.s[i] / self.ds[i]);
            }
            if self.dz[i] < 0.0 {
                alpha = alpha.min(-self.z[i] / self.dz[i]);
            }
        }
        if fraction < 1.0 { (fraction * alpha).min(1.0) } else { alpha }
    }
}

/// `A` (`m x n`) by columns, each from its first row other than 0: the normal matrix's entries
/// and the products with `A` and `A^T` are then sums over long stretches of rows, from where
/// the columns' zeros end (the cueing's later blocks of unknowns reach only the later points'
/// rows).
#[derive(Clone, Debug)]
struct Columns {
    m: usize,
    /// Row-major `n x m`: column `j` is `values[j m..(j + 1) m]`.
    values: Vec<f64>,
    /// Each column's first row that is not 0 (`m` for a column of zeros; -0.0 counts as 0,
    /// NaN does not).
    first_row: Vec<usize>,
}

impl Columns {
    /// Takes `a` (row-major `m x n`).
    fn set(&mut self, a: &[f64]) {
        let (m, n) = (self.m, self.first_row.len());
        for j in 0..n {
            let column = &mut self.values[j * m..(j + 1) * m];
            for (i, entry) in column.iter_mut().enumerate() {
                *entry = a[i * n + j];
            }
            self.first_row[j] = column.iter().position(|&v| v != 0.0).unwrap_or(m);
        }
    }

    /// Column `j`'s first row other than 0, and the whole column.
    fn column(&self, j: usize) -> (usize, &[f64]) {
        (self.first_row[j], &self.values[j * self.m..(j + 1) * self.m])
    }

    /// `A^T`'s row `j` times `v`, from the column's first row other than 0.
    fn dot(&self, j: usize, v: &[f64]) -> f64 {
        let (from, column) = self.column(j);
        dot(&column[from..], &v[from..])
    }

    /// `A v` into `out`, column by column.
    fn times(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        if self.m == 0 {
            // No rows (and `chunks_exact` takes no chunk size 0).
            return;
        }
        for (j, (column, &from)) in self.values.chunks_exact(self.m).zip(&self.first_row).enumerate() {
            axpy(v[j], &column[from..], &mut out[from..]);
        }
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// `a . b` in four partial sums, element `i` into sum `i mod 4`, added as `(s0 + s2) + (s1 +
/// s3)`: one order everywhere (the same bits on every platform), and four dependency chains
/// instead of one, which the solve's short dot products are bound by. `a` and `b` are of one
/// length (debug builds check it; release builds would take the shorter).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut sums = [0.0f64; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (a_rest, b_rest) = (a4.remainder(), b4.remainder());
    for (x, y) in a4.zip(b4) {
        for lane in 0..4 {
            sums[lane] += x[lane] * y[lane];
        }
    }
    for (lane, (x, y)) in a_rest.iter().zip(b_rest).enumerate() {
        sums[lane] += x * y;
    }
    (sums[0] + sums[2]) + (sums[1] + sums[3])
}

/// `y += alpha x`, element by element.
#[inline]
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += alpha * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small QP with a known answer: minimise (x1 - 1)^2 + (x2 - 2)^2 subject to
    /// x1 + x2 <= 2: the projection of (1, 2) onto the half-plane, (0.5, 1.5); and an
    /// infeasible one.
    #[test]
    fn a_projection_onto_a_half_plane_and_an_infeasible_problem() {
        let mut qp =
            DenseQp::new(2, 1, QpSettings { max_iterations: 50, tolerance: 1e-10, acceptable_tolerance: 1e-10 })
                .unwrap();
        let mut x = [0.0; 2];
        let outcome = qp.solve(&[2.0, 0.0, 0.0, 2.0], &[-2.0, -4.0], &[1.0, 1.0], &[2.0], &mut x);
        assert!(matches!(outcome, QpOutcome::Solved { .. }), "{outcome:?}");
        assert!((x[0] - 0.5).abs() < 1e-9 && (x[1] - 1.5).abs() < 1e-9, "{x:?}");
        let mut qp =
            DenseQp::new(1, 2, QpSettings { max_iterations: 50, tolerance: 1e-10, acceptable_tolerance: 1e-10 })
                .unwrap();
        let mut x = [7.0];
        let outcome = qp.solve(&[1.0], &[0.0], &[1.0, -1.0], &[-1.0, -1.0], &mut x);
        assert!(matches!(outcome, QpOutcome::Failed { .. }), "{outcome:?}");
        assert_eq!(x, [7.0], "a failed solve leaves x as it was");
    }

    /// A solve that cannot reach its tolerance (1e-300) returns its last iterate within the
    /// acceptable one, which is the projection to that accuracy; with no acceptable level
    /// (equal to the tolerance) the same solve fails and leaves `x` as it was.
    /// Without inequalities the solve is the unconstrained minimum `-H^-1 g`.
    #[test]
    fn no_inequalities_give_the_unconstrained_minimum() {
        let h = [4.0, 1.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 2.0];
        let g = [1.0, -2.0, 0.5];
        let mut x = [0.0; 3];
        let settings = QpSettings { max_iterations: 20, tolerance: 1e-12, acceptable_tolerance: 1e-12 };
        let outcome = DenseQp::new(3, 0, settings).unwrap().solve(&h, &g, &[], &[], &mut x);
        assert!(matches!(outcome, QpOutcome::Solved { .. }), "{outcome:?}");
        // [[4, 1], [1, 3]] (x0, x1) = (-1, 2): x0 = -5/11, x1 = 9/11; 2 x2 = -0.5.
        let expected = [-5.0 / 11.0, 9.0 / 11.0, -0.25];
        // (Each step goes 0.99 of the way: the residual falls a hundredfold per iteration.)
        for k in 0..3 {
            assert!((x[k] - expected[k]).abs() < 1e-10, "{x:?} against {expected:?}");
        }
    }

    #[test]
    fn an_unreachable_tolerance_ends_at_the_acceptable_iterate() {
        let (h, g, a, b) = ([2.0, 0.0, 0.0, 2.0], [-2.0, -4.0], [1.0, 1.0], [2.0]);
        let settings = QpSettings { max_iterations: 40, tolerance: 1e-300, acceptable_tolerance: 1e-6 };
        let mut x = [0.0; 2];
        let outcome = DenseQp::new(2, 1, settings).unwrap().solve(&h, &g, &a, &b, &mut x);
        assert!(matches!(outcome, QpOutcome::Acceptable { iterations: 40 }), "{outcome:?}");
        assert!((x[0] - 0.5).abs() < 1e-5 && (x[1] - 1.5).abs() < 1e-5, "{x:?}");
        let settings = QpSettings { acceptable_tolerance: 1e-300, ..settings };
        let mut x = [7.0, 7.0];
        let outcome = DenseQp::new(2, 1, settings).unwrap().solve(&h, &g, &a, &b, &mut x);
        assert!(matches!(outcome, QpOutcome::Failed { .. }), "{outcome:?}");
        assert_eq!(x, [7.0, 7.0]);
    }

    /// Random dense QPs of the cueing's size against Clarabel (the crate the tests hold the
    /// solver against): the same solutions to 1e-7 relative, active constraints or not.
    #[test]
    fn random_qps_against_clarabel() {
        use clarabel::algebra::CscMatrix;
        use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};
        let mut next = crate::test_support::xorshift(0x9e37_79b9_7f4a_7c15);
        let (n, m) = (24, 128);
        let (mut worst_unknowns, mut worst_objective, mut worst_violation) = (0.0f64, 0.0f64, 0.0f64);
        for case in 0..20 {
            let l: Vec<f64> = (0..n * n).map(|_| next()).collect();
            let h: Vec<f64> = (0..n * n)
                .map(|ij| {
                    let (i, j) = (ij / n, ij % n);
                    (0..n).map(|k| l[i * n + k] * l[j * n + k]).sum::<f64>() + if i == j { 0.5 } else { 0.0 }
                })
                .collect();
            // Dense in half the cases; in the others as the cueing's: row block `r` (32 rows)
            // reaches the first `6 (r + 1)` unknowns, the last row none, in some cases the last
            // unknown no row, and in some the zeros are -0.0.
            let a: Vec<f64> = (0..m * n)
                .map(|ij| {
                    let (i, j) = (ij / n, ij % n);
                    let value = next();
                    let reached =
                        case % 2 == 0 || (j < 6 * (i / 32 + 1) && i != m - 1 && !(case % 5 == 3 && j == n - 1));
                    match (reached, case % 4) {
                        (true, _) => value,
                        (false, 3) => -0.0,
                        (false, _) => 0.0,
                    }
                })
                .collect();
            let g: Vec<f64> = (0..n).map(|_| 10.0 * next()).collect();
            // Some cases with no active constraint, the others with many.
            let b: Vec<f64> = (0..m)
                .map(|i| {
                    if case % 4 == 0 {
                        1e3
                    } else if i % 3 == 0 {
                        0.1
                    } else {
                        2.0
                    }
                })
                .collect();
            let mut ours = vec![0.0; n];
            // (The cueing's zeros leave rows that differ in few unknowns: their solves stall
            // short of 1e-10, as the row-wise form's did.)
            let tolerance = if case % 2 == 0 { 1e-10 } else { 1e-9 };
            let settings = QpSettings { max_iterations: 100, tolerance, acceptable_tolerance: tolerance };
            let outcome = DenseQp::new(n, m, settings).unwrap().solve(&h, &g, &a, &b, &mut ours);
            assert!(matches!(outcome, QpOutcome::Solved { .. }), "case {case}: {outcome:?}");
            let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
            for j in 0..n {
                for i in 0..=j {
                    rowval.push(i);
                    nzval.push(h[i * n + j]);
                }
                colptr.push(rowval.len());
            }
            let p = CscMatrix::new(n, n, colptr, rowval, nzval);
            let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
            for j in 0..n {
                for i in 0..m {
                    rowval.push(i);
                    nzval.push(a[i * n + j]);
                }
                colptr.push(rowval.len());
            }
            let am = CscMatrix::new(m, n, colptr, rowval, nzval);
            let settings = DefaultSettingsBuilder::default()
                .verbose(false)
                .tol_gap_abs(1e-11)
                .tol_gap_rel(1e-11)
                .tol_feas(1e-11)
                .build()
                .unwrap();
            let mut reference = DefaultSolver::new(&p, &g, &am, &b, &[NonnegativeConeT(m)], settings).unwrap();
            reference.solve();
            assert_eq!(reference.solution.status, SolverStatus::Solved, "case {case}");
            let size = reference.solution.x.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            // Dense: the same unknowns. The cueing's zeros: the same optimum, and feasible (the
            // solves end at 1e-9, where the unknowns may still differ by some 1e-6 of their
            // size along directions the objective hardly weighs).
            if case % 2 == 0 {
                for k in 0..n {
                    worst_unknowns = worst_unknowns.max((ours[k] - reference.solution.x[k]).abs() / size);
                }
            } else {
                let objective = |x: &[f64]| {
                    (0..n).map(|i| x[i] * (g[i] + 0.5 * (0..n).map(|j| h[i * n + j] * x[j]).sum::<f64>())).sum::<f64>()
                };
                let best = objective(&reference.solution.x);
                worst_objective = worst_objective.max((objective(&ours) - best).abs() / best.abs().max(1.0));
                let violation =
                    (0..m).map(|i| (0..n).map(|j| a[i * n + j] * ours[j]).sum::<f64>() - b[i]).fold(0.0, f64::max);
                worst_violation = worst_violation.max(violation);
            }
        }
        println!(
            "against Clarabel over 20 QPs of 24 x 128: dense, the unknowns' largest relative difference \
             {worst_unknowns:e}; with the cueing's zeros, the objective's {worst_objective:e} and the largest \
             violation {worst_violation:e}"
        );
        assert!(worst_unknowns < 1e-7 && worst_objective < 1e-9 && worst_violation < 1e-9);
    }
}
