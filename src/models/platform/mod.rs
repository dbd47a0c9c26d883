//! The `StewartPlatform` model: the stand's parameters and initial pose as FMI parameters,
//! the six leg forces as inputs, the pose, legs and energy as outputs (SPEC §3).

pub mod variables;

use nalgebra::Vector3;

use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::VariableRef;
use super::{DefaultExperiment, FmuModel, ModelInfo, StepError};
use crate::integration::dopri5::Dopri5Memory;
use crate::integration::{Integrator, IntegratorStats, Method, SolverSettings};
use crate::physics::body_state::{BodyState, STATE_DIM, StateVector, layout};
use crate::physics::configuration::ConfigurationGuard;
use crate::physics::forces::HeldForces;
use crate::physics::kinematics::rotation_from_angles;
use crate::physics::special_form::SpecialForm;
use crate::physics::stand::{LEG_COUNT, PAPER_EQUILIBRIUM_LEG_FORCE, Stand};
use crate::simulation::{PlatformOutputs, PlatformSimulation, Stabilisation};
use variables::group;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "StewartPlatform",
    model_identifier: "StewartPlatform",
    description: "Loaded Stewart platform (hexapod): rigid-body dynamics in the special form of Zegzhda, Petrova and \
                  Yushkov (2020), six axial leg forces in, pose and leg lengths out",
    groups: variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 3.0, step_size: 1e-2 },
    documentation: include_str!("documentation.html"),
    states: variables::STATES,
    model_exchange: true,
    directional_derivatives: true,
};

/// Everything set through parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PlatformParameters {
    pub stand: Stand,
    pub r0: Vector3<f64>,
    pub angles0: Vector3<f64>,
    pub v0: Vector3<f64>,
    pub w0: Vector3<f64>,
    pub settings: SolverSettings,
    pub stabilisation: Stabilisation,
    /// Baumgarte rate (1/s) for Model Exchange and `Stabilisation::Baumgarte`.
    pub baumgarte_rate: f64,
}

impl Default for PlatformParameters {
    /// The default stand at rest in its neutral pose (SPEC §2-3).
    fn default() -> Self {
        PlatformParameters {
            stand: Stand::truck_cabin(),
            r0: Stand::truck_cabin_neutral_position(),
            angles0: Vector3::zeros(),
            v0: Vector3::zeros(),
            w0: Vector3::zeros(),
            settings: SolverSettings::default(),
            stabilisation: Stabilisation::Projection,
            baumgarte_rate: DEFAULT_BAUMGARTE_RATE,
        }
    }
}

impl PlatformParameters {
    pub fn initial_state(&self) -> BodyState {
        BodyState::from_pose(self.r0, self.v0, &rotation_from_angles(&self.angles0), &self.w0)
    }

    fn validate_settings(&self) -> Result<(), String> {
        let s = &self.settings;
        if !(s.rel_tol > 0.0 && s.rel_tol < 1.0) {
            return Err(format!("parameter solver.relTol: must be in (0, 1), got {}", s.rel_tol));
        }
        if s.rel_tol < 1e-15 {
            return Err(format!("parameter solver.relTol: {} is below double precision (minimum 1e-15)", s.rel_tol));
        }
        if !(s.abs_tol >= 0.0) {
            return Err(format!("parameter solver.absTol: must be >= 0, got {}", s.abs_tol));
        }
        if !(s.max_step >= 0.0) {
            return Err(format!("parameter solver.maxStep: must be >= 0 s (0 = no limit), got {}", s.max_step));
        }
        if !(s.fixed_step >= 0.0) {
            return Err(format!(
                "parameter solver.fixedStep: must be >= 0 s (0 = one step per communication step), got {}",
                s.fixed_step
            ));
        }
        if !(self.baumgarte_rate >= 0.0) {
            return Err(format!("parameter solver.baumgarteRate: must be >= 0 1/s, got {}", self.baumgarte_rate));
        }
        Ok(())
    }
}

