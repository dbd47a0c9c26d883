//! The workspace limiter (SPEC §11, docs/cueing.md): a commanded pose that would put a leg
//! outside `[lmin_k + margin, lmax_k - margin]` is pulled back along the straight line (in
//! position and angles) towards neutral, smoothly, so the command's velocity and acceleration
//! stay continuous.
//!
//! A leg's excursion `e_k` at a pose is its length's distance from neutral over the distance
//! to the bound on that side (1: at the bound). For the washout's deviation `d` from neutral
//! the usage is `rho = (sum over k, i of (e_k(mu_i d) / mu_i)^64)^(1/64)` over the multiples
//! `mu_i = i/16`, i = 1..16: a smooth bound of the largest excursion per unit of the line (for
//! legs whose length changes in proportion along the line, the pose's own largest excursion).
//! The command is `neutral + c d` with `c = sigma(rho)/rho`, `sigma(rho) = rho` up to the onset
//! `rho_0` and `rho_0 + (1 - rho_0) tanh((rho - rho_0)/(1 - rho_0))` beyond it: twice
//! continuously differentiable and below 1, so at the multiples `mu_i` every leg's excursion
//! `e_k(c d) <= c rho <= sigma < 1`. Between them a leg is checked at `c d` itself: one that
//! would still leave its margins (a length that turns sharply along the line) pulls the command
//! back further, a jump taken only then. The limiter has no state of its own: it is a function
//! of the washout's states and inputs, which the FMU state holds.

use nalgebra::{Matrix3, Vector3};

use super::jet::{Jet, Trig};
use super::washout::{rotation, rotation_of};
use crate::maths;
use crate::physics::number::Real;
use crate::physics::stand::LEG_COUNT;
use num_traits::One;

/// The multiples of the deviation at which the legs are measured: `i / SAMPLES`, i = 1..SAMPLES.
const SAMPLES: usize = 16;
/// The exponent of the smooth maximum: 96 equal terms weigh 1.074 times one.
const POWER_HALVINGS: usize = 6; // 2^6 = 64

/// The stand's legs as the limiter sees them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Workspace {
    pub base_joints: [Vector3<f64>; LEG_COUNT],
    pub platform_joints: [Vector3<f64>; LEG_COUNT],
    /// `lmin_k + margin`, m.
    pub lower: [f64; LEG_COUNT],
    /// `lmax_k - margin`, m.
    pub upper: [f64; LEG_COUNT],
    /// The neutral centre of mass, m (no rotation).
    pub neutral: Vector3<f64>,
    /// `rho_0`: the usage from which the limiter acts, in (0, 1).
    pub onset: f64,
}

/// A limited pose command: centre of mass and angles with two derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitedPose {
    pub r: [Jet; 3],
    pub angles: [Jet; 3],
    /// `rho` of the washout's pose (1: a leg at its bound).
    pub usage: f64,
    /// `c`: the share of the washout's deviation from neutral commanded (1: all of it).
    pub scale: f64,
}

/// The value part of [`rotation`] on jets: each angle's sine and cosine from one `sin_cos`, as a
/// jet's are (`rotation` on `f64` takes `sin` and `cos` apart), so that the limiter's values are
/// the jets' values to the bit.
fn rotation_as_jets_value(a: &[f64; 3]) -> Matrix3<f64> {
    let pairs = a.map(maths::sin_cos);
    rotation_of(pairs.map(|p| p.0), pairs.map(|p| p.1))
}

impl Workspace {
    /// `l_k` at the pose `neutral + dr`, angles `da`.
    pub fn leg_length<T: Trig>(&self, k: usize, dr: &[T; 3], da: &[T; 3]) -> T {
        self.leg_length_rotated(k, dr, &rotation(da))
    }

