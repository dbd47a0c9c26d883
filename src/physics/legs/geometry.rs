//! Leg geometry of a state: attachment arms, lengths, unit directions and length rates.
//! Computed once per right-hand-side evaluation and shared by the force law and the
//! special-form accelerations (no recomputation of the geometry).

use nalgebra::{Scalar, Vector3};

use super::per_leg::{Lanes, Narrow, PerLeg, components};
use crate::physics::body::state::BodyState;
use crate::physics::number::{Real, lift};
use crate::physics::stand::{LEG_COUNT, Stand};

/// Geometry of the six legs for one state, in the number type `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegGeometry<T: Scalar = f64> {
    /// Arms `R A_k` from the centre of mass to platform joint k, inertial components, m.
    pub arm: [Vector3<T>; LEG_COUNT],
    /// Leg vectors `a_k - B_k = r + R A_k - B_k`, m.
    pub leg: [Vector3<T>; LEG_COUNT],
    /// Leg lengths `l_k`, m.
    pub length: [T; LEG_COUNT],
    /// Unit leg directions `n_k = (a_k - B_k) / l_k` (zero for a collapsed leg, never NaN).
    pub direction: [Vector3<T>; LEG_COUNT],
}

impl<T: Real> LegGeometry<T> {
    #[inline(always)]
    pub fn new(stand: &Stand, state: &BodyState<T>) -> Self {
        let mut arm = [Vector3::zeros(); LEG_COUNT];
        let mut leg = [Vector3::zeros(); LEG_COUNT];
        let mut length = [T::zero(); LEG_COUNT];
        let mut direction = [Vector3::zeros(); LEG_COUNT];
        for k in 0..LEG_COUNT {
            arm[k] = state.body_vector(&stand.platform_joints[k]);
            leg[k] = state.r + arm[k] - lift(&stand.base_joints[k]);
            length[k] = leg[k].dot(&leg[k]).sqrt();
            // One division, three multiplications.
            if length[k] > T::zero() {
                direction[k] = leg[k] * (T::one() / length[k]);
            }
        }
        LegGeometry { arm, leg, length, direction }
    }

    /// Leg length rates `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s.
    #[inline(always)]
    pub fn length_rates(&self, stand: &Stand, state: &BodyState<T>) -> [T; LEG_COUNT] {
        std::array::from_fn(|k| self.direction[k].dot(&(state.v + state.body_vector_rate(&stand.platform_joints[k]))))
    }
}

impl LegGeometry {
    /// Resultant force `sum_k u_k n_k` and moment about the centre of mass
    /// `L = sum_k (R A_k) x (u_k n_k)` of the leg forces `u`.
    #[inline(always)]
    pub fn resultant(&self, u: &[f64; LEG_COUNT]) -> (Vector3<f64>, Vector3<f64>) {
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for k in 0..LEG_COUNT {
            let f = self.direction[k] * u[k];
            force += f;
            moment += self.arm[k].cross(&f);
        }
        (force, moment)
    }
}

/// The stand's joint coordinates as arrays over the legs (`[component][leg]`), so that the six
/// legs of a state are computed side by side ([`PerLeg`], [`JointArrays::legs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointArrays {
    /// `A_k`, body frame, m.
    pub platform: [[f64; LEG_COUNT]; 3],
    /// `B_k`, inertial frame, m.
    pub base: [[f64; LEG_COUNT]; 3],
}

impl JointArrays {
    pub fn new(stand: &Stand) -> Self {
        let by_component = |p: &[Vector3<f64>; LEG_COUNT]| std::array::from_fn(|c| p.map(|v| v[c]));
        JointArrays { platform: by_component(&stand.platform_joints), base: by_component(&stand.base_joints) }
    }

    /// The legs of a state, side by side, for the right-hand side. The same arithmetic in the
    /// same order as [`LegGeometry::new`] (arm `e1 A1 + e2 A2 + e3 A3`, leg `r + arm - B`,
    /// length), so arms, legs and lengths are equal to the bit.
    #[inline(always)]
    pub fn legs<L: Lanes>(&self, state: &BodyState) -> LegLanes<L> {
        let [e1, e2, e3] = &state.e;
        let a = components!(|c| PerLeg::<L>::new(&self.platform[c]));
        let arm =
            components!(|c| PerLeg::splat(e1[c]) * a[0] + PerLeg::splat(e2[c]) * a[1] + PerLeg::splat(e3[c]) * a[2]);
        let leg = components!(|c| PerLeg::splat(state.r[c]) + arm[c] - PerLeg::new(&self.base[c]));
        let length = (leg[0] * leg[0] + leg[1] * leg[1] + leg[2] * leg[2]).sqrt();
        LegLanes { arm, leg, length }
    }

