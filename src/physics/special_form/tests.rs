use nalgebra::Vector3;

use super::*;
use crate::physics::actuators::HeldForces;
use crate::physics::body::kinematics::rotation_from_angles;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::legs::{bodies::LegBodies, friction::Friction, joint_limits::JointLimits};
use crate::simd::Wide;

/// The states the fast paths are checked in: the neutral pose, and deep in the lower and the
/// upper stops, each moving and tilted, and each slightly off the constraint manifold (so that
/// Baumgarte terms, where on, act).
fn test_states() -> impl Iterator<Item = StateVector> {
    [(0.0, 0.0, 0.0), (0.02, 0.05, 0.3), (-0.45, 0.1, -1.0), (0.45, -0.2, 2.0)].into_iter().map(|(dz, roll, w)| {
        let state = BodyState::from_pose(
            Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, dz),
            Vector3::new(0.1, -0.3, 0.7),
            &rotation_from_angles(&Vector3::new(roll, -0.04, 0.02)),
            &Vector3::new(w, 0.2, -0.1),
        );
        let mut y = state.to_vector();
        y[10] += 1e-4;
        y
    })
}

/// The same held forces seen as a law that depends on the state (through `LegGeometry`).
struct ThroughGeometry(HeldForces);

impl LegForceLaw for ThroughGeometry {
    fn leg_forces(&self, t: f64, _state: &BodyState, _legs: &LegGeometry) -> [f64; LEG_COUNT] {
        self.0.leg_forces_at(t)
    }
}

/// The fast path is the definition to the bit: legs and axes side by side in SSE2 (and,
/// where the processor has it, AVX) registers against [`SpecialForm::rate`] leg by leg,
/// inside the strokes and deep in both stops, on and beyond the joint limits, with and
/// without Baumgarte terms, for held forces and for a law that depends on the state.
#[test]
fn the_fast_path_gives_the_bits_of_the_definition() {
    let stand = Stand::truck_cabin();
    let stops = EndStops::default();
    let law = HeldForces { value: [5900.0, -1200.0, 8000.0, 0.0, 3.5e4, 6100.0], slope: [10.0; 6], t0: 0.0 };
    let mut contacts = 0;
    let r0 = Stand::truck_cabin_neutral_position();
    let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
    let mut joint_contacts = 0;
    for (rate, joints) in [(0.0, None), (10.0, None), (0.0, Some(limits)), (10.0, Some(limits))] {
        let form = SpecialForm::new(stand.clone()).with_end_stops(Some(stops)).with_baumgarte_rate(rate).with_machine(
            LegBodies::default(),
            Friction::default(),
            joints,
        );
        for y in test_states() {
            let legs = LegGeometry::new(&stand, &BodyState::from_vector(&y));
            contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
            joint_contacts +=
                usize::from(form.loads(&BodyState::from_vector(&y), Actuation::Forces(&[0.0; LEG_COUNT])).machine_acts);
            let (reference, p) = form.rate(&y, &law.leg_forces_at(0.3));
            let bits = |x: &[f64; 24]| x.map(f64::to_bits);
            for held in [true, false] {
                let mut fast = [0.0; 24];
                let q = if held {
                    form.derivative(0.3, &y, &law, &mut fast)
                } else {
                    form.derivative(0.3, &y, &ThroughGeometry(law), &mut fast)
                };
                assert_eq!(bits(&fast), bits(&reference), "z = {}, Baumgarte {rate}, held {held}", y[2]);
                assert_eq!(
                    (q.actuator.to_bits(), q.dissipation.to_bits()),
                    (p.actuator.to_bits(), p.dissipation.to_bits())
                );
            }
            if crate::simd::wide_testable() {
                let mut wide = [0.0; 24];
                // SAFETY: AVX2 and FMA checked just now.
                let q = unsafe { wide_derivative(&form, &y, &law, &mut wide) };
                assert_eq!(bits(&wide), bits(&reference), "AVX: z = {}, Baumgarte {rate}", y[2]);
                assert_eq!(q, p);
            }
        }
    }
    assert!(contacts >= 12, "the end-stop branch was exercised ({contacts} legs in contact)");
    assert!(joint_contacts >= 2, "the joint-limit branch was exercised ({joint_contacts} states)");
}

