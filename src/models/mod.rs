//! The FMU models in safe Rust: what each variable means, how parameters become a
//! simulation, what a co-simulation step does. Nothing here knows an FMI version: the shared
//! instance ([`crate::fmi`]) and the two C boundaries ([`crate::fmi2`], [`crate::fmi3`])
//! handle pointers, call sequences and logging and call into these.
//!
//! | module | what it holds |
//! |---|---|
//! | [`variables`] | variable groups, value references, access metadata |
//! | [`declare`] | `declare_variables!`: each variable declared once, bound to its storage |
//! | [`units`] | unit definitions |
//! | [`snapshot`] | the byte format of serialized FMU states |
//! | [`platform`] | the `StewartPlatform` model |
//! | [`controller`] | the `StewartController` model (programme, direct problem, feedback) |
//! | [`cueing`] | the `StewartCueing` model (washout and workspace limiter) |
//! | [`trivial`] | `TrivialPlatform`, the benchmarks' no-physics floor |
//!
//! One binary serves every model: `fmi2Instantiate`/`fmi3Instantiate*` pick the model by the
//! GUID or instantiation token the importer passes (each FMU's `modelDescription.xml` carries
//! its own; see [`crate::fmi::description`]).

pub mod declare;
pub mod machine;
pub mod snapshot;
pub mod units;
pub mod variables;

use snapshot::{ByteReader, ByteWriter, SnapshotError};
use variables::{EnumerationType, UnitDefinition, VariableGroup, VariableRef};

/// `<DefaultExperiment>`.
#[derive(Clone, Copy, Debug)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub step_size: f64,
}

/// Static facts about a model: identity, variables, types, units.
pub struct ModelInfo {
    pub model_name: &'static str,
    pub model_identifier: &'static str,
    pub description: &'static str,
    pub groups: &'static [VariableGroup],
    pub enumerations: &'static [EnumerationType],
    pub units: &'static [UnitDefinition],
    pub default_experiment: DefaultExperiment,
    /// Extra HTML for `documentation/index.html` (conventions, references).
    pub documentation: &'static str,
    /// The continuous states in the order of the state vector (Model Exchange): `(group
    /// name, element index)`; FMI 2's `<Derivatives>` is written in this order.
    pub states: &'static [(&'static str, usize)],
    /// What the model supports, declared in the model descriptions and enforced by the
    /// instance.
    pub capabilities: Capabilities,
}

impl ModelInfo {
    /// Where an element sits in the continuous state vector (`None`: it is not a state).
    pub fn state_index(&self, var: VariableRef) -> Option<usize> {
        let name = self.groups.get(var.group)?.name;
        self.states.iter().position(|&(g, i)| g == name && i == var.index)
    }

    /// Where the state an element of a derivative variable is the derivative of sits in the
    /// continuous state vector (`der(v)[2]`: `v[2]`'s place).
    pub fn derivative_state_index(&self, var: VariableRef) -> Option<usize> {
        let of = self.groups.get(var.group)?.derivative_of?;
        self.states.iter().position(|&(g, i)| g == of && i == var.index)
    }
}

/// A model's capabilities: written into both model descriptions, checked by the FMI layer.
#[derive(Clone, Copy, Debug)]
pub struct Capabilities {
    /// Model Exchange is implemented.
    pub model_exchange: bool,
    /// Directional derivatives (Jacobian-vector products) of outputs and derivatives.
    pub directional_derivatives: bool,
    /// Adjoint derivatives (vector-Jacobian products, FMI 3).
    pub adjoint_derivatives: bool,
    /// Co-Simulation: inputs follow their derivatives over a step (FMI 2
    /// `canInterpolateInputs`).
    pub can_interpolate_inputs: bool,
    /// Co-Simulation: highest order of exact output derivatives (0: none).
    pub max_output_derivative_order: u32,
    /// Number of event indicators (Model Exchange), and in Co-Simulation whether steps report
    /// events (FMI 3 `hasEventMode`, early return at them) when it is not 0.
    pub event_indicators: usize,
}