    /// [`JointArrays::legs`] as plain arrays, with the inverse lengths, for the checks at the
    /// end of a step (the guard, the switching functions, the outputs). Written as loops over
    /// arrays rather than through [`PerLeg`], which compile to fewer instructions here; the
    /// same arithmetic in the same order, so the two are equal to the bit (tested).
    #[inline(always)]
    pub fn kinematics(&self, state: &BodyState) -> LegKinematics {
        let (a, b) = (&self.platform, &self.base);
        let [e1, e2, e3] = &state.e;
        let mut arm = [[0.0; LEG_COUNT]; 3];
        let mut leg = [[0.0; LEG_COUNT]; 3];
        for c in 0..3 {
            for k in 0..LEG_COUNT {
                arm[c][k] = e1[c] * a[0][k] + e2[c] * a[1][k] + e3[c] * a[2][k];
                leg[c][k] = state.r[c] + arm[c][k] - b[c][k];
            }
        }
        let mut length = [0.0; LEG_COUNT];
        let mut inverse_length = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            length[k] = (leg[0][k] * leg[0][k] + leg[1][k] * leg[1][k] + leg[2][k] * leg[2][k]).sqrt();
            inverse_length[k] = 1.0 / length[k];
        }
        LegKinematics { arm, leg, length, inverse_length }
    }

    /// [`JointArrays::kinematics`], computed in lanes `V` where they are cheaper for it
    /// ([`Lanes::FOR_CHECKS`]); the same bits either way.
    #[inline(always)]
    pub fn kinematics_in<V: Lanes>(&self, state: &BodyState) -> LegKinematics {
        if !V::FOR_CHECKS {
            return self.kinematics(state);
        }
        let LegLanes { arm, leg, length } = self.legs::<V>(state);
        LegKinematics {
            arm: components!(|c| arm[c].to_array()),
            leg: components!(|c| leg[c].to_array()),
            length: length.to_array(),
            inverse_length: (PerLeg::splat(1.0) / length).to_array(),
        }
    }

    /// [`JointArrays::length_rates`], in lanes `V` as [`JointArrays::kinematics_in`].
    #[inline(always)]
    pub fn length_rates_in<V: Lanes>(&self, state: &BodyState, legs: &LegKinematics) -> [f64; LEG_COUNT] {
        if !V::FOR_CHECKS {
            return self.length_rates(state, legs);
        }
        let leg = components!(|c| PerLeg::<V>::new(&legs.leg[c]));
        let (_, rates) =
            self.directions_and_rates(state, &leg, PerLeg::new(&legs.length), PerLeg::new(&legs.inverse_length));
        rates.to_array()
    }

    /// Unit leg directions (0 for a collapsed leg) and length rates
    /// `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s, of legs given side by side: the arithmetic of
    /// [`JointArrays::length_rates`] in lanes, for the end stops' contact law and the AVX2
    /// copy's checks.
    #[inline(always)]
    pub fn directions_and_rates<V: Lanes>(
        &self,
        state: &BodyState,
        leg: &[PerLeg<V>; 3],
        length: PerLeg<V>,
        inverse_length: PerLeg<V>,
    ) -> ([PerLeg<V>; 3], PerLeg<V>) {
        let (n, l_dot, _) = self.directions_rates_and_velocities(state, leg, length, inverse_length);
        (n, l_dot)
    }

    /// [`JointArrays::directions_and_rates`] and the platform joints' velocities
    /// `v + d(R A_k)/dt`, m/s, per component.
    #[inline(always)]
    pub fn directions_rates_and_velocities<V: Lanes>(
        &self,
        state: &BodyState,
        leg: &[PerLeg<V>; 3],
        length: PerLeg<V>,
        inverse_length: PerLeg<V>,
    ) -> ([PerLeg<V>; 3], PerLeg<V>, [PerLeg<V>; 3]) {
        let [d1, d2, d3] = &state.e_dot;
        let a = components!(|c| PerLeg::<V>::new(&self.platform[c]));
        let n = components!(|c| length.where_positive(leg[c] * inverse_length));
        let velocity = components!(|c| {
            PerLeg::splat(state.v[c])
                + (PerLeg::splat(d1[c]) * a[0] + PerLeg::splat(d2[c]) * a[1] + PerLeg::splat(d3[c]) * a[2])
        });
        (n, n[0] * velocity[0] + n[1] * velocity[1] + n[2] * velocity[2], velocity)
    }

    /// Leg length rates `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s, as [`LegGeometry::length_rates`]
    /// (the same arithmetic; 0 for a collapsed leg).
    #[inline(always)]
    pub fn length_rates(&self, state: &BodyState, legs: &LegKinematics) -> [f64; LEG_COUNT] {
        let a = &self.platform;
        let [d1, d2, d3] = &state.e_dot;
        let mut rates = [0.0; LEG_COUNT];
        for k in 0..LEG_COUNT {
            let mut rate = 0.0;
            for c in 0..3 {
                let velocity = state.v[c] + (d1[c] * a[0][k] + d2[c] * a[1][k] + d3[c] * a[2][k]);
                let n = legs.direction_component(c, k);
                rate = if c == 0 { n * velocity } else { rate + n * velocity };
            }
            rates[k] = rate;
        }
        rates
    }
}