/// The drives' fast path is the definition (`rate_driven`) to round-off: massless legs with
/// the rotors' axial mass, on and off the end stops and the joint limits, with Baumgarte
/// terms, in SSE2 and AVX2.
#[test]
fn the_drives_fast_path_is_the_definition_to_round_off() {
    use crate::physics::actuators::drives::ElectricDrives;
    let stand = Stand::truck_cabin();
    let stops = EndStops::default();
    let r0 = Stand::truck_cabin_neutral_position();
    let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
    let currents = [18.0, -4.0, 25.0, 30.0, 11.0, 19.5];
    let voltages = [7.5, 120.0, -80.0, 0.0, 250.0, 40.0];
    let (mut worst, mut contacts, mut joint_contacts): (f64, usize, usize) = (0.0, 0, 0);
    for (rate, joints) in [(0.0, None), (10.0, Some(limits))] {
        let form = SpecialForm::new(stand.clone())
            .with_end_stops(Some(stops))
            .with_baumgarte_rate(rate)
            .with_machine(LegBodies::default(), Friction::default(), joints)
            .with_drives(Some(ElectricDrives::default()));
        assert!(form.has_driven_fast_path());
        for y in test_states() {
            let legs = LegGeometry::new(&stand, &BodyState::from_vector(&y));
            contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, legs.length[k])).count();
            joint_contacts +=
                usize::from(form.loads(&BodyState::from_vector(&y), Actuation::Forces(&[0.0; LEG_COUNT])).machine_acts);
            let (reference, power, drives) = form.rate_driven(&y, &currents, &voltages);
            let mut fast = [0.0; 24];
            let rates = form.derivative_driven_in::<Narrow>(&y, &currents, &voltages, &mut fast);
            let scale = reference.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let mut error = (0..24).map(|i| (fast[i] - reference[i]).abs()).fold(0.0, f64::max) / scale;
            let lost = power.dissipation + sum_over_legs(&drives.map(|d| d.dissipation));
            let electric = sum_over_legs(&drives.map(|d| d.electric_power));
            error = error.max((rates.dissipation - lost).abs() / lost.abs().max(1.0));
            error = error.max((rates.electric_power - electric).abs() / electric.abs().max(1.0));
            for k in 0..LEG_COUNT {
                let r = drives[k].current_rate;
                error = error.max((rates.current_rate[k] - r).abs() / r.abs().max(1.0));
            }
            if crate::simd::wide_testable() {
                let mut wide = [0.0; 24];
                // SAFETY: AVX2 and FMA checked just now.
                unsafe { wide_driven(&form, &y, &currents, &voltages, &mut wide) };
                error = error.max((0..24).map(|i| (wide[i] - reference[i]).abs()).fold(0.0, f64::max) / scale);
            }
            worst = worst.max(error);
        }
    }
    println!("drives' fast path against the definition: largest relative difference {worst:.1e}");
    assert!(worst < 1e-12, "{worst:e}");
    assert!(contacts >= 6 && joint_contacts >= 1, "contacts exercised: stops {contacts}, joints {joint_contacts}");
}

/// # Safety
/// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx,avx2,fma"))]
unsafe fn wide_driven(
    form: &SpecialForm,
    y: &StateVector,
    currents: &[f64; LEG_COUNT],
    voltages: &[f64; LEG_COUNT],
    dy: &mut StateVector,
) {
    form.derivative_driven_in::<Wide>(y, currents, voltages, dy);
}

/// # Safety
/// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx,avx2,fma"))]
unsafe fn wide_derivative(form: &SpecialForm, y: &StateVector, law: &HeldForces, dy: &mut StateVector) -> LegPower {
    form.derivative_in::<HeldForces, Wide>(0.3, y, law, dy)
}
