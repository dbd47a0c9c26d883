//! Leg geometry of a state: attachment arms, lengths, unit directions and length rates.
//! Computed once per right-hand-side evaluation and shared by the force law and the
//! special-form accelerations (no recomputation of the geometry).

use nalgebra::{Scalar, Vector3};

use super::per_leg::{Lanes, Narrow, PerLeg, components};
use crate::physics::body::state::BodyState;
use crate::physics::number::{Number, Real};
use crate::physics::stand::{LEG_COUNT, Stand};
use crate::simd::Plain;

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
        let (e, r) = (state.e.map(|v| [v.x, v.y, v.z]), [state.r.x, state.r.y, state.r.z]);
        for k in 0..LEG_COUNT {
            let joints = (constants(&stand.platform_joints[k]), constants(&stand.base_joints[k]));
            let (a, l, len) = leg_vectors(&e, &r, &joints.0, &joints.1);
            let n = unit_direction(&l, len, T::one() / len);
            (arm[k], leg[k], length[k], direction[k]) = (Vector3::from(a), Vector3::from(l), len, Vector3::from(n));
        }
        LegGeometry { arm, leg, length, direction }
    }

    /// Leg length rates `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s.
    #[inline(always)]
    pub fn length_rates(&self, stand: &Stand, state: &BodyState<T>) -> [T; LEG_COUNT] {
        let (v, e_dot) = ([state.v.x, state.v.y, state.v.z], state.e_dot.map(|w| [w.x, w.y, w.z]));
        std::array::from_fn(|k| {
            let n = [self.direction[k].x, self.direction[k].y, self.direction[k].z];
            length_rate(&v, &e_dot, &constants(&stand.platform_joints[k]), &n).0
        })
    }
}

/// The laws of one leg, written once over [`Number`]: one leg in `f64` or
/// [`crate::physics::number::Dual`] ([`LegGeometry`]), or six side by side ([`PerLeg`]: the
/// step's fast path in vector registers, the checks' arrays in [`Plain`] lanes); the same
/// arithmetic in every form, so the same bits.
///
/// The leg's arm `R A = e1 A_1 + e2 A_2 + e3 A_3` (inertial components), its vector
/// `a - B = r + R A - B` and its length, for the body axes `e[axis][component]`, the centre of
/// mass `r`, the platform joint `a` (body frame) and the base joint `b`, m.
#[inline(always)]
pub fn leg_vectors<T: Number>(e: &[[T; 3]; 3], r: &[T; 3], a: &[T; 3], b: &[T; 3]) -> ([T; 3], [T; 3], T) {
    let arm = components!(|c| e[0][c] * a[0] + e[1][c] * a[1] + e[2][c] * a[2]);
    let leg = components!(|c| r[c] + arm[c] - b[c]);
    (arm, leg, (leg[0] * leg[0] + leg[1] * leg[1] + leg[2] * leg[2]).sqrt())
}

/// The leg's unit direction `n = (a - B) / l`, 0 for a collapsed leg (never NaN).
#[inline(always)]
pub fn unit_direction<T: Number>(leg: &[T; 3], length: T, inverse_length: T) -> [T; 3] {
    components!(|c| length.where_positive(leg[c] * inverse_length))
}

/// The leg's length rate `dl/dt = n . (v + d(R A)/dt)`, m/s, and the platform joint's velocity
/// `v + e1' A_1 + e2' A_2 + e3' A_3`, for the body axes' rates `e_dot[axis][component]`.
#[inline(always)]
pub fn length_rate<T: Number>(v: &[T; 3], e_dot: &[[T; 3]; 3], a: &[T; 3], n: &[T; 3]) -> (T, [T; 3]) {
    let velocity = components!(|c| v[c] + (e_dot[0][c] * a[0] + e_dot[1][c] * a[1] + e_dot[2][c] * a[2]));
    (n[0] * velocity[0] + n[1] * velocity[1] + n[2] * velocity[2], velocity)
}

