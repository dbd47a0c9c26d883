//! `TrivialPlatform`: the benchmarks' floor. The same variables as `StewartPlatform` and no
//! physics: every output copies a leg force (`output i = F[(i mod 6) + 1]`), a step only
//! advances the time. Whatever a host spends on it is the host's own cost per step.
//! Packaged for the comparison script only (`target/fmu/bench/`), not a product.

use super::platform::{PlatformModel, variables::group};
use super::snapshot::{ByteReader, ByteWriter, SnapshotError};
use super::variables::{Causality, VariableRef};
use super::{DefaultExperiment, FmuModel, ModelInfo, StepError, StepReport};
use crate::models::Initialised;

pub static INFO: ModelInfo = ModelInfo {
    model_name: "TrivialPlatform",
    model_identifier: "TrivialPlatform",
    description: "Benchmark floor: the StewartPlatform interface without physics (outputs copy the leg forces)",
    groups: super::platform::variables::GROUPS,
    enumerations: &[],
    units: super::units::UNITS,
    default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 3.0, step_size: 1e-2 },
    documentation: "<p>Benchmark floor for the performance comparison: no physics.</p>",
    states: super::platform::variables::STATES,
    // No physics: no derivatives of any kind.
    capabilities: super::Capabilities::NONE,
};

#[derive(Clone, Debug, Default)]
pub struct TrivialModel {
    /// Holds the parameters and inputs (its simulation is never built).
    pub storage: PlatformModel,
    pub time: f64,
}

impl FmuModel for TrivialModel {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }
    fn get_real(&mut self, var: VariableRef) -> f64 {
        if var.group == group::TIME {
            return self.time;
        }
        // Every value computed from the state copies a force (classified by causality).
        if let Some(g) = INFO.groups.get(var.group)
            && matches!(g.causality, Causality::Output | Causality::Local)
        {
            return self.storage.inputs.forces[var.index % 6];
        }
        self.storage.get_real(var)
    }
    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String> {
        self.storage.set_real(var, value)
    }
    fn get_integer(&mut self, var: VariableRef) -> i32 {
        self.storage.get_integer(var)
    }
    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String> {
        self.storage.set_integer(var, value)
    }
    fn get_boolean(&mut self, var: VariableRef) -> bool {
        self.storage.get_boolean(var)
    }
    fn set_boolean(&mut self, var: VariableRef, value: bool) -> Result<(), String> {
        self.storage.set_boolean(var, value)
    }
    fn exit_initialization(
        &mut self,
        start_time: f64,
        _tolerance: Option<f64>,
        _model_exchange: bool,
    ) -> Result<Initialised, String> {
        self.time = start_time;
        Ok(String::from("trivial model: no physics").into())
    }
    fn do_step(&mut self, t: f64, h: f64, _stop_at_event: bool) -> Result<StepReport, StepError> {
        self.time = t + h;
        Ok(StepReport { reached: t + h, event: false, warning: None })
    }
    fn set_input_derivative(&mut self, _var: VariableRef, _value: f64) {}
    fn output_derivative(&mut self, _var: VariableRef) -> f64 {
        0.0
    }
    fn save(&self, w: &mut ByteWriter) {
        self.storage.save(w);
        w.f64(self.time);
    }
    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError> {
        let storage = PlatformModel::restore(r)?;
        Ok(TrivialModel { storage, time: r.finite("time")? })
    }
}