/// Default Baumgarte rate, 1/s: the constraint residual decays with a 0.1 s time constant,
/// faster than the stand's own motion (sqrt(R_b/g) = 0.39 s) and slow enough not to make the
/// equations stiff for an explicit integrator at millisecond steps.
pub const DEFAULT_BAUMGARTE_RATE: f64 = 10.0;

/// Default leg force input: the paper's equilibrium force `0.2005 M g` of the default stand.
pub fn default_leg_force() -> f64 {
    let s = Stand::truck_cabin();
    PAPER_EQUILIBRIUM_LEG_FORCE * s.mass * s.gravity
}

/// The platform FMU model.
#[derive(Clone, Debug, PartialEq)]
pub struct PlatformModel {
    pub parameters: PlatformParameters,
    /// Leg forces `F[k]`, N.
    pub forces: [f64; LEG_COUNT],
    /// Their time derivatives for the next step, N/s (cleared after each step).
    pub force_rates: [f64; LEG_COUNT],
    /// Present after `fmi2ExitInitializationMode`.
    pub simulation: Option<PlatformSimulation>,
    /// Outputs of the current state, computed on the first read after a change.
    outputs: Option<PlatformOutputs>,
}

impl Default for PlatformModel {
    fn default() -> Self {
        PlatformModel {
            parameters: PlatformParameters::default(),
            forces: [default_leg_force(); LEG_COUNT],
            force_rates: [0.0; LEG_COUNT],
            simulation: None,
            outputs: None,
        }
    }
}

impl PlatformModel {
    /// The outputs of the current state, computed on the first read after a change.
    fn outputs(&mut self) -> &PlatformOutputs {
        let (simulation, parameters) = (&self.simulation, &self.parameters);
        self.outputs.get_or_insert_with(|| match simulation {
            Some(sim) => PlatformOutputs::compute(sim.stand(), &sim.body_state()),
            None => PlatformOutputs::compute(&parameters.stand, &parameters.initial_state()),
        })
    }

    fn held_forces(&self, t0: f64) -> HeldForces {
        HeldForces { value: self.forces, slope: self.force_rates, t0 }
    }

    fn parameter_slot(&mut self, var: VariableRef) -> Option<&mut f64> {
        let p = &mut self.parameters;
        let i = var.index;
        Some(match var.group {
            group::M => &mut p.stand.mass,
            group::J => p.stand.inertia.get_mut(i)?,
            group::G => &mut p.stand.gravity,
            group::B => p.stand.base_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::A => p.stand.platform_joints.get_mut(i / 3)?.get_mut(i % 3)?,
            group::R0 => p.r0.get_mut(i)?,
            group::ANGLES0 => p.angles0.get_mut(i)?,
            group::V0 => p.v0.get_mut(i)?,
            group::W0 => p.w0.get_mut(i)?,
            group::REL_TOL => &mut p.settings.rel_tol,
            group::ABS_TOL => &mut p.settings.abs_tol,
            group::MAX_STEP => &mut p.settings.max_step,
            group::FIXED_STEP => &mut p.settings.fixed_step,
            group::BAUMGARTE_RATE => &mut p.baumgarte_rate,
            group::F => self.forces.get_mut(i)?,
            _ => return None,
        })
    }

    /// Runs `f` with the special form and the state the model is at: the simulation's, or
    /// before initialisation the one the parameters describe.
    fn with_current<R>(&self, f: impl FnOnce(&SpecialForm, &StateVector, f64) -> R) -> R {
        match &self.simulation {
            Some(sim) => f(&sim.form, &sim.state, sim.time),
            None => {
                f(&SpecialForm::new(self.parameters.stand.clone()), &self.parameters.initial_state().to_vector(), 0.0)
            }
        }
    }