impl Capabilities {
    /// Co-Simulation only, no derivatives, no events: a model without dynamics of its own.
    pub const NONE: Capabilities = Capabilities {
        model_exchange: false,
        directional_derivatives: false,
        adjoint_derivatives: false,
        can_interpolate_inputs: false,
        max_output_derivative_order: 0,
        event_indicators: 0,
    };
}

/// What a completed co-simulation step did.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// The time the step reached: its end, or an earlier event where the step was asked to
    /// stop at events.
    pub reached: f64,
    /// Whether a non-smooth event (an end-stop contact onset or release) happened in the step.
    pub event: bool,
    /// A condition the host should know of (logged as a warning; the step stands).
    pub warning: Option<String>,
}

/// Why a co-simulation step could not be completed. The model is left as it was before the
/// step (rolled back).
#[derive(Clone, Debug, PartialEq)]
pub struct StepError {
    /// What happened, when and to which leg.
    pub message: String,
    /// Shorter communication steps from the same point can succeed (the limit of internal
    /// steps per call was reached); otherwise the simulation cannot go on from here.
    pub retry_shorter: bool,
}

/// A model that left Initialization Mode.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Initialised {
    /// The parameters in use, for `logEvents`.
    pub summary: String,
    /// A setting that works but is probably not what the user meant (status Warning).
    pub warning: Option<String>,
}

impl From<String> for Initialised {
    fn from(summary: String) -> Self {
        Initialised { summary, warning: None }
    }
}

/// What an event update (`fmi2NewDiscreteStates`) found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EventUpdate {
    /// The simulation must stop here, and why.
    pub terminate: Option<String>,
}

