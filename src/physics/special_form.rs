//! The loaded platform's equations of motion: the special form of the rigid body
//! ([`super::body::accelerations`]) driven by the legs. Each leg acts on the body at `A_k`
//! along its direction with the actuator force `u_k` plus, outside its stroke, its end stop's
//! force ([`super::legs::end_stops`]). With the forces given, nothing here is singular at a
//! singular leg arrangement: only a collapsed leg (no direction) is, and it carries nothing.
//!
//! [`SpecialForm::rate`] is the definition, written once and generic over the number type:
//! in `f64` it is the right-hand side, in [`Dual`] its exact directional derivative
//! ([`SpecialForm::derivative_tangent`]). [`SpecialForm::derivative`] is the step's fast
//! path: the same operations in the same order with the six legs side by side in vector
//! registers ([`PerLeg`]) and the three axes likewise ([`AxisRows`]), pinned to the
//! definition bit for bit by a test.

use nalgebra::Vector3;

use super::actuators::LegForceLaw;
use super::body::accelerations::RigidBody;
use super::body::per_axis::AxisRows;
use super::body::state::{BodyState, STATE_DIM, StateVector, axes_rates};
use super::legs::end_stops::EndStops;
use super::legs::geometry::{JointArrays, LegGeometry, LegLanes};
use super::legs::per_leg::{Lanes, Narrow, PerLeg, components};
use super::number::{Dual, Real};
use super::stand::{LEG_COUNT, Stand};

/// A stand with its legs' end stops, and the coefficients a right-hand side needs.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecialForm {
    pub stand: Stand,
    /// The special form's coefficients (and the Baumgarte rate).
    pub body: RigidBody,
    /// The legs' end stops, or `None` for the paper's idealised legs of unlimited stroke.
    stops: Option<EndStops>,
    /// The strokes `[lmin, lmax]` (`[-inf, inf]` without stops), kept beside `stops` (written
    /// only by [`SpecialForm::set_end_stops`]) so that the fast path tests all six legs with
    /// one comparison and no branch on the option.
    stroke: [[f64; LEG_COUNT]; 2],
    /// The joints as arrays over the legs, for the fast path.
    pub joints: JointArrays,
}

/// The sum over the six legs in the fixed order `((x1 + x3) + x5) + ((x2 + x4) + x6)`, that of
/// [`PerLeg::sum`].
#[inline(always)]
fn sum_over_legs<T: Real>(x: &[T; LEG_COUNT]) -> T {
    ((x[0] + x[2]) + x[4]) + ((x[1] + x[3]) + x[5])
}

/// [`sum_over_legs`] of each component.
#[inline(always)]
fn sum_vectors<T: Real>(v: &[Vector3<T>; LEG_COUNT]) -> Vector3<T> {
    Vector3::new(sum_over_legs(&v.map(|x| x.x)), sum_over_legs(&v.map(|x| x.y)), sum_over_legs(&v.map(|x| x.z)))
}

impl SpecialForm {
    /// The equations of a stand (which should have passed [`Stand::validate`]; otherwise the
    /// coefficients may be infinite), without end stops.
    pub fn new(stand: Stand) -> Self {
        SpecialForm {
            body: RigidBody::new(&stand),
            stops: None,
            stroke: [[f64::NEG_INFINITY; LEG_COUNT], [f64::INFINITY; LEG_COUNT]],
            joints: JointArrays::new(&stand),
            stand,
        }
    }

    /// The same form with end stops (`None`: without).
    pub fn with_end_stops(mut self, stops: Option<EndStops>) -> Self {
        self.set_end_stops(stops);
        self
    }

    /// Replaces the end stops (`None`: without).
    pub fn set_end_stops(&mut self, stops: Option<EndStops>) {
        self.stroke = match &stops {
            Some(s) => [s.lower, s.upper],
            None => [[f64::NEG_INFINITY; LEG_COUNT], [f64::INFINITY; LEG_COUNT]],
        };
        self.stops = stops;
    }

    /// The legs' end stops, or `None` for the paper's idealised legs.
    pub fn stops(&self) -> Option<&EndStops> {
        self.stops.as_ref()
    }

    /// The same form with Baumgarte stabilisation at `rate` (1/s; 0 = off).
    pub fn with_baumgarte_rate(mut self, rate: f64) -> Self {
        self.body.baumgarte_rate = rate;
        self
    }