    /// `der(v)`, `der(R)`, `der(R,2)`: the derivative variables of Model Exchange.
    fn derivative_value(&self, var: VariableRef) -> f64 {
        let forces = self.forces;
        self.with_current(|form, y, t| {
            let mut dy = [0.0; STATE_DIM];
            form.derivative(t, y, &HeldForces::constant(forces), &mut dy);
            match var.group {
                group::DER_V => dy.get(layout::V + var.index).copied().unwrap_or(f64::NAN),
                group::DER_R => y.get(rotation_state_index(layout::E_DOT, var.index)).copied().unwrap_or(f64::NAN),
                _ => dy.get(rotation_state_index(layout::E_DOT, var.index)).copied().unwrap_or(f64::NAN),
            }
        })
    }

    fn output_value(o: &PlatformOutputs, var: VariableRef) -> f64 {
        let i = var.index;
        let pick3 = |v: &Vector3<f64>| v.get(i).copied().unwrap_or(0.0);
        let pick6 = |v: &[f64; LEG_COUNT]| v.get(i).copied().unwrap_or(0.0);
        match var.group {
            group::R => pick3(&o.r),
            group::V => pick3(&o.v),
            // R[a,b], row-major index a*3+b.
            group::ROT => o.rotation.get((i / 3, i % 3)).copied().unwrap_or(0.0),
            group::ANGLES => pick3(&o.angles),
            group::W => pick3(&o.w),
            group::L => pick6(&o.l),
            group::LDOT => pick6(&o.ldot),
            group::E => o.energy,
            group::CONSTRAINT_ERROR => o.constraint_error,
            _ => 0.0,
        }
    }
}

