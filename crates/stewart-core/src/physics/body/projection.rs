//! Projection of a state back onto the constraint manifold `e_a . e_b = delta_ab` and its
//! tangent space (velocities of a rigid rotation). The exact solution stays on the manifold;
//! an integrator drifts off it by its truncation error each step, so the FMU projects after
//! every internal step (docs/model.md §1).

use nalgebra::Matrix3;

use super::per_axis::{AxisLanes, AxisRows, Pair};
use super::state::{StateVector, axes, axes_rates};

/// Newton-Schulz iterations stop once the orthogonality defect is below this.
const ORTHOGONALITY_TARGET: f64 = 1e-15;
/// A defect this large means the frame is far from a rotation (e.g. long unstabilised drift):
/// use a polar decomposition by SVD instead of the iteration, which needs a small defect.
const NEWTON_SCHULZ_LIMIT: f64 = 0.1;

/// The frame's products `e_a . e_a` (lane `a`) and `e_a . e_(a+1)`: the entries of `Q^T Q`
/// for `Q = [e1 e2 e3]` (symmetric, so these six are all of them).
#[inline(always)]
fn gram<A: AxisLanes>(e: &AxisRows<A>) -> (A, A) {
    (e.dot(e), e.dot(&e.next()))
}

/// `max |Q^T Q - I|` over the entries; infinite if any is not finite.
#[inline(always)]
fn defect<A: AxisLanes>(e: &AxisRows<A>) -> f64 {
    let (diagonal, off) = gram(e);
    let (diagonal, off) = (diagonal.to_array(), off.to_array());
    let entries = [diagonal[0] - 1.0, diagonal[1] - 1.0, diagonal[2] - 1.0, off[0], off[1], off[2]];
    let finite = entries.iter().fold(true, |all, x| all & x.is_finite());
    if finite { entries.iter().fold(0.0, |d: f64, x| d.max(x.abs())) } else { f64::INFINITY }
}

/// Replaces `e1, e2, e3` by the nearest orthonormal frame (polar factor of `Q = [e1 e2 e3]`,
/// no axis preferred, unlike Gram-Schmidt) and `e1', e2', e3'` by their projection on the
/// tangent space at that frame: `Q' <- Q skew(Q^T Q')`. Written per axis in lanes
/// ([`AxisRows`]): the matrix products are the dot products `e_a . e_b`, `e_a . e_b'` and
/// combinations of the axes.
#[inline(always)]
pub fn project_onto_constraints(y: &mut StateVector) {
    project_onto_constraints_in::<Pair>(y)
}

/// [`project_onto_constraints`] with the axes in lanes `A`: the same bits in each.
#[inline(always)]
pub(crate) fn project_onto_constraints_in<A: AxisLanes>(y: &mut StateVector) {
    let components = axes(y);
    let mut e = AxisRows::<A>::from_components(components);
    let mut d = defect(&e);
    if d > NEWTON_SCHULZ_LIMIT {
        let q = Matrix3::from_column_slice(components);
        let svd = q.svd(true, true);
        if let (Some(u), Some(v_t)) = (svd.u, svd.v_t) {
            let polar = u * v_t;
            if let Ok(c) = <&[f64; 9]>::try_from(polar.as_slice()) {
                e = AxisRows::from_components(c);
            }
        }
        d = defect(&e);
    }
    // Newton-Schulz for the polar factor: Q <- Q (3I - Q^T Q)/2, quadratic convergence;
    // from an integrator's drift of 1e-10 two iterations reach round-off. Per axis:
    // e_b <- (3 - e_b.e_b)/2 e_b - (e_b.e_(b+1))/2 e_(b+1) - (e_(b-1).e_b)/2 e_(b-1).
    let mut iterations = 0;
    while d > ORTHOGONALITY_TARGET && iterations < 6 {
        let (diagonal, off) = gram(&e);
        let half = A::splat(0.5);
        let own = A::splat(3.0).sub(diagonal).mul(half);
        let next = A::splat(0.0).sub(off.mul(half));
        e = e.combine(own, next, next.previous());
        d = defect(&e);
        iterations += 1;
    }
    // Q^T Q' is e_a . e_b'; its skew part W has W_(a,a+1) = (e_a.e_(a+1)' - e_(a+1).e_a')/2,
    // and column b of Q W is e_b' <- W_(b-1,b) e_(b-1) - W_(b,b+1) e_(b+1).
    let e_dot = AxisRows::<A>::from_components(axes_rates(y));
    let w = e.dot(&e_dot.next()).sub(e.next().dot(&e_dot)).mul(A::splat(0.5));
    let e_dot = e.combine(A::splat(0.0), A::splat(0.0).sub(w), w.previous());
    // The whole state written as one array, as `SpecialForm::derivative` writes its result:
    // the next step reads it back in wide loads.
    let ([e1, e2, e3, e4, e5, e6, e7, e8, e9], [d1, d2, d3, d4, d5, d6, d7, d8, d9]) =
        (e.components(), e_dot.components());
    *y = [y[0], y[1], y[2], y[3], y[4], y[5], e1, e2, e3, e4, e5, e6, e7, e8, e9, d1, d2, d3, d4, d5, d6, d7, d8, d9];
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::body::kinematics::rotation_from_angles;
    use crate::physics::body::state::BodyState;
    use crate::physics::body::state::layout;
    use nalgebra::Vector3;

    #[test]
    fn projection_restores_constraints_and_keeps_a_consistent_state_unchanged() {
        let rot = rotation_from_angles(&Vector3::new(0.4, 0.3, -1.0));
        let s =
            BodyState::from_pose(Vector3::new(0.0, 0.0, 2.0), Vector3::zeros(), &rot, &Vector3::new(1.0, -2.0, 0.5));
        let mut y = s.to_vector();
        project_onto_constraints(&mut y);
        let diff = y.iter().zip(s.to_vector().iter()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(diff < 1e-15, "{diff}");
        // Perturb the frame and its rates and project back.
        let mut z = s.to_vector();
        for (i, x) in z.iter_mut().enumerate().skip(6) {
            *x += 1e-6 * ((i * 7 % 5) as f64 - 2.0);
        }
        project_onto_constraints(&mut z);
        let p = BodyState::from_vector(&z);
        assert!(p.constraint_residual() < 1e-15, "{}", p.constraint_residual());
        assert!(p.velocity_constraint_residual() < 1e-14, "{}", p.velocity_constraint_residual());
    }

    #[test]
    fn far_off_frames_are_still_projected() {
        let mut y = [0.0; 24];
        y[layout::E..layout::E + 9].copy_from_slice(&[1.3, 0.2, 0.0, 0.1, 0.7, 0.3, 0.0, -0.2, 1.9]);
        project_onto_constraints(&mut y);
        assert!(BodyState::from_vector(&y).constraint_residual() < 1e-15);
    }
}
