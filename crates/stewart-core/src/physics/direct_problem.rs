//! The direct problem (paper section 3, eqs. 2.2-2.7): the leg forces that produce a
//! prescribed motion.
//!
//! The resultant `F = M (r'' + g ez)` follows from the centre-of-mass theorem, the moment
//! about the centre of mass from Euler's equations `L = R (J w' + w x J w)` (equivalent to
//! the paper's eq. 2.4). The six `u_k` then solve the 6x6 linear system of force and moment
//! balance with the current leg directions:
//!
//! ```text
//! sum_k u_k n_k = F,   sum_k u_k (R A_k) x n_k = L.
//! ```
//!
//! Legs with mass ([`LegBodies`]) carry their own weight and inertia: their forces on the
//! platform at the joints for the prescribed motion (all known then) are taken from `F` and
//! `L` before the system is solved.

use nalgebra::{Matrix6, SVD, U6, Vector3};

use super::body::kinematics::PoseTrajectoryPoint;
use super::body::state::BodyState;
use super::full_pivot_lu::FullPivotLu6;
use super::legs::bodies::{LegBodies, LegMotion};
use super::legs::geometry::{LegGeometry, LegKinematics};
use super::stand::{LEG_COUNT, Stand};

/// Condition number (of the dimensionless force/moment matrix) above which a configuration is
/// treated as singular. A well-designed hexapod has condition numbers of order 1-100; above
/// 1e8 the leg forces for an ordinary load exceed it by eight orders of magnitude and lose
/// half of the double-precision digits.
pub const SINGULAR_CONDITION_NUMBER: f64 = 1e8;

/// The largest condition number reported, `1/eps` = 4.5e15: past it double precision cannot
/// tell the matrix from a singular one, and at a singular arrangement the condition number is
/// this bound (a finite number: an FMU output is never infinite).
pub const CONDITION_NUMBER_BOUND: f64 = 1.0 / f64::EPSILON;

/// Condition numbers up to this are computed from the Gram matrix `M^T M` (relative error a
/// few `eps kappa^2`, at most about 1e-11), larger ones by the SVD (see
/// [`ForceMomentMatrix::condition_number`]). A working hexapod's poses lie far below.
pub const GRAM_CONDITION_LIMIT: f64 = 100.0;

/// Most sweeps the condition number's SVD may take: a 6x6 matrix of numbers converges in a few
/// dozen; past this it is reported singular rather than iterated without end.
const SVD_ITERATIONS: usize = 1000;

/// Why the direct problem has no trustworthy answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DirectProblemError {
    /// The leg directions do not span force and moment space.
    Singular { condition_number: f64 },
    /// A leg has zero length, so its direction is undefined.
    LegCollapsed { leg: usize },
}

impl std::fmt::Display for DirectProblemError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DirectProblemError::Singular { condition_number } => write!(
                f,
                "singular leg configuration: the force/moment matrix has condition number {condition_number:e} \
                 (limit {SINGULAR_CONDITION_NUMBER:e})"
            ),
            DirectProblemError::LegCollapsed { leg } => write!(f, "leg {leg} has zero length"),
        }
    }
}

impl std::error::Error for DirectProblemError {}

/// The 6x6 matrix mapping leg forces `u` to the wrench `[F; L / ell]`, with the moment rows
/// divided by the stand's characteristic length `ell` so that the matrix is dimensionless and
/// its condition number means something.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceMomentMatrix {
    pub matrix: Matrix6<f64>,
    pub moment_scale: f64,
}

impl ForceMomentMatrix {
    pub fn new(stand: &Stand, legs: &LegGeometry) -> Self {
        let ell = stand.characteristic_length().max(f64::MIN_POSITIVE);
        let mut matrix = Matrix6::zeros();
        for k in 0..LEG_COUNT {
            let n = legs.direction[k];
            let m = legs.arm[k].cross(&n) / ell;
            matrix.fixed_view_mut::<3, 1>(0, k).copy_from(&n);
            matrix.fixed_view_mut::<3, 1>(3, k).copy_from(&m);
        }
        ForceMomentMatrix { matrix, moment_scale: ell }
    }