impl FmuModel for PlatformModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }

    fn get_real(&mut self, var: VariableRef) -> f64 {
        if var.group == group::TIME {
            return self.simulation.as_ref().map_or(0.0, |s| s.time);
        }
        match var.group {
            group::DER_V | group::DER_R | group::DER2_R => self.derivative_value(var),
            g if group::is_output_or_derivative(g) => Self::output_value(self.outputs(), var),
            _ => self.parameter_slot(var).map_or(f64::NAN, |slot| *slot),
        }
    }

    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        let slot = self.parameter_slot(var).ok_or("not a settable Real variable")?;
        *slot = value;
        if self.simulation.is_none() {
            // In Initialization Mode outputs follow the parameters.
            self.outputs = None;
        }
        Ok(())
    }

    fn get_integer(&mut self, var: VariableRef) -> i32 {
        match var.group {
            group::METHOD => self.parameters.settings.method.code(),
            group::STABILISATION => self.parameters.stabilisation.code(),
            _ => 0,
        }
    }

    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        match var.group {
            group::METHOD => {
                self.parameters.settings.method = Method::from_code(value)
                    .ok_or_else(|| format!("{value} is not a method (1 = Dormand-Prince 5(4), 2 = Runge-Kutta 4)"))?;
            }
            group::STABILISATION => {
                self.parameters.stabilisation = Stabilisation::from_code(value).ok_or_else(|| {
                    format!("{value} is not a stabilisation (1 = none, 2 = projection, 3 = Baumgarte)")
                })?;
            }
            _ => return Err("not a settable Integer variable".into()),
        }
        Ok(())
    }

    fn exit_initialization(
        &mut self,
        start_time: f64,
        tolerance: Option<f64>,
        model_exchange: bool,
    ) -> Result<String, String> {
        let mut p = self.parameters.clone();
        if let Some(tol) = tolerance {
            p.settings.rel_tol = tol;
        }
        p.validate_settings()?;
        let mut sim =
            PlatformSimulation::new(p.stand.clone(), p.initial_state(), p.settings, p.stabilisation, start_time)
                .map_err(|e| e.to_string())?;
        // Model Exchange cannot project (the host's integrator owns the state): Baumgarte
        // terms keep the constraints unless stabilisation is off.
        let baumgarte = if model_exchange {
            p.stabilisation != Stabilisation::None
        } else {
            p.stabilisation == Stabilisation::Baumgarte
        };
        sim.form.baumgarte_rate = if baumgarte { p.baumgarte_rate } else { 0.0 };
        let legs = PlatformOutputs::compute(sim.stand(), &sim.body_state()).l;
        let summary = format!(
            "initialised at t = {start_time}: M = {} kg, J = {:?} kg.m2, g = {} m/s2, leg lengths {:?} m, \
             method {:?}, relTol {:e}{}, stabilisation {:?}",
            p.stand.mass,
            p.stand.inertia,
            p.stand.gravity,
            legs,
            p.settings.method,
            p.settings.rel_tol,
            if tolerance.is_some() { " (from fmi2SetupExperiment)" } else { "" },
            if sim.form.baumgarte_rate > 0.0 {
                format!("Baumgarte {} 1/s", sim.form.baumgarte_rate)
            } else {
                format!("{:?}", p.stabilisation)
            }
        );
        self.simulation = Some(sim);
        self.outputs = None;
        Ok(summary)
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), StepError> {
        let law = self.held_forces(t);
        let Some(sim) = self.simulation.as_mut() else {
            return Err(StepError { message: "the model is not initialised".into() });
        };
        let t_end = t + h;
        let result = if t_end > sim.time { sim.advance(&law, t_end) } else { Ok(()) };
        self.force_rates = [0.0; LEG_COUNT];
        match result {
            Ok(()) => {
                self.outputs = None;
                Ok(())
            }
            Err(failure) => Err(StepError {
                message: format!("step from t = {t} to {t_end} rolled back: {failure}; leg forces {:?} N", self.forces),
            }),
        }
    }

    fn set_input_derivative(&mut self, var: VariableRef, value: f64) {
        if var.group == group::F
            && let Some(slot) = self.force_rates.get_mut(var.index)
        {
            *slot = value;
        }
    }

    fn output_derivative(&mut self, var: VariableRef) -> f64 {
        let Some(sim) = &self.simulation else {
            return 0.0;
        };
        let law = HeldForces { value: self.forces, slope: [0.0; LEG_COUNT], t0: sim.time };
        let dy = sim.derivative(&law);
        let d = PlatformOutputs::time_derivatives(sim.stand(), &sim.body_state(), &dy);
        Self::output_value(&d, var)
    }

    fn set_time(&mut self, t: f64) {
        if let Some(sim) = self.simulation.as_mut() {
            sim.time = t;
        }
    }

    fn continuous_states(&self, x: &mut [f64]) {
        if let Some(sim) = &self.simulation {
            for (xi, yi) in x.iter_mut().zip(sim.state.iter()) {
                *xi = *yi;
            }
        }
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        if let Some(sim) = self.simulation.as_mut() {
            for (yi, xi) in sim.state.iter_mut().zip(x) {
                *yi = *xi;
            }
            self.outputs = None;
        }
    }

    fn derivatives(&mut self, dx: &mut [f64]) {
        let forces = self.forces;
        let Some(sim) = &self.simulation else { return };
        let mut dy = [0.0; STATE_DIM];
        sim.form.derivative(sim.time, &sim.state, &HeldForces::constant(forces), &mut dy);
        for (d, v) in dx.iter_mut().zip(dy) {
            *d = v;
        }
    }

    fn completed_integrator_step(&mut self) -> Result<(), StepError> {
        let Some(sim) = &self.simulation else { return Ok(()) };
        let state = BodyState::from_vector(&sim.state);
        sim.guard
            .check_all(sim.stand(), &state)
            .map_err(|f| StepError { message: format!("at t = {}: {f}; the simulation cannot go on", sim.time) })
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[VariableRef],
        knowns: &[VariableRef],
        seeds: &[f64],
        out: &mut [f64],
    ) -> Result<(), String> {
        let mut dy = [0.0; STATE_DIM];
        let mut du = [0.0; LEG_COUNT];
        for (k, &seed) in knowns.iter().zip(seeds) {
            match seed_of(*k) {
                Some(Seed::State(i)) => dy[i] += seed,
                Some(Seed::Force(i)) => du[i] += seed,
                None => {
                    return Err(format!(
                        "known {} is neither a state nor an input (derivatives are with respect to r, v, R, der(R) and F)",
                        variables::GROUPS.get(k.group).map_or(String::new(), |g| g.element_name(k.index))
                    ));
                }
            }
        }
        let forces = self.forces;
        let (df, doutputs) = self.with_current(|form, y, _t| {
            let df = form.derivative_tangent(y, &forces, &dy, &du);
            let o = PlatformOutputs::tangent(&form.stand, &BodyState::from_vector(y), &BodyState::from_vector(&dy));
            (df, o)
        });
        for (value, u) in out.iter_mut().zip(unknowns) {
            *value = match u.group {
                group::DER_V => df[layout::V + u.index],
                group::DER_R => dy[rotation_state_index(layout::E_DOT, u.index)],
                group::DER2_R => df[rotation_state_index(layout::E_DOT, u.index)],
                g if group::is_output_or_derivative(g) => Self::output_value(&doutputs, *u),
                _ => {
                    return Err(format!(
                        "unknown {} is not an output, state or derivative",
                        variables::GROUPS.get(u.group).map_or(String::new(), |g| g.element_name(u.index))
                    ));
                }
            };
        }
        Ok(())
    }

    fn save(&self, w: &mut ByteWriter) {
        let p = &self.parameters;
        w.stand(&p.stand);
        for v in [&p.r0, &p.angles0, &p.v0, &p.w0] {
            w.f64s(v.as_slice());
        }
        save_settings(w, &p.settings);
        w.i32(p.stabilisation.code());
        w.f64(p.baumgarte_rate);
        w.f64s(&self.forces);
        w.f64s(&self.force_rates);
        match &self.simulation {
            None => w.bool(false),
            Some(sim) => {
                w.bool(true);
                // The stand and stabilisation equal the parameters'; the guard, integrator,
                // time and state are the simulation's own.
                w.stand(sim.stand());
                w.i32(sim.stabilisation.code());
                w.f64(sim.form.baumgarte_rate);
                save_settings(w, &sim.integrator.settings);
                w.f64(sim.integrator.dopri5.h_next);
                w.f64(sim.integrator.dopri5.err_old);
                let st = &sim.integrator.stats;
                for n in [st.accepted_steps, st.rejected_steps, st.rhs_evaluations] {
                    w.u64(n);
                }
                let g = &sim.guard;
                w.f64s(&[g.min_leg_length, g.base_plane, g.side, g.reference_determinant, g.characteristic_length]);
                w.bool(g.detect_singularities);
                w.f64(sim.time);
                w.f64s(&sim.state);
            }
        }
    }

    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let stand = r.stand()?;
        let r0 = Vector3::from(r.finite_array::<3>("r0")?);
        let angles0 = Vector3::from(r.finite_array::<3>("angles0")?);
        let v0 = Vector3::from(r.finite_array::<3>("v0")?);
        let w0 = Vector3::from(r.finite_array::<3>("w0")?);
        let settings = read_settings(r)?;
        let stabilisation = read_stabilisation(r)?;
        let baumgarte_rate = r.finite("solver.baumgarteRate")?;
        let forces = r.finite_array::<LEG_COUNT>("F")?;
        let force_rates = r.finite_array::<LEG_COUNT>("der(F)")?;
        let simulation = if r.bool()? {
            let sim_stand = r.stand()?;
            let sim_stabilisation = read_stabilisation(r)?;
            let sim_baumgarte = r.finite("Baumgarte rate")?;
            let sim_settings = read_settings(r)?;
            let dopri5 = Dopri5Memory { h_next: r.finite("h_next")?, err_old: r.finite("err_old")? };
            let stats =
                IntegratorStats { accepted_steps: r.u64()?, rejected_steps: r.u64()?, rhs_evaluations: r.u64()? };
            let [min_leg_length, base_plane, side, reference_determinant, characteristic_length] =
                r.finite_array::<5>("guard")?;
            let detect_singularities = r.bool()?;
            let guard = ConfigurationGuard {
                min_leg_length,
                base_plane,
                side,
                reference_determinant,
                characteristic_length,
                detect_singularities,
            };
            let time = r.finite("time")?;
            let state = r.finite_array::<STATE_DIM>("state")?;
            Some(PlatformSimulation {
                form: SpecialForm::new(sim_stand).with_baumgarte_rate(sim_baumgarte),
                guard,
                stabilisation: sim_stabilisation,
                integrator: Integrator { settings: sim_settings, dopri5, stats },
                time,
                state,
            })
        } else {
            None
        };
        Ok(PlatformModel {
            parameters: PlatformParameters { stand, r0, angles0, v0, w0, settings, stabilisation, baumgarte_rate },
            forces,
            force_rates,
            simulation,
            outputs: None,
        })
    }
}

