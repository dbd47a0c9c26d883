use nalgebra::Vector3;

use super::*;
use crate::physics::actuators::HeldForces;
use crate::physics::actuators::drives::DriveRate;
use crate::physics::body::kinematics::rotation_from_angles;
use crate::physics::legs::end_stops::EndStops;
use crate::physics::legs::{bodies::LegBodies, friction::Friction, joint_limits::JointLimits};
use crate::simd::{Plain, Wide};

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

/// The machine's fast path is the definition (`rate`, `rate_driven`) to round-off: massless
/// legs with the drives' rotors, heavy legs under given forces, heavy legs with friction and
/// drives, each on and off the end stops and the joint limits, with Baumgarte terms, in SSE2
/// and AVX2.
#[test]
fn the_machines_fast_path_is_the_definition_to_round_off() {
    use crate::physics::actuators::drives::ElectricDrives;
    let stand = Stand::truck_cabin();
    let stops = EndStops::default();
    let r0 = Stand::truck_cabin_neutral_position();
    let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
    let heavy = LegBodies {
        cylinder_mass: 40.0,
        rod_mass: 15.0,
        cylinder_inertia: 2.5,
        rod_inertia: 0.6,
        ..LegBodies::default()
    };
    let friction = Friction { coulomb: 300.0, static_: 450.0, viscous: 2000.0, ..Friction::default() };
    let forces = [5900.0, -1200.0, 8000.0, 0.0, 3.5e4, 6100.0];
    let currents = [18.0, -4.0, 25.0, 30.0, 11.0, 19.5];
    let voltages = [7.5, 120.0, -80.0, 0.0, 250.0, 40.0];
    let machines = [
        ("drives, massless legs", LegBodies::default(), Friction::default(), true),
        ("heavy legs, forces", heavy, Friction::default(), false),
        ("friction, forces", LegBodies::default(), friction, false),
        ("heavy legs, friction, drives", heavy, friction, true),
    ];
    for (name, legs, friction, driven) in machines {
        let (mut worst, mut contacts, mut joint_contacts): (f64, usize, usize) = (0.0, 0, 0);
        for (rate, joints) in [(0.0, None), (10.0, Some(limits))] {
            let form = SpecialForm::new(stand.clone())
                .with_end_stops(Some(stops))
                .with_baumgarte_rate(rate)
                .with_machine(legs, friction, joints)
                .with_drives(driven.then(ElectricDrives::default));
            // The joint limits alone, to see where they act.
            let joints_only =
                SpecialForm::new(stand.clone()).with_machine(LegBodies::default(), Friction::default(), joints);
            for y in test_states() {
                let geometry = LegGeometry::new(&stand, &BodyState::from_vector(&y));
                contacts += (0..LEG_COUNT).filter(|&k| stops.is_outside(k, geometry.length[k])).count();
                joint_contacts += usize::from(
                    joints_only.loads(&BodyState::from_vector(&y), Actuation::Forces(&[0.0; LEG_COUNT])).machine_acts,
                );
                let (reference, power, drives) = if driven {
                    form.rate_driven(&y, &currents, &voltages)
                } else {
                    let (rate, power) = form.rate(&y, &forces);
                    (rate, power, [DriveRate::zero(); LEG_COUNT])
                };
                let actuation = if driven {
                    Actuation::Drives { currents: &currents, voltages: &voltages }
                } else {
                    Actuation::Forces(&forces)
                };
                let mut fast = [0.0; 24];
                let rates = form.derivative_machine_in::<Narrow>(&y, actuation, &mut fast);
                let scale = reference.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                let relative = |a: f64, b: f64| (a - b).abs() / b.abs().max(1.0);
                let rates_error =
                    |dy: &StateVector| (0..24).map(|i| (dy[i] - reference[i]).abs()).fold(0.0, f64::max) / scale;
                let mut errors = vec![
                    ("rates", rates_error(&fast)),
                    ("dissipation", relative(rates.power.dissipation, power.dissipation)),
                    ("actuator power", if driven { 0.0 } else { relative(rates.power.actuator, power.actuator) }),
                    ("drive losses", relative(rates.drive_dissipation, sum_over_legs(&drives.map(|d| d.dissipation)))),
                    (
                        "electric power",
                        relative(rates.electric_power, sum_over_legs(&drives.map(|d| d.electric_power))),
                    ),
                ];
                for k in 0..LEG_COUNT {
                    errors.push(("current rate", relative(rates.current_rate[k], drives[k].current_rate)));
                }
                // Every form of the lanes gives the same bits, and the step's entry takes this path.
                let same = |dy: &StateVector, r: &MachineRates, form_name: &str| {
                    let all = |dy: &StateVector, r: &MachineRates| {
                        let mut v = dy.to_vec();
                        v.extend([r.power.actuator, r.power.dissipation, r.electric_power, r.drive_dissipation]);
                        v.extend(r.current_rate);
                        v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
                    };
                    assert_eq!(all(dy, r), all(&fast, &rates), "{name}: {form_name} against SSE2, z = {}", y[2]);
                };
                if crate::simd::wide_testable() {
                    let mut wide = [0.0; 24];
                    // SAFETY: AVX2 and FMA checked just now.
                    let wide_rates = unsafe { wide_machine(&form, &y, actuation, &mut wide) };
                    same(&wide, &wide_rates, "AVX2");
                }
                if !driven {
                    let mut entry = [0.0; 24];
                    let power = form.derivative(0.3, &y, &HeldForces::constant(forces), &mut entry);
                    same(&entry, &MachineRates { power, ..rates }, "SpecialForm::derivative");
                }
                for (what, error) in errors {
                    assert!(error < 1e-12, "{name}, {what}: {error:e} at z = {}, Baumgarte {rate}", y[2]);
                    worst = worst.max(error);
                }
            }
        }
        println!("{name}: the machine's fast path against the definition, largest relative difference {worst:.1e}");
        assert!(
            contacts >= 6 && joint_contacts >= 1,
            "{name}: contacts exercised: stops {contacts}, joints {joint_contacts}"
        );
    }
}