/// [`length_rate`] of the leg from the body state `state` to platform joint `a` (body frame)
/// along the direction `n` (or the leg vector, for the rate times the length): the rate and the
/// joint's velocity `v + d(R a)/dt`, in any number type.
#[inline(always)]
pub fn joint_rate<T: Real>(state: &BodyState<T>, a: &Vector3<f64>, n: &Vector3<T>) -> (T, Vector3<T>) {
    let (v, e_dot) = ([state.v.x, state.v.y, state.v.z], state.e_dot.map(|w| [w.x, w.y, w.z]));
    let (rate, velocity) = length_rate(&v, &e_dot, &constants(a), &[n.x, n.y, n.z]);
    (rate, Vector3::from(velocity))
}

/// A point's coordinates as constants of the number type.
#[inline(always)]
fn constants<T: Number>(p: &Vector3<f64>) -> [T; 3] {
    [T::constant(p.x), T::constant(p.y), T::constant(p.z)]
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
        let e = components!(|axis| components!(|c| PerLeg::<L>::splat(state.e[axis][c])));
        let r = components!(|c| PerLeg::splat(state.r[c]));
        let (a, b) = (components!(|c| PerLeg::new(&self.platform[c])), components!(|c| PerLeg::new(&self.base[c])));
        let (arm, leg, length) = leg_vectors(&e, &r, &a, &b);
        LegLanes { arm, leg, length }
    }

    /// [`JointArrays::legs`] as plain arrays, with the inverse lengths, for the checks at the
    /// end of a step (the guard, the switching functions, the outputs): the same law in
    /// [`Plain`] lanes, so the same bits. (In SSE2 pairs instead the hover cycle counted 4,166
    /// instructions against 4,154, the adaptive one 7,247 against 7,241: callgrind, one run.)
    #[inline(always)]
    pub fn kinematics(&self, state: &BodyState) -> LegKinematics {
        self.kinematics_in::<Plain>(state)
    }

    /// [`JointArrays::kinematics`], computed in the checks' lanes of `V` ([`Lanes::Checks`]);
    /// the same bits in any.
    #[inline(always)]
    pub fn kinematics_in<V: Lanes>(&self, state: &BodyState) -> LegKinematics {
        self.kinematics_lanes::<V::Checks>(state)
    }

    #[inline(always)]
    fn kinematics_lanes<V: Lanes>(&self, state: &BodyState) -> LegKinematics {
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
        let leg = components!(|c| PerLeg::<V::Checks>::new(&legs.leg[c]));
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
        let e_dot = components!(|axis| components!(|c| PerLeg::<V>::splat(state.e_dot[axis][c])));
        let v = components!(|c| PerLeg::splat(state.v[c]));
        let a = components!(|c| PerLeg::<V>::new(&self.platform[c]));
        let n = unit_direction(leg, length, inverse_length);
        let (rate, velocity) = length_rate(&v, &e_dot, &a, &n);
        (n, rate, velocity)
    }

    /// Leg length rates `dl_k/dt = n_k . (v + d(R A_k)/dt)`, m/s, as [`LegGeometry::length_rates`]
    /// (the same arithmetic; 0 for a collapsed leg).
    #[inline(always)]
    pub fn length_rates(&self, state: &BodyState, legs: &LegKinematics) -> [f64; LEG_COUNT] {
        let a = &self.platform;
        let (v, e_dot) = ([state.v.x, state.v.y, state.v.z], state.e_dot.map(|w| [w.x, w.y, w.z]));
        std::array::from_fn(|k| {
            let n = legs.direction(k);
            length_rate(&v, &e_dot, &[a[0][k], a[1][k], a[2][k]], &n).0
        })
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
        let n: [[f64; 3]; LEG_COUNT] = std::array::from_fn(|k| self.direction(k));
        std::array::from_fn(|c| n.map(|d| d[c]))
    }

    /// The unit direction of leg `k` ([`unit_direction`]).
    #[inline(always)]
    fn direction(&self, k: usize) -> [f64; 3] {
        let leg = [self.leg[0][k], self.leg[1][k], self.leg[2][k]];
        unit_direction(&leg, self.length[k], self.inverse_length[k])
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
            if crate::simd::wide_testable() {
                use crate::simd::Wide;
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
            assert_eq!(
                bits(joints.length_rates_in::<Narrow>(&state, &arrays)),
                bits(single.length_rates(&stand, &state))
            );
        }
    }
}
