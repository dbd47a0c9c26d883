//! The classical washout (Schmidt and Conrad; Reid and Nahon 1985; docs/cueing.md): scaling
//! and limits, tilt coordination through a low-pass and an ideal rate limiter, the rotational
//! high-pass, the third-order translational high-pass. Linear filters per axis, written as
//! states whose integrals are the filters' outputs, so the head's displacement, velocity and
//! acceleration and the attitude with its rates are states or exact functions of them.
//!
//! Frames (SPEC §11): the vehicle's axes are the cabin's (body) axes, x forward, y left, z up;
//! the inertial frame is the stand's, z up; angles the 1-2-3 sequence `R = Rx Ry Rz`.

use nalgebra::{Matrix3, Vector3};

use super::jet::{Jet, Trig};
use crate::physics::number::Real;

/// Number of the washout's continuous states.
pub const STATE_DIM: usize = 21;

/// Where each state sits in the state vector (the FMU's Model Exchange order).
pub mod layout {
    /// `q`, the translational filter's first state per inertial axis (m.s): the head's
    /// displacement is `q'`.
    pub const TRANSLATION_Q: usize = 0;
    /// The head's displacement from its neutral position, inertial axes, m.
    pub const HEAD_R: usize = 3;
    /// Its velocity, m/s.
    pub const HEAD_V: usize = 6;
    /// The low-passed specific force `f_l` (x, y of the cabin), m/s².
    pub const TILT_F: usize = 9;
    /// Its rate, m/s³.
    pub const TILT_FDOT: usize = 11;
    /// The tilt coordination's roll and pitch, rad.
    pub const TILT_ANGLES: usize = 13;
    /// `z`, the rotational filter's first state per angle (rad.s): the angle is `z'`.
    pub const ROTATION_Q: usize = 15;
    /// The rotational channel's roll, pitch and yaw, rad.
    pub const ROTATION_ANGLES: usize = 18;
}
use layout::*;

/// The ideal rate limiter of each tilt angle (SPEC §11): the angle equals its target while the
/// target moves no faster than `tilt.rateLimit` (`Following`), and otherwise slews towards it
/// at the limit (`Rising`, `Falling`) until it catches up. A switch is where
/// [`WashoutParameters::tilt_switching`] crosses zero: Co-Simulation locates it within its
/// steps, Model Exchange as an event.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TiltMode {
    #[default]
    Following,
    Rising,
    Falling,
}

/// The modes of the roll and the pitch tilt.
pub type TiltModes = [TiltMode; 2];

/// The first [`WashoutParameters::tilt_switching`] functions are the modes' (a crossing below
/// zero switches the mode); the others the targets' clips (a crossing either way only marks a
/// jump of the targets' rates).
pub const TILT_MODE_SWITCHES: usize = 2;

impl TiltMode {
    /// The mode's code in the FMU state (0, 1, 2).
    pub fn code(self) -> u8 {
        match self {
            TiltMode::Following => 0,
            TiltMode::Rising => 1,
            TiltMode::Falling => 2,
        }
    }

    pub fn from_code(code: u8) -> Option<TiltMode> {
        match code {
            0 => Some(TiltMode::Following),
            1 => Some(TiltMode::Rising),
            2 => Some(TiltMode::Falling),
            _ => None,
        }
    }
}

/// The washout's parameters (units SI; defaults: docs/cueing.md, a truck cabin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WashoutParameters {
    /// `g`, m/s².
    pub gravity: f64,
    /// `K_f` per cabin axis.
    pub scale_f: [f64; 3],
    /// `K_w` per cabin axis.
    pub scale_omega: [f64; 3],
    /// Limit of the scaled specific force's deviation from rest, per component, m/s².
    pub f_max: f64,
    /// Limit of the scaled angular velocity, per component, rad/s.
    pub omega_max: f64,
    /// `w_t`, rad/s, per inertial axis.
    pub hp_f_omega: [f64; 3],
    /// `zeta_t` per inertial axis.
    pub hp_f_damping: [f64; 3],
    /// `w_b`, rad/s, per inertial axis.
    pub hp_f_break: [f64; 3],
    /// `w_l`, rad/s.
    pub tilt_omega: f64,
    /// `zeta_l`.
    pub tilt_damping: f64,
    /// Tilt rate limit, rad/s.
    pub tilt_rate_limit: f64,
    /// Tilt angle limit, rad.
    pub tilt_max: f64,
    /// `w_r`, rad/s, per angle.
    pub hp_w_omega: [f64; 3],
    /// `zeta_r` per angle.
    pub hp_w_damping: [f64; 3],
}