    /// The right-hand side `dy/dt` of the body state `y` for the leg forces `u`, and the leg
    /// powers (the integrands of `work.F` and `work.dissipated`): the definition.
    pub fn rate<T: Real>(&self, y: &[T; STATE_DIM], u: &[T; LEG_COUNT]) -> ([T; STATE_DIM], LegPower<T>) {
        let state = BodyState::from_vector(y);
        let w = self.wrench(&state, u);
        let c = std::array::from_fn::<_, 3, _>(|a| state.e[a].cross(&state.e_dot[a]).dot(&w.moment));
        // `F.v + L.omega` with the inertial angular velocity `omega = 1/2 sum_a e_a x e_a'`.
        let power =
            LegPower { actuator: w.force.dot(&state.v) + (c[0] + c[1] + c[2]) * 0.5, dissipation: w.stop.dissipation };
        let (a, e_dd) = self.body.accelerations(&state, &(w.force + w.stop.force), &(w.moment + w.stop.moment));
        let mut dy = [T::zero(); STATE_DIM];
        let rates = [state.v, a, state.e_dot[0], state.e_dot[1], state.e_dot[2], e_dd[0], e_dd[1], e_dd[2]];
        for (i, v) in rates.iter().enumerate() {
            dy[3 * i..3 * i + 3].copy_from_slice(v.as_slice());
        }
        (dy, power)
    }

    /// The legs' resultant about the centre of mass for actuator forces `u`, actuators and
    /// stops apart, leg by leg and summed in [`sum_over_legs`]'s order. A collapsed (or
    /// non-finite) leg carries nothing.
    fn wrench<T: Real>(&self, state: &BodyState<T>, u: &[T; LEG_COUNT]) -> LegWrench<T> {
        let legs = LegGeometry::new(&self.stand, state);
        let zero = Vector3::zeros();
        let (mut f, mut m, mut fs, mut ms) =
            ([zero; LEG_COUNT], [zero; LEG_COUNT], [zero; LEG_COUNT], [zero; LEG_COUNT]);
        let mut dissipation = T::zero();
        for k in 0..LEG_COUNT {
            let (arm, leg, l) = (legs.arm[k], legs.leg[k], legs.length[k]);
            if !(l > T::zero()) {
                continue;
            }
            f[k] = leg * (u[k] / l);
            m[k] = arm.cross(&f[k]);
            if let Some(stops) = &self.stops
                && stops.is_outside(k, l.value())
            {
                let n = leg * (T::one() / l);
                let ldot = n.dot(&(state.v + state.body_vector_rate(&self.stand.platform_joints[k])));
                let contact = stops.contact(k, l, ldot);
                fs[k] = n * contact.force;
                ms[k] = arm.cross(&fs[k]);
                dissipation += contact.dissipation;
            }
        }
        LegWrench {
            force: sum_vectors(&f),
            moment: sum_vectors(&m),
            stop: StopWrench { force: sum_vectors(&fs), moment: sum_vectors(&ms), dissipation },
        }
    }

    /// Directional derivative (Jacobian-vector product) of [`SpecialForm::rate`]: the change
    /// of `dy/dt` and of the leg powers for a change `dy` of the state and `du` of the forces,
    /// exact (the definition evaluated on duals), for `fmi2GetDirectionalDerivative` and
    /// linearisation.
    pub fn derivative_tangent(
        &self,
        y: &StateVector,
        u: &[f64; LEG_COUNT],
        dy: &StateVector,
        du: &[f64; LEG_COUNT],
    ) -> (StateVector, LegPower) {
        let (rate, power) = self.rate(&Dual::seeded(y, dy), &Dual::seeded(u, du));
        (Dual::tangents(&rate), LegPower { actuator: power.actuator.eps, dissipation: power.dissipation.eps })
    }

    /// The right-hand side `dy/dt` for leg forces given by `law` at time `t`, end stops
    /// included, and the leg powers: [`SpecialForm::rate`]'s numbers, computed in vector
    /// registers (the step's fast path).
    #[inline(always)]
    pub fn derivative<L: LegForceLaw + ?Sized>(
        &self,
        t: f64,
        y: &StateVector,
        law: &L,
        dy: &mut StateVector,
    ) -> LegPower {
        self.derivative_in::<L, Narrow>(t, y, law, dy)
    }

