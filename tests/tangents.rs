//! The exact directional derivatives (right-hand side with and without Baumgarte terms and
//! end stops, the leg powers, the outputs and `kappa`) against central finite differences at
//! random states, on and off the constraint manifold, with legs inside their strokes and in
//! contact with their lower and upper stops: relative error <= 1e-6.

use crate::common::dyn_law;
use nalgebra::Vector3;
use stewart_fmu::physics::actuators::HeldForces;
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::{BodyState, StateVector};
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::legs::geometry::LegGeometry;
use stewart_fmu::physics::special_form::SpecialForm;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::outputs::{condition_number, condition_number_tangent};
use stewart_fmu::simulation::{PlatformOutputs, SimulationState};

struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    fn vec(&mut self, scale: f64) -> Vector3<f64> {
        Vector3::new(self.uniform(), self.uniform(), self.uniform()) * scale
    }
}

fn random_case(rng: &mut Rng, off_manifold: bool) -> (StateVector, [f64; 6], StateVector, [f64; 6]) {
    let rot = rotation_from_angles(&rng.vec(0.3));
    let s =
        BodyState::from_pose(Stand::truck_cabin_neutral_position() + rng.vec(0.05), rng.vec(0.3), &rot, &rng.vec(0.8));
    let mut y = s.to_vector();
    if off_manifold {
        for x in y.iter_mut().skip(6) {
            *x += 1e-3 * rng.uniform();
        }
    }
    let u: [f64; 6] = std::array::from_fn(|_| 5900.0 * (1.0 + 0.2 * rng.uniform()));
    let dy: StateVector = std::array::from_fn(|_| rng.uniform());
    let du: [f64; 6] = std::array::from_fn(|_| 1000.0 * rng.uniform());
    (y, u, dy, du)
}

/// End stops around the state's legs: leg k inside its stroke, on its lower stop or on its
/// upper stop (3 mm in) by `k % 3` shifted by `case`.
fn stops_around(y: &StateVector, case: usize) -> EndStops {
    let stand = Stand::truck_cabin();
    let legs = LegGeometry::new(&stand, &BodyState::from_vector(y));
    let mut stops = EndStops::default();
    for k in 0..6 {
        let l = legs.length[k];
        (stops.lower[k], stops.upper[k]) = match (k + case) % 3 {
            0 => (l - 0.2, l + 0.2),
            1 => (l + 0.003, l + 0.3),
            _ => (l - 0.3, l - 0.003),
        };
    }
    // Alternate damping so that the clamp of the damper is met on some legs and not others.
    stops.damping = if case.is_multiple_of(2) { 1e5 } else { 1e7 };
    stops
}

fn extended(y: &StateVector, work: [f64; 2]) -> SimulationState {
    std::array::from_fn(|i| if i < 24 { y[i] } else { work.get(i - 24).copied().unwrap_or(0.0) })
}

fn relative_error(exact: &[f64], fd: &[f64]) -> f64 {
    let scale = exact.iter().chain(fd).map(|x| x.abs()).fold(0.0, f64::max).max(1e-12);
    exact.iter().zip(fd).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale
}

#[test]
fn right_hand_side_tangent_matches_central_differences() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut worst: f64 = 0.0;
    for case in 0..40 {
        let (y, u, dy, du) = random_case(&mut rng, case % 4 >= 2);
        let stops = (case % 8 >= 4).then(|| stops_around(&y, case));
        let mut form = SpecialForm::new(Stand::truck_cabin()).with_end_stops(stops);
        form.body.baumgarte_rate = if case % 2 == 0 { 0.0 } else { 10.0 };
        let (exact, dpower) = form.derivative_tangent(&y, &u, &dy, &du);
        let h = 1e-6;
        let eval = |sign: f64| {
            let yy: StateVector = std::array::from_fn(|i| y[i] + sign * h * dy[i]);
            let uu: [f64; 6] = std::array::from_fn(|k| u[k] + sign * h * du[k]);
            let mut f = [0.0; 24];
            let p = form.derivative(0.0, &yy, dyn_law(&HeldForces::constant(uu)), &mut f);
            let mut v = f.to_vec();
            v.extend([p.actuator / 1e4, p.dissipation / 1e4]);
            v
        };
        let (fp, fm) = (eval(1.0), eval(-1.0));
        let fd: Vec<f64> = (0..26).map(|i| (fp[i] - fm[i]) / (2.0 * h)).collect();
        let mut exact = exact.to_vec();
        exact.extend([dpower.actuator / 1e4, dpower.dissipation / 1e4]);
        let e = relative_error(&exact, &fd);
        worst = worst.max(e);
        assert!(e <= 1e-6, "case {case}: relative error {e:e}");
    }
    println!("right-hand side: max relative error of the exact tangent vs central differences: {worst:.1e}");
}