/// The default stand's washout (docs/cueing.md: where each value comes from).
pub const DEFAULT_WASHOUT: WashoutParameters = WashoutParameters {
    gravity: crate::physics::stand::DEFAULT_GRAVITY,
    scale_f: [0.6, 0.6, 0.6],
    scale_omega: [0.6, 0.6, 0.6],
    f_max: 6.0,
    omega_max: 1.0,
    hp_f_omega: [2.5, 2.5, 4.0],
    hp_f_damping: [1.0, 1.0, 1.0],
    hp_f_break: [0.5, 0.5, 0.5],
    tilt_omega: 3.0,
    tilt_damping: 1.0,
    tilt_rate_limit: 3.0 * std::f64::consts::PI / 180.0,
    tilt_max: 10.0 * std::f64::consts::PI / 180.0,
    hp_w_omega: [1.0, 1.0, 1.0],
    hp_w_damping: [1.0, 1.0, 1.0],
};

/// The vehicle's motion at the head: specific force (m/s², cabin axes, `g ez` at rest) and
/// angular velocity (rad/s, cabin axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleMotion {
    pub f: [f64; 3],
    pub omega: [f64; 3],
}

/// The washout's pose before the workspace limiter: the head's displacement from neutral
/// (inertial axes) and the attitude, each with two derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WashoutPose {
    pub head: [Jet; 3],
    pub angles: [Jet; 3],
}

/// `x` limited to `[-limit, limit]` (never panics: a negative or NaN limit, which validation
/// refuses, gives NaN or `-limit`, not a crash).
fn clip(x: f64, limit: f64) -> f64 {
    x.max(-limit).min(limit)
}

/// Rotation body -> inertial of 1-2-3 angles, `Rx(roll) Ry(pitch) Rz(yaw)`.
pub fn rotation<T: Trig>(a: &[T; 3]) -> Matrix3<T> {
    rotation_of(a.map(|x| x.sin()), a.map(|x| x.cos()))
}

/// [`rotation`] from the angles' sines and cosines.
pub fn rotation_of<T: Real>(sin: [T; 3], cos: [T; 3]) -> Matrix3<T> {
    let ([sa, sb, sc], [ca, cb, cc]) = (sin, cos);
    Matrix3::new(
        cb * cc,
        -(cb * sc),
        sb,
        ca * sc + sa * sb * cc,
        ca * cc - sa * sb * sc,
        -(sa * cb),
        sa * sc - ca * sb * cc,
        sa * cc + ca * sb * sc,
        ca * cb,
    )
}

/// Body angular velocity `E(angles) angles'` of the 1-2-3 sequence.
pub fn body_rates<T: Trig>(a: &[T; 3], d: &[T; 3]) -> Vector3<T> {
    let (sb, cb) = (a[1].sin(), a[1].cos());
    let (sc, cc) = (a[2].sin(), a[2].cos());
    Vector3::new(d[0] * cb * cc + d[1] * sc, d[1] * cc - d[0] * cb * sc, d[0] * sb + d[2])
}

/// Angle rates `E(angles)^-1 w` of the 1-2-3 sequence (the pitch stays within the tilt and
/// rotational limits, far from the gimbal lock at 90 deg).
pub fn angle_rates<T: Trig>(a: &[T; 3], w: &[T; 3]) -> [T; 3] {
    let (sb, cb) = (a[1].sin(), a[1].cos());
    let (sc, cc) = (a[2].sin(), a[2].cos());
    let roll = (w[0] * cc - w[1] * sc) / cb;
    [roll, w[0] * sc + w[1] * cc, w[2] - roll * sb]
}

