//! The LU factorisation with full pivoting of a 6x6 matrix and its solve, written out as
//! nalgebra's `Matrix::full_piv_lu` and `FullPivLU::solve` (0.35) compute them: the same
//! pivots, the same operations in the same order, so the same bits (the tests below compare
//! them on thousands of matrices). The controller's direct problem solves with it every step;
//! nalgebra's generic views and permutation sequences cost about three times the
//! instructions, and the closed loop's results have been nalgebra's bits since before the
//! machine model (`tests/python/test_machine.py` holds them).

const N: usize = 6;

/// `P A Q = L U` of a 6x6 matrix.
#[derive(Clone, Copy, Debug)]
pub struct FullPivotLu6 {
    /// `L` (below the diagonal, unit diagonal implied) and `U` (on and above), column by
    /// column: `lu[c][r]`, as nalgebra stores it.
    lu: [[f64; N]; N],
    /// Step `i` swapped rows `i` and `row_swaps[i]` (`i` where none, or after the
    /// factorisation stopped at a zero block).
    row_swaps: [usize; N],
    /// Step `i` swapped columns `i` and `column_swaps[i]`.
    column_swaps: [usize; N],
}

/// Step `I` of the factorisation: pivot, swap, eliminate below row `I`. `false` where the
/// rest of the matrix is zero (the factorisation stops there, as nalgebra's does).
#[inline(always)]
fn eliminate<const I: usize>(a: &mut [[f64; N]; N], row_swaps: &mut [usize; N], column_swaps: &mut [usize; N]) -> bool {
    // The largest |entry| of the block a[I.., I..], scanned column by column; only a strictly
    // larger one moves the pivot (nalgebra's `icamax_full`).
    let (mut row, mut column) = (I, I);
    let mut max = a[I][I].abs();
    for c in I..N {
        for r in I..N {
            let x = a[c][r].abs();
            if x > max {
                max = x;
                (row, column) = (r, c);
            }
        }
    }
    let diag = a[column][row];
    if diag == 0.0 {
        return false;
    }
    a.swap(I, column);
    column_swaps[I] = column;
    // nalgebra swaps the rows in the columns before I, then in the pivot column, then in each
    // later column as it eliminates it: one whole-row swap, the same result.
    row_swaps[I] = row;
    for col in a.iter_mut() {
        col.swap(I, row);
    }
    let inv_diag = 1.0 / diag;
    for r in I + 1..N {
        a[I][r] *= inv_diag;
    }
    let coeffs = a[I];
    for c in I + 1..N {
        // nalgebra's axpy: y = (-p) x 1 + 1 y, the same bits as y + (-p x).
        let p = a[c][I];
        for r in I + 1..N {
            a[c][r] += -p * coeffs[r];
        }
    }
    true
}

impl FullPivotLu6 {
    /// Factorises `a` given column by column (`a[c][r]`).
    pub fn new(mut a: [[f64; N]; N]) -> Self {
        let mut row_swaps = [0, 1, 2, 3, 4, 5];
        let mut column_swaps = row_swaps;
        // One step per column, each with its index a constant, so that every loop unrolls.
        let _ = eliminate::<0>(&mut a, &mut row_swaps, &mut column_swaps)
            && eliminate::<1>(&mut a, &mut row_swaps, &mut column_swaps)
            && eliminate::<2>(&mut a, &mut row_swaps, &mut column_swaps)
            && eliminate::<3>(&mut a, &mut row_swaps, &mut column_swaps)
            && eliminate::<4>(&mut a, &mut row_swaps, &mut column_swaps)
            && eliminate::<5>(&mut a, &mut row_swaps, &mut column_swaps);
        FullPivotLu6 { lu: a, row_swaps, column_swaps }
    }

    /// Whether the factors can be solved with (nalgebra's test: the last pivot is not zero).
    pub fn is_invertible(&self) -> bool {
        self.lu[N - 1][N - 1] != 0.0
    }

    /// `x` with `A x = b`, `None` where [`FullPivotLu6::is_invertible`] is false.
    pub fn solve(&self, b: &[f64; N]) -> Option<[f64; N]> {
        if !self.is_invertible() {
            return None;
        }
        let mut x = *b;
        for i in 0..N {
            x.swap(i, self.row_swaps[i]);
        }
        // L y = P b, unit diagonal (nalgebra divides by the diagonal 1, which changes nothing).
        for i in 0..N - 1 {
            let coeff = x[i];
            for r in i + 1..N {
                x[r] += -coeff * self.lu[i][r];
            }
        }
        // U z = y. nalgebra stops at a zero pivot and keeps what it has (only an inner pivot
        // can be zero here, which full pivoting never leaves before a non-zero last one).
        for i in (0..N).rev() {
            let diag = self.lu[i][i];
            if diag == 0.0 {
                break;
            }
            let coeff = x[i] / diag;
            x[i] = coeff;
            for r in 0..i {
                x[r] += -coeff * self.lu[i][r];
            }
        }
        for i in (0..N).rev() {
            x.swap(i, self.column_swaps[i]);
        }
        Some(x)
    }

