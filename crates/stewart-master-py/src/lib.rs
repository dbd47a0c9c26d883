//! `stewart_fmu._master`: the compiled co-simulation master (crate `stewart-master`) as a
//! Python extension module. `stewart_fmu.master` is its Python face; this module converts
//! arguments and results and keeps the loop in Rust with the GIL released.
//!
//! No panic reaches Python as one: a run that panics is reported as the run's error (a
//! study row with status "error", or `RuntimeError`), and the system's instances are freed so
//! that the next run starts from new ones.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::sync::{Arc, Mutex};

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt};
use stewart_master::record::Recorder;
use stewart_master::ssd::SystemDescription;
use stewart_master::system::convert;
use stewart_master::{Fmu, Given, Override, RunSpec, Scheme, System};

fn panic_text(payload: Box<dyn std::any::Any + Send>) -> String {
    let text = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into());
    format!("panic in the compiled master: {text}")
}

fn given(value: &Bound<'_, PyAny>, name: &str) -> PyResult<Given> {
    if value.is_instance_of::<PyBool>() {
        Ok(Given::Bool(value.extract()?))
    } else if value.is_instance_of::<PyInt>() {
        value
            .extract::<i64>()
            .map(Given::Int)
            .map_err(|_| PyValueError::new_err(format!("{name} = {value}: the integer does not fit in 64 bits")))
    } else if value.is_instance_of::<PyFloat>() {
        Ok(Given::Float(value.extract()?))
    } else {
        // NumPy scalars and other numbers: as a float if they can be one.
        value
            .extract::<f64>()
            .map(Given::Float)
            .map_err(|_| PyValueError::new_err(format!("{name} = {value}: a number or true/false is expected")))
    }
}

/// A system of FMUs: `System(fmus, ssd=None)` with `fmus` a dict of component name -> FMU
/// (a path, or the FMU file's bytes) and `ssd` the text of an SSP system description naming
/// those components (without it, the FMUs run unconnected); or `System.from_ssp(path)`.
/// Instances are made at the first run and reused (`fmi2Reset`) by the next.
#[pyclass(module = "stewart_fmu._master")]
struct PySystem {
    inner: Mutex<Option<System>>,
    names: Vec<String>,
}

/// An input table from Python: (component, times, [(input name, values)]).
type InputTableArgs = (String, Vec<f64>, Vec<(String, Vec<f64>)>);

/// A study point from Python: (steps, step, values by qualified name, overrides as (qualified
/// name, value, from time)).
type Point<'py> = (usize, f64, Vec<(String, Bound<'py, PyAny>)>, Vec<(String, f64, f64)>);

impl PySystem {
    fn wrap(system: System) -> PySystem {
        let names = system.component_names();
        PySystem { inner: Mutex::new(Some(system)), names }
    }

    /// The run's values and overrides by qualified name, checked against the system.
    #[allow(clippy::type_complexity)]
    fn spec(
        system: &System,
        values: Vec<(String, Bound<'_, PyAny>)>,
        overrides: Vec<(String, f64, f64)>,
    ) -> PyResult<(Vec<Vec<(u32, stewart_master::fmi2::Value)>>, Vec<Override>)> {
        let mut per_component = vec![vec![]; system.component_count()];
        for (name, value) in &values {
            let (c, vr, kind) = system.resolve(name).map_err(PyValueError::new_err)?;
            let v = convert(kind, given(value, name)?)
                .map_err(|expected| PyValueError::new_err(format!("{name} = {value}: {expected} is expected")))?;
            per_component[c].push((vr, v));
        }
        let mut list = vec![];
        for (name, value, from) in overrides {
            let (component, value_reference, kind) = system.resolve(&name).map_err(PyValueError::new_err)?;
            if kind != stewart_master::description::Type::Real {
                return Err(PyValueError::new_err(format!("override {name}: only Real inputs can be overridden")));
            }
            list.push(Override { component, value_reference, value, from });
        }
        Ok((per_component, list))
    }
}

#[pymethods]
impl PySystem {
    #[new]
    #[pyo3(signature = (fmus, ssd = None))]
    fn new(py: Python<'_>, fmus: Vec<(String, Bound<'_, PyAny>)>, ssd: Option<String>) -> PyResult<PySystem> {
        let description = match &ssd {
            Some(text) => Some(SystemDescription::parse(text).map_err(PyValueError::new_err)?),
            None => None,
        };
        let mut sources: Vec<(String, Result<Vec<u8>, String>)> = vec![];
        for (name, fmu) in &fmus {
            if let Ok(bytes) = fmu.cast::<PyBytes>() {
                sources.push((name.clone(), Ok(bytes.as_bytes().to_vec())));
            } else {
                let path: std::path::PathBuf = fmu.extract()?;
                sources.push((name.clone(), Err(path.to_string_lossy().into_owned())));
            }
        }
        let system = py.detach(move || -> Result<System, String> {
            let mut loaded = vec![];
            for (name, source) in sources {
                let fmu = match source {
                    Ok(bytes) => Fmu::from_bytes(&bytes, &format!("{name}.fmu"))?,
                    Err(path) => Fmu::from_path(Path::new(&path))?,
                };
                loaded.push((name, Arc::new(fmu)));
            }
            System::new(loaded, description.as_ref())
        });
        Ok(PySystem::wrap(system.map_err(PyValueError::new_err)?))
    }

