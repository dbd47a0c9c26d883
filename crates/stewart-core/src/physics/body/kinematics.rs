//! Orientation angles (the textbook's 1-2-3 sequence) and inverse kinematics.
//!
//! `R = Rx(roll) Ry(pitch) Rz(yaw)` with the elementary rotations of textbook eq. (1.23),
//! counter-clockwise positive. Angular velocity `w` is in body components.

use nalgebra::{Matrix3, Vector3};

use crate::maths;
use crate::physics::number::Real;

/// `(sin x, cos x)`, at `x = ±0` the exact `(±0, 1)` without the library call: a programme's
/// constant degrees of freedom and zero angles are most of the controller's sines (the same
/// bits as `maths::sin_cos(x)` everywhere).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x == 0.0 { (x, 1.0) } else { maths::sin_cos(x) }
}

/// Elementary rotation about x by the angle of sine `s` and cosine `c` (textbook `c1`).
pub fn rotation_x<T: Real>(s: T, c: T) -> Matrix3<T> {
    let (o, z) = (T::one(), T::zero());
    Matrix3::new(o, z, z, z, c, -s, z, s, c)
}

/// Elementary rotation about y (textbook `c2`).
pub fn rotation_y<T: Real>(s: T, c: T) -> Matrix3<T> {
    let (o, z) = (T::one(), T::zero());
    Matrix3::new(c, z, s, z, o, z, -s, z, c)
}

/// Elementary rotation about z (textbook `c3`).
pub fn rotation_z<T: Real>(s: T, c: T) -> Matrix3<T> {
    let (o, z) = (T::one(), T::zero());
    Matrix3::new(c, -s, z, s, c, z, z, z, o)
}

/// Rotation body -> inertial `Rx(roll) Ry(pitch) Rz(yaw)` of the 1-2-3 angles whose sines
/// `s` and cosines `c` are given (`[roll, pitch, yaw]`), in any number type: `f64`, duals, the
/// washout's jets (`crate::physics::cueing::jet::Jet`, with `Trig::cos`). The elementary
/// rotations' product, the one form of the 1-2-3 rotation (a product written out term by term
/// gives the same numbers but for the sign of some zeros).
pub fn rotation_from_sines_cosines<T: Real>(s: [T; 3], c: [T; 3]) -> Matrix3<T> {
    rotation_x(s[0], c[0]) * rotation_y(s[1], c[1]) * rotation_z(s[2], c[2])
}

/// Rotation body -> inertial from `(roll, pitch, yaw)`, rad.
pub fn rotation_from_angles(angles: &Vector3<f64>) -> Matrix3<f64> {
    let [(s0, c0), (s1, c1), (s2, c2)] = [angles.x, angles.y, angles.z].map(sin_cos);
    rotation_from_sines_cosines([s0, s1, s2], [c0, c1, c2])
}

/// `(roll, pitch, yaw)` of a rotation matrix, rad. Pitch lies in `[-pi/2, pi/2]`, roll and
/// yaw in `(-pi, pi]`. At the gimbal lock (`|pitch| = pi/2`) roll and yaw are not unique;
/// the result is still finite.
pub fn angles_from_rotation<T: Real>(rot: &Matrix3<T>) -> Vector3<T> {
    // R = Rx Ry Rz: R02 = sin(pitch), R12 = -sin(roll) cos(pitch), R22 = cos(roll) cos(pitch),
    // R01 = -cos(pitch) sin(yaw), R00 = cos(pitch) cos(yaw).
    let pitch = rot[(0, 2)].clamp_to(T::constant(-1.0), T::one()).asin();
    let roll = (-rot[(1, 2)]).atan2(rot[(2, 2)]);
    let yaw = (-rot[(0, 1)]).atan2(rot[(0, 0)]);
    Vector3::new(roll, pitch, yaw)
}

/// Time derivatives of `(roll, pitch, yaw)` for body angular velocity `w`. Singular at the
/// gimbal lock; there the rates of roll and yaw are returned as 0 (never NaN) and only the
/// pitch rate is meaningful.
pub fn angle_rates(angles: &Vector3<f64>, w: &Vector3<f64>) -> Vector3<f64> {
    // w1 = a' cos b cos c + b' sin c, w2 = -a' cos b sin c + b' cos c, w3 = a' sin b + c'.
    let (sb, cb) = maths::sin_cos(angles.y);
    let (sc, cc) = maths::sin_cos(angles.z);
    let pitch_rate = w.x * sc + w.y * cc;
    let roll_rate = if cb.abs() > 1e-12 { (w.x * cc - w.y * sc) / cb } else { 0.0 };
    let yaw_rate = if cb.abs() > 1e-12 { w.z - roll_rate * sb } else { 0.0 };
    Vector3::new(roll_rate, pitch_rate, yaw_rate)
}

/// A rigid-body pose with its first and second time derivatives: a programme motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseTrajectoryPoint {
    /// Centre of mass, m.
    pub r: Vector3<f64>,
    /// Its velocity, m/s.
    pub v: Vector3<f64>,
    /// Its acceleration, m/s².
    pub a: Vector3<f64>,
    /// Rotation body -> inertial.
    pub rotation: Matrix3<f64>,
    /// Angular velocity, body components, rad/s.
    pub w: Vector3<f64>,
    /// Angular acceleration, body components, rad/s² (`dw/dt` of the body components).
    pub w_dot: Vector3<f64>,
}