    /// Determinant (see [`determinant6`]).
    pub fn determinant(&self) -> f64 {
        let mut a = [[0.0f64; 6]; 6];
        for (i, row) in a.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = self.matrix[(i, j)];
            }
        }
        determinant6(a)
    }

    /// The matrix's SVD, `None` where the matrix is not all numbers (a pose of overflowed
    /// coordinates: no leg arrangement) or the SVD does not converge in `SVD_ITERATIONS`
    /// sweeps. Every SVD of this matrix goes through here, so none can hang.
    pub fn svd(&self, compute_u: bool, compute_v: bool) -> Option<SVD<f64, U6, U6>> {
        if !self.matrix.iter().all(|x| x.is_finite()) {
            return None;
        }
        self.matrix.try_svd_unordered(compute_u, compute_v, f64::EPSILON, SVD_ITERATIONS)
    }

    /// 2-norm condition number `sigma_max / sigma_min`, at most [`CONDITION_NUMBER_BOUND`]: the
    /// bound where the matrix is singular (or numerically so, or not made of numbers).
    ///
    /// Well-conditioned arrangements (`kappa <= GRAM_CONDITION_LIMIT`, every ordinary pose of a
    /// working hexapod) take the eigenvalues of the Gram matrix `M^T M`; the others, and the
    /// decisions near [`SINGULAR_CONDITION_NUMBER`], the SVD of `M`.
    pub fn condition_number(&self) -> f64 {
        if let Some(kappa) = self.condition_number_from_gram() {
            return kappa;
        }
        self.condition_number_by_svd()
    }

    /// `kappa` from the SVD of `M`: relative error about `eps kappa`.
    pub fn condition_number_by_svd(&self) -> f64 {
        let Some(svd) = self.svd(false, false) else { return CONDITION_NUMBER_BOUND };
        let sv = svd.singular_values;
        let (max, min) = (sv.max(), sv.min());
        if min > 0.0 { (max / min).min(CONDITION_NUMBER_BOUND) } else { CONDITION_NUMBER_BOUND }
    }

    /// `kappa = sqrt(lambda_max / lambda_min)` of `M^T M`, where it is at most
    /// [`GRAM_CONDITION_LIMIT`]; `None` elsewhere. Squaring the matrix squares its condition:
    /// the smallest eigenvalue carries an error of a few `eps lambda_max`, so `kappa`'s relative
    /// error is a few `eps kappa^2` (2e-12 at the limit, against the SVD's `eps kappa`), and
    /// costs a sixth of the SVD.
    pub fn condition_number_from_gram(&self) -> Option<f64> {
        let columns = &self.matrix.data.0;
        let mut gram = [[0.0; 6]; 6];
        for r in 0..6 {
            for c in 0..=r {
                gram[r][c] = (0..6).fold(0.0, |s, k| s + columns[r][k] * columns[c][k]);
            }
        }
        let (min, max) = crate::physics::symmetric6::extreme_eigenvalues(&gram)?;
        let squared = max / min;
        (min > 0.0 && squared <= GRAM_CONDITION_LIMIT * GRAM_CONDITION_LIMIT).then(|| squared.sqrt())
    }

    /// Leg forces producing the resultant `force` and moment `moment` (about the centre of mass),
    /// refused where the condition number is [`SINGULAR_CONDITION_NUMBER`] or more. The
    /// decision is the SVD's, but the SVD (most of the cost) runs only where the cheap bound
    /// `kappa_2 <= kappa_F = |M|_F |M^-1|_F` (`kappa_F <= 6 kappa_2` for a 6x6 matrix), from the
    /// LU factors the solve needs anyway, does not already clear the arrangement with a margin
    /// of two for the bound's round-off.
    pub fn solve(&self, force: &Vector3<f64>, moment: &Vector3<f64>) -> Result<[f64; LEG_COUNT], DirectProblemError> {
        // nalgebra's full-pivot LU, written out (its solution's bits are the ones the closed
        // loop has given since before the machine model: tests/python/test_machine.py
        // compares them).
        let lu = FullPivotLu6::new(self.matrix.data.0);
        let frobenius_bound = lu.inverse_frobenius_norm().map(|inverse| self.matrix.norm() * inverse);
        if !frobenius_bound.is_some_and(|bound| bound < 0.5 * SINGULAR_CONDITION_NUMBER) {
            let condition_number = self.condition_number();
            if !(condition_number < SINGULAR_CONDITION_NUMBER) {
                return Err(DirectProblemError::Singular { condition_number });
            }
        }
        let s = self.moment_scale;
        let rhs = [force.x, force.y, force.z, moment.x / s, moment.y / s, moment.z / s];
        lu.solve(&rhs).ok_or_else(|| DirectProblemError::Singular { condition_number: self.condition_number() })
    }
}

