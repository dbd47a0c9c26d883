//! The smallest and largest eigenvalues of a symmetric 6x6 matrix, for the condition number of
//! the force/moment matrix `M` from its Gram matrix `M^T M` (singular values squared): a
//! Householder reduction to tridiagonal form (Golub and Van Loan, Matrix Computations, section
//! 8.3.1), then, for each end of the spectrum, Laguerre's iteration on the tridiagonal's
//! characteristic polynomial from a Gershgorin bound. All the roots are real, so from outside
//! the spectrum it moves monotonically onto the nearest one, cubically (Wilkinson, The
//! Algebraic Eigenvalue Problem, 7.10); only the two wanted eigenvalues are computed. A study
//! reads `kappa` at every step.

const N: usize = 6;

/// Most Laguerre steps for one end: three to six reach the eigenvalue to round-off; two close
/// eigenvalues (a pose near a symmetric one) take more, converging linearly until the step is
/// inside their gap. Past this the caller falls back (to the SVD).
const LAGUERRE_STEPS: usize = 60;

/// A coupling at most `SPLIT eps |T|` splits the tridiagonal (see [`extreme_eigenvalues`]).
const SPLIT: f64 = 8.0;

/// `(min, max)` eigenvalue of the symmetric matrix whose lower triangle `lower` holds (the
/// upper is not read), or `None` where an entry is not finite or the iteration does not converge.
pub fn extreme_eigenvalues(lower: &[[f64; N]; N]) -> Option<(f64, f64)> {
    let mut a: [[f64; N]; N] = std::array::from_fn(|r| std::array::from_fn(|c| lower[r.max(c)][r.min(c)]));
    if !a.iter().flatten().all(|x| x.is_finite()) {
        return None;
    }
    // Householder: the reflections that zero each column below its subdiagonal, applied to
    // the trailing block from both sides (each step's index a constant, so that its loops
    // unroll). d: the diagonal; e[i]: the entry coupling rows i and i + 1.
    let (mut d, mut e) = ([0.0; N], [0.0; N]);
    reflect::<0>(&mut a, &mut d, &mut e);
    reflect::<1>(&mut a, &mut d, &mut e);
    reflect::<2>(&mut a, &mut d, &mut e);
    reflect::<3>(&mut a, &mut d, &mut e);
    d[N - 2] = a[N - 2][N - 2];
    e[N - 2] = a[N - 1][N - 2];
    d[N - 1] = a[N - 1][N - 1];
    e[N - 1] = 0.0;
    // Where a coupling is negligible the tridiagonal splits into blocks. A repeated eigenvalue
    // (the stand's symmetric poses have one at either end) leaves such a coupling, of a few
    // eps |T|; inside a block the eigenvalues are distinct, where Laguerre's iteration is
    // cubic (onto a double one only linear). Dropping a coupling moves no eigenvalue by more
    // than its size.
    let radius = |i: usize| if i > 0 { e[i - 1].abs() } else { 0.0 } + e[i].abs();
    let norm = (0..N).fold(0.0, |m: f64, i| m.max(d[i].abs() + radius(i)));
    let mut e2 = [0.0; N];
    let mut starts = [false; N];
    starts[0] = true;
    for i in 1..N {
        if e[i - 1].abs() <= SPLIT * f64::EPSILON * norm {
            starts[i] = true;
        } else {
            e2[i] = e[i - 1] * e[i - 1];
        }
    }
    // Each block's Gershgorin interval (its own couplings only), then its extreme eigenvalues
    // where they could be the matrix's: blocks whose interval lies inside what the others
    // reached are skipped.
    let mut blocks = [(0, 0, 0.0, 0.0); N];
    let mut count = 0;
    for i in 0..N {
        if starts[i] {
            blocks[count] = (i, i, f64::INFINITY, f64::NEG_INFINITY);
            count += 1;
        }
        let b = &mut blocks[count - 1];
        let r =
            if starts[i] { 0.0 } else { e[i - 1].abs() } + if i + 1 < N && !starts[i + 1] { e[i].abs() } else { 0.0 };
        b.1 = i + 1;
        b.2 = f64::min(b.2, d[i] - r);
        b.3 = f64::max(b.3, d[i] + r);
    }
    let blocks = &blocks[..count];
    // The end of the block reaching furthest first; another block only where its
    // eigenvalues reach past that end by more than a split could have moved them (a count of
    // its pivots' signs says so, one evaluation instead of an iteration).
    let tolerance = SPLIT * f64::EPSILON * norm;
    let first = (0..count).fold(0, |k, j| if blocks[j].3 > blocks[k].3 { j } else { k });
    let mut max = block_extreme(&d, &e2, blocks[first], true)?;
    for (j, &block) in blocks.iter().enumerate() {
        let (lo, hi, _, above) = block;
        if j != first && above > max + tolerance && pivots(&d, &e2, lo, hi, max + tolerance).2 < hi - lo {
            max = max.max(block_extreme(&d, &e2, block, true)?);
        }
    }
    let first = (0..count).fold(0, |k, j| if blocks[j].2 < blocks[k].2 { j } else { k });
    let mut min = block_extreme(&d, &e2, blocks[first], false)?;
    for (j, &block) in blocks.iter().enumerate() {
        let (lo, hi, below, _) = block;
        if j != first && below < min - tolerance && pivots(&d, &e2, lo, hi, min - tolerance).2 > 0 {
            min = min.min(block_extreme(&d, &e2, block, false)?);
        }
    }
    (min.is_finite() && max.is_finite()).then_some((min, max))
}