impl PoseTrajectoryPoint {
    /// A pose at rest.
    pub fn at_rest(r: Vector3<f64>, rotation: Matrix3<f64>) -> Self {
        PoseTrajectoryPoint {
            r,
            v: Vector3::zeros(),
            a: Vector3::zeros(),
            rotation,
            w: Vector3::zeros(),
            w_dot: Vector3::zeros(),
        }
    }

    /// The pose from 1-2-3 angles and their first and second derivatives.
    pub fn from_angles(
        r: Vector3<f64>,
        v: Vector3<f64>,
        a: Vector3<f64>,
        angles: &Vector3<f64>,
        angles_dot: &Vector3<f64>,
        angles_ddot: &Vector3<f64>,
    ) -> Self {
        let (w, w_dot) = body_rates_from_angle_rates(angles, angles_dot, angles_ddot);
        PoseTrajectoryPoint { r, v, a, rotation: rotation_from_angles(angles), w, w_dot }
    }
}

/// Body angular velocity and acceleration from 1-2-3 angles and their derivatives.
pub fn body_rates_from_angle_rates(
    angles: &Vector3<f64>,
    d: &Vector3<f64>,
    dd: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let (sb, cb) = sin_cos(angles.y);
    let (sc, cc) = sin_cos(angles.z);
    let (ad, bd, cd) = (d.x, d.y, d.z);
    let w = Vector3::new(ad * cb * cc + bd * sc, -ad * cb * sc + bd * cc, ad * sb + cd);
    // Differentiate each component by the product rule.
    let w_dot = Vector3::new(
        dd.x * cb * cc - ad * sb * bd * cc - ad * cb * sc * cd + dd.y * sc + bd * cc * cd,
        -dd.x * cb * sc + ad * sb * bd * sc - ad * cb * cc * cd + dd.y * cc - bd * sc * cd,
        dd.x * sb + ad * cb * bd + dd.z,
    );
    (w, w_dot)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The washout's rotation, written out term by term over `Trig`, is this product's numbers
    /// but for the signs of some zeros: the cueing can take the one form.
    #[test]
    fn the_washouts_rotation_is_the_product() {
        use crate::physics::cueing::washout::rotation;
        for a in [[0.3, -0.2, 1.1], [-2.5, 1.2, 3.0], [0.0, 0.4, 0.0], [1.5, -std::f64::consts::FRAC_PI_2, -0.7]] {
            let product = rotation_from_sines_cosines(a.map(maths::sin), a.map(maths::cos));
            for (x, y) in product.iter().zip(rotation(&a).iter()) {
                assert!(x.to_bits() == y.to_bits() || (*x == 0.0 && *y == 0.0), "{a:?}: {x:e} against {y:e}");
            }
        }
    }

    #[test]
    fn angles_round_trip() {
        for angles in [Vector3::new(0.1, -0.2, 0.3), Vector3::new(-2.5, 1.2, 3.0), Vector3::new(0.0, 0.0, 0.0)] {
            let back = angles_from_rotation(&rotation_from_angles(&angles));
            assert!((back - angles).norm() < 1e-14, "{angles:?} -> {back:?}");
        }
    }

    #[test]
    fn angle_rates_agree_with_finite_differences_of_the_rotation() {
        let angles = Vector3::new(0.3, -0.4, 0.7);
        let angles_dot = Vector3::new(0.5, -0.2, 1.3);
        let (w, _) = body_rates_from_angle_rates(&angles, &angles_dot, &Vector3::zeros());
        // R' = R [w]x: check against a central difference of R along the angle path.
        let h = 1e-6;
        let rp = rotation_from_angles(&(angles + angles_dot * h));
        let rm = rotation_from_angles(&(angles - angles_dot * h));
        let r_dot = (rp - rm) / (2.0 * h);
        let skew = rotation_from_angles(&angles).transpose() * r_dot;
        let w_fd = Vector3::new(skew[(2, 1)], skew[(0, 2)], skew[(1, 0)]);
        assert!((w - w_fd).norm() < 1e-8, "{w:?} vs {w_fd:?}");
        let back = angle_rates(&angles, &w);
        assert!((back - angles_dot).norm() < 1e-14);
    }

    #[test]
    fn angular_acceleration_agrees_with_finite_differences() {
        let angles = Vector3::new(0.3, -0.4, 0.7);
        let d = Vector3::new(0.5, -0.2, 1.3);
        let dd = Vector3::new(-0.7, 0.9, 0.1);
        let (_, w_dot) = body_rates_from_angle_rates(&angles, &d, &dd);
        let h = 1e-5;
        let at = |t: f64| {
            let a = angles + d * t + dd * (0.5 * t * t);
            let ad = d + dd * t;
            body_rates_from_angle_rates(&a, &ad, &dd).0
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        assert!((w_dot - fd).norm() < 1e-8, "{w_dot:?} vs {fd:?}");
    }
}