    /// `|A^-1|_F = |U^-1 L^-1|_F` (the permutations do not change it), `None` where a pivot is
    /// zero. For a bound only: not nalgebra's operation order.
    pub fn inverse_frobenius_norm(&self) -> Option<f64> {
        if (0..N).any(|i| self.lu[i][i] == 0.0) {
            return None;
        }
        let inv_diag: [f64; N] = std::array::from_fn(|i| 1.0 / self.lu[i][i]);
        let sum = self.inverse_column_norm2::<0>(&inv_diag)
            + self.inverse_column_norm2::<1>(&inv_diag)
            + self.inverse_column_norm2::<2>(&inv_diag)
            + self.inverse_column_norm2::<3>(&inv_diag)
            + self.inverse_column_norm2::<4>(&inv_diag)
            + self.inverse_column_norm2::<5>(&inv_diag);
        Some(sum.sqrt())
    }

    /// `|U^-1 L^-1 e_J|^2`: `L y = e_J` (zero above row `J`), then `U z = y`.
    #[inline(always)]
    fn inverse_column_norm2<const J: usize>(&self, inv_diag: &[f64; N]) -> f64 {
        let mut x = [0.0; N];
        x[J] = 1.0;
        for i in J..N - 1 {
            let coeff = x[i];
            for r in i + 1..N {
                x[r] -= coeff * self.lu[i][r];
            }
        }
        for i in (0..N).rev() {
            let coeff = x[i] * inv_diag[i];
            x[i] = coeff;
            for r in 0..i {
                x[r] -= coeff * self.lu[i][r];
            }
        }
        x.iter().map(|v| v * v).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix6, Vector6};

    fn columns(m: &Matrix6<f64>) -> [[f64; N]; N] {
        std::array::from_fn(|c| std::array::from_fn(|r| m[(r, c)]))
    }

    /// In [-0.5, 0.5).
    fn random() -> impl FnMut() -> f64 {
        let mut uniform = crate::test_support::xorshift(0x9e37_79b9_7f4a_7c15);
        move || 0.5 * uniform()
    }

    /// Matrices that exercise every branch: random, with repeated entries (ties in the pivot
    /// search), integer entries, zero rows and columns, rank-deficient, diagonal, NaN.
    fn cases() -> Vec<Matrix6<f64>> {
        let mut next = random();
        let mut out = vec![Matrix6::identity(), Matrix6::zeros(), Matrix6::from_element(1.0)];
        for case in 0..3000 {
            let mut m = Matrix6::from_fn(|_, _| next());
            match case % 8 {
                1 => m = m.map(|x| (x * 8.0).round()),
                2 => m.set_column(case % 6, &Vector6::zeros()),
                3 => m.set_row(case % 6, &nalgebra::RowVector6::zeros()),
                4 => {
                    let c = m.column(0) * 2.0 + m.column(1);
                    m.set_column(5, &c);
                }
                5 => m = Matrix6::from_diagonal(&Vector6::from_fn(|i, _| (i as f64 - 2.5) * next())),
                6 if case % 48 == 6 => m[(case % 6, (case / 6) % 6)] = f64::NAN,
                7 => m *= 1e-300,
                _ => {}
            }
            out.push(m);
        }
        out
    }

    #[test]
    fn the_factors_and_solutions_are_nalgebras_to_the_bit() {
        let mut next = random();
        let mut solved = 0;
        for m in cases() {
            let ours = FullPivotLu6::new(columns(&m));
            let theirs = m.full_piv_lu();
            let (l, u) = (theirs.l(), theirs.u());
            for c in 0..N {
                for r in 0..N {
                    let theirs = if r > c { l[(r, c)] } else { u[(r, c)] };
                    assert_eq!(ours.lu[c][r].to_bits(), theirs.to_bits(), "LU ({r}, {c}) of {m}");
                }
            }
            assert_eq!(ours.is_invertible(), theirs.is_invertible());
            let b = Vector6::from_fn(|_, _| next());
            let x = ours.solve(&[b[0], b[1], b[2], b[3], b[4], b[5]]);
            match theirs.solve(&b) {
                Some(y) => {
                    let x = x.expect("ours solves where nalgebra does");
                    for i in 0..N {
                        assert_eq!(x[i].to_bits(), y[i].to_bits(), "x[{i}] of {m}");
                    }
                    solved += 1;
                }
                None => assert!(x.is_none()),
            }
        }
        assert!(solved > 2000, "{solved}");
    }

    #[test]
    fn the_inverse_norm_is_the_inverses() {
        let mut worst: f64 = 0.0;
        for m in cases() {
            let ours = FullPivotLu6::new(columns(&m)).inverse_frobenius_norm();
            match m.full_piv_lu().try_inverse() {
                // Where the inverse means something (a condition number below 1e8).
                Some(inverse) if inverse.norm() * m.norm() < 1e8 => {
                    let (ours, theirs) = (ours.expect("invertible"), inverse.norm());
                    worst = worst.max((ours - theirs).abs() / theirs);
                }
                _ => {}
            }
        }
        assert!(worst < 1e-12, "{worst:e}");
    }
}
