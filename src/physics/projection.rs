//! Projection of a state back onto the constraint manifold `e_a . e_b = delta_ab` and its
//! tangent space (velocities of a rigid rotation). The exact solution stays on the manifold;
//! an integrator drifts off it by its truncation error each step, so the FMU projects after
//! every internal step (docs/model.md §1).

use nalgebra::Matrix3;

use super::body_state::{StateVector, layout};

/// Newton-Schulz iterations stop once the orthogonality defect is below this.
const ORTHOGONALITY_TARGET: f64 = 1e-15;
/// A defect this large means the frame is far from a rotation (e.g. long unstabilised drift):
/// use a polar decomposition by SVD instead of the iteration, which needs a small defect.
const NEWTON_SCHULZ_LIMIT: f64 = 0.1;

fn defect(q: &Matrix3<f64>) -> f64 {
    (q.transpose() * q - Matrix3::identity()).abs().max()
}

/// Replaces `e1, e2, e3` by the nearest orthonormal frame (polar factor of `R`, no axis
/// preferred, unlike Gram-Schmidt) and `e1', e2', e3'` by their projection on the tangent
/// space at that frame: `R' <- R skew(R^T R')`.
#[inline(always)]
pub fn project_onto_constraints(y: &mut StateVector) {
    let mut q = Matrix3::from_column_slice(&y[layout::E..layout::E + 9]);
    let mut d = defect(&q);
    if d > NEWTON_SCHULZ_LIMIT || !d.is_finite() {
        let svd = q.svd(true, true);
        if let (Some(u), Some(v_t)) = (svd.u, svd.v_t) {
            q = u * v_t;
        }
        d = defect(&q);
    }
    // Newton-Schulz for the polar factor: Q <- Q (3I - Q^T Q)/2, quadratic convergence;
    // from an integrator's drift of 1e-10 two iterations reach round-off.
    let mut iterations = 0;
    while d > ORTHOGONALITY_TARGET && iterations < 6 {
        q = q * (Matrix3::identity() * 3.0 - q.transpose() * q) * 0.5;
        d = defect(&q);
        iterations += 1;
    }
    let q_dot = Matrix3::from_column_slice(&y[layout::E_DOT..layout::E_DOT + 9]);
    let s = q.transpose() * q_dot;
    let w = (s - s.transpose()) * 0.5;
    let q_dot = q * w;
    y[layout::E..layout::E + 9].copy_from_slice(q.as_slice());
    y[layout::E_DOT..layout::E_DOT + 9].copy_from_slice(q_dot.as_slice());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::body_state::BodyState;
    use crate::physics::kinematics::rotation_from_angles;
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