/// What the FMI layer needs from a model. Value references are already resolved to
/// [`VariableRef`]s of the right type and access rules are already checked.
pub trait FmuModel {
    fn info(&self) -> &'static ModelInfo;
    /// Any Real variable's current value (outputs computed from the current state, or in
    /// Initialization Mode from the current parameters).
    fn get_real(&mut self, var: VariableRef) -> f64;
    /// The block of the instance's value cache a Real group is read through: values computed
    /// together, at most once per change of the model, and then read by value reference with
    /// no call into the model (the fast path of `fmi2GetReal`/`fmi3GetFloat64`). `None`: read
    /// element by element through [`FmuModel::get_real`] (parameters, values that are costly
    /// or computed on request). At most [`CACHE_BLOCKS`] blocks.
    fn cache_block(&self, _group: usize) -> Option<u8> {
        None
    }
    /// Writes the current values of every element of the groups in cache block `block` into
    /// `cache` at their value references; `true` if one of them is NaN (so that reads of the
    /// block check their values for NaN only then).
    fn fill_cache(&mut self, _block: u8, _cache: &mut [f64]) -> bool {
        false
    }
    /// Stores a finite Real value of a parameter or input; may refuse a value outside the
    /// variable's domain.
    fn set_real(&mut self, var: VariableRef, value: f64) -> Result<(), String>;
    /// Stores finite values of consecutive elements of one Real group, `first` naming the
    /// first (a set of an array's elements in order, e.g. the six leg forces: the fast path
    /// of `fmi2SetReal`/`fmi3SetFloat64`). The default sets them one by one.
    fn set_real_run(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        set_one_by_one(self, first, values)
    }
    fn get_integer(&mut self, var: VariableRef) -> i32;
    fn set_integer(&mut self, var: VariableRef, value: i32) -> Result<(), String>;
    fn get_boolean(&mut self, _var: VariableRef) -> bool {
        false
    }
    fn set_boolean(&mut self, _var: VariableRef, _value: bool) -> Result<(), String> {
        Err("not a settable Boolean variable".into())
    }
    /// A String variable's value (`None`: not one).
    fn get_string(&mut self, _var: VariableRef) -> Option<String> {
        None
    }
    /// Stores a String parameter.
    fn set_string(&mut self, _var: VariableRef, _value: &str) -> Result<(), String> {
        Err("not a settable String variable".into())
    }
    /// Validates the parameters and builds the simulation at `start_time`. `tolerance` is
    /// the importer's tolerance, if defined. Returns a summary for the log and, for a usable
    /// but probably unintended setting, a warning.
    fn exit_initialization(
        &mut self,
        start_time: f64,
        tolerance: Option<f64>,
        model_exchange: bool,
    ) -> Result<Initialised, String>;
    /// Advances from the communication point `t` to exactly `t + h`, or with `stop_at_event`
    /// to the first event before it.
    fn do_step(&mut self, t: f64, h: f64, stop_at_event: bool) -> Result<StepReport, StepError>;
    /// After a successful step: describes the events met during it (contacts, singular
    /// arrangements passed), one message each, for `logEvents`.
    fn report_events(&mut self, _sink: &mut dyn FnMut(&str)) {}
    /// Whether events that only get reported (passages through singular arrangements) are
    /// wanted: the instance says so whenever it can deliver `logEvents` messages, and always
    /// in Model Exchange (the event indicators). Off, a model may skip the bookkeeping of
    /// such events; nothing that changes the motion may depend on it.
    fn set_event_reporting(&mut self, _on: bool) {}
    /// First derivative of a Real input for the next step (`fmi2SetRealInputDerivatives`).
    fn set_input_derivative(&mut self, var: VariableRef, value: f64);
    /// First time derivative of a Real output (`fmi2GetRealOutputDerivatives`).
    fn output_derivative(&mut self, var: VariableRef) -> f64;
    /// Why the outputs are not numbers now (they are NaN where the model cannot compute them),
    /// naming the parameter or input at fault; `None` if the model cannot say.
    fn undefined_reason(&self) -> Option<String> {
        None
    }
    /// Model Exchange: sets the time of the continuous states.
    fn set_time(&mut self, _t: f64) {}
    /// Model Exchange: the continuous states, in the order of `ModelInfo::states`.
    fn continuous_states(&self, _x: &mut [f64]) {}
    /// Model Exchange: replaces the continuous states (finite values, right length).
    fn set_continuous_states(&mut self, _x: &[f64]) {}
    /// Model Exchange: the state derivatives at the current time, states and inputs.
    fn derivatives(&mut self, _dx: &mut [f64]) {}
    /// Model Exchange: the event indicators (`ModelInfo::event_indicators` of them).
    fn event_indicators(&mut self, _z: &mut [f64]) {}
    /// Model Exchange: an event update at the current time and state (the event indicators'
    /// signs are taken as the new reference); messages describe what happened.
    fn event_update(&mut self, _sink: &mut dyn FnMut(&str)) -> EventUpdate {
        EventUpdate::default()
    }
    /// Model Exchange: after an accepted integrator step, whether the state is still one the
    /// motion can continue from.
    fn completed_integrator_step(&mut self) -> Result<(), StepError> {
        Ok(())
    }
    /// `dv_unknown = J dv_known` for the Jacobian of `unknowns` (outputs, states,
    /// derivatives) with respect to `knowns` (inputs, states).
    fn directional_derivative(
        &mut self,
        _unknowns: &[VariableRef],
        _knowns: &[VariableRef],
        _seeds: &[f64],
        _out: &mut [f64],
    ) -> Result<(), String> {
        Err("directional derivatives are not provided by this model".into())
    }
    /// Appends everything that determines the model's future to `w`.
    fn save(&self, w: &mut ByteWriter);
    /// Reads what [`FmuModel::save`] wrote into a fresh model.
    fn restore(r: &mut ByteReader) -> Result<Self, SnapshotError>
    where
        Self: Sized;
}

/// Largest start time, s, at which a double still resolves a microsecond (2^33 s, 272 years):
/// Unix times fit; beyond it the communication points and a controller's programme lose their
/// resolution.
pub const MAX_START_TIME: f64 = 8_589_934_592.0;

/// A start time the models can run from, or why not.
pub fn check_start_time(start_time: f64) -> Result<(), String> {
    if start_time.abs() > MAX_START_TIME {
        let resolution = start_time.abs() * f64::EPSILON;
        return Err(format!(
            "startTime {start_time:e} s: a double resolves only {resolution:e} s there, so the communication points \
             (and a controller's programme) lose their resolution; start within +-{MAX_START_TIME:e} s (272 years, \
             which includes Unix times), for example at 0"
        ));
    }
    Ok(())
}

