//! The smallest and largest eigenvalues of a symmetric 6x6 matrix, for the condition number of
//! the force/moment matrix `M` from its Gram matrix `M^T M` (singular values squared): a
//! Householder reduction to tridiagonal form, then the implicit QL method with Wilkinson's shift
//! (Golub and Van Loan, Matrix Computations, sections 8.3.1 and 8.3.5), written out for six
//! rows. About a sixth of the instructions of a general SVD of `M` (nalgebra's), which a
//! study reading `kappa` at every step pays.

/// Most QL iterations for one eigenvalue: it converges cubically, a handful suffice; past this
/// the matrix is not made of ordinary numbers and the caller falls back.
const QL_ITERATIONS: usize = 30;

/// `(min, max)` eigenvalue of the symmetric matrix whose lower triangle `lower` holds (the
/// upper is not read), or `None` where an entry is not finite or the iteration does not converge.
pub fn extreme_eigenvalues(lower: &[[f64; 6]; 6]) -> Option<(f64, f64)> {
    const N: usize = 6;
    let mut a: [[f64; N]; N] = std::array::from_fn(|r| std::array::from_fn(|c| lower[r.max(c)][r.min(c)]));
    if !a.iter().flatten().all(|x| x.is_finite()) {
        return None;
    }
    // Householder: for each column k, the reflection `I - beta v v^T` that zeroes its entries
    // below the subdiagonal, applied from both sides. The loops run over all six rows with
    // `v` zero above row k + 1 (the leading block is untouched), so that they unroll.
    let mut d = [0.0; N];
    let mut e = [0.0; N];
    for k in 0..N - 2 {
        let column: [f64; N] = std::array::from_fn(|i| if i > k { a[i][k] } else { 0.0 });
        let norm2 = column.iter().fold(0.0, |s, x| s + x * x);
        let x0 = column[k + 1];
        let alpha = if x0 > 0.0 { -norm2.sqrt() } else { norm2.sqrt() };
        d[k] = a[k][k];
        e[k] = alpha;
        // v = x - alpha e1, |v|^2 = 2 (|x|^2 - alpha x0).
        let v_norm2 = 2.0 * (norm2 - alpha * x0);
        if !(v_norm2 > 0.0) {
            // The column is already reduced.
            e[k] = x0;
            continue;
        }
        let mut v = column;
        v[k + 1] = x0 - alpha;
        let beta = 2.0 / v_norm2;
        // p = beta A v, q = p - (beta/2)(v.p) v, A' = A - v q^T - q v^T (rows and columns
        // above k + 1 unchanged, as v is zero there and they meet only zero rows of v).
        let p: [f64; N] = std::array::from_fn(|i| beta * (0..N).fold(0.0, |s, j| s + a[i][j] * v[j]));
        let half = 0.5 * beta * (0..N).fold(0.0, |s, i| s + v[i] * p[i]);
        let q: [f64; N] = std::array::from_fn(|i| if i > k { p[i] - half * v[i] } else { 0.0 });
        for i in 0..N {
            for j in 0..N {
                a[i][j] -= v[i] * q[j] + q[i] * v[j];
            }
        }
    }
    d[N - 2] = a[N - 2][N - 2];
    e[N - 2] = a[N - 1][N - 2];
    d[N - 1] = a[N - 1][N - 1];
    e[N - 1] = 0.0;
    // Implicit QL on the tridiagonal (d, e): e[i] couples rows i and i + 1.
    for l in 0..N {
        let mut iterations = 0;
        loop {
            let mut m = l;
            while m < N - 1 {
                let scale = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= f64::EPSILON * scale {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iterations += 1;
            if iterations > QL_ITERATIONS {
                return None;
            }
            // Wilkinson's shift from the leading 2x2 block.
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = (g * g + 1.0).sqrt();
            g = d[m] - d[l] + e[l] / (g + if g >= 0.0 { r } else { -r });
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut deflated = false;
            let mut i = m;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                r = (f * f + g * g).sqrt();
                e[i + 1] = r;
                if r == 0.0 {
                    // An exact zero split the matrix: undo the last shift and start again.
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    deflated = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
            }
            if !deflated {
                d[l] -= p;
                e[l] = g;
                e[m] = 0.0;
            }
        }
    }
    if !d.iter().all(|x| x.is_finite()) {
        return None;
    }
    Some(d.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;

    /// Against nalgebra's symmetric eigenvalues, on matrices with known and with random
    /// spectra, including repeated eigenvalues and an already diagonal one.
    #[test]
    fn the_extreme_eigenvalues_are_nalgebras() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
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