    /// `l_k` at the pose `neutral + dr` with the angles' rotation `rot` (worked out once per
    /// pose by the callers: it is most of a leg's cost).
    fn leg_length_rotated<T: Real>(&self, k: usize, dr: &[T; 3], rot: &Matrix3<T>) -> T {
        let a = self.platform_joints[k];
        let mut s = T::zero();
        for i in 0..3 {
            let arm = rot[(i, 0)] * a.x + rot[(i, 1)] * a.y + rot[(i, 2)] * a.z;
            let c = dr[i] + arm + (self.neutral[i] - self.base_joints[k][i]);
            s += c * c;
        }
        s.sqrt()
    }

    /// Leg k's excursion at the pose `neutral + dr`, rotation `rot`, from its neutral length `l0`:
    /// towards the upper bound and towards the lower, each 0 on the other side.
    fn excursions<T: Real>(&self, k: usize, l0: f64, dr: &[T; 3], rot: &Matrix3<T>) -> [T; 2] {
        let l = self.leg_length_rotated(k, dr, rot);
        let up = (l - l0) / (self.upper[k] - l0);
        let down = (l - l0) / (self.lower[k] - l0);
        [T::select(up.greater(T::zero()), up, T::zero()), T::select(down.greater(T::zero()), down, T::zero())]
    }

    /// `rho` of the deviation `dr`, `da` (the module's smooth maximum), in jets or in values:
    /// `rotate` gives a pose's rotation from its angles.
    fn usage<T: Real>(
        &self,
        neutral: &[f64; LEG_COUNT],
        dr: &[T; 3],
        da: &[T; 3],
        rotate: impl Fn(&[T; 3]) -> Matrix3<T>,
    ) -> T {
        let mut largest = 0.0f64;
        let mut all = [[T::zero(); 2 * LEG_COUNT]; SAMPLES];
        for (i, row) in all.iter_mut().enumerate() {
            let mu = (i + 1) as f64 / SAMPLES as f64;
            let (r, rot) = (dr.map(|x| x * mu), rotate(&da.map(|x| x * mu)));
            for k in 0..LEG_COUNT {
                let [up, down] = self.excursions(k, neutral[k], &r, &rot);
                row[2 * k] = up / mu;
                row[2 * k + 1] = down / mu;
                largest = largest.max(row[2 * k].value()).max(row[2 * k + 1].value());
            }
        }
        // Scaled by the largest term so that the 64th powers stay finite.
        if largest > 0.0 {
            let mut sum = T::zero();
            for t in all.iter().flatten() {
                let mut x = *t / largest;
                for _ in 0..POWER_HALVINGS {
                    x = x * x;
                }
                sum += x;
            }
            let mut root = sum;
            for _ in 0..POWER_HALVINGS {
                root = root.sqrt();
            }
            root * largest
        } else {
            T::zero()
        }
    }

    /// The legs' lengths at neutral.
    fn neutral_lengths(&self) -> [f64; LEG_COUNT] {
        let rot = rotation(&[0.0; 3]);
        std::array::from_fn(|k| self.leg_length_rotated(k, &[0.0; 3], &rot))
    }

    /// Whether every leg is strictly inside its bounds at `neutral + s d` (values).
    fn fits(&self, s: f64, dr: &[f64; 3], da: &[f64; 3]) -> bool {
        let (r, rot) = (dr.map(|x| s * x), rotation(&da.map(|x| s * x)));
        (0..LEG_COUNT).all(|k| {
            let l = self.leg_length_rotated(k, &r, &rot);
            l > self.lower[k] && l < self.upper[k]
        })
    }