    /// The system an SSP file describes, with the FMUs it carries.
    #[staticmethod]
    fn from_ssp(py: Python<'_>, path: std::path::PathBuf) -> PyResult<PySystem> {
        let (system, _) = py.detach(move || stewart_master::ssp::open(&path)).map_err(PyValueError::new_err)?;
        Ok(PySystem::wrap(system))
    }

    /// The components' names, in element order.
    #[getter]
    fn components(&self) -> Vec<String> {
        self.names.clone()
    }

    /// The variables of a component: a list of (name, type, causality).
    fn variables(&self, component: &str) -> PyResult<Vec<(String, String, String)>> {
        let guard = self.inner.lock().map_err(|_| PyRuntimeError::new_err("the system is unusable after a panic"))?;
        let system = guard.as_ref().ok_or_else(|| PyRuntimeError::new_err("the system is closed"))?;
        let c = system.component_index(component).map_err(PyValueError::new_err)?;
        Ok(system
            .fmu(c)
            .description
            .variables
            .iter()
            .map(|v| (v.name.clone(), format!("{:?}", v.kind), v.causality.clone()))
            .collect())
    }

    /// Runs `steps` communication steps of `step` from `start_time`; returns a dict: `times`
    /// and `values` (float64 bytes, row-major, one column per `record` name, every `every`-th
    /// point), `steps` done, `time` reached, `status` ("ok", "discard", "error"), `message`
    /// (the FMU's last problem), `call` (the FMI call that failed, e.g. "fmi2DoStep failed
    /// with status 2 (discard).") and `component` (its component).
    #[pyo3(signature = (steps, step, *, scheme = "gauss-seidel", start_time = 0.0,
                        values = vec![], overrides = vec![], record = vec![], every = 1, inputs = vec![]))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &self,
        py: Python<'py>,
        steps: usize,
        step: f64,
        scheme: &str,
        start_time: f64,
        values: Vec<(String, Bound<'py, PyAny>)>,
        overrides: Vec<(String, f64, f64)>,
        record: Vec<String>,
        every: usize,
        inputs: Vec<InputTableArgs>,
    ) -> PyResult<Bound<'py, PyDict>> {
        // Written so that NaN fails too.
        let good = step.is_finite() && step > 0.0 && start_time.is_finite();
        if !good {
            return Err(PyValueError::new_err(format!("step = {step}, start_time = {start_time}: finite, step > 0")));
        }
        let scheme = Scheme::parse(scheme).map_err(PyValueError::new_err)?;
        let mut guard =
            self.inner.lock().map_err(|_| PyRuntimeError::new_err("the system is unusable after a panic"))?;
        let system = guard.as_mut().ok_or_else(|| PyRuntimeError::new_err("the system is closed"))?;
        let (values, overrides) = PySystem::spec(system, values, overrides)?;
        let tables = inputs
            .into_iter()
            .map(|(component, times, columns)| system.input_table(&component, times, columns))
            .collect::<Result<Vec<_>, _>>()
            .map_err(PyValueError::new_err)?;
        let mut recorder = Recorder::new(system, &record, every).map_err(PyValueError::new_err)?;
        let spec = RunSpec { start_time, step, steps, scheme, values, overrides, tables };
        let outcome = py.detach(|| catch_unwind(AssertUnwindSafe(|| system.run(&spec, &mut recorder))));
        let outcome = match outcome {
            Ok(outcome) => outcome,
            Err(payload) => {
                system.free_instances();
                return Err(PyRuntimeError::new_err(panic_text(payload)));
            }
        };
        let d = PyDict::new(py);
        let bytes = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        d.set_item("times", PyBytes::new(py, &bytes(&recorder.times)))?;
        d.set_item("values", PyBytes::new(py, &bytes(&recorder.values)))?;
        d.set_item("steps", outcome.steps)?;
        d.set_item("time", outcome.time)?;
        match &outcome.failure {
            None => {
                d.set_item("status", "ok")?;
                d.set_item("message", "")?;
                d.set_item("call", "")?;
                d.set_item("component", py.None())?;
            }
            Some(f) => {
                let status = if f.cause.is_discard() { "discard" } else { "error" };
                d.set_item("status", status)?;
                d.set_item("message", f.problems.get(f.component).cloned().unwrap_or_default())?;
                d.set_item("call", f.cause.to_string())?;
                d.set_item("component", self.names[f.component].clone())?;
            }
        }
        Ok(d)
    }

    /// Runs design-study points (`stewart_fmu.study`): each a tuple (steps, step, values,
    /// overrides) with `values` a list of (qualified name, value) and `overrides` a list of
    /// (qualified name, value, from time). Component 0 is the platform; `closed_loop` says the
    /// component "controller" closes the loop. Returns one dict per point: status, message,
    /// discard_time and the metrics, and `seconds` (the run's wall time). A point that cannot
    /// run (a bad name or value, a panic) is a row with status "error" and the reason.
    fn study<'py>(
        &self,
        py: Python<'py>,
        closed_loop: bool,
        points: Vec<Point<'py>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let mut guard =
            self.inner.lock().map_err(|_| PyRuntimeError::new_err("the system is unusable after a panic"))?;
        let system = guard.as_mut().ok_or_else(|| PyRuntimeError::new_err("the system is closed"))?;
        let controller =
            if closed_loop { Some(system.component_index("controller").map_err(PyValueError::new_err)?) } else { None };
        // Resolve every point first (with the GIL), then run them all without it.
        let mut specs = vec![];
        for (steps, step, values, overrides) in points {
            let spec = PySystem::spec(system, values, overrides).map(|(values, overrides)| RunSpec {
                start_time: 0.0,
                step,
                steps,
                scheme: Scheme::GaussSeidel,
                values,
                overrides,
                tables: vec![],
            });
            specs.push(spec.map_err(|e| format!("ValueError: {}", e.value(py))));
        }
        let rows = py.detach(|| {
            specs
                .iter()
                .map(|spec| {
                    let started = std::time::Instant::now();
                    let row = match spec {
                        Err(message) => Err(message.clone()),
                        Ok(spec) => match catch_unwind(AssertUnwindSafe(|| {
                            stewart_master::study::run(system, controller, spec)
                        })) {
                            Ok(row) => row,
                            Err(payload) => {
                                system.free_instances();
                                Err(panic_text(payload))
                            }
                        },
                    };
                    (row, started.elapsed().as_secs_f64())
                })
                .collect::<Vec<_>>()
        });
        let mut out = vec![];
        for (row, seconds) in rows {
            let d = PyDict::new(py);
            match row {
                Ok(r) => {
                    d.set_item("status", r.status)?;
                    d.set_item("message", r.message)?;
                    d.set_item("discard_time", r.discard_time)?;
                    d.set_item("max_leg_error", r.max_leg_error)?;
                    d.set_item("max_pose_error", r.max_pose_error)?;
                    d.set_item("min_kappa", r.min_kappa)?;
                    d.set_item("max_stop_force", r.max_stop_force)?;
                    d.set_item("energy_residual", r.energy_residual)?;
                    d.set_item("peak_deceleration", r.peak_deceleration)?;
                    d.set_item("final_z", r.final_z)?;
                    d.set_item("min_supply_pressure", r.min_supply_pressure)?;
                    d.set_item("landing_deceleration", r.landing_deceleration)?;
                }
                Err(message) => {
                    d.set_item("status", "error")?;
                    d.set_item("message", message)?;
                }
            }
            d.set_item("seconds", seconds)?;
            out.push(d);
        }
        Ok(out)
    }

    /// Frees the instances now (a later run makes new ones).
    fn free_instances(&self) -> PyResult<()> {
        if let Ok(mut guard) = self.inner.lock()
            && let Some(system) = guard.as_mut()
        {
            system.free_instances();
        }
        Ok(())
    }

    /// Frees the instances, unloads the FMUs and removes their folders.
    fn close(&self) {
        if let Ok(mut guard) = self.inner.lock() {
            guard.take();
        }
    }

    fn __repr__(&self) -> String {
        format!("<stewart_fmu._master.System of {}>", self.names.join(", "))
    }
}

/// The `stewart-master` command line with `args` (without the program's name); returns its
/// exit status.
#[pyfunction]
fn cli(py: Python<'_>, args: Vec<String>) -> i32 {
    py.detach(|| match catch_unwind(|| stewart_master::cli::main(&args)) {
        Ok(status) => status,
        Err(payload) => {
            eprintln!("stewart-master: {}", panic_text(payload));
            70
        }
    })
}

/// The compiled co-simulation master (Rust, crate stewart-master): FMI 2 Co-Simulation FMUs
/// connected as an SSP system describes, stepped with the Gauss-Seidel or Jacobi scheme.
#[pymodule]
fn _master(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySystem>()?;
    m.add("System", m.getattr("PySystem")?)?;
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
