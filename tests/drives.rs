//! The electric drives of docs/model.md §9 against an independent formulation
//! (`common::machine_oracle`, written from the specification alone: the rotor as a particle of
//! mass `J_m N²` on the leg's length, the circuit integrated with the mechanics by RK4 at
//! 10 µs), their energy balance, and the fixed-step method's exponential treatment of the fast
//! armature circuit against a tight reference.

use crate::common;
use common::dyn_law;

use common::machine_oracle::{OracleDrives, OracleInputs, OracleMachine, OracleState};
use nalgebra::Vector3;
use stewart_fmu::integration::{
    CrossingLog, Integrator, LinearDecay, MAX_SWITCHING, Method, OdeSystem, SolverSettings, SwitchingKind,
};
use stewart_fmu::physics::actuators::drives::ElectricDrives;
use stewart_fmu::physics::actuators::{HeldForces, LegForceLaw};
use stewart_fmu::physics::body::kinematics::rotation_from_angles;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::error::PhysicsFault;
use stewart_fmu::physics::legs::bodies::LegBodies;
use stewart_fmu::physics::legs::end_stops::EndStops;
use stewart_fmu::physics::legs::friction::Friction;
use stewart_fmu::physics::legs::joint_limits::JointLimits;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::PlatformDynamics;
use stewart_fmu::simulation::{LegOutputs, PlatformOutputs, PlatformSimulation, SIMULATION_DIM, Stabilisation};

fn oracle_drives(d: &ElectricDrives) -> OracleDrives {
    OracleDrives {
        resistance: d.resistance,
        inductance: d.inductance,
        ke: d.ke,
        kt: d.kt,
        rotor_inertia: d.rotor_inertia,
        damping: d.damping,
        gear_ratio: d.gear_ratio,
        screw_lead: d.screw_lead,
    }
}

/// The neutral pose's holding current and voltage of each leg (the static model: massless
/// legs, the rotor's weight along the leg is nil).
fn holding(d: &ElectricDrives) -> (f64, f64) {
    let s = Stand::truck_cabin();
    d.static_current_and_voltage(0.2005 * s.mass * s.gravity, 0.0)
}

/// Voltages from the legs at a communication point: the holding voltage, a feedback on the
/// leg lengths and rates about the neutral legs through the drive's static model (the
/// default controller's gains), and a ripple that keeps the platform moving.
fn voltage_law(d: ElectricDrives, ripple: f64) -> impl Fn(f64, &[f64; 6], &[f64; 6]) -> [f64; 6] {
    let (_, u_hold) = holding(&d);
    let volts_per_newton = d.resistance / (d.transmission() * d.kt);
    let l0 = 1.7550860729486566;
    move |t, l, ldot| {
        std::array::from_fn(|k| {
            u_hold * (1.0 + ripple * (3.0 * t + k as f64).sin())
                + volts_per_newton * (2.0e5 * (l0 - l[k]) - 2.0e4 * ldot[k])
        })
    }
}

fn simulation(
    start: &BodyState,
    drives: ElectricDrives,
    currents: [f64; 6],
    settings: SolverSettings,
) -> PlatformSimulation {
    PlatformSimulation::new(Stand::truck_cabin(), *start, settings, Stabilisation::Projection, 0.0)
        .and_then(|s| s.with_end_stops(None))
        .and_then(|s| s.with_drives(Some(drives), currents))
        .expect("valid drives")
}

fn oracle_state(s: &BodyState, currents: [f64; 6]) -> OracleState {
    let rotation = s.rotation();
    OracleState {
        r: s.r.into(),
        rotation: std::array::from_fn(|a| std::array::from_fn(|b| rotation[(a, b)])),
        v: s.v.into(),
        w: s.angular_velocity_body().into(),
        currents,
        pa: [0.0; 6],
        pb: [0.0; 6],
        spool: [0.0; 6],
        spool_rate: [0.0; 6],
        supply_pressure: 0.0,
        lowest_pressure: f64::INFINITY,
    }
}

/// The largest difference of pose, velocities (m, m/s, rad/s, rotation entries) and currents
/// (in units of 100 A) between the FMU's state and the oracle's.
fn difference(sim: &PlatformSimulation, o: &OracleState) -> f64 {
    let s = sim.body_state();
    let rotation = s.rotation();
    let w = s.angular_velocity_body();
    let mut worst: f64 = 0.0;
    for a in 0..3 {
        worst = worst.max((s.r[a] - o.r[a]).abs()).max((s.v[a] - o.v[a]).abs()).max((w[a] - o.w[a]).abs());
        for b in 0..3 {
            worst = worst.max((rotation[(a, b)] - o.rotation[a][b]).abs());
        }
    }
    let currents = sim.currents();
    for k in 0..6 {
        worst = worst.max((currents[k] - o.currents[k]).abs() / 100.0);
    }
    worst
}