#[test]
fn output_tangent_matches_central_differences() {
    let mut rng = Rng(0x0fed_cba9_8765_4321);
    let flatten = |o: &PlatformOutputs| -> Vec<f64> {
        let mut v = vec![];
        v.extend(o.r.iter());
        v.extend(o.v.iter());
        v.extend(o.rotation.iter());
        v.extend(o.angles.iter());
        v.extend(o.w.iter());
        v.extend(o.l.iter());
        v.extend(o.ldot.iter());
        v.push(o.energy / 1e4);
        v.extend(o.stop_force.iter().map(|f| f / 1e5));
        v.push(o.work_of_forces);
        v.push(o.dissipated_energy);
        v
    };
    let mut worst: f64 = 0.0;
    for case in 0..40 {
        let (y, _, dy, _) = random_case(&mut rng, false);
        let stops = (case % 2 == 1).then(|| stops_around(&y, case));
        let form = SpecialForm::new(Stand::truck_cabin()).with_end_stops(stops);
        let (y, dy) = (extended(&y, [12.0, 3.0]), extended(&dy, [0.4, -0.7]));
        let mut exact = flatten(&PlatformOutputs::tangent(&form, &y, &dy));
        exact.push(condition_number_tangent(&form.stand, &y, &dy));
        let h = 1e-6;
        let at = |sign: f64| {
            let yy: SimulationState = std::array::from_fn(|i| y[i] + sign * h * dy[i]);
            let mut v = flatten(&PlatformOutputs::compute(&form, &yy, None));
            v.push(condition_number(&form.stand, &yy));
            v
        };
        let (p, m) = (at(1.0), at(-1.0));
        let fd: Vec<f64> = p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        assert_eq!(exact.len(), fd.len());
        let e = relative_error(&exact, &fd);
        worst = worst.max(e);
        assert!(e <= 1e-6, "case {case}: relative error {e:e}");
    }
    println!("outputs: max relative error of the exact tangent vs central differences: {worst:.1e}");
}

/// The machine's terms (legs with mass, friction, joint limits in contact) in the exact
/// derivatives of the right-hand side and of the joints' forces, against central differences.
#[test]
fn machine_tangent_matches_central_differences() {
    use nalgebra::Matrix3;
    use stewart_fmu::physics::legs::bodies::LegBodies;
    use stewart_fmu::physics::legs::friction::Friction;
    use stewart_fmu::physics::legs::joint_limits::JointLimits;
    use stewart_fmu::physics::number::Dual;
    let stand = Stand::truck_cabin();
    let r0 = Stand::truck_cabin_neutral_position();
    let n0 = std::array::from_fn(|k| (r0 + stand.platform_joints[k] - stand.base_joints[k]).normalize());
    let legs = LegBodies {
        cylinder_mass: 40.0,
        rod_mass: 15.0,
        cylinder_com: 0.45,
        rod_com: 0.55,
        cylinder_inertia: 2.5,
        rod_inertia: 0.6,
        // A drive's rotor reflected along the leg (docs/model.md §9).
        axial_mass: 120.0,
    };
    let friction = Friction { coulomb: 150.0, static_: 250.0, viscous: 800.0, ..Friction::default() };
    let mut rng = Rng(0x5eed_0000_1111_2222);
    let (mut worst, mut worst_forces, mut contacts): (f64, f64, usize) = (0.0, 0.0, 0);
    for case in 0..24 {
        let (y, u, dy, du) = random_case(&mut rng, case % 4 >= 2);
        // Limits from tight (joints in contact) to loose (none).
        let limit = [0.03, 0.08, 1.0][case % 3];
        let limits = JointLimits::new(limit, limit * 1.2, 1e6, 5e4, n0, &Matrix3::identity());
        let form = SpecialForm::new(stand.clone())
            .with_end_stops((case % 2 == 1).then(|| stops_around(&y, case)))
            .with_machine(legs, friction, Some(limits));
        let (exact, dpower) = form.derivative_tangent(&y, &u, &dy, &du);
        let h = 1e-6;
        let eval = |sign: f64| {
            let yy: StateVector = std::array::from_fn(|i| y[i] + sign * h * dy[i]);
            let uu: [f64; 6] = std::array::from_fn(|k| u[k] + sign * h * du[k]);
            let (f, p) = form.rate(&yy, &uu);
            let mut v = f.to_vec();
            v.extend([p.actuator / 1e4, p.dissipation / 1e4]);
            let forces = form.joint_forces(&yy, &uu);
            (v, forces.iter().flat_map(|f| f.iter().map(|x| x / 1e4).collect::<Vec<_>>()).collect::<Vec<_>>())
        };
        let ((fp, jp), (fm, jm)) = (eval(1.0), eval(-1.0));
        let fd: Vec<f64> = (0..26).map(|i| (fp[i] - fm[i]) / (2.0 * h)).collect();
        let mut exact = exact.to_vec();
        exact.extend([dpower.actuator / 1e4, dpower.dissipation / 1e4]);
        let e = relative_error(&exact, &fd);
        worst = worst.max(e);
        assert!(e <= 1e-6, "case {case}: relative error {e:e}");
        let forces = form.joint_forces(&Dual::seeded(&y, &dy), &Dual::seeded(&u, &du));
        let exact_forces: Vec<f64> =
            forces.iter().flat_map(|f| f.iter().map(|x| x.eps / 1e4).collect::<Vec<_>>()).collect();
        let fd_forces: Vec<f64> = jp.iter().zip(&jm).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        let e = relative_error(&exact_forces, &fd_forces);
        worst_forces = worst_forces.max(e);
        assert!(e <= 1e-6, "case {case}: joint forces' relative error {e:e}");
        contacts += usize::from(limit < 0.1);
    }
    println!(
        "machine: max relative error of the exact tangent vs central differences {worst:.1e} (right-hand side), \
         {worst_forces:.1e} (joint forces); {contacts} cases with joints in contact"
    );
}
