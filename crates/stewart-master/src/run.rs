//! What a run of a [`crate::System`] is given and gives back: the coupling scheme, the values
//! and their conversion to a variable's type, the overrides and input tables, the observer and
//! its readings, and how the run ended.

use crate::description::Type;
use crate::fmi2::{CallError, Value};
use crate::ssd::ParameterValue;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    GaussSeidel,
    Jacobi,
}

impl Scheme {
    pub fn parse(text: &str) -> Result<Scheme, String> {
        match text {
            "gauss-seidel" => Ok(Scheme::GaussSeidel),
            "jacobi" => Ok(Scheme::Jacobi),
            _ => Err(format!("scheme {text:?}: 'gauss-seidel' or 'jacobi'")),
        }
    }
}

/// A value given for a variable before its type is known (from Python, the command line or
/// an SSP): converted by the variable's type as FMPy's `set_values` converts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Given {
    Float(f64),
    Int(i64),
    Bool(bool),
}

impl std::fmt::Display for Given {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Given::Float(x) => write!(f, "{x:?}"),
            Given::Int(n) => write!(f, "{n}"),
            Given::Bool(b) => write!(f, "{}", if *b { "True" } else { "False" }),
        }
    }
}

impl From<&ParameterValue> for Given {
    fn from(p: &ParameterValue) -> Given {
        match *p {
            ParameterValue::Real(x) => Given::Float(x),
            ParameterValue::Integer(n) => Given::Int(n),
            ParameterValue::Boolean(b) => Given::Bool(b),
        }
    }
}

/// `given` as a value of a variable of type `kind`, or what is expected instead.
pub fn convert(kind: Type, given: Given) -> Result<Value, &'static str> {
    match kind {
        Type::Real => Ok(Value::Real(match given {
            Given::Float(x) => x,
            Given::Int(n) => n as f64,
            Given::Bool(b) => b as i32 as f64,
        })),
        Type::Integer | Type::Enumeration => match given {
            Given::Int(n) => i32::try_from(n).map(Value::Integer).map_err(|_| "an integer of 32 bits"),
            Given::Float(x) if x.is_finite() && x.trunc() == x && x.abs() < 2.2e9 => {
                i32::try_from(x as i64).map(Value::Integer).map_err(|_| "an integer of 32 bits")
            }
            _ => Err("an integer"),
        },
        Type::Boolean => match given {
            Given::Bool(b) => Ok(Value::Boolean(b)),
            Given::Int(n) if n == 0 || n == 1 => Ok(Value::Boolean(n == 1)),
            Given::Float(x) if x == 0.0 || x == 1.0 => Ok(Value::Boolean(x == 1.0)),
            _ => Err("true or false"),
        },
        Type::String => Err("a value this master can set (String variables cannot be set)"),
    }
}

/// An input set to a constant from a time on (a failed actuator, a power loss).
#[derive(Clone, Debug)]
pub struct Override {
    pub component: usize,
    pub value_reference: u32,
    pub value: f64,
    pub from: f64,
}

/// Inputs no connection drives, from a table (a vehicle's motion from a file): at each
/// communication point the values interpolated linearly between the table's times, as
/// `numpy.interp` does it (the same bits), the first row before the first time, the last after
/// the last.
#[derive(Clone, Debug)]
pub struct InputTable {
    pub component: usize,
    pub value_references: Vec<u32>,
    /// Increasing times, s.
    pub times: Vec<f64>,
    /// One column per value reference, one value per time.
    pub columns: Vec<Vec<f64>>,
}

impl InputTable {
    /// The values at `t` into `out`; `cursor` remembers where the last call found `t` (the
    /// communication points increase, so the search is a step or two).
    pub fn at(&self, t: f64, cursor: &mut usize, out: &mut Vec<f64>) {
        let n = self.times.len();
        out.clear();
        if t <= self.times[0] || n == 1 {
            out.extend(self.columns.iter().map(|c| c[0]));
            return;
        }
        if t >= self.times[n - 1] {
            out.extend(self.columns.iter().map(|c| c[n - 1]));
            return;
        }
        if *cursor >= n - 1 || self.times[*cursor] > t {
            *cursor = 0;
        }
        while self.times[*cursor + 1] <= t {
            *cursor += 1;
        }
        let j = *cursor;
        let (x0, x1) = (self.times[j], self.times[j + 1]);
        out.extend(self.columns.iter().map(|c| {
            let slope = (c[j + 1] - c[j]) / (x1 - x0);
            slope * (t - x0) + c[j]
        }));
    }

