//! The stand: mass, inertia, gravity and the twelve joint positions (docs/model.md §1, §3).

use nalgebra::Vector3;

use super::error::ParameterError;
use crate::maths;

pub use super::LEG_COUNT;

/// Base joint circle radius `R_b` of the default stand, m.
pub const DEFAULT_BASE_RADIUS: f64 = 1.5;
/// Platform joint circle radius `R_p` of the default stand, m.
pub const DEFAULT_PLATFORM_RADIUS: f64 = 1.0;
/// Depth `h_c` of the platform joint plane below the centre of mass, m.
pub const DEFAULT_JOINT_DEPTH: f64 = 0.5;
/// `g` of the default stand, m/s² (docs/model.md §3).
pub const DEFAULT_GRAVITY: f64 = 9.81;
/// Height `H0` of the platform joint plane in the neutral pose, m. Chosen so that every leg
/// carries exactly `0.2005 M g` in static equilibrium (the paper's section 5 leg force).
pub const DEFAULT_NEUTRAL_JOINT_HEIGHT: f64 = 1.4589244164161732;
/// Non-dimensional equilibrium leg force of the paper (units of `M g`).
pub const PAPER_EQUILIBRIUM_LEG_FORCE: f64 = 0.2005;
/// Base joint azimuths of the default stand, degrees (docs/model.md §3).
pub const DEFAULT_BASE_AZIMUTHS_DEG: [f64; LEG_COUNT] = [-10.0, 10.0, 110.0, 130.0, 230.0, 250.0];
/// Platform joint azimuths of the default stand, degrees (docs/model.md §3).
pub const DEFAULT_PLATFORM_AZIMUTHS_DEG: [f64; LEG_COUNT] = [-50.0, 50.0, 70.0, 170.0, 190.0, 290.0];

/// Relative size (against the stand's characteristic length) below which two joints count as
/// coincident or a leg as having zero length. Far below any manufacturing tolerance, far above
/// round-off.
pub const COINCIDENCE_TOLERANCE: f64 = 1e-9;

/// The mechanical description of a loaded Stewart platform.
///
/// All quantities are in one consistent system of units: SI (m, kg, s, N) by default, or the
/// paper's non-dimensional units (see [`crate::physics::scaling`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Stand {
    /// Mass `M` of the loaded platform (platform plus payload), kg.
    pub mass: f64,
    /// Principal central moments of inertia `J1, J2, J3` about the body axes `e1, e2, e3`,
    /// kg·m².
    pub inertia: [f64; 3],
    /// Gravitational acceleration `g`, acting along `-z`, m/s².
    pub gravity: f64,
    /// Base joints `B_k`, fixed in the ground, inertial frame, m.
    pub base_joints: [Vector3<f64>; LEG_COUNT],
    /// Platform joints `A_k`, fixed in the body, body frame with origin at the centre of
    /// mass, m.
    pub platform_joints: [Vector3<f64>; LEG_COUNT],
}

impl Default for Stand {
    /// The truck-cabin motion stand of docs/model.md §3.
    fn default() -> Self {
        Self::truck_cabin()
    }
}

impl Stand {
    /// The truck-cabin motion stand of docs/model.md §3: `M = 3000 kg`, `J = (1500, 1500, 2200) kg m²`,
    /// base joints on a 1.5 m circle, platform joints on a 1.0 m circle 0.5 m below the
    /// centre of mass.
    pub fn truck_cabin() -> Self {
        let base_joints = DEFAULT_BASE_AZIMUTHS_DEG.map(|deg: f64| {
            let phi = deg.to_radians();
            Vector3::new(DEFAULT_BASE_RADIUS * maths::cos(phi), DEFAULT_BASE_RADIUS * maths::sin(phi), 0.0)
        });
        let platform_joints = DEFAULT_PLATFORM_AZIMUTHS_DEG.map(|deg: f64| {
            let phi = deg.to_radians();
            Vector3::new(
                DEFAULT_PLATFORM_RADIUS * maths::cos(phi),
                DEFAULT_PLATFORM_RADIUS * maths::sin(phi),
                -DEFAULT_JOINT_DEPTH,
            )
        });
        Stand {
            mass: 3000.0,
            inertia: [1500.0, 1500.0, 2200.0],
            gravity: DEFAULT_GRAVITY,
            base_joints,
            platform_joints,
        }
    }

    /// Centre of mass of the default stand's neutral pose, m.
    pub fn truck_cabin_neutral_position() -> Vector3<f64> {
        Vector3::new(0.0, 0.0, DEFAULT_NEUTRAL_JOINT_HEIGHT + DEFAULT_JOINT_DEPTH)
    }

    /// The paper's second moments `I1 = (J2 + J3 - J1)/2` etc. (`∫x² dm` about the principal
    /// axes). All positive exactly when the moments of inertia obey the triangle inequality.
    pub fn second_moments(&self) -> [f64; 3] {
        let [j1, j2, j3] = self.inertia;
        [(j2 + j3 - j1) / 2.0, (j3 + j1 - j2) / 2.0, (j1 + j2 - j3) / 2.0]
    }

    /// Characteristic length of the stand: the largest joint distance from its frame's origin.
    /// Used to make geometric tolerances scale-free. (One square root, of the largest square:
    /// the root is monotonic and correctly rounded, so the same bits as the largest root.)
    pub fn characteristic_length(&self) -> f64 {
        let joints = self.base_joints.iter().chain(self.platform_joints.iter());
        joints.map(|p| p.norm_squared()).fold(0.0, f64::max).sqrt()
    }