/// State-vector index of element `index` of the rotation matrix `R` (row-major `R[a,b]`,
/// column `b` is `e_b`) or of `der(R)`, counted from `first`.
fn rotation_state_index(first: usize, index: usize) -> usize {
    first + 3 * (index % 3) + index / 3
}

/// Where a known of a directional derivative sits: a state component or a leg force.
enum Seed {
    State(usize),
    Force(usize),
}

fn seed_of(var: VariableRef) -> Option<Seed> {
    Some(match var.group {
        group::R => Seed::State(layout::R + var.index),
        group::V => Seed::State(layout::V + var.index),
        group::ROT => Seed::State(rotation_state_index(layout::E, var.index)),
        group::DER_R => Seed::State(rotation_state_index(layout::E_DOT, var.index)),
        group::F => Seed::Force(var.index),
        _ => return None,
    })
}

fn save_settings(w: &mut ByteWriter, s: &SolverSettings) {
    w.i32(s.method.code());
    w.f64s(&[s.rel_tol, s.abs_tol, s.max_step, s.fixed_step]);
    w.u64(s.max_steps_per_call);
}

fn read_settings(r: &mut ByteReader) -> Result<SolverSettings, SnapshotError> {
    let code = r.i32()?;
    let method = Method::from_code(code).ok_or_else(|| SnapshotError(format!("invalid integration method {code}")))?;
    let [rel_tol, abs_tol, max_step, fixed_step] = r.finite_array::<4>("solver settings")?;
    Ok(SolverSettings { method, rel_tol, abs_tol, max_step, fixed_step, max_steps_per_call: r.u64()? })
}

