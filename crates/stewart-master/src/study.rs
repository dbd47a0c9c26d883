//! One run of a design study (`stewart_fmu.study`): the metrics accumulated in the loop, step
//! by step, exactly as the FMPy master (`stewart_fmu.study._execute`) computes them, so that
//! both give the same rows to the bit. Every comparison is written as Python's `max(a, b)`
//! (`b` only if `b > a`) and `min`, and a maximum over legs as NumPy's, which is NaN if any
//! element is.
//!
//! The energy residual is `|E - E(0) - (work.F + work.electric + supplied - work.compression -
//! work.dissipated)|` (docs/model.md §9, §10, §10b) with `supplied` the hydraulic supply's
//! work: `work.pump` with the power unit (taken to be there when its line's pressure
//! `supply.linePressure` is not 0 at the start), `work.hydraulic` without. With forces every
//! term but `work.F` and `work.dissipated` is 0, and their rows keep their bits.

use crate::system::{Failure, Observer, Readings, RunSpec, System};

/// A list of watched names and, beside it, an enum whose values are their positions: each name
/// is declared once, with the identifier the metrics read it by.
macro_rules! watched {
    ($(#[$doc:meta])* $list:ident, $index:ident { $($id:ident = $name:literal,)* }) => {
        $(#[$doc])*
        pub const $list: [&str; [$($name),*].len()] = [$($name),*];
        /// Positions in the list beside it.
        #[derive(Clone, Copy)]
        #[allow(dead_code)] // the runs' later elements are read by offset from the first
        enum $index {
            $($id),*
        }
    };
}

watched!(
    /// The platform's variables a study reads after every step, in this order.
    PLATFORM_WATCHED, P {
        E = "E",
        WorkF = "work.F",
        WorkDissipated = "work.dissipated",
        Kappa = "kappa",
        R1 = "r[1]",
        R2 = "r[2]",
        R3 = "r[3]",
        Vz = "v[3]",
        Fstop1 = "Fstop[1]",
        Fstop2 = "Fstop[2]",
        Fstop3 = "Fstop[3]",
        Fstop4 = "Fstop[4]",
        Fstop5 = "Fstop[5]",
        Fstop6 = "Fstop[6]",
        L1 = "l[1]",
        L2 = "l[2]",
        L3 = "l[3]",
        L4 = "l[4]",
        L5 = "l[5]",
        L6 = "l[6]",
        WorkHydraulic = "work.hydraulic",
        WorkPump = "work.pump",
        WorkCompression = "work.compression",
        LinePressure = "supply.linePressure",
        SupplyPressure = "supply.pressure",
        WorkElectric = "work.electric",
    }
);

watched!(
    /// The controller's (closed loop), in this order.
    CONTROLLER_WATCHED, C {
        Lp1 = "lp[1]",
        Lp2 = "lp[2]",
        Lp3 = "lp[3]",
        Lp4 = "lp[4]",
        Lp5 = "lp[5]",
        Lp6 = "lp[6]",
        Rp1 = "rp[1]",
        Rp2 = "rp[2]",
        Rp3 = "rp[3]",
    }
);

/// A study run's row: status ("ok", "discard", "error"), message and metrics (NaN where the
/// run gives none).
#[derive(Clone, Debug, PartialEq)]
pub struct StudyRow {
    pub status: &'static str,
    pub message: String,
    pub discard_time: f64,
    pub max_leg_error: f64,
    pub max_pose_error: f64,
    pub min_kappa: f64,
    pub max_stop_force: f64,
    pub energy_residual: f64,
    pub peak_deceleration: f64,
    pub final_z: f64,
    /// The lowest `supply.pressure` after a step, Pa (gauge).
    pub min_supply_pressure: f64,
    /// The largest upward acceleration of the centre of mass over a step that starts at or
    /// after the scenario's event (the earliest override's time: a pump stop, a failed leg, a
    /// power loss), m/s²; NaN without one.
    pub landing_deceleration: f64,
    /// Steps completed.
    pub steps: usize,
}

/// NumPy's `np.max` of six values: NaN if any is NaN.
fn max_propagating(values: impl Iterator<Item = f64>) -> f64 {
    let mut m = f64::NEG_INFINITY;
    for x in values {
        if x.is_nan() {
            return f64::NAN;
        }
        if x > m {
            m = x;
        }
    }
    m
}

/// Python's `max(current, x)` for floats.
fn python_max(current: &mut f64, x: f64) {
    if x > *current {
        *current = x;
    }
}

struct Metrics {
    closed: bool,
    platform: Vec<u32>,
    controller: Vec<u32>,
    controller_index: usize,
    step: f64,
    e0: f64,
    leg_error: f64,
    pose_error: f64,
    stop_force: f64,
    residual: f64,
    deceleration: f64,
    kappa_min: f64,
    v_prev: Option<f64>,
    final_z: Option<f64>,
    /// The work supplied is `work.pump` (the power unit), else `work.hydraulic`.
    powered: bool,
    supply_min: f64,
    /// The scenario's event, s (infinite without one), the current step's start and the
    /// largest upward acceleration from the event on.
    event: f64,
    step_start: f64,
    landing: f64,
}

impl Observer for Metrics {
    fn watched(&self) -> Vec<Vec<u32>> {
        let mut w = vec![vec![]; self.controller_index + 1];
        w[0] = self.platform.clone();
        if self.closed {
            w[self.controller_index] = self.controller.clone();
        }
        w
    }

    fn initial(&mut self, values: &Readings) {
        let p = values.of(0);
        self.e0 = p[P::E as usize];
        self.powered = p[P::LinePressure as usize] != 0.0;
    }

    fn step(&mut self, _step: usize, time: f64, values: &Readings) {
        let p = values.of(0);
        let at = |v: P| p[v as usize];
        let (energy, work, dissipated, kappa, z, vz) =
            (at(P::E), at(P::WorkF), at(P::WorkDissipated), at(P::Kappa), at(P::R3), at(P::Vz));
        let supplied = if self.powered { at(P::WorkPump) } else { at(P::WorkHydraulic) };
        let work = work + ((at(P::WorkElectric) + supplied) - at(P::WorkCompression));
        python_max(&mut self.residual, ((energy - self.e0) - (work - dissipated)).abs());
        if at(P::SupplyPressure) < self.supply_min {
            self.supply_min = at(P::SupplyPressure);
        }
        if kappa < self.kappa_min {
            self.kappa_min = kappa;
        }
        python_max(
            &mut self.stop_force,
            max_propagating(p[P::Fstop1 as usize..=P::Fstop6 as usize].iter().map(|f| f.abs())),
        );
        if let Some(v_prev) = self.v_prev {
            python_max(&mut self.deceleration, (vz - v_prev) / self.step);
            if self.step_start >= self.event {
                python_max(&mut self.landing, (vz - v_prev) / self.step);
            }
        }
        self.step_start = time;
        self.v_prev = Some(vz);
        self.final_z = Some(z);
        if self.closed {
            let c = values.of(self.controller_index);
            python_max(
                &mut self.leg_error,
                max_propagating((0..6).map(|k| (p[P::L1 as usize + k] - c[C::Lp1 as usize + k]).abs())),
            );
            let (dx, dy, dz) =
                (at(P::R1) - c[C::Rp1 as usize], at(P::R2) - c[C::Rp2 as usize], at(P::R3) - c[C::Rp3 as usize]);
            python_max(&mut self.pose_error, (dx * dx + dy * dy + dz * dz).sqrt());
        }
    }
}

/// The value references of `names` in component `c`.
fn references(system: &System, c: usize, names: &[&str]) -> Result<Vec<u32>, String> {
    names.iter().map(|n| system.variable(c, n).map(|(vr, _)| vr)).collect()
}

/// Runs one study point on `system` (its component 0 the platform; with `controller`, that
/// component closes the loop) and returns its row.
pub fn run(system: &mut System, controller: Option<usize>, spec: &RunSpec) -> Result<StudyRow, String> {
    let platform = references(system, 0, &PLATFORM_WATCHED)?;
    let controller_refs = match controller {
        Some(c) => references(system, c, &CONTROLLER_WATCHED)?,
        None => vec![],
    };
    let mut metrics = Metrics {
        closed: controller.is_some(),
        platform,
        controller: controller_refs,
        controller_index: controller.unwrap_or(0),
        step: spec.step,
        e0: 0.0,
        leg_error: 0.0,
        pose_error: 0.0,
        stop_force: 0.0,
        residual: 0.0,
        deceleration: 0.0,
        kappa_min: f64::INFINITY,
        v_prev: None,
        final_z: None,
        powered: false,
        supply_min: f64::INFINITY,
        event: spec.overrides.iter().map(|o| o.from).fold(f64::INFINITY, f64::min),
        step_start: spec.start_time,
        landing: f64::NEG_INFINITY,
    };
    let outcome = system.run(spec, &mut metrics);
    let nan = f64::NAN;
    let mut row = StudyRow {
        status: "ok",
        message: String::new(),
        discard_time: nan,
        max_leg_error: nan,
        max_pose_error: nan,
        min_kappa: nan,
        max_stop_force: nan,
        energy_residual: nan,
        peak_deceleration: nan,
        final_z: nan,
        min_supply_pressure: nan,
        landing_deceleration: nan,
        steps: outcome.steps,
    };
    match outcome.failure {
        Some(Failure { cause, problems, initialising: true, .. }) => {
            // As the FMPy master: the last component's problem that has one, else the call.
            row.status = "error";
            row.message = problems.iter().rev().find(|p| !p.is_empty()).cloned().unwrap_or_else(|| cause.to_string());
            return Ok(row);
        }
        Some(Failure { cause, problems, terminated, .. }) => {
            let problem = problems.iter().find(|p| !p.is_empty()).cloned().unwrap_or_else(|| cause.to_string());
            let terminated = terminated[0].unwrap_or(true);
            row.status = if cause.is_discard() { "discard" } else { "error" };
            row.discard_time = outcome.time;
            row.message = problem + if terminated { "" } else { " (recoverable with shorter steps)" };
        }
        None => {}
    }
    row.max_stop_force = metrics.stop_force;
    row.energy_residual = metrics.residual;
    row.min_kappa = if metrics.kappa_min < f64::INFINITY { metrics.kappa_min } else { nan };
    row.peak_deceleration = metrics.deceleration;
    row.final_z = metrics.final_z.unwrap_or(nan);
    row.min_supply_pressure = if metrics.supply_min < f64::INFINITY { metrics.supply_min } else { nan };
    row.landing_deceleration = if metrics.landing > f64::NEG_INFINITY { metrics.landing } else { nan };
    if metrics.closed {
        row.max_leg_error = metrics.leg_error;
        row.max_pose_error = metrics.pose_error;
    }
    Ok(row)
}