    /// [`SpecialForm::derivative`] in lanes `V` (see [`Lanes`]): the same bits in each.
    #[inline(always)]
    pub(crate) fn derivative_in<L: LegForceLaw + ?Sized, V: Lanes>(
        &self,
        t: f64,
        y: &StateVector,
        law: &L,
        dy: &mut StateVector,
    ) -> LegPower {
        let state = BodyState::from_vector(y);
        let u = if law.depends_on_state() {
            law.leg_forces(t, &state, &LegGeometry::new(&self.stand, &state))
        } else {
            law.leg_forces_at(t)
        };
        let w = self.wrench_in::<V>(&state, &u);
        let (e, e_dot) = (AxisRows::<V::Axes>::of(&state.e), AxisRows::of(&state.e_dot));
        let power = LegPower {
            actuator: w.force.dot(&state.v) + e.cross_sum_dot(&e_dot, &w.moment) * 0.5,
            dissipation: w.stop.dissipation,
        };
        let (a, e_dd) =
            self.body.accelerations_in(&state, &e, &e_dot, &(w.force + w.stop.force), &(w.moment + w.stop.moment));
        // One array written whole, not piece by piece: the method reads it back at once in
        // wide loads, which a load spanning several smaller stores would stall.
        let [e1, e2, e3] = e_dd;
        let [d1, d2, d3, d4, d5, d6, d7, d8, d9] = *axes_rates(y);
        *dy = [
            state.v.x, state.v.y, state.v.z, a.x, a.y, a.z, d1, d2, d3, d4, d5, d6, d7, d8, d9, e1.x, e1.y, e1.z, e2.x,
            e2.y, e2.z, e3.x, e3.y, e3.z,
        ];
        power
    }

    /// [`SpecialForm::wrench`] with the six legs side by side. The end stops' forces are
    /// computed only when a leg is outside its stroke, by the one contact law leg by leg.
    #[inline(always)]
    fn wrench_in<V: Lanes>(&self, state: &BodyState, u: &[f64; LEG_COUNT]) -> LegWrench {
        let LegLanes { arm, leg, length } = self.joints.legs::<V>(state);
        let scale = length.where_positive(PerLeg::new(u) / length);
        let f = components!(|c| leg[c] * scale);
        let moment = PerLeg::cross(&arm, &f);
        let touches = length.any_outside(PerLeg::new(&self.stroke[0]), PerLeg::new(&self.stroke[1]));
        let stop = match &self.stops {
            Some(stops) if touches => {
                // Contact is rare: keep the hot path's registers for the free motion.
                std::hint::cold_path();
                self.stop_wrench_in(stops, state, &arm, &leg, length)
            }
            _ => StopWrench::default(),
        };
        LegWrench {
            force: Vector3::new(f[0].sum(), f[1].sum(), f[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            stop,
        }
    }

    /// The end stops' forces ([`EndStops::contact`], leg by leg) on the legs given side by side.
    #[inline(always)]
    fn stop_wrench_in<V: Lanes>(
        &self,
        stops: &EndStops,
        state: &BodyState,
        arm: &[PerLeg<V>; 3],
        leg: &[PerLeg<V>; 3],
        length: PerLeg<V>,
    ) -> StopWrench {
        let (n, ldot) = self.joints.directions_and_rates(state, leg, length, PerLeg::splat(1.0) / length);
        let (l, ldot) = (length.to_array(), ldot.to_array());
        let mut force = [0.0; LEG_COUNT];
        let mut dissipation = 0.0;
        for k in 0..LEG_COUNT {
            if l[k] > 0.0 && stops.is_outside(k, l[k]) {
                let contact = stops.contact(k, l[k], ldot[k]);
                force[k] = contact.force;
                dissipation += contact.dissipation;
            }
        }
        let force = PerLeg::new(&force);
        let fs = components!(|c| n[c] * force);
        let moment = PerLeg::cross(arm, &fs);
        StopWrench {
            force: Vector3::new(fs[0].sum(), fs[1].sum(), fs[2].sum()),
            moment: Vector3::new(moment[0].sum(), moment[1].sum(), moment[2].sum()),
            dissipation,
        }
    }
}

/// The powers of a right-hand-side evaluation (or their changes, from
/// [`SpecialForm::derivative_tangent`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LegPower<T = f64> {
    /// Power of the actuator forces, `sum_k F_k ldot_k = F.v + L.omega`, W.
    pub actuator: T,
    /// Power taken by the end stops' damping, W (>= 0).
    pub dissipation: T,
}

/// Resultant of the legs about the centre of mass: actuators and end stops apart.
#[derive(Clone, Copy, Debug, Default)]
struct LegWrench<T: nalgebra::Scalar = f64> {
    force: Vector3<T>,
    moment: Vector3<T>,
    stop: StopWrench<T>,
}

/// Resultant of the end stops' forces and the power their damping takes.
#[derive(Clone, Copy, Debug, Default)]
struct StopWrench<T: nalgebra::Scalar = f64> {
    force: Vector3<T>,
    moment: Vector3<T>,
    dissipation: T,
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::physics::actuators::HeldForces;
    use crate::physics::body::kinematics::rotation_from_angles;
    use crate::physics::legs::end_stops::EndStops;
    use crate::physics::legs::per_leg::Wide;

