//! End stops: the stroke `lmin_k <= l_k <= lmax_k` of each leg, enforced by a unilateral
//! virtual potential (Baganov, Bardachov, Rusanov, source document 002, eq. (7) with the
//! polynomial approximation (12) of the delta function) plus contact damping.
//!
//! Outside its stroke a leg meets its stop, which acts along the leg exactly like the
//! actuator force `u_k` (so it enters the special form through the same `u_k n_k` terms).
//! With the penetration `delta_k = lmin_k - l_k` (lower stop) or `l_k - lmax_k` (upper stop):
//!
//! ```text
//! V_k    = 1/2 k_s delta_k²                                   (delta_k > 0, else 0)
//! f_c    = k_s delta_k                                        spring part, from -dV_k/dl_k
//! f_d    = clamp(c_s delta_k', -f_c, f_c)                     damping part, in contact only
//! |Fstop_k| = f_c + f_d  in [0, 2 f_c]
//! ```
//!
//! pushing (`Fstop_k >= 0`) at the lower stop and pulling (`<= 0`) at the upper stop. The
//! damping is the linear damper `c_s` (N s/m) of a Kelvin-Voigt contact, limited to the
//! spring force as in the Modelica Standard Library's `ElastoGap`: the force is continuous at
//! contact onset (it starts from zero), and it never sticks (it never pulls at a lower stop or
//! pushes at an upper one), whatever the rate. The document's constant term `pi/a` carries no
//! force and is dropped, so that the energy is continuous; `k_s = 2 pi a` in its notation.
//!
//! The damping takes the power `P_d = f_d delta_k' >= 0` (the clamp keeps the sign of
//! `c_s delta_k'`), so that `E(t) - E(0) = W_F - W_d` with `E` including `sum V_k`.

use crate::physics::error::ParameterError;
use crate::physics::number::Real;
use crate::physics::stand::{LEG_COUNT, Stand};

/// Lower end of the default stand's stroke, m. The neutral leg is 1.755 m; the default heave
/// programme keeps every leg clear of both ends (docs/model.md §4 gives its legs' range).
pub const DEFAULT_LOWER: f64 = 1.45;
/// Upper end of the default stand's stroke, m.
pub const DEFAULT_UPPER: f64 = 2.15;
/// Default stop stiffness `k_s`, N/m: an elastomer cushion of 10 kN/mm. The default platform
/// resting on its six lower stops sinks 0.66 mm into them, and dropped from its neutral pose
/// (0.39 m of heave, 2.0 m/s at the legs) it penetrates 2 cm at most. The contact frequency
/// on the stops, about 17 Hz in heave, is resolved by the default integrators at 1 ms.
pub const DEFAULT_STIFFNESS: f64 = 1.0e7;
/// Default contact damping `c_s`, N s/m: about half the critical damping of the heave mode of
/// the default platform resting on its lower stops, so that it comes to rest within a
/// fraction of a second after landing.
pub const DEFAULT_DAMPING: f64 = 1.0e5;

/// The stroke limits and contact law of the six legs (units of the stand: m, N/m, N s/m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndStops {
    /// `lmin_k`, m.
    pub lower: [f64; LEG_COUNT],
    /// `lmax_k`, m.
    pub upper: [f64; LEG_COUNT],
    /// `k_s`, N/m.
    pub stiffness: f64,
    /// `c_s`, N s/m.
    pub damping: f64,
}

impl Default for EndStops {
    fn default() -> Self {
        EndStops {
            lower: [DEFAULT_LOWER; LEG_COUNT],
            upper: [DEFAULT_UPPER; LEG_COUNT],
            stiffness: DEFAULT_STIFFNESS,
            damping: DEFAULT_DAMPING,
        }
    }
}

/// The stop's force on one leg and the power its damping takes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StopContact<T = f64> {
    /// `Fstop_k`, N, sign as the actuator force (positive pushes the platform away).
    pub force: T,
    /// `P_d >= 0`, W.
    pub dissipation: T,
}

/// Number of switching functions of the stops: `l_k - lmin_k` then `lmax_k - l_k`.
pub const STROKE_LIMITS: usize = 2 * LEG_COUNT;

impl EndStops {
    /// Whether leg `k` of length `l` is outside its stroke (in contact with a stop).
    #[inline(always)]
    pub fn is_outside(&self, k: usize, l: f64) -> bool {
        l < self.lower[k] || l > self.upper[k]
    }

    /// Penetration `delta` (m, > 0 in contact) and the sign `s` of the stop force (+1 lower,
    /// -1 upper); `delta <= 0` inside the stroke.
    #[inline(always)]
    fn penetration<T: Real>(&self, k: usize, l: T) -> (T, f64) {
        let below = T::constant(self.lower[k]) - l;
        if below > T::zero() { (below, 1.0) } else { (l - self.upper[k], -1.0) }
    }