fn tilted_start() -> BodyState {
    BodyState::from_pose(
        Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, 0.03),
        Vector3::new(0.05, 0.02, -0.1),
        &rotation_from_angles(&Vector3::new(0.02, -0.03, 0.05)),
        &Vector3::new(0.1, -0.05, 0.2),
    )
}

/// Drives on a moving stand (massless legs, then heavy legs with friction): voltages from a
/// feedback held over 10 ms steps, starting 10 % off the holding current so that the circuit's
/// transient is in the run. The FMU's motion and currents agree with the oracle's over 3 s.
#[test]
fn drives_agree_with_the_independent_formulation() {
    let drives = ElectricDrives::default();
    let (i_hold, _) = holding(&drives);
    let heavy = LegBodies {
        cylinder_mass: 40.0,
        rod_mass: 15.0,
        cylinder_com: 0.45,
        rod_com: 0.55,
        cylinder_inertia: 2.5,
        rod_inertia: 0.6,
        axial_mass: 0.0,
    };
    let friction = Friction { coulomb: 150.0, static_: 250.0, viscous: 800.0, ..Friction::default() };
    for (name, legs, friction) in
        [("massless legs", LegBodies::default(), Friction::default()), ("heavy legs", heavy, friction)]
    {
        let oracle = OracleMachine {
            drives: Some(oracle_drives(&drives)),
            cylinder_mass: legs.cylinder_mass,
            rod_mass: legs.rod_mass,
            cylinder_com: legs.cylinder_com,
            rod_com: legs.rod_com,
            cylinder_inertia: legs.cylinder_inertia,
            rod_inertia: legs.rod_inertia,
            friction: common::machine_oracle::OracleFriction {
                coulomb: friction.coulomb,
                static_: friction.static_,
                stribeck_velocity: friction.stribeck_velocity,
                smoothing: friction.smoothing,
                viscous: friction.viscous,
            },
            ..OracleMachine::default_stand()
        };
        let law = voltage_law(drives, 0.3);
        let start = tilted_start();
        let currents = [0.9 * i_hold; 6];
        let settings = SolverSettings { method: Method::DormandPrince45, ..SolverSettings::tight() };
        let mut sim =
            simulation(&start, drives, currents, settings).with_machine(legs, friction, None).expect("valid legs");
        let mut reference = oracle_state(&start, currents);
        let (h, steps) = (0.01, 300);
        let (mut worst, mut moved, mut peak_current): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for i in 0..steps {
            let t = i as f64 * h;
            let o = LegOutputs::compute(&sim.form, &sim.state);
            sim.advance(dyn_law(&HeldForces::constant(law(t, &o.l, &o.ldot))), t + h).expect("steps");
            let u = law(t, &oracle.leg_lengths(&reference), &oracle.leg_rates(&reference));
            reference = oracle.simulate(&reference, h, 1, &|_| OracleInputs::Voltages(u))[1];
            worst = worst.max(difference(&sim, &reference));
            moved = moved.max((sim.body_state().r - start.r).norm());
            peak_current = sim.currents().iter().fold(peak_current, |m, i| m.max(i.abs()));
        }
        let _figures = common::figures::print_figures(&format!(
            "drives, {name}, 3 s at 10 ms: largest difference from the oracle {worst:.2e} (m, m/s, rad/s, 100 A); \
             moved up to {moved:.3} m, currents up to {peak_current:.1} A (holding {i_hold:.2} A)"
        ));
        assert!(worst < 1e-9, "{name}: {worst:e}");
        assert!(moved > 0.01, "{name}: the platform moved ({moved})");
    }
}