/// The legs of one state side by side: see [`JointArrays::legs`].
#[derive(Clone, Copy)]
pub struct LegLanes<L: Lanes = Narrow> {
    /// Arms `R A_k`, inertial components, m.
    pub arm: [PerLeg<L>; 3],
    /// Leg vectors `a_k - B_k = r + R A_k - B_k`, m.
    pub leg: [PerLeg<L>; 3],
    /// `l_k`, m.
    pub length: PerLeg<L>,
}

/// The legs of one state as arrays over the legs (`[component][leg]`): see
/// [`JointArrays::kinematics`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegKinematics {
    /// Arms `R A_k`, inertial components, m.
    pub arm: [[f64; LEG_COUNT]; 3],
    /// Leg vectors `a_k - B_k = r + R A_k - B_k`, m.
    pub leg: [[f64; LEG_COUNT]; 3],
    /// `l_k`, m.
    pub length: [f64; LEG_COUNT],
    /// `1 / l_k`, 1/m (infinite for a collapsed leg).
    pub inverse_length: [f64; LEG_COUNT],
}

impl LegKinematics {
    /// The six leg lengths, m.
    #[inline(always)]
    pub fn lengths(&self) -> [f64; LEG_COUNT] {
        self.length
    }

    /// Unit leg directions `[component][leg]` (zero for a collapsed leg, never NaN), as
    /// [`LegGeometry::direction`].
    #[inline(always)]
    pub fn directions(&self) -> [[f64; LEG_COUNT]; 3] {
        std::array::from_fn(|c| std::array::from_fn(|k| self.direction_component(c, k)))
    }

    /// Component `c` of the unit direction of leg `k`: the one definition of a direction.
    #[inline(always)]
    fn direction_component(&self, c: usize, k: usize) -> f64 {
        if self.length[k] > 0.0 { self.leg[c][k] * self.inverse_length[k] } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::body::kinematics::rotation_from_angles;

    /// The legs side by side, as arrays and one by one are the same numbers to the bit.
    #[test]
    fn the_three_forms_of_the_legs_agree_to_the_bit() {
        let stand = Stand::truck_cabin();
        let joints = JointArrays::new(&stand);
        for (dz, roll) in [(0.0, 0.0), (0.1, 0.2), (-0.3, -0.1)] {
            let state = BodyState::from_pose(
                Stand::truck_cabin_neutral_position() + Vector3::new(0.02, -0.01, dz),
                Vector3::new(0.1, -0.3, 0.7),
                &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
                &Vector3::new(0.3, 0.2, -0.1),
            );
            let lanes = joints.legs::<Narrow>(&state);
            let arrays = joints.kinematics(&state);
            assert_eq!(joints.kinematics_in::<Narrow>(&state), arrays);
            let single = LegGeometry::new(&stand, &state);
            let bits = |x: [f64; LEG_COUNT]| x.map(f64::to_bits);
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx") {
                use super::super::per_leg::Wide;
                let wide_arrays = joints.kinematics_in::<Wide>(&state);
                assert_eq!(wide_arrays, arrays);
                assert_eq!(
                    bits(joints.length_rates_in::<Wide>(&state, &arrays)),
                    bits(joints.length_rates(&state, &arrays))
                );
                let wide = joints.legs::<Wide>(&state);
                assert_eq!(bits(wide.length.to_array()), bits(arrays.length));
                for c in 0..3 {
                    assert_eq!(bits(wide.arm[c].to_array()), bits(arrays.arm[c]));
                    assert_eq!(bits(wide.leg[c].to_array()), bits(arrays.leg[c]));
                }
            }
            assert_eq!(bits(lanes.length.to_array()), bits(arrays.length));
            assert_eq!(bits(arrays.length), bits(single.length));
            for c in 0..3 {
                assert_eq!(bits(lanes.arm[c].to_array()), bits(arrays.arm[c]));
                assert_eq!(bits(lanes.leg[c].to_array()), bits(arrays.leg[c]));
                assert_eq!(bits(arrays.arm[c]), bits(single.arm.map(|a| a[c])));
                assert_eq!(bits(arrays.directions()[c]), bits(single.direction.map(|n| n[c])));
            }
            assert_eq!(bits(joints.length_rates(&state, &arrays)), bits(single.length_rates(&stand, &state)));
        }
    }
}
