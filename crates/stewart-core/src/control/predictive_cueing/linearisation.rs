//! The simulator's cues and the legs at a pose, with their derivatives: what the predictive
//! method linearises about its predicted trajectory at each solve.

use nalgebra::{Matrix3, Vector3};

use crate::physics::cueing::jet::Jet;
use crate::physics::cueing::limiter::Workspace;
use crate::physics::cueing::washout::{body_rates, rotation};
use crate::physics::stand::LEG_COUNT;

/// The rotation `R(beta)` and its partial derivatives `dR/dbeta_i` (1-2-3 angles).
pub fn rotation_and_partials(angles: &[f64; 3]) -> (Matrix3<f64>, [Matrix3<f64>; 3]) {
    let value = rotation(angles);
    let partials = std::array::from_fn(|i| {
        let seeded: [Jet; 3] = std::array::from_fn(|k| Jet::new(angles[k], if k == i { 1.0 } else { 0.0 }, 0.0));
        rotation(&seeded).map(|x| x.d1)
    });
    (value, partials)
}

/// The simulator's cues at one pose and their Jacobians: `fsim = R(beta)^T (A + g ez)`,
/// `omegasim = E(beta) beta'`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Cues {
    pub fsim: [f64; 3],
    pub omegasim: [f64; 3],
    /// `d fsim / d A` (row: output, column: the head's acceleration per inertial axis).
    pub fsim_by_acceleration: [[f64; 3]; 3],
    /// `d fsim / d beta`.
    pub fsim_by_angles: [[f64; 3]; 3],
    /// `d omegasim / d beta`.
    pub omegasim_by_angles: [[f64; 3]; 3],
    /// `d omegasim / d beta'` (`E(beta)`).
    pub omegasim_by_rates: [[f64; 3]; 3],
}

impl Cues {
    pub fn at(gravity: f64, acceleration: &[f64; 3], angles: &[f64; 3], rates: &[f64; 3]) -> Cues {
        let (r, dr) = rotation_and_partials(angles);
        let specific = Vector3::new(acceleration[0], acceleration[1], acceleration[2] + gravity);
        let fsim = r.transpose() * specific;
        let omegasim = body_rates(angles, rates);
        let mut cues = Cues {
            fsim: fsim.into(),
            omegasim: omegasim.into(),
            fsim_by_acceleration: std::array::from_fn(|o| std::array::from_fn(|c| r[(c, o)])),
            ..Cues::default()
        };
        for i in 0..3 {
            let by_angle = dr[i].transpose() * specific;
            let seeded: [Jet; 3] = std::array::from_fn(|k| Jet::new(angles[k], if k == i { 1.0 } else { 0.0 }, 0.0));
            let held: [Jet; 3] = rates.map(|w| Jet::new(w, 0.0, 0.0));
            let e_column = body_rates(angles, &std::array::from_fn(|k| if k == i { 1.0 } else { 0.0 }));
            let by_angle_rate = body_rates(&seeded, &held).map(|x| x.d1);
            for o in 0..3 {
                cues.fsim_by_angles[o][i] = by_angle[o];
                cues.omegasim_by_angles[o][i] = by_angle_rate[o];
                cues.omegasim_by_rates[o][i] = e_column[o];
            }
        }
        cues
    }
}

/// The legs at a pose given by the head's displacement `p` from its neutral position and the
/// angles: lengths and their Jacobian with respect to `(p, beta)`, which is also the map from
/// `(p', beta')` to the legs' speeds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Legs {
    pub length: [f64; LEG_COUNT],
    pub jacobian: [[f64; 6]; LEG_COUNT],
}

impl Legs {
    /// The cabin rotates about the head point `head` (body frame, from the centre of mass): the
    /// centre of mass is `neutral + head + p - R head`, leg k's vector
    /// `neutral + head + p + R (A_k - head) - B_k`.
    pub fn at(ws: &Workspace, head: &Vector3<f64>, p: &[f64; 3], angles: &[f64; 3]) -> Legs {
        let (r, dr) = rotation_and_partials(angles);
        let origin = ws.neutral + head + Vector3::new(p[0], p[1], p[2]);
        let mut legs = Legs::default();
        for k in 0..LEG_COUNT {
            let arm = ws.platform_joints[k] - head;
            let s = origin + r * arm - ws.base_joints[k];
            let l = s.norm();
            let unit = s / l;
            legs.length[k] = l;
            for i in 0..3 {
                legs.jacobian[k][i] = unit[i];
                legs.jacobian[k][3 + i] = unit.dot(&(dr[i] * arm));
            }
        }
        legs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::truck_workspace as workspace;

    /// Every Jacobian against central differences.
    #[test]
    fn the_jacobians_are_the_derivatives() {
        let (a, b, w) = ([0.4, -1.1, 0.3], [0.05, -0.08, 0.12], [0.2, -0.1, 0.3]);
        let c = Cues::at(9.81, &a, &b, &w);
        let d = 1e-6;
        for i in 0..3 {
            let bump =
                |x: &[f64; 3], s: f64| -> [f64; 3] { std::array::from_fn(|k| x[k] + if k == i { s } else { 0.0 }) };
            let (fa, fb) = (Cues::at(9.81, &bump(&a, d), &b, &w), Cues::at(9.81, &bump(&a, -d), &b, &w));
            let (ga, gb) = (Cues::at(9.81, &a, &bump(&b, d), &w), Cues::at(9.81, &a, &bump(&b, -d), &w));
            let (ha, hb) = (Cues::at(9.81, &a, &b, &bump(&w, d)), Cues::at(9.81, &a, &b, &bump(&w, -d)));
            for o in 0..3 {
                let close = |x: f64, y: f64| (x - y).abs() < 1e-8;
                assert!(close(c.fsim_by_acceleration[o][i], (fa.fsim[o] - fb.fsim[o]) / (2.0 * d)));
                assert!(close(c.fsim_by_angles[o][i], (ga.fsim[o] - gb.fsim[o]) / (2.0 * d)));
                assert!(close(c.omegasim_by_angles[o][i], (ga.omegasim[o] - gb.omegasim[o]) / (2.0 * d)));
                assert!(close(c.omegasim_by_rates[o][i], (ha.omegasim[o] - hb.omegasim[o]) / (2.0 * d)));
            }
        }
        let ws = workspace();
        let head = Vector3::new(0.5, 0.4, 1.0);
        let (p, angles) = ([0.1, -0.05, 0.03], [0.04, -0.06, 0.1]);
        let legs = Legs::at(&ws, &head, &p, &angles);
        for i in 0..6 {
            let shifted = |s: f64| {
                let mut q = [p[0], p[1], p[2], angles[0], angles[1], angles[2]];
                q[i] += s;
                Legs::at(&ws, &head, &[q[0], q[1], q[2]], &[q[3], q[4], q[5]])
            };
            let (up, down) = (shifted(d), shifted(-d));
            for k in 0..LEG_COUNT {
                let numeric = (up.length[k] - down.length[k]) / (2.0 * d);
                assert!((legs.jacobian[k][i] - numeric).abs() < 1e-8, "leg {k}, coordinate {i}");
            }
        }
        // The head at neutral, no rotation: the legs are the limiter's (the same stand).
        let zero = Legs::at(&ws, &head, &[0.0; 3], &[0.0; 3]);
        for k in 0..LEG_COUNT {
            assert!((zero.length[k] - ws.leg_length(k, &[0.0; 3], &[0.0; 3])).abs() < 1e-14);
        }
    }
}