/// `E(t) - E(0) = work.F + work.electric - work.dissipated` with drives, through end-stop and
/// joint-limit contacts, for an ideal machine (`k_t = k_e`) and one with a conversion
/// mismatch; `work.F` stays 0 (the drives' forces are internal).
#[test]
fn the_drives_energy_balance_holds() {
    for kt in [1.0, 0.85] {
        let drives = ElectricDrives { kt, ..ElectricDrives::default() };
        let (i_hold, u_hold) = holding(&drives);
        let n0 = std::array::from_fn(|k| {
            let stand = Stand::truck_cabin();
            (Stand::truck_cabin_neutral_position() + stand.platform_joints[k] - stand.base_joints[k]).normalize()
        });
        let joints = JointLimits::new(0.2, 0.3, 1e6, 5e4, n0, &nalgebra::Matrix3::identity());
        let settings = SolverSettings { rel_tol: 1e-11, abs_tol: 1e-13, ..SolverSettings::default() };
        let mut sim =
            PlatformSimulation::new(Stand::truck_cabin(), tilted_start(), settings, Stabilisation::Projection, 0.0)
                .and_then(|s| s.with_end_stops(Some(EndStops::default())))
                .and_then(|s| s.with_machine(LegBodies::default(), Friction::default(), Some(joints)))
                .and_then(|s| s.with_drives(Some(drives), [i_hold; 6]))
                .expect("valid");
        let e0 = PlatformOutputs::compute(&sim.form, &sim.state, None).energy;
        let (mut worst, mut contacts, mut electric, mut dissipated) = (0.0f64, 0, 0.0, 0.0);
        for i in 0..400 {
            let t = i as f64 * 0.01;
            // Full voltage on three legs, reversed on the others: the platform rolls onto its
            // stops and joint limits; then the supply drops and the drives brake.
            let u: [f64; 6] =
                std::array::from_fn(|k| if t < 1.5 { u_hold + if k % 2 == 0 { 150.0 } else { -150.0 } } else { 0.0 });
            sim.advance(dyn_law(&HeldForces::constant(u)), t + 0.01).expect("the motion goes on");
            contacts += sim.crossings.as_slice().len();
            let o = PlatformOutputs::compute(&sim.form, &sim.state, None);
            let balance = o.energy - e0 - (o.work_of_forces + o.electric_work - o.dissipated_energy);
            worst = worst.max(balance.abs());
            assert_eq!(o.work_of_forces, 0.0);
            (electric, dissipated) = (o.electric_work, o.dissipated_energy);
        }
        let _figures = common::figures::print_figures(&format!(
            "drives, kt = {kt}: largest |E - E0 - (work.F + work.electric - work.dissipated)| = {worst:.2e} J over 4 s \
             ({contacts} contacts located; {electric:.0} J supplied, {dissipated:.0} J dissipated, E(0) = {e0:.0} J)"
        ));
        assert!(contacts >= 2, "contacts with stops or joint limits ({contacts})");
        assert!(worst < 1e-6 * dissipated, "{worst:e} J");
    }
}

/// The platform's dynamics with the exponential treatment of the circuit switched off: the
/// classical method, for comparison.
struct Classical<'a>(PlatformDynamics<'a, dyn LegForceLaw + 'a>);

impl OdeSystem<SIMULATION_DIM> for Classical<'_> {
    type Fault = PhysicsFault;
    fn derivative(&self, t: f64, y: &[f64; SIMULATION_DIM], dy: &mut [f64; SIMULATION_DIM]) {
        self.0.derivative(t, y, dy)
    }
    fn after_step(&self, y: &mut [f64; SIMULATION_DIM]) {
        self.0.after_step(y)
    }
    fn modifies_state_after_step(&self) -> bool {
        OdeSystem::<SIMULATION_DIM>::modifies_state_after_step(&self.0)
    }
    fn active_dimension(&self) -> usize {
        OdeSystem::<SIMULATION_DIM>::active_dimension(&self.0)
    }
    fn linear_decay(&self) -> Option<LinearDecay> {
        None
    }
    fn check(&self, t: f64, y: &[f64; SIMULATION_DIM]) -> Result<(), PhysicsFault> {
        self.0.check(t, y)
    }
    fn switching_count(&self) -> usize {
        OdeSystem::<SIMULATION_DIM>::switching_count(&self.0)
    }
    fn switching(&self, t: f64, y: &[f64; SIMULATION_DIM], g: &mut [f64; MAX_SWITCHING]) {
        self.0.switching(t, y, g)
    }
    fn switching_kind(&self, index: usize) -> SwitchingKind {
        OdeSystem::<SIMULATION_DIM>::switching_kind(&self.0, index)
    }
}