    /// The base joint circle radius `R_b`, the paper's unit of length: the largest horizontal
    /// distance of a base joint from the `z` axis.
    pub fn base_radius(&self) -> f64 {
        self.base_joints.iter().map(|b| b.xy().norm()).fold(0.0, f64::max)
    }

    /// Checks everything about the stand that does not depend on a pose. The error names the
    /// offending FMI parameter.
    pub fn validate(&self) -> Result<(), ParameterError> {
        check_finite("M", self.mass)?;
        if self.mass <= 0.0 {
            return Err(ParameterError::new("M", format!("mass must be positive, got {:?} kg", self.mass)));
        }
        for (a, &j) in self.inertia.iter().enumerate() {
            let name = format!("J[{}]", a + 1);
            check_finite(&name, j)?;
            if j <= 0.0 {
                return Err(ParameterError::new(name, format!("moment of inertia must be positive, got {j:?} kg.m2")));
            }
        }
        let [j1, j2, j3] = self.inertia;
        for (a, (ja, jb, jc)) in [(j1, j2, j3), (j2, j3, j1), (j3, j1, j2)].into_iter().enumerate() {
            if ja >= jb + jc {
                let (b, c) = ((a + 1) % 3 + 1, (a + 2) % 3 + 1);
                let why = if ja == jb + jc {
                    "a body with all its mass in one plane (a thin plate) has exactly these moments, but then the \
                     paper's second moment I{n} = (J[{b}] + J[{c}] - J[{n}])/2 is 0 and the special form has no \
                     equation for e{n}; give the plate a small thickness"
                } else {
                    "no rigid body has such moments (the paper's second moment I{n} would be negative)"
                };
                let why = why
                    .replace("{n}", &(a + 1).to_string())
                    .replace("{b}", &b.to_string())
                    .replace("{c}", &c.to_string());
                return Err(ParameterError::new(
                    format!("J[{}]", a + 1),
                    format!(
                        "moments of inertia violate the strict triangle inequality: J[{}] = {ja:?} must be less than \
                         J[{b}] + J[{c}] = {:?}: {why}",
                        a + 1,
                        jb + jc,
                    ),
                ));
            }
        }
        check_finite("g", self.gravity)?;
        if self.gravity < 0.0 {
            return Err(ParameterError::new(
                "g",
                format!("gravity must be >= 0 (it acts along -z), got {:?}", self.gravity),
            ));
        }
        for (k, (b, a)) in self.base_joints.iter().zip(self.platform_joints.iter()).enumerate() {
            for i in 0..3 {
                for (symbol, x) in [("B", b[i]), ("A", a[i])] {
                    let name = format!("{symbol}[{},{}]", k + 1, i + 1);
                    check_finite(&name, x)?;
                    if x.abs() > MAX_COORDINATE {
                        return Err(ParameterError::new(
                            name,
                            format!(
                                "{x:e} is beyond any stand: joint coordinates are limited to +-{MAX_COORDINATE:e} (m, \
                                 or the non-dimensional unit of length), where the stand's geometry stays in double \
                                 precision"
                            ),
                        ));
                    }
                }
            }
        }
        let tolerance = COINCIDENCE_TOLERANCE * self.characteristic_length().max(f64::MIN_POSITIVE);
        for (joints, symbol) in [(&self.base_joints, "B"), (&self.platform_joints, "A")] {
            for i in 0..LEG_COUNT {
                for j in (i + 1)..LEG_COUNT {
                    let distance = (joints[i] - joints[j]).norm();
                    if distance <= tolerance {
                        return Err(ParameterError::new(
                            format!("{symbol}[{},1]", j + 1),
                            format!(
                                "joints {symbol}[{}] and {symbol}[{}] coincide (distance {distance:e} m)",
                                i + 1,
                                j + 1
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Largest joint coordinate, m (or the non-dimensional unit of length): a stand of a thousand
/// kilometres; beyond it lengths squared leave double precision.
pub const MAX_COORDINATE: f64 = 1e6;

/// `Ok` if `value` is finite, else the error naming the parameter `name`.
pub fn check_finite(name: &str, value: f64) -> Result<(), ParameterError> {
    if value.is_finite() { Ok(()) } else { Err(ParameterError::new(name, format!("must be finite, got {value:?}"))) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_stand_neutral_pose_matches_spec_numbers() {
        let stand = Stand::truck_cabin();
        stand.validate().unwrap();
        // Horizontal leg projection d and neutral leg length from docs/model.md §3.
        let a = stand.platform_joints[0] + Vector3::new(0.0, 0.0, DEFAULT_NEUTRAL_JOINT_HEIGHT + DEFAULT_JOINT_DEPTH);
        let d = (a - stand.base_joints[0]).xy().norm();
        assert!((d - 0.9756365463855202).abs() < 1e-15, "d = {d}");
        let l = (a - stand.base_joints[0]).norm();
        assert!((l - 1.7550860729486566).abs() < 1e-15, "l = {l}");
        assert_eq!(stand.second_moments(), [1100.0, 1100.0, 400.0]);
        assert!((stand.base_radius() - 1.5).abs() < 1e-15);
    }

    #[test]
    fn triangle_inequality_is_enforced_with_the_offending_moment_named() {
        let mut stand = Stand::truck_cabin();
        stand.inertia = [1500.0, 1500.0, 3000.0];
        let err = stand.validate().unwrap_err();
        assert_eq!(err.parameter, "J[3]");
        assert!(err.message.contains("triangle"), "{err}");
    }
}