/// Householder step `K`: the reflection `I - beta v v^T` that zeroes column `K` below row
/// `K + 1`, applied to the trailing block `a[K+1.., K+1..]` (only its lower triangle's values
/// matter; both are kept).
#[inline(always)]
fn reflect<const K: usize>(a: &mut [[f64; N]; N], d: &mut [f64; N], e: &mut [f64; N]) {
    d[K] = a[K][K];
    let mut v = [0.0; N];
    let mut norm2 = 0.0;
    for i in K + 1..N {
        v[i] = a[i][K];
        norm2 += v[i] * v[i];
    }
    let x0 = v[K + 1];
    let alpha = if x0 > 0.0 { -norm2.sqrt() } else { norm2.sqrt() };
    // v = x - alpha e1, |v|^2 = 2 (|x|^2 - alpha x0).
    let v_norm2 = 2.0 * (norm2 - alpha * x0);
    if !(v_norm2 > 0.0) {
        // The column is already reduced.
        e[K] = x0;
        return;
    }
    e[K] = alpha;
    v[K + 1] = x0 - alpha;
    let beta = 2.0 / v_norm2;
    // p = beta B v, q = p - (beta/2)(v.p) v, B' = B - v q^T - q v^T.
    let mut p = [0.0; N];
    for i in K + 1..N {
        let mut s = 0.0;
        for j in K + 1..N {
            s += a[i][j] * v[j];
        }
        p[i] = beta * s;
    }
    let mut vp = 0.0;
    for i in K + 1..N {
        vp += v[i] * p[i];
    }
    let half = 0.5 * beta * vp;
    let mut q = [0.0; N];
    for i in K + 1..N {
        q[i] = p[i] - half * v[i];
    }
    for i in K + 1..N {
        for j in K + 1..N {
            a[i][j] -= v[i] * q[j] + q[i] * v[j];
        }
    }
}

/// The smallest (or with `above` the largest) eigenvalue of the tridiagonal block
/// `(lo, hi, below, above)` (its rows, its Gershgorin interval).
fn block_extreme(
    d: &[f64; N],
    e2: &[f64; N],
    (lo, hi, below, above): (usize, usize, f64, f64),
    up: bool,
) -> Option<f64> {
    match hi - lo {
        1 => Some(d[lo]),
        _ => laguerre(d, e2, lo, hi, if up { above } else { below }, up),
    }
}