/// # Safety
/// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx,avx2,fma"))]
unsafe fn wide_machine(
    form: &SpecialForm,
    y: &StateVector,
    actuation: Actuation<'_, f64>,
    dy: &mut StateVector,
) -> MachineRates {
    form.derivative_machine_in::<Wide>(y, actuation, dy)
}

/// # Safety
/// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx,avx2,fma"))]
unsafe fn wide_derivative(form: &SpecialForm, y: &StateVector, law: &HeldForces, dy: &mut StateVector) -> LegPower {
    form.derivative_in::<HeldForces, Wide>(0.3, y, law, dy)
}

/// The joint limits' switching functions are the cosines of the joints' angles less the
/// limits' (each angle from the leg and the joint's reference axis, written out here), and
/// every register width gives the same bits.
#[test]
fn the_joint_margins_are_the_joint_angles_in_every_width() {
    let stand = Stand::truck_cabin();
    let r0 = Stand::truck_cabin_neutral_position();
    let n0: [Vector3<f64>; LEG_COUNT] =
        std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    let rotation0 = rotation_from_angles(&Vector3::new(0.02, -0.01, 0.03));
    let limits = JointLimits::new(0.1, 0.15, 1e6, 5e4, n0, &rotation0);
    let form = SpecialForm::new(stand.clone()).with_machine(LegBodies::default(), Friction::default(), Some(limits));
    for y in test_states() {
        let state = BodyState::from_vector(&y);
        let legs = form.joints.kinematics(&state);
        let margins = |f: &dyn Fn(&mut [f64; LEG_COUNT], &mut [f64; LEG_COUNT])| {
            let (mut base, mut platform) = ([0.0; LEG_COUNT], [0.0; LEG_COUNT]);
            f(&mut base, &mut platform);
            (base.map(f64::to_bits), platform.map(f64::to_bits))
        };
        let plain = margins(&|b, p| form.joint_margins::<Plain>(&state, &legs, b, p));
        assert_eq!(margins(&|b, p| form.joint_margins::<Narrow>(&state, &legs, b, p)), plain);
        if crate::simd::wide_testable() {
            // SAFETY: AVX2 and FMA checked just now.
            assert_eq!(margins(&|b, p| unsafe { wide_joint_margins(&form, &state, &legs, b, p) }), plain);
        }
        let rotation = nalgebra::Matrix3::from_columns(&state.e);
        let geometry = LegGeometry::new(&stand, &state);
        for k in 0..LEG_COUNT {
            let direction = geometry.leg[k] / geometry.length[k];
            let cos_base = direction.dot(&n0[k]);
            // The platform joint's axis turns with the platform from its reference pose.
            let cos_platform = direction.dot(&(rotation * rotation0.transpose() * n0[k]));
            assert!((f64::from_bits(plain.0[k]) - (cos_base - maths::cos(0.1))).abs() < 1e-14, "base joint {k}");
            assert!((f64::from_bits(plain.1[k]) - (cos_platform - maths::cos(0.15))).abs() < 1e-14, "platform {k}");
        }
    }
}