    /// The pose command for the washout's deviation `dr` (centre of mass from neutral) and
    /// angles `da`, each with two derivatives.
    pub fn limit(&self, dr: &[Jet; 3], da: &[Jet; 3]) -> LimitedPose {
        let neutral = self.neutral_lengths();
        let (vr, va) = (dr.map(|x| x.v), da.map(|x| x.v));
        // Inside the onset the command is the washout's own (scale 1), and `rho`'s value is all
        // that is needed: worked out in values first, so jets only beyond it.
        let values = self.usage(&neutral, &vr, &va, rotation_as_jets_value);
        let (usage, mut scale) = if values <= self.onset {
            (values, Jet::one())
        } else {
            let usage = self.usage(&neutral, dr, da, rotation);
            let span = 1.0 - self.onset;
            let sigma = ((usage - self.onset) / span).tanh() * span + self.onset;
            (usage.v, sigma / usage)
        };
        // Between the multiples a leg may still leave its margins: pull back until it fits.
        if !self.fits(scale.v, &vr, &va) {
            let (mut lo, mut hi) = (0.0, scale.v);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if self.fits(mid, &vr, &va) { lo = mid } else { hi = mid }
            }
            scale = scale * (lo / scale.v);
        }
        LimitedPose {
            r: std::array::from_fn(|i| dr[i] * scale + self.neutral[i]),
            angles: da.map(|a| a * scale),
            usage,
            scale: scale.v,
        }
    }

    /// The net behind a method that keeps the legs inside by itself (the predictive
    /// method's plans): the command as it is while every leg is inside its margins, else
    /// pulled back along the line towards neutral until every leg is (a jump, taken only
    /// then). `usage` is the largest leg excursion at the pose itself.
    pub fn net(&self, dr: &[Jet; 3], da: &[Jet; 3]) -> LimitedPose {
        let (vr, va) = (dr.map(|x| x.v), da.map(|x| x.v));
        let (neutral, rot) = (self.neutral_lengths(), rotation(&va));
        let mut usage = 0.0f64;
        for (k, &l0) in neutral.iter().enumerate() {
            let l = self.leg_length_rotated(k, &vr, &rot);
            let e = if l > l0 { (l - l0) / (self.upper[k] - l0) } else { (l - l0) / (self.lower[k] - l0) };
            usage = usage.max(e);
        }
        let mut scale = 1.0;
        if !self.fits(1.0, &vr, &va) {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if self.fits(mid, &vr, &va) { lo = mid } else { hi = mid }
            }
            scale = lo;
        }
        LimitedPose {
            r: std::array::from_fn(|i| dr[i] * scale + self.neutral[i]),
            angles: da.map(|a| a * scale),
            usage,
            scale,
        }
    }

    /// Why the workspace cannot be used: the neutral pose must keep every leg inside its
    /// margins, and the onset must lie in (0, 1).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.onset > 0.0 && self.onset < 1.0) {
            return Err(format!("parameter limiter.onset: must lie in (0, 1), got {:?}", self.onset));
        }
        for k in 0..LEG_COUNT {
            let l = self.leg_length(k, &[0.0; 3], &[0.0; 3]);
            if !(l > self.lower[k] && l < self.upper[k]) {
                return Err(format!(
                    "parameter neutral: leg {} is {l:.4} m long there, outside [lmin + margin, lmax - margin] = \
                     [{:.4}, {:.4}] m; move neutral or reduce margin",
                    k + 1,
                    self.lower[k],
                    self.upper[k]
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{truck_workspace, xorshift};

    /// The value path that `limit` takes inside the onset gives the jets' `rho` to the bit,
    /// over deviations from tiny to far beyond the legs' bounds (a fixed pseudo-random walk).
    #[test]
    fn rho_in_values_is_the_jets_value_to_the_bit() {
        let ws = truck_workspace();
        let neutral = ws.neutral_lengths();
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        let (mut inside, mut beyond) = (0, 0);
        for case in 0..2000 {
            let size = 10f64.powi(case % 8 - 6); // 1e-6 .. 10: m and rad
            let dr: [Jet; 3] = std::array::from_fn(|_| Jet::new(size * next(), next(), next()));
            let da: [Jet; 3] = std::array::from_fn(|_| Jet::new(0.3 * size * next(), next(), next()));
            let jets = ws.usage(&neutral, &dr, &da, rotation);
            let values = ws.usage(&neutral, &dr.map(|x| x.v), &da.map(|x| x.v), rotation_as_jets_value);
            assert_eq!(values.to_bits(), jets.v.to_bits(), "case {case}: {values:e} against {:e}", jets.v);
            if values <= ws.onset { inside += 1 } else { beyond += 1 }
        }
        assert!(inside > 400 && beyond > 400, "{inside} inside the onset, {beyond} beyond");
    }
}