    /// Stop force and dissipation on leg `k` with length `l` and rate `ldot` (the law of the
    /// module documentation; its derivative where it has a kink is that of the branch taken).
    #[inline(always)]
    pub fn contact<T: Real>(&self, k: usize, l: T, ldot: T) -> StopContact<T> {
        let (delta, s) = self.penetration(k, l);
        if !(delta > T::zero()) {
            return StopContact { force: T::zero(), dissipation: T::zero() };
        }
        // delta' = -s ldot: the lower stop is penetrated by a shortening leg.
        let delta_rate = ldot * -s;
        let spring = delta * self.stiffness;
        let damper = (delta_rate * self.damping).clamp_to(-spring, spring);
        StopContact { force: (spring + damper) * s, dissipation: damper * delta_rate }
    }

    /// Potential energy `sum_k V_k` of the stops for leg lengths `l`, J.
    pub fn potential_energy<T: Real>(&self, l: &[T; LEG_COUNT]) -> T {
        let mut energy = T::zero();
        for k in 0..LEG_COUNT {
            let (delta, _) = self.penetration(k, l[k]);
            if delta > T::zero() {
                energy += delta * (0.5 * self.stiffness) * delta;
            }
        }
        energy
    }

    /// The twelve switching functions `l_k - lmin_k` (k = 1..6), then `lmax_k - l_k`: positive
    /// inside the stroke, a sign change is a contact onset or release.
    #[inline]
    pub fn stroke_margins(&self, l: &[f64; LEG_COUNT], g: &mut [f64]) {
        for k in 0..LEG_COUNT {
            if let Some(x) = g.get_mut(k) {
                *x = l[k] - self.lower[k];
            }
            if let Some(x) = g.get_mut(LEG_COUNT + k) {
                *x = self.upper[k] - l[k];
            }
        }
    }

    /// The penetration at which one stop alone carries the platform's weight, `M g / k_s`, m:
    /// how far outside its stroke an initial pose may be (a platform starting at rest on its
    /// stops sinks in by less than this).
    pub fn static_penetration(&self, stand: &Stand) -> f64 {
        stand.mass * stand.gravity / self.stiffness
    }