/// # Safety
/// AVX2 and FMA must be available ([`crate::simd::wide_available`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx,avx2,fma"))]
unsafe fn wide_joint_margins(
    form: &SpecialForm,
    state: &BodyState,
    legs: &LegKinematics,
    base: &mut [f64; LEG_COUNT],
    platform: &mut [f64; LEG_COUNT],
) {
    form.joint_margins::<Wide>(state, legs, base, platform)
}

/// The 6x6 system of the legs' inertia as the definition makes it (each leg's terms,
/// `InertiaSums::leg_terms`, their sums, and `SpecialForm::inertia_matrix`, the one form the
/// fast path solves too) against the Newton-Euler blocks written out as matrices:
/// `[[M I + sum M_k, -sum M_k [rho_k]x], [sum [rho_k]x M_k, J_w - sum [rho_k]x M_k [rho_k]x]]`
/// with `M_k = a_k I + c_k n_k n_k^T`, for tilted axes and legs of unequal mass and inertia.
#[test]
fn the_legs_inertia_system_is_the_newton_euler_blocks() {
    use super::machine::InertiaSums;
    use nalgebra::{Matrix3, Matrix6};
    let stand = Stand::truck_cabin();
    let form = SpecialForm::new(stand.clone());
    let rotation = rotation_from_angles(&Vector3::new(0.3, -0.2, 1.1));
    let e: [Vector3<f64>; 3] = std::array::from_fn(|a| rotation.column(a).into_owned());
    let skew = |v: &Vector3<f64>| Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0);
    let j_w = (0..3).fold(Matrix3::zeros(), |m, a| m + e[a] * e[a].transpose() * stand.inertia[a]);
    // The blocks (force, moment) x (r'', omega').
    let mut blocks = [[Matrix3::identity() * stand.mass, Matrix3::zeros()], [Matrix3::zeros(), j_w]];
    let mut terms = [([0.0; 21], [0.0; 11]); LEG_COUNT];
    for k in 0..LEG_COUNT {
        let rho = rotation * stand.platform_joints[k];
        let n = (rho + Stand::truck_cabin_neutral_position() - stand.base_joints[k]).normalize();
        let (a, c) = (0.4 + 0.1 * k as f64, 55.0 + 3.0 * k as f64);
        let m_k = Matrix3::identity() * a + n * n.transpose() * c;
        let x = skew(&rho);
        blocks[0][0] += m_k;
        blocks[1][0] += x * m_k;
        blocks[0][1] -= m_k * x;
        blocks[1][1] -= x * m_k * x;
        terms[k] = InertiaSums::leg_terms(&rho, &n, c, a);
    }
    let sums = InertiaSums::over_legs(&terms);
    let reference = Matrix6::from_fn(|r, col| blocks[r / 3][col / 3][(r % 3, col % 3)]);
    let matrix = form.inertia_matrix(&e, &sums);
    assert!((reference - reference.transpose()).amax() < 1e-9 * reference.amax(), "the blocks are symmetric");
    let mut worst: f64 = 0.0;
    for r in 0..6 {
        for col in 0..=r {
            worst = worst.max((matrix[r][col] - reference[(r, col)]).abs() / reference.amax());
        }
        for col in r + 1..6 {
            assert_eq!(matrix[r][col], 0.0, "the lower triangle only");
        }
    }
    assert!(worst < 1e-14, "the 6x6 system differs from the Newton-Euler blocks by {worst:e} relative");
}