/// A closed loop over `seconds` at 1 ms communication steps: returns the largest leg error
/// against the programme and the final state's heave and currents; `None` if the run failed.
fn heave_in_closed_loop(
    drives: ElectricDrives,
    settings: SolverSettings,
    classical: bool,
    seconds: f64,
) -> Option<([f64; SIMULATION_DIM], f64)> {
    let (i_hold, _) = holding(&drives);
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &nalgebra::Matrix3::identity(),
        &Vector3::zeros(),
    );
    let mut sim = simulation(&start, drives, [i_hold; 6], settings);
    let law = voltage_law(drives, 0.2);
    let h = 1e-3;
    let mut peak: f64 = 0.0;
    for i in 0..(seconds / h).round() as usize {
        let t = i as f64 * h;
        let o = LegOutputs::compute(&sim.form, &sim.state);
        let held = HeldForces::constant(law(t, &o.l, &o.ldot));
        if classical {
            let system = Classical(sim.dynamics(dyn_law(&held)));
            let mut y = sim.state;
            Integrator::new(settings).integrate(&system, t, &mut y, t + h, &mut CrossingLog::default()).ok()?;
            sim.state = y;
            sim.time = t + h;
        } else {
            sim.advance(dyn_law(&held), t + h).ok()?;
        }
        if !sim.state.iter().all(|x| x.is_finite() && x.abs() < 1e6) {
            return None;
        }
        peak = peak.max(sim.currents().iter().fold(0.0, |m: f64, i| m.max(i.abs())));
    }
    Some((sim.state, peak))
}

fn state_difference(a: &[f64; SIMULATION_DIM], b: &[f64; SIMULATION_DIM]) -> (f64, f64) {
    let body = (0..24).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
    let currents = (26..32).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max);
    (body, currents)
}

/// RK4 at the default 1 ms step integrates the armature circuit exponentially: against the
/// adaptive method at relTol 1e-12 it is accurate with the default drive (`L/R` = 1 ms) and
/// stays so with a circuit ten times faster (`L/R` = 0.1 ms), where classical RK4 at the same
/// step diverges.
#[test]
fn the_fixed_step_method_integrates_the_circuit_exponentially() {
    let tight =
        SolverSettings { method: Method::DormandPrince45, rel_tol: 1e-12, abs_tol: 1e-14, ..Default::default() };
    let rk4 = SolverSettings { method: Method::RungeKutta4, fixed_step: 1e-3, ..Default::default() };
    for inductance in [0.4e-3, 0.04e-3] {
        let drives = ElectricDrives { inductance, ..ElectricDrives::default() };
        let (reference, peak) = heave_in_closed_loop(drives, tight, false, 2.0).expect("the reference runs");
        let (etd, _) = heave_in_closed_loop(drives, rk4, false, 2.0).expect("ETDRK4 runs");
        let (body, currents) = state_difference(&etd, &reference);
        let classical = heave_in_closed_loop(drives, rk4, true, 2.0);
        let classical_error = classical.map(|(y, _)| state_difference(&y, &reference));
        let _figures = common::figures::print_figures(&format!(
            "L/R = {:.1} ms, 2 s of feedback with a 20 % ripple: currents up to {peak:.1} A; RK4 at 1 ms with the \
             exponential circuit differs from the adaptive method at relTol 1e-12 by {body:.2e} (pose, velocities) and \
             {currents:.2e} A; classical RK4: {}",
            1e3 * inductance / drives.resistance,
            match classical_error {
                Some((b, c)) => format!("{b:.2e} and {c:.2e} A"),
                None => "diverged".to_string(),
            }
        ));
        assert!(body < 1e-6 && currents < 1e-3, "{body:e} {currents:e}");
        if inductance < 1e-4 {
            assert!(classical_error.is_none_or(|(b, _)| b > 1e3 * body), "classical RK4 should fail at L/R = 0.1 ms");
        }
    }
}

/// Holding: the default stand at its neutral pose on the holding voltage `R I` and current
/// stays put (the equilibrium is neutral in heave with the drives' electric damping, unstable in
/// tilt like the paper's, so round-off grows only slowly), and its currents stay the static
/// model's.
#[test]
fn the_holding_voltage_holds_the_stand() {
    let drives = ElectricDrives::default();
    let (i_hold, u_hold) = holding(&drives);
    let start = BodyState::from_pose(
        Stand::truck_cabin_neutral_position(),
        Vector3::zeros(),
        &nalgebra::Matrix3::identity(),
        &Vector3::zeros(),
    );
    let mut sim = simulation(&start, drives, [i_hold; 6], SolverSettings::default());
    sim.advance(dyn_law(&HeldForces::constant([u_hold; 6])), 2.0).expect("holds");
    let drift = (sim.body_state().r - start.r).norm();
    let current = sim.currents().iter().map(|i| (i - i_hold).abs()).fold(0.0, f64::max);
    let _figures = common::figures::print_figures(&format!(
        "holding the default stand for 2 s: {u_hold:.4} V and {i_hold:.4} A per leg, drift {drift:.2e} m, currents \
         within {current:.2e} A"
    ));
    assert!(drift < 1e-9, "{drift:e}");
    // Round-off seeds the equilibrium's slow growth; the currents follow it by their back EMF.
    assert!(current < 1e-6, "{current:e}");
}