/// The legs that take part in a singular arrangement: the entries of the force combination
/// `x` with `M x = 0` (the right singular vector of the smallest singular value) larger than a
/// tenth of the largest. Far from a singular arrangement this names the legs of the weakest
/// combination.
pub fn singular_legs(stand: &Stand, legs: &LegGeometry) -> [bool; LEG_COUNT] {
    let mut out = [false; LEG_COUNT];
    let Some(svd) = ForceMomentMatrix::new(stand, legs).svd(false, true) else { return out };
    let Some(v_t) = svd.v_t else { return out };
    let weakest = svd.singular_values.imin();
    let x = v_t.row(weakest);
    let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..LEG_COUNT {
        out[k] = x[k].abs() >= 0.1 * largest;
    }
    out
}

/// Determinant of the dimensionless force/moment matrix straight from the legs of a state
/// (columns `[n_k; (R A_k) x n_k / ell]`), without building a nalgebra matrix: the
/// once-per-step singularity check of the FMU.
#[inline(always)]
pub fn force_moment_determinant(legs: &LegKinematics, ell: f64) -> f64 {
    let mut a = [[0.0f64; 6]; 6];
    let inv_ell = 1.0 / ell;
    // Row by row over the legs (vector registers), the arithmetic of nalgebra's cross product.
    a[..3].copy_from_slice(&legs.directions());
    let arm = &legs.arm;
    for k in 0..LEG_COUNT {
        let n = [a[0][k], a[1][k], a[2][k]];
        a[3][k] = (arm[1][k] * n[2] - arm[2][k] * n[1]) * inv_ell;
        a[4][k] = (arm[2][k] * n[0] - arm[0][k] * n[2]) * inv_ell;
        a[5][k] = (arm[0][k] * n[1] - arm[1][k] * n[0]) * inv_ell;
    }
    determinant6(a)
}

/// Determinant of a 6x6 matrix (rows) by Gaussian elimination with partial pivoting. Each
/// elimination stage is a separate instance of `eliminate` with its column as a constant,
/// so every loop has constant bounds and unrolls without bounds checks.
#[inline(always)]
pub fn determinant6(mut a: [[f64; 6]; 6]) -> f64 {
    let mut det = 1.0;
    eliminate::<0>(&mut a, &mut det);
    eliminate::<1>(&mut a, &mut det);
    eliminate::<2>(&mut a, &mut det);
    eliminate::<3>(&mut a, &mut det);
    eliminate::<4>(&mut a, &mut det);
    eliminate::<5>(&mut a, &mut det);
    det
}

#[inline(always)]
fn eliminate<const COL: usize>(a: &mut [[f64; 6]; 6], det: &mut f64) {
    let mut pivot = COL;
    let mut best = a[COL][COL].abs();
    for row in COL + 1..6 {
        let x = a[row][COL].abs();
        if x > best {
            best = x;
            pivot = row;
        }
    }
    if pivot != COL {
        a.swap(pivot, COL);
        *det = -*det;
    }
    let p = a[COL][COL];
    *det *= p;
    if p == 0.0 {
        return;
    }
    let inv = 1.0 / p;
    for row in COL + 1..6 {
        let factor = a[row][COL] * inv;
        for k in COL + 1..6 {
            a[row][k] -= factor * a[COL][k];
        }
    }
}

/// The resultant force and moment about the centre of mass (inertial components) that the
/// legs must supply for the prescribed motion.
pub fn required_wrench(stand: &Stand, point: &PoseTrajectoryPoint) -> (Vector3<f64>, Vector3<f64>) {
    let force = (point.a + Vector3::new(0.0, 0.0, stand.gravity)) * stand.mass;
    let j = Vector3::from(stand.inertia);
    let jw = j.component_mul(&point.w);
    let moment_body = j.component_mul(&point.w_dot) + point.w.cross(&jw);
    (force, point.rotation * moment_body)
}

/// Everything the direct problem gives for one instant of a programme motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectProblemSolution {
    /// Leg forces `u_k`, N.
    pub forces: [f64; LEG_COUNT],
    /// Programme leg lengths `l_k`, m.
    pub lengths: [f64; LEG_COUNT],
    /// Programme leg length rates, m/s.
    pub rates: [f64; LEG_COUNT],
}