impl WashoutParameters {
    /// The scaled and limited specific force `f_s` (with `g ez`) and angular velocity `w_s`.
    pub fn scaled(&self, m: &VehicleMotion) -> ([f64; 3], [f64; 3]) {
        let g = [0.0, 0.0, self.gravity];
        let f = std::array::from_fn(|i| clip(self.scale_f[i] * (m.f[i] - g[i]), self.f_max) + g[i]);
        let w = std::array::from_fn(|i| clip(self.scale_omega[i] * m.omega[i], self.omega_max));
        (f, w)
    }

    /// The tilt targets (roll, pitch) for which gravity alone gives the low-passed specific
    /// force `f_l` (jets of `f_l`: the targets' jets).
    fn tilt_targets(&self, f_l: [Jet; 2]) -> [Jet; 2] {
        let s_max = crate::maths::sin(self.tilt_max);
        let arcsine = |x: Jet| if x.v.abs() < s_max { x.asin() } else { Jet::new(clip(x.v, s_max), 0.0, 0.0).asin() };
        let roll = arcsine(f_l[1] / self.gravity);
        let pitch = -arcsine(f_l[0] / (roll.cos() * self.gravity));
        [roll, pitch]
    }

    /// The low-passed force's jets: `f_l`, its rate (a state) and its second derivative.
    fn low_passed(&self, x: &[f64; STATE_DIM], f_s: &[f64; 3]) -> [Jet; 2] {
        let (w, z) = (self.tilt_omega, self.tilt_damping);
        std::array::from_fn(|i| {
            let (f, fd) = (x[TILT_F + i], x[TILT_FDOT + i]);
            Jet::new(f, fd, w * w * (f_s[i] - f) - 2.0 * z * w * fd)
        })
    }

    /// The tilt angles with their rates and second derivatives: each follows its target, or
    /// slews at the rate limit (the ideal limiter, by mode).
    fn tilt(&self, x: &[f64; STATE_DIM], f_s: &[f64; 3], modes: &TiltModes) -> [Jet; 2] {
        let targets = self.tilt_targets(self.low_passed(x, f_s));
        std::array::from_fn(|i| {
            let angle = x[TILT_ANGLES + i];
            match modes[i] {
                TiltMode::Following => Jet::new(angle, targets[i].d1, targets[i].d2),
                TiltMode::Rising => Jet::new(angle, self.tilt_rate_limit, 0.0),
                TiltMode::Falling => Jet::new(angle, -self.tilt_rate_limit, 0.0),
            }
        })
    }

    /// The tilt's switching functions: for the roll and the pitch, positive while each
    /// angle's mode holds (following, `tilt.rateLimit - |target'|`; slewing, the distance left
    /// to the target; [`TILT_MODE_SWITCHES`]); then for each target, positive while its
    /// arcsine's argument is inside `+-sin(tilt.max)` (a sign change either way is where the
    /// target's rate jumps to 0 or from it: a following angle's rate, and the cues, jump).
    pub fn tilt_switching(&self, x: &[f64; STATE_DIM], m: &VehicleMotion, modes: &TiltModes) -> [f64; 4] {
        let (f_s, _) = self.scaled(m);
        let f_l = self.low_passed(x, &f_s);
        let targets = self.tilt_targets(f_l);
        let s_max = crate::maths::sin(self.tilt_max);
        let roll_argument = f_l[1].v / self.gravity;
        let pitch_argument = f_l[0].v / (self.gravity * crate::maths::cos(targets[0].v));
        let mode = |i: usize| match modes[i] {
            TiltMode::Following => self.tilt_rate_limit - targets[i].d1.abs(),
            TiltMode::Rising => targets[i].v - x[TILT_ANGLES + i],
            TiltMode::Falling => x[TILT_ANGLES + i] - targets[i].v,
        };
        [mode(0), mode(1), s_max - roll_argument.abs(), s_max - pitch_argument.abs()]
    }