/// [`FmuModel::set_real_run`] element by element, stopping at the first value refused.
pub fn set_one_by_one<M: FmuModel + ?Sized>(model: &mut M, first: VariableRef, values: &[f64]) -> Result<(), String> {
    for (i, &x) in values.iter().enumerate() {
        model.set_real(VariableRef { group: first.group, index: first.index + i }, x)?;
    }
    Ok(())
}

/// Most blocks a model's value cache may have (see [`FmuModel::cache_block`]).
pub const CACHE_BLOCKS: u8 = 31;

/// Every model this binary implements, each named once: its kind, its code in the
/// instantiation tokens (`crate::fmi::description`), its module (declared here; it holds the
/// model's [`ModelInfo`] `INFO`) and model type, and, marked `benchmark_floor`, one packaged
/// for the benchmarks only. [`ModelKind`] (`ALL`, `info`, `code`, `instantiate`), [`AnyModel`]
/// and the dispatch of its methods to the model follow: a new FMU is its folder and one line.
macro_rules! models {
    ($($(#[$floor:ident])? $kind:ident = $code:literal => $module:ident :: $model:ident,)*) => {
        models!(@with ($) $($(#[$floor])? $kind = $code => $module :: $model,)*);
    };
    (@with ($d:tt) $($(#[$floor:ident])? $kind:ident = $code:literal => $module:ident :: $model:ident,)*) => {
        $(pub mod $module;)*

        /// Every model this binary implements.
        pub enum AnyModel {
            $($kind(Box<$module::$model>),)*
        }

        /// The models, for instantiation by GUID and for packaging.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum ModelKind {
            $($kind,)*
        }

        impl ModelKind {
            pub const ALL: [ModelKind; 0 $(+ models!(@one $kind))*] = [$(ModelKind::$kind),*];

            /// Packaged for the benchmarks only (`target/fmu/bench/`), not a product FMU.
            pub fn is_benchmark_floor(self) -> bool {
                match self {
                    $(ModelKind::$kind => models!(@floor $($floor)?),)*
                }
            }

            pub fn info(self) -> &'static ModelInfo {
                match self {
                    $(ModelKind::$kind => &$module::INFO,)*
                }
            }

            pub fn code(self) -> u8 {
                match self {
                    $(ModelKind::$kind => $code,)*
                }
            }

            /// A model with its start values.
            pub fn instantiate(self) -> AnyModel {
                match self {
                    $(ModelKind::$kind => AnyModel::$kind(Box::default()),)*
                }
            }
        }

        macro_rules! dispatch {
            ($d self_:expr, $d m:ident => $d e:expr) => {
                match $d self_ {
                    $(AnyModel::$kind($d m) => $d e,)*
                }
            };
        }

        impl AnyModel {
            pub fn kind(&self) -> ModelKind {
                match self {
                    $(AnyModel::$kind(_) => ModelKind::$kind,)*
                }
            }

            pub fn restore(kind: ModelKind, r: &mut ByteReader) -> Result<AnyModel, SnapshotError> {
                Ok(match kind {
                    $(ModelKind::$kind => AnyModel::$kind(Box::new($module::$model::restore(r)?)),)*
                })
            }
        }
    };
    (@one $kind:ident) => { 1 };
    (@floor benchmark_floor) => { true };
    (@floor) => { false };
}

models! {
    Platform = 1 => platform::PlatformModel,
    Controller = 2 => controller::ControllerModel,
    Cueing = 4 => cueing::CueingModel,
    #[benchmark_floor]
    Trivial = 3 => trivial::TrivialModel,
}

/// `AnyModel`'s methods that forward to the model's [`FmuModel`] method of the same name and
/// signature, each named once (`shared` takes `&self`, `exclusive` `&mut self`).
macro_rules! forward_to_the_model {
    (@one shared $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?) => {
        pub fn $name(&self, $($arg: $ty),*) $(-> $ret)? {
            dispatch!(self, m => m.$name($($arg),*))
        }
    };
    (@one exclusive $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?) => {
        pub fn $name(&mut self, $($arg: $ty),*) $(-> $ret)? {
            dispatch!(self, m => m.$name($($arg),*))
        }
    };
    ($($receiver:ident fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?;)*) => {
        impl AnyModel {
            $(forward_to_the_model!(@one $receiver $name($($arg: $ty),*) $(-> $ret)?);)*
        }
    };
}

forward_to_the_model! {
    shared fn info() -> &'static ModelInfo;
    exclusive fn get_real(var: VariableRef) -> f64;
    exclusive fn set_real(var: VariableRef, value: f64) -> Result<(), String>;
    exclusive fn get_integer(var: VariableRef) -> i32;
    exclusive fn set_integer(var: VariableRef, value: i32) -> Result<(), String>;
    exclusive fn get_boolean(var: VariableRef) -> bool;
    exclusive fn set_boolean(var: VariableRef, value: bool) -> Result<(), String>;
    exclusive fn get_string(var: VariableRef) -> Option<String>;
    exclusive fn set_string(var: VariableRef, value: &str) -> Result<(), String>;
    exclusive fn report_events(sink: &mut dyn FnMut(&str));
    exclusive fn set_event_reporting(on: bool);
    exclusive fn event_indicators(z: &mut [f64]);
    exclusive fn event_update(sink: &mut dyn FnMut(&str)) -> EventUpdate;
    exclusive fn exit_initialization(start_time: f64, tolerance: Option<f64>, model_exchange: bool)
        -> Result<Initialised, String>;
    exclusive fn set_time(t: f64);
    shared fn continuous_states(x: &mut [f64]);
    exclusive fn set_continuous_states(x: &[f64]);
    exclusive fn derivatives(dx: &mut [f64]);
    exclusive fn completed_integrator_step() -> Result<(), StepError>;
    exclusive fn directional_derivative(unknowns: &[VariableRef], knowns: &[VariableRef], seeds: &[f64],
        out: &mut [f64]) -> Result<(), String>;
    exclusive fn do_step(t: f64, h: f64, stop_at_event: bool) -> Result<StepReport, StepError>;
    exclusive fn set_input_derivative(var: VariableRef, value: f64);
    exclusive fn output_derivative(var: VariableRef) -> f64;
    shared fn undefined_reason() -> Option<String>;
    shared fn save(w: &mut ByteWriter);
}

/// The methods with more than forwarding: several values in one dispatch, and the
/// platform's calls of a step's cycle first.
impl AnyModel {
    /// Sets several values, in order, stopping at the first refused (one dispatch for all).
    #[inline]
    pub fn set_reals(&mut self, values: impl Iterator<Item = (VariableRef, f64)>) -> Result<(), String> {
        dispatch!(self, m => {
            for (var, x) in values {
                m.set_real(var, x)?;
            }
            Ok(())
        })
    }
    /// (The platform's first, inline: its forces are the set of a step's cycle; the others
    /// out of its way.)
    #[inline]
    pub fn set_real_run(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        if let AnyModel::Platform(m) = self {
            return m.set_real_run(first, values);
        }
        std::hint::cold_path();
        self.set_real_run_other(first, values)
    }

    #[inline(never)]
    fn set_real_run_other(&mut self, first: VariableRef, values: &[f64]) -> Result<(), String> {
        dispatch!(self, m => m.set_real_run(first, values))
    }
    pub fn cache_block(&self, group: usize) -> Option<u8> {
        dispatch!(self, m => m.cache_block(group)).filter(|&b| b < CACHE_BLOCKS)
    }
    /// (The platform's fill first: it is the one in a step's cycle; the others out of its way.)
    #[inline]
    pub fn fill_cache(&mut self, block: u8, cache: &mut [f64]) -> bool {
        if let AnyModel::Platform(m) = self {
            return m.fill_cache(block, cache);
        }
        std::hint::cold_path();
        dispatch!(self, m => m.fill_cache(block, cache))
    }
}