/// Solves the direct problem for one instant of a programme motion, with legs `bodies`.
pub fn solve_direct_problem(
    stand: &Stand,
    bodies: &LegBodies,
    point: &PoseTrajectoryPoint,
) -> Result<DirectProblemSolution, DirectProblemError> {
    let state = BodyState::from_pose(point.r, point.v, &point.rotation, &point.w);
    let legs = LegGeometry::new(stand, &state);
    if let Some(k) = legs.length.iter().position(|&l| l <= 0.0) {
        return Err(DirectProblemError::LegCollapsed { leg: k + 1 });
    }
    let matrix = ForceMomentMatrix::new(stand, &legs);
    let (mut force, mut moment) = required_wrench(stand, point);
    if bodies.has_mass() {
        // The legs' own forces on the platform for this motion: each joint's velocity and
        // acceleration a' = v + omega x rho, a'' = r'' + omega' x rho + omega x (omega x rho).
        let omega = point.rotation * point.w;
        let omega_dot = point.rotation * point.w_dot;
        for k in 0..LEG_COUNT {
            let rho = legs.arm[k];
            let a_dot = point.v + omega.cross(&rho);
            let a_ddot = point.a + omega_dot.cross(&rho) + omega.cross(&omega.cross(&rho));
            let motion = LegMotion::new(&legs.leg[k], legs.length[k], &a_dot);
            let inertia = bodies.inertia(&motion, stand.gravity);
            let own = inertia.bias - inertia.times(&motion.n, &a_ddot);
            force -= own;
            moment -= rho.cross(&own);
        }
    }
    let forces = matrix.solve(&force, &moment)?;
    Ok(DirectProblemSolution { forces, lengths: legs.length, rates: legs.length_rates(stand, &state) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::legs::geometry::JointArrays;
    use crate::physics::stand::PAPER_EQUILIBRIUM_LEG_FORCE;
    use nalgebra::{Matrix3, Vector6};

    #[test]
    fn neutral_pose_of_the_default_stand_needs_the_papers_equilibrium_force_in_every_leg() {
        let stand = Stand::truck_cabin();
        let point = PoseTrajectoryPoint::at_rest(Stand::truck_cabin_neutral_position(), Matrix3::identity());
        let sol = solve_direct_problem(&stand, &LegBodies::default(), &point).unwrap();
        let mg = stand.mass * stand.gravity;
        for u in sol.forces {
            assert!((u / mg - PAPER_EQUILIBRIUM_LEG_FORCE).abs() < 1e-13, "{}", u / mg);
        }
        let state = BodyState::from_pose(point.r, point.v, &point.rotation, &point.w);
        let kappa = ForceMomentMatrix::new(&stand, &LegGeometry::new(&stand, &state)).condition_number();
        assert!(kappa > 1.0 && kappa < 100.0, "{kappa}");
    }

    /// Matrices `U diag(s) V^T` of a given condition number `s_max / s_min` (singular values
    /// spread geometrically), with orthogonal `U`, `V` from the QR of pseudo-random matrices.
    struct KnownConditionNumbers(Box<dyn FnMut() -> f64>);

    impl KnownConditionNumbers {
        fn new(seed: u64) -> Self {
            KnownConditionNumbers(Box::new(crate::test_support::xorshift(seed)))
        }

        /// In [-1, 1).
        fn random(&mut self) -> f64 {
            (self.0)()
        }

        fn matrix(&mut self, kappa: f64) -> ForceMomentMatrix {
            let u = Matrix6::from_fn(|_, _| self.random()).qr().q();
            let v = Matrix6::from_fn(|_, _| self.random()).qr().q();
            let s = Matrix6::from_diagonal(&Vector6::from_fn(|i, _| 1.0 / kappa.powf(i as f64 / 5.0)));
            ForceMomentMatrix { matrix: u * s * v.transpose(), moment_scale: 1.0 }
        }
    }

    #[test]
    fn the_solve_refuses_exactly_where_the_svd_condition_number_reaches_the_limit() {
        // M = U diag(s) V^T with orthogonal U, V from the QR of pseudo-random matrices and
        // condition numbers s_max / s_min from 1 to 1e12, dense about the limit 1e8 and about
        // 1e8 / 6 (where the Frobenius bound alone would stop clearing).
        let mut known = KnownConditionNumbers::new(0x2545_f491_4f6c_dd1d);
        let mut kappas: Vec<f64> = (0..=48).map(|i| 10f64.powf(i as f64 / 4.0)).collect();
        for centre in [SINGULAR_CONDITION_NUMBER, SINGULAR_CONDITION_NUMBER / 6.0] {
            kappas.extend((-20..=20).map(|i| centre * (1.0 + i as f64 * 2e-3)));
        }
        let (mut refused, mut accepted) = (0, 0);
        for &kappa in &kappas {
            let m = known.matrix(kappa);
            let by_svd = m.condition_number() < SINGULAR_CONDITION_NUMBER;
            let result = m.solve(&Vector3::new(0.3, -0.2, 1.0), &Vector3::new(0.1, 0.2, -0.1));
            assert_eq!(result.is_ok(), by_svd, "kappa {kappa:e}: svd {:e}, solve {result:?}", m.condition_number());
            if by_svd { accepted += 1 } else { refused += 1 }
        }
        assert!(refused > 20 && accepted > 20, "{refused} refused, {accepted} accepted");
    }

    /// `kappa` from the Gram matrix equals the SVD's to a few `eps kappa^2` on matrices of
    /// known condition number 1..1e4 (the SVD taking over past the limit) and on the default
    /// stand over a grid of poses; exactly `kappa` where it is known.
    #[test]
    fn the_gram_condition_number_is_the_svds_below_its_limit() {
        let mut known = KnownConditionNumbers::new(0x9e37_79b9_7f4a_7c15);
        let mut worst: f64 = 0.0;
        let (mut by_gram, mut by_svd) = (0, 0);
        for i in 0..=64 {
            let kappa = 10f64.powf(i as f64 / 16.0);
            let m = known.matrix(kappa);
            let error = (m.condition_number() / kappa - 1.0).abs();
            match m.condition_number_from_gram() {
                Some(_) => {
                    by_gram += 1;
                    worst = worst.max(error / (kappa * kappa));
                }
                None => {
                    by_svd += 1;
                    assert!(kappa > 0.99 * GRAM_CONDITION_LIMIT, "kappa {kappa:e} left to the SVD");
                }
            }
        }
        let stand = Stand::truck_cabin();
        let mut worst_pose: f64 = 0.0;
        for i in 0..200 {
            let t = i as f64;
            let r = Stand::truck_cabin_neutral_position()
                + Vector3::new(0.3 * (0.7 * t).sin(), 0.3 * (1.1 * t).cos(), 0.4 * (0.3 * t).sin());
            let angles = Vector3::new(0.3 * (0.5 * t).sin(), 0.3 * (0.9 * t).sin(), 0.6 * (0.2 * t).cos());
            let rot = crate::physics::body::kinematics::rotation_from_angles(&angles);
            let state = BodyState::from_pose(r, Vector3::zeros(), &rot, &Vector3::zeros());
            let m = ForceMomentMatrix::new(&stand, &LegGeometry::new(&stand, &state));
            if let Some(kappa) = m.condition_number_from_gram() {
                let svd = m.condition_number_by_svd();
                worst_pose = worst_pose.max((kappa / svd - 1.0).abs() / (svd * svd));
            }
        }
        println!(
            "kappa from the Gram matrix against the SVD: {by_gram} known (largest error {worst:.1e} kappa^2), {by_svd} past the limit; stand poses {worst_pose:.1e} kappa^2"
        );
        assert!(worst < 50.0 * f64::EPSILON && worst_pose < 50.0 * f64::EPSILON, "{worst:e} {worst_pose:e}");
        assert!(by_gram > 20 && by_svd > 20, "{by_gram} by the Gram matrix, {by_svd} by the SVD");
    }

    #[test]
    fn determinant_matches_the_lu_one() {
        let stand = Stand::truck_cabin();
        let rot = crate::physics::body::kinematics::rotation_from_angles(&Vector3::new(0.1, -0.2, 0.7));
        let state = BodyState::from_pose(Vector3::new(0.05, 0.02, 1.9), Vector3::zeros(), &rot, &Vector3::zeros());
        let m = ForceMomentMatrix::new(&stand, &LegGeometry::new(&stand, &state));
        let (ours, lu) = (m.determinant(), m.matrix.determinant());
        assert!((ours - lu).abs() < 1e-13 * lu.abs(), "{ours} vs {lu}");
        let direct =
            force_moment_determinant(&JointArrays::new(&stand).kinematics(&state), stand.characteristic_length());
        assert!((direct - lu).abs() < 1e-13 * lu.abs(), "{direct} vs {lu}");
    }

    #[test]
    fn planar_platform_over_its_base_is_singular() {
        // Platform joints directly above the base joints, all legs vertical: no horizontal
        // force is possible.
        let mut stand = Stand::truck_cabin();
        stand.platform_joints = stand.base_joints.map(|b| Vector3::new(b.x, b.y, -0.5));
        let point = PoseTrajectoryPoint::at_rest(Vector3::new(0.0, 0.0, 2.0), Matrix3::identity());
        match solve_direct_problem(&stand, &LegBodies::default(), &point) {
            Err(DirectProblemError::Singular { condition_number }) => {
                assert!(condition_number >= SINGULAR_CONDITION_NUMBER)
            }
            other => panic!("expected a singular configuration, got {other:?}"),
        }
    }
}