/// The characteristic polynomial `p` of the tridiagonal block `lo..hi` (diagonal `d`, squared
/// couplings `e2[i]` between rows `i - 1` and `i`, zero where a block starts) at `x`, through
/// the pivots `u_i = d_i - x - e2_i / u_{i-1}` of `T - x I = L U` (`p` their product: backward
/// stable, and never overflows): `G = p'/p = sum u'/u` and `H = G^2 - p''/p =
/// sum (u'/u)^2 - u''/u`, and how many of the block's pivots are negative: how many of its
/// eigenvalues lie below `x` (Sylvester's law of inertia). All six rows are run (so that the
/// loop unrolls); only the block's count.
#[inline(always)]
fn pivots(d: &[f64; N], e2: &[f64; N], lo: usize, hi: usize, x: f64) -> (f64, f64, usize) {
    let (mut g, mut h, mut negative) = (0.0, 0.0, 0);
    let (mut inv, mut du, mut ddu) = (0.0, 0.0, 0.0);
    for i in 0..N {
        // (A zero pivot in the block before must not make 0 x inf here.)
        let t = if e2[i] == 0.0 { 0.0 } else { e2[i] * inv };
        let u = d[i] - x - t;
        let ddu_i = t * inv * (ddu - 2.0 * du * du * inv);
        du = t * inv * du - 1.0;
        ddu = ddu_i;
        inv = 1.0 / u;
        if (lo..hi).contains(&i) {
            let ratio = du * inv;
            g += ratio;
            h += ratio * ratio - ddu * inv;
            negative += usize::from(u < 0.0);
        }
    }
    (g, h, negative)
}

/// The extreme eigenvalue (the largest if `above`) of the tridiagonal block `lo..hi`, from `x`
/// outside its spectrum on that side: Laguerre's iteration
/// `x -= n / (G +- sqrt((n - 1)(n H - G^2)))`, which moves monotonically onto the nearest
/// eigenvalue; it stops where round-off ends that (a step that does not shrink or turns back).
fn laguerre(d: &[f64; N], e2: &[f64; N], lo: usize, hi: usize, mut x: f64, above: bool) -> Option<f64> {
    let n = (hi - lo) as f64;
    let mut last_step = f64::INFINITY;
    for _ in 0..LAGUERRE_STEPS {
        let (g, h, _) = pivots(d, e2, lo, hi, x);
        if !(g.is_finite() && h.is_finite()) {
            // A pivot is zero: x is an eigenvalue, the extreme one.
            return Some(x);
        }
        let root = ((n - 1.0) * (n * h - g * g)).max(0.0).sqrt();
        let step = n / if above { g + root } else { g - root };
        // Only towards the eigenvalue, each step shorter: past the eigenvalue (by round-off)
        // G changes sign.
        let towards = if above { step > 0.0 } else { step < 0.0 };
        if !(towards && step.abs() < last_step) {
            return Some(x);
        }
        x -= step;
        if step.abs() <= f64::EPSILON * x.abs() {
            return Some(x);
        }
        last_step = step.abs();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;

    /// Against nalgebra's symmetric eigenvalues, on matrices with known and with random
    /// spectra, including repeated eigenvalues and an already diagonal one.
    #[test]
    fn the_extreme_eigenvalues_are_nalgebras() {
        let mut uniform = crate::test_support::xorshift(0x2545_f491_4f6c_dd1d);
        let mut next = || 0.5 * uniform(); // in [-0.5, 0.5)
        let mut worst: f64 = 0.0;
        for case in 0..500 {
            let m = Matrix6::from_fn(|_, _| next());
            let a = match case {
                0 => Matrix6::identity() * 3.0,
                1 => Matrix6::from_diagonal(&nalgebra::Vector6::new(1.0, 5.0, 2.0, 2.0, 9.0, 0.5)),
                _ => m.transpose() * m + Matrix6::identity() * (case % 3) as f64,
            };
            let lower: [[f64; 6]; 6] =
                std::array::from_fn(|r| std::array::from_fn(|c| if c <= r { a[(r, c)] } else { 0.0 }));
            let (min, max) = extreme_eigenvalues(&lower).expect("converges");
            let reference = a.symmetric_eigenvalues();
            let scale = reference.amax();
            worst = worst.max((min - reference.min()).abs() / scale).max((max - reference.max()).abs() / scale);
        }
        println!("extreme eigenvalues against nalgebra: largest difference {worst:.1e} of the largest");
        assert!(worst < 1e-14, "{worst:e}");
    }

    #[test]
    fn entries_not_numbers_give_none() {
        let mut a = [[1.0; 6]; 6];
        a[3][1] = f64::NAN;
        assert_eq!(extreme_eigenvalues(&a), None);
    }
}