    /// Why the table cannot be used: no rows, times that do not increase, a value that is not
    /// finite.
    pub fn check(&self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("the table has no rows".into());
        }
        if self.times.iter().any(|t| !t.is_finite()) {
            return Err("a time is not a finite number".into());
        }
        if let Some(i) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "the times must increase: row {} has {} after {}",
                i + 2,
                self.times[i + 1],
                self.times[i]
            ));
        }
        for column in &self.columns {
            if let Some(i) = column.iter().position(|x| !x.is_finite()) {
                return Err(format!("row {} holds a value that is not a finite number", i + 1));
            }
        }
        Ok(())
    }
}

/// What a run reads after every step and does with it.
pub trait Observer {
    /// Per component, the Real value references to read after each step.
    fn watched(&self) -> Vec<Vec<u32>>;
    /// The watched values after initialisation.
    fn initial(&mut self, _values: &Readings) {}
    /// The watched values after step `step` (0-based), at communication point `time`.
    fn step(&mut self, step: usize, time: f64, values: &Readings);
}

/// The values read after a step: per component, a buffer whose tail holds the watched values.
pub struct Readings {
    pub(crate) buffers: Vec<Vec<f64>>,
    pub(crate) offsets: Vec<usize>,
}

impl Readings {
    /// Component `c`'s watched values, in the order its observer asked for them.
    pub fn of(&self, c: usize) -> &[f64] {
        &self.buffers[c][self.offsets[c]..]
    }
}

/// Why a run ended early.
#[derive(Clone, Debug, PartialEq)]
pub enum Cause {
    /// An FMI call returned Discard, Error or Fatal.
    Call(CallError),
    /// `fmi2Instantiate` gave no instance (the component's problem says why).
    Instantiate,
    /// The run's tables or overrides close an algebraic loop, which a Gauss-Seidel step cannot
    /// order (the first component's problem names the components).
    AlgebraicLoop,
}

impl Cause {
    /// The FMU asked for a shorter step (fmi2Discard): a discard, not an error.
    pub fn is_discard(&self) -> bool {
        matches!(self, Cause::Call(CallError { status: crate::fmi2::DISCARD, .. }))
    }
}

/// As FMPy's `FMICallException` for a failed call, so that a row's message is the same
/// whichever master ran it.
impl std::fmt::Display for Cause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Cause::Call(error) => error.fmt(f),
            Cause::Instantiate => f.write_str("fmi2Instantiate returned no instance."),
            Cause::AlgebraicLoop => f.write_str("the Gauss-Seidel order of the components: an algebraic loop."),
        }
    }
}

/// How a run ended early: why, in which component, and each component's last problem message
/// and whether it says it has terminated.
#[derive(Clone, Debug)]
pub struct Failure {
    pub component: usize,
    pub cause: Cause,
    /// Per component, the last discard/error message of this run ("" if none).
    pub problems: Vec<String>,
    /// Per component, `fmi2GetBooleanStatus(fmi2Terminated)` (None: not available).
    pub terminated: Vec<Option<bool>>,
    /// The failure came while initialising (before the first step).
    pub initialising: bool,
}

/// How a run ended.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Steps completed.
    pub steps: usize,
    /// The communication point reached: the end, or the start of the step that failed.
    pub time: f64,
    pub failure: Option<Failure>,
}

/// One run: its timing, scheme, the values set in initialisation mode (per component, after
/// the SSD's bindings) and the overrides.
#[derive(Clone, Debug)]
pub struct RunSpec {
    pub start_time: f64,
    pub step: f64,
    pub steps: usize,
    pub scheme: Scheme,
    pub values: Vec<Vec<(u32, Value)>>,
    pub overrides: Vec<Override>,
    /// Inputs from tables (none: an empty list).
    pub tables: Vec<InputTable>,
}