    /// The same held forces seen as a law that depends on the state (through `LegGeometry`).
    struct ThroughGeometry(HeldForces);

    impl LegForceLaw for ThroughGeometry {
        fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
            self.0.leg_forces_at(t)
        }
    }

    /// The fast path is the definition to the bit: legs and axes side by side in SSE2 (and,
    /// where the processor has it, AVX) registers against [`SpecialForm::rate`] leg by leg,
    /// inside the strokes and deep in both stops, with and without Baumgarte terms, for held
    /// forces and for a law that depends on the state.
    #[test]
    fn the_fast_path_gives_the_bits_of_the_definition() {
        let stand = Stand::truck_cabin();
        let stops = EndStops::default();
        let law = HeldForces { value: [5900.0, -1200.0, 8000.0, 0.0, 3.5e4, 6100.0], slope: [10.0; 6], t0: 0.0 };
        let mut contacts = 0;
        for rate in [0.0, 10.0] {
            let form = SpecialForm::new(stand.clone()).with_end_stops(Some(stops)).with_baumgarte_rate(rate);
            for (dz, roll, w) in [(0.0, 0.0, 0.0), (0.02, 0.05, 0.3), (-0.45, 0.1, -1.0), (0.45, -0.2, 2.0)] {
                let state = BodyState::from_pose(
                    Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, dz),
                    Vector3::new(0.1, -0.3, 0.7),
                    &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
                    &Vector3::new(w, 0.2, -0.1),
                );
                let mut y = state.to_vector();
                y[10] += 1e-4; // off the constraint manifold: the Baumgarte terms act
                let legs = LegGeometry::new(&stand, &BodyState::from_vector(&y));
                contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
                let (reference, p) = form.rate(&y, &law.leg_forces_at(0.3));
                let bits = |x: &[f64; 24]| x.map(f64::to_bits);
                for held in [true, false] {
                    let mut fast = [0.0; 24];
                    let q = if held {
                        form.derivative(0.3, &y, &law, &mut fast)
                    } else {
                        form.derivative(0.3, &y, &ThroughGeometry(law), &mut fast)
                    };
                    assert_eq!(bits(&fast), bits(&reference), "dz = {dz}, Baumgarte {rate}, held {held}");
                    assert_eq!(
                        (q.actuator.to_bits(), q.dissipation.to_bits()),
                        (p.actuator.to_bits(), p.dissipation.to_bits())
                    );
                }
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let mut wide = [0.0; 24];
                    // SAFETY: AVX2 detected just now.
                    let q = unsafe { wide_derivative(&form, &y, &law, &mut wide) };
                    assert_eq!(bits(&wide), bits(&reference), "AVX: dz = {dz}, Baumgarte {rate}");
                    assert_eq!(q, p);
                }
            }
        }
        assert!(contacts >= 12, "the end-stop branch was exercised ({contacts} legs in contact)");
    }

    /// # Safety
    /// AVX2 must be available.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma")]
    unsafe fn wide_derivative(form: &SpecialForm, y: &StateVector, law: &HeldForces, dy: &mut StateVector) -> LegPower {
        form.derivative_in::<HeldForces, Wide>(0.3, y, law, dy)
    }
}