    /// Tilt angle `i`'s mode after its switching function crossed zero at `x`: a follower
    /// whose target outran the limit slews after it; a slewing angle that caught up follows
    /// (and takes the target's value), unless the target moves away faster than the limit.
    pub fn switch_tilt(&self, x: &mut [f64; STATE_DIM], m: &VehicleMotion, modes: &mut TiltModes, i: usize) {
        let (f_s, _) = self.scaled(m);
        let target = self.tilt_targets(self.low_passed(x, &f_s))[i];
        modes[i] = if target.d1.abs() <= self.tilt_rate_limit && modes[i] != TiltMode::Following {
            x[TILT_ANGLES + i] = target.v;
            TiltMode::Following
        } else if target.d1 > 0.0 {
            TiltMode::Rising
        } else {
            TiltMode::Falling
        };
    }

    /// Following angles set to their targets' values (after a step: a follower equals its
    /// target, the integration's error aside).
    pub fn follow_targets(&self, x: &mut [f64; STATE_DIM], m: &VehicleMotion, modes: &TiltModes) {
        let (f_s, _) = self.scaled(m);
        let targets = self.tilt_targets(self.low_passed(x, &f_s));
        for i in 0..2 {
            if modes[i] == TiltMode::Following {
                x[TILT_ANGLES + i] = targets[i].v;
            }
        }
    }

    /// The washout's attitude (rotational channel plus tilt) with its rate; the rotational
    /// channel's input `u = E^-1 w_s` and the rates `y'` of its angles.
    fn attitude(
        &self,
        x: &[f64; STATE_DIM],
        f_s: &[f64; 3],
        w_s: &[f64; 3],
        modes: &TiltModes,
    ) -> ([Jet; 3], [Jet; 3], [f64; 3]) {
        let tilt = self.tilt(x, f_s, modes);
        let value: [f64; 3] = std::array::from_fn(|i| x[ROTATION_ANGLES + i] + if i < 2 { tilt[i].v } else { 0.0 });
        let u = angle_rates(&value, w_s);
        let rotation_rate: [f64; 3] = std::array::from_fn(|i| {
            let (w, z) = (self.hp_w_omega[i], self.hp_w_damping[i]);
            u[i] - 2.0 * z * w * x[ROTATION_ANGLES + i] - w * w * x[ROTATION_Q + i]
        });
        let attitude = std::array::from_fn(|i| {
            let t = if i < 2 { tilt[i] } else { Jet::default() };
            Jet::new(value[i], rotation_rate[i] + t.d1, 0.0)
        });
        let tilt3 = [tilt[0], tilt[1], Jet::default()];
        (attitude, tilt3, rotation_rate)
    }

    /// The head's acceleration along inertial axis `i`: `W_t`'s output for its input `u`
    /// (`R f_s + g_vec`), `u - c2 x'' - c1 x' - c0 x` with `c2, c1, c0` its denominator's.
    fn translation(&self, x: &[f64; STATE_DIM], i: usize, u: f64) -> f64 {
        let (w, z, b) = (self.hp_f_omega[i], self.hp_f_damping[i], self.hp_f_break[i]);
        let (c2, c1, c0) = (2.0 * z * w + b, w * w + 2.0 * z * w * b, w * w * b);
        u - c2 * x[HEAD_V + i] - c1 * x[HEAD_R + i] - c0 * x[TRANSLATION_Q + i]
    }