    /// The height of the centre of mass at which a platform in its level pose rests on its six
    /// lower stops without leg forces: the vertical stop forces `sum_k k_s delta_k n_k.z`
    /// carry `M g` (damping vanishes at rest). Exact for a stand whose level rest is pure
    /// heave (the default stand, by its symmetry); `None` if the stops cannot carry the
    /// platform level.
    pub fn level_rest_height(&self, stand: &Stand) -> Option<f64> {
        let lift = |z: f64| -> f64 {
            let mut up = 0.0;
            for k in 0..LEG_COUNT {
                let leg = nalgebra::Vector3::new(0.0, 0.0, z) + stand.platform_joints[k] - stand.base_joints[k];
                let l = leg.norm();
                let delta = self.lower[k] - l;
                if delta > 0.0 && l > 0.0 {
                    up += self.stiffness * delta * leg.z / l;
                }
            }
            up - stand.mass * stand.gravity
        };
        // The highest touching height: every lower stop touches at or below it.
        let mut hi = f64::NEG_INFINITY;
        for k in 0..LEG_COUNT {
            let d = (stand.platform_joints[k] - stand.base_joints[k]).xy().norm();
            let h =
                (self.lower[k] * self.lower[k] - d * d).sqrt() - (stand.platform_joints[k].z - stand.base_joints[k].z);
            hi = hi.max(h);
        }
        if !hi.is_finite() || lift(hi) > 0.0 {
            return None;
        }
        let mut lo = hi;
        let mut step = 1e-3 * stand.characteristic_length();
        while lift(lo) <= 0.0 {
            lo -= step;
            step *= 2.0;
            if !(lo > hi - 10.0 * stand.characteristic_length()) {
                return None;
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if lift(mid) > 0.0 { lo = mid } else { hi = mid }
        }
        Some(0.5 * (lo + hi))
    }

    /// Checks the stroke and contact parameters (FMI names in the errors).
    pub fn validate(&self) -> Result<(), ParameterError> {
        for k in 0..LEG_COUNT {
            let (lo, hi) = (self.lower[k], self.upper[k]);
            let (lo_name, hi_name) = (format!("lmin[{}]", k + 1), format!("lmax[{}]", k + 1));
            crate::physics::stand::check_finite(&lo_name, lo)?;
            crate::physics::stand::check_finite(&hi_name, hi)?;
            if lo <= 0.0 {
                return Err(ParameterError::new(
                    lo_name,
                    format!("the shortest leg length must be positive, got {lo:?} m"),
                ));
            }
            if lo >= hi {
                return Err(ParameterError::new(
                    lo_name,
                    format!("the stroke is empty: lmin[{0}] = {lo:?} m must be less than lmax[{0}] = {hi:?} m", k + 1),
                ));
            }
        }
        crate::physics::stand::check_finite("stops.stiffness", self.stiffness)?;
        if self.stiffness <= 0.0 {
            return Err(ParameterError::new(
                "stops.stiffness",
                format!("the stop stiffness must be positive, got {:?} N/m", self.stiffness),
            ));
        }
        crate::physics::stand::check_finite("stops.damping", self.damping)?;
        if self.damping < 0.0 {
            return Err(ParameterError::new(
                "stops.damping",
                format!("the contact damping must be >= 0 N.s/m (0 = elastic stops), got {:?}", self.damping),
            ));
        }
        Ok(())
    }

    /// Checks that an initial pose with leg lengths `l` is inside the strokes, or outside by
    /// less than [`EndStops::static_penetration`].
    pub fn validate_initial_lengths(&self, stand: &Stand, l: &[f64; LEG_COUNT]) -> Result<(), ParameterError> {
        let allowed = self.static_penetration(stand);
        for k in 0..LEG_COUNT {
            let (delta, s) = self.penetration(k, l[k]);
            if delta > allowed {
                let (which, name, limit) =
                    if s > 0.0 { ("below", "lmin", self.lower[k]) } else { ("above", "lmax", self.upper[k]) };
                return Err(ParameterError::new(
                    "r0",
                    format!(
                        "in the initial pose leg {} has length {} m, {delta:e} m {which} its stroke limit \
                         {name}[{}] = {limit} m; at most the static penetration M g / stops.stiffness = {allowed:e} m \
                         is allowed (move the initial pose, or change the stroke)",
                        k + 1,
                        l[k],
                        k + 1
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_is_continuous_at_onset_pushes_below_pulls_above_and_never_sticks() {
        let s = EndStops::default();
        assert_eq!(s.contact(0, 1.5, -3.0), StopContact::default());
        // Just touching: the force starts from zero whatever the rate.
        let onset = s.contact(0, DEFAULT_LOWER - 1e-12, -2.0);
        assert!(onset.force > 0.0 && onset.force < 1e-4, "{onset:?}");
        // Fast release from the lower stop: the damper would pull, the clamp stops it at 0.
        let release = s.contact(0, DEFAULT_LOWER - 1e-3, 5.0);
        assert_eq!(release.force, 0.0);
        assert!(release.dissipation >= 0.0);
        // Upper stop pulls.
        let up = s.contact(0, DEFAULT_UPPER + 1e-3, 0.0);
        assert!((up.force + 1e4).abs() < 1e-6, "{up:?}");
        for (l, ld) in [(1.44, -1.0), (1.44, 0.01), (2.16, 1.0), (2.16, -0.01), (1.4499, 0.3)] {
            assert!(s.contact(0, l, ld).dissipation >= 0.0);
        }
    }

    /// The law's derivative through duals against central differences, on each branch.
    #[test]
    fn derivative_matches_central_differences_on_each_branch() {
        use crate::physics::number::Dual;
        let s = EndStops::default();
        for (l, ld) in [(1.44, -0.01), (1.44, -2.0), (1.44, 0.5), (2.16, 0.02), (2.16, 2.0), (2.16, -1.5)] {
            let (dl, dld) = (0.3, -0.7);
            let eps = 1e-9;
            let p = s.contact(0, l + eps * dl, ld + eps * dld);
            let m = s.contact(0, l - eps * dl, ld - eps * dld);
            let t = s.contact(0, Dual::new(l, dl), Dual::new(ld, dld));
            let fd_force = (p.force - m.force) / (2.0 * eps);
            let fd_diss = (p.dissipation - m.dissipation) / (2.0 * eps);
            assert!((t.force.eps - fd_force).abs() <= 1e-5 * fd_force.abs().max(1.0), "{l} {ld}: {t:?} vs {fd_force}");
            assert!(
                (t.dissipation.eps - fd_diss).abs() <= 1e-5 * fd_diss.abs().max(1.0),
                "{l} {ld}: {t:?} vs {fd_diss}"
            );
        }
    }

    #[test]
    fn level_rest_height_balances_the_weight() {
        let stand = Stand::truck_cabin();
        let z = EndStops::default().level_rest_height(&stand).unwrap();
        // 0.66 mm into the stops, 0.39 m below the neutral pose.
        assert!((z - 1.5717790).abs() < 1e-6, "{z}");
    }

    #[test]
    fn refusals_name_the_parameter() {
        let mut s = EndStops::default();
        s.lower[2] = 2.2;
        assert_eq!(s.validate().unwrap_err().parameter, "lmin[3]");
        let mut s = EndStops::default();
        s.lower[0] = 0.0;
        assert_eq!(s.validate().unwrap_err().parameter, "lmin[1]");
        let s = EndStops { stiffness: 0.0, ..Default::default() };
        assert_eq!(s.validate().unwrap_err().parameter, "stops.stiffness");
        let s = EndStops { damping: -1.0, ..Default::default() };
        assert_eq!(s.validate().unwrap_err().parameter, "stops.damping");
        let s = EndStops::default();
        let stand = Stand::truck_cabin();
        assert!(s.validate_initial_lengths(&stand, &[1.45 - 1e-3; 6]).is_ok());
        let e = s.validate_initial_lengths(&stand, &[1.755, 1.755, 1.3, 1.755, 1.755, 1.755]).unwrap_err();
        assert!(e.message.contains("leg 3") && e.message.contains("lmin[3]"), "{e}");
    }
}