fn read_stabilisation(r: &mut ByteReader) -> Result<Stabilisation, SnapshotError> {
    let code = r.i32()?;
    Stabilisation::from_code(code).ok_or_else(|| SnapshotError(format!("invalid stabilisation {code}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn group_indices_match_the_table() {
        let names = [
            (group::TIME, "time"),
            (group::F, "F"),
            (group::M, "M"),
            (group::J, "J"),
            (group::G, "g"),
            (group::B, "B"),
            (group::A, "A"),
            (group::R0, "r0"),
            (group::ANGLES0, "angles0"),
            (group::V0, "v0"),
            (group::W0, "w0"),
            (group::METHOD, "solver.method"),
            (group::REL_TOL, "solver.relTol"),
            (group::ABS_TOL, "solver.absTol"),
            (group::MAX_STEP, "solver.maxStep"),
            (group::FIXED_STEP, "solver.fixedStep"),
            (group::STABILISATION, "solver.stabilisation"),
            (group::R, "r"),
            (group::V, "v"),
            (group::ROT, "R"),
            (group::ANGLES, "angles"),
            (group::W, "w"),
            (group::L, "l"),
            (group::LDOT, "ldot"),
            (group::E, "E"),
            (group::CONSTRAINT_ERROR, "constraintError"),
            (group::BAUMGARTE_RATE, "solver.baumgarteRate"),
            (group::DER_V, "der(v)"),
            (group::DER_R, "der(R)"),
            (group::DER2_R, "der2(R)"),
        ];
        assert_eq!(names.len(), variables::GROUPS.len());
        for (i, name) in names {
            assert_eq!(variables::GROUPS[i].name, name);
        }
    }
}