    /// The state's rate with the vehicle's motion `m` held and the tilt's modes `modes`.
    pub fn rate(&self, x: &[f64; STATE_DIM], m: &VehicleMotion, modes: &TiltModes) -> [f64; STATE_DIM] {
        let (f_s, w_s) = self.scaled(m);
        let mut dx = [0.0; STATE_DIM];
        let f_l = self.low_passed(x, &f_s);
        for i in 0..2 {
            dx[TILT_F + i] = f_l[i].d1;
            dx[TILT_FDOT + i] = f_l[i].d2;
        }
        let (attitude, tilt, rotation_rate) = self.attitude(x, &f_s, &w_s, modes);
        for i in 0..2 {
            dx[TILT_ANGLES + i] = tilt[i].d1;
        }
        dx[ROTATION_Q..ROTATION_Q + 3].copy_from_slice(&x[ROTATION_ANGLES..ROTATION_ANGLES + 3]);
        dx[ROTATION_ANGLES..ROTATION_ANGLES + 3].copy_from_slice(&rotation_rate);
        let angles = attitude.map(|a| a.v);
        let u = rotation(&angles) * Vector3::from(f_s) - Vector3::new(0.0, 0.0, self.gravity);
        for i in 0..3 {
            dx[TRANSLATION_Q + i] = x[HEAD_R + i];
            dx[HEAD_R + i] = x[HEAD_V + i];
            dx[HEAD_V + i] = self.translation(x, i, u[i]);
        }
        dx
    }

    /// The washout's pose with its exact first and second derivatives (the vehicle's motion
    /// held).
    pub fn pose(&self, x: &[f64; STATE_DIM], m: &VehicleMotion, modes: &TiltModes) -> WashoutPose {
        let (f_s, w_s) = self.scaled(m);
        let (attitude, tilt, rotation_rate) = self.attitude(x, &f_s, &w_s, modes);
        // u' = d/dt E(angles)^-1 w_s along the attitude's rate (w_s held).
        let moving = attitude.map(|a| Jet::new(a.v, a.d1, 0.0));
        let u = angle_rates(&moving, &w_s.map(|w| Jet::new(w, 0.0, 0.0)));
        let angles = std::array::from_fn(|i| {
            let (w, z) = (self.hp_w_omega[i], self.hp_w_damping[i]);
            let rotation_acceleration = u[i].d1 - 2.0 * z * w * rotation_rate[i] - w * w * x[ROTATION_ANGLES + i];
            Jet::new(attitude[i].v, attitude[i].d1, rotation_acceleration + tilt[i].d2)
        });
        // The head's jerk is not needed: its acceleration is the pose's second derivative.
        let accel = rotation(&angles.map(|a| a.v)) * Vector3::from(f_s) - Vector3::new(0.0, 0.0, self.gravity);
        let head = std::array::from_fn(|i| Jet::new(x[HEAD_R + i], x[HEAD_V + i], self.translation(x, i, accel[i])));
        WashoutPose { head, angles }
    }

    /// Why the parameters cannot be used, naming the parameter.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x > 0.0 && x.is_finite() { Ok(()) } else { Err(format!("parameter {name}: must be > 0, got {x:?}")) }
        };
        positive("g", self.gravity)?;
        positive("fmax", self.f_max)?;
        positive("omegamax", self.omega_max)?;
        positive("tilt.omega", self.tilt_omega)?;
        positive("tilt.damping", self.tilt_damping)?;
        positive("tilt.rateLimit", self.tilt_rate_limit)?;
        if !(self.tilt_max > 0.0 && self.tilt_max < 1.2) {
            return Err(format!("parameter tilt.max: must lie in (0, 1.2) rad (69 deg), got {:?}", self.tilt_max));
        }
        for i in 0..3 {
            let n = i + 1;
            for (name, x) in [("scale.f", self.scale_f[i]), ("scale.omega", self.scale_omega[i])] {
                if !(x >= 0.0 && x.is_finite()) {
                    return Err(format!("parameter {name}[{n}]: must be >= 0 (0 switches the axis off), got {x:?}"));
                }
            }
            positive(&format!("hp.f.omega[{n}]"), self.hp_f_omega[i])?;
            positive(&format!("hp.f.damping[{n}]"), self.hp_f_damping[i])?;
            positive(&format!("hp.f.break[{n}]"), self.hp_f_break[i])?;
            positive(&format!("hp.w.omega[{n}]"), self.hp_w_omega[i])?;
            positive(&format!("hp.w.damping[{n}]"), self.hp_w_damping[i])?;
        }
        Ok(())
    }
}
