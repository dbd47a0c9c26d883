//! A system of FMU instances connected as an SSP system describes, stepped at a fixed
//! communication step with one of two coupling schemes (those of `stewart_fmu.cosim`):
//!
//! - **Gauss-Seidel**: at each communication point the inputs of each component are set from
//!   its sources' outputs at that point, the components whose outputs depend directly on their
//!   inputs (the controller) after the components they read; then every component steps. In the
//!   closed loop: the platform's legs go to the controller, its forces to the platform, then
//!   both step.
//! - **Jacobi** (FMPy's SSP algorithm, `fmpy/ssp/simulation.py`): the connections start at 0.0;
//!   each component in element order gets its inputs from the connections, steps and writes
//!   its outputs; then the connections take the new outputs. A value reaches its destination
//!   one communication step later.
//!
//! A run sets parameters, steps, and hands the values an `Observer` asks for to it after every
//! step; nothing else is recorded. Instances are made once and reused with `fmi2Reset`. What a
//! run is given and gives back is `run.rs`'s; the Gauss-Seidel order is `order.rs`'s.

mod order;

use std::sync::Arc;

use crate::description::Type;
use crate::fmi2::{CallError, Instance, Value};
use crate::fmu::Fmu;
pub use crate::run::{
    Cause, Failure, Given, InputTable, Observer, Outcome, Override, Readings, RunSpec, Scheme, convert,
};
use crate::ssd::SystemDescription;
use order::{Reader, gauss_seidel_order};

struct Component {
    name: String,
    fmu: Arc<Fmu>,
    instance: Option<Instance>,
    /// Whether the instance is new (no `fmi2Reset` needed before the next run).
    fresh: bool,
    /// The SSD's parameter bindings, set before a run's own values.
    bindings: Vec<(u32, Value)>,
    /// Real outputs that start connections (value references).
    sources: Vec<u32>,
    /// Real inputs fed by connections: (value reference, source component, index in its `sources`).
    inputs: Vec<(u32, usize, usize)>,
    /// The inputs (value references) each output of `sources` depends on directly.
    source_feeds: Vec<Vec<u32>>,
    /// Whether an output in `sources` depends directly on an input a connection drives.
    connected_feedthrough: bool,
    /// The same in the current run: also through the inputs its tables and overrides drive
    /// ([`System::run`]).
    feedthrough: bool,
    /// Why the last `fmi2Instantiate` failed.
    instantiate_error: String,
}

pub struct System {
    components: Vec<Component>,
    /// Gauss-Seidel: the order in which components get their inputs.
    order: Vec<usize>,
    pub name: String,
}

impl System {
    /// Components named as in `description` (or, without one, the given FMUs unconnected, in
    /// the order given), each with the FMU of its name in `fmus`.
    pub fn new(fmus: Vec<(String, Arc<Fmu>)>, description: Option<&SystemDescription>) -> Result<System, String> {
        let names: Vec<String> = match description {
            Some(d) => d.components.iter().map(|c| c.name.clone()).collect(),
            None => fmus.iter().map(|(n, _)| n.clone()).collect(),
        };
        let mut components = vec![];
        for name in &names {
            let fmu = fmus
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, f)| f.clone())
                .ok_or_else(|| format!("no FMU given for the component {name:?}"))?;
            let mut bindings = vec![];
            if let Some(c) = description.and_then(|d| d.components.iter().find(|c| &c.name == name)) {
                for (pname, value) in &c.parameters {
                    let v = fmu.description.find(pname).map_err(|e| format!("{name}'s parameter binding: {e}"))?;
                    let value = convert(v.kind, value.into())
                        .map_err(|expected| format!("{name}.{pname}: the bound value is not {expected}"))?;
                    bindings.push((v.value_reference, value));
                }
            }
            components.push(Component {
                name: name.clone(),
                fmu,
                instance: None,
                fresh: false,
                bindings,
                sources: vec![],
                inputs: vec![],
                source_feeds: vec![],
                connected_feedthrough: false,
                feedthrough: false,
                instantiate_error: String::new(),
            });
        }
        let mut feeds = vec![];
        for connection in description.map(|d| d.connections.as_slice()).unwrap_or_default() {
            let index =
                |element: &str| components.iter().position(|c| c.name == element).expect("checked by the SSD parser");
            let (from, to) = (index(&connection.start_element), index(&connection.end_element));
            let variable = |c: usize, name: &str, causality: &str| -> Result<(u32, Vec<u32>), String> {
                let v = components[c]
                    .fmu
                    .description
                    .find(name)
                    .map_err(|e| format!("connection {}.{name}: {e}", components[c].name))?;
                if v.kind != Type::Real {
                    return Err(format!(
                        "connection {}.{name}: only Real connections are supported",
                        components[c].name
                    ));
                }
                if v.causality != causality {
                    return Err(format!(
                        "connection {}.{name}: is {}, not {causality}",
                        components[c].name, v.causality
                    ));
                }
                Ok((v.value_reference, v.feeds_from.clone()))
            };
            let (out_vr, feeds_from) = variable(from, &connection.start_connector, "output")?;
            let (in_vr, _) = variable(to, &connection.end_connector, "input")?;
            let slot = match components[from].sources.iter().position(|&vr| vr == out_vr) {
                Some(slot) => slot,
                None => {
                    components[from].sources.push(out_vr);
                    components[from].source_feeds.push(feeds_from.clone());
                    components[from].sources.len() - 1
                }
            };
            feeds.push((from, feeds_from));
            if components[to].inputs.iter().any(|&(vr, _, _)| vr == in_vr) {
                return Err(format!(
                    "{}.{} has more than one connection into it",
                    components[to].name, connection.end_connector
                ));
            }
            components[to].inputs.push((in_vr, from, slot));
        }
        // A component feeds through where a connected output depends directly on a connected
        // input: an output that depends only on inputs no connection drives (held from
        // outside, say) closes no loop.
        for (from, feeds_from) in feeds {
            let inputs = &components[from].inputs;
            components[from].connected_feedthrough |=
                feeds_from.iter().any(|vr| inputs.iter().any(|&(input, _, _)| input == *vr));
        }
        // The connections' loops are refused here; each run orders again with its own inputs.
        let connected: Vec<bool> = components.iter().map(|c| c.connected_feedthrough).collect();
        let order = gauss_seidel_order(&components.iter().map(Reader::of).collect::<Vec<_>>(), &connected)?;
        let name = description.map(|d| d.name.clone()).unwrap_or_else(|| names.join("+"));
        Ok(System { components, order, name })
    }

    pub fn component_count(&self) -> usize {
        self.components.len()
    }

    pub fn component_names(&self) -> Vec<String> {
        self.components.iter().map(|c| c.name.clone()).collect()
    }

    pub fn component_index(&self, name: &str) -> Result<usize, String> {
        self.components.iter().position(|c| c.name == name).ok_or_else(|| {
            format!("the system has no component {name:?} (components: {})", self.component_names().join(", "))
        })
    }

    pub fn fmu(&self, component: usize) -> &Fmu {
        &self.components[component].fmu
    }

    /// The value reference and type of `component.variable`, or a message.
    pub fn variable(&self, component: usize, name: &str) -> Result<(u32, Type), String> {
        let v = self.components[component].fmu.description.find(name)?;
        Ok((v.value_reference, v.kind))
    }

    /// Resolves "component.variable" (the component's name up to the first dot).
    pub fn resolve(&self, qualified: &str) -> Result<(usize, u32, Type), String> {
        let (component, variable) = qualified
            .split_once('.')
            .ok_or_else(|| format!("{qualified:?}: name a variable as component.variable, e.g. platform.M"))?;
        let c = self.component_index(component)?;
        let (vr, kind) = self.variable(c, variable)?;
        Ok((c, vr, kind))
    }

    /// An input table of `component` for the variables `columns` (names and values, one
    /// value per time): each must be a Real input that no connection drives.
    pub fn input_table(
        &self,
        component: &str,
        times: Vec<f64>,
        columns: Vec<(String, Vec<f64>)>,
    ) -> Result<InputTable, String> {
        let c = self.component_index(component)?;
        let connected = self.connected_inputs(c);
        let mut value_references = vec![];
        let mut values = vec![];
        for (name, column) in columns {
            let (vr, kind) = self.variable(c, &name)?;
            let causality = &self.fmu(c).description.find(&name)?.causality;
            if causality != "input" || kind != Type::Real {
                return Err(format!("{component}.{name} is not a Real input ({causality}): a table sets inputs only"));
            }
            if connected.contains(&vr) {
                return Err(format!(
                    "{component}.{name} is driven by a connection of the system: a table cannot set it"
                ));
            }
            if column.len() != times.len() {
                return Err(format!("{component}.{name}: {} values for {} times", column.len(), times.len()));
            }
            value_references.push(vr);
            values.push(column);
        }
        let table = InputTable { component: c, value_references, times, columns: values };
        table.check().map_err(|e| format!("the input table of {component}: {e}"))?;
        Ok(table)
    }

    /// Per component, the input value references connections drive.
    pub fn connected_inputs(&self, component: usize) -> Vec<u32> {
        self.components[component].inputs.iter().map(|&(vr, _, _)| vr).collect()
    }

    /// Frees every instance (the next run makes new ones).
    pub fn free_instances(&mut self) {
        for c in &mut self.components {
            c.instance = None;
        }
    }

    /// Each component's messages of the current run.
    pub fn messages(&self, component: usize) -> Vec<crate::fmi2::Message> {
        self.components[component].instance.as_ref().map(|i| i.messages()).unwrap_or_default()
    }

    fn failure(&mut self, component: usize, cause: Cause, initialising: bool) -> Failure {
        let problems = self
            .components
            .iter()
            .map(|c| match &c.instance {
                Some(i) => i.last_problem(),
                None => c.instantiate_error.clone(),
            })
            .collect();
        let terminated = self.components.iter_mut().map(|c| c.instance.as_mut().and_then(|i| i.terminated())).collect();
        Failure { component, cause, problems, terminated, initialising }
    }

    /// Instantiates (or resets) and initialises every component in element order: setup, the
    /// bindings and the run's values set in initialisation mode, exit.
    fn initialise(&mut self, spec: &RunSpec) -> Result<(), (usize, Cause)> {
        for c in &mut self.components {
            c.instantiate_error.clear();
            if let Some(i) = &c.instance {
                i.clear_messages();
            }
        }
        for (k, c) in self.components.iter_mut().enumerate() {
            let reuse = match (&mut c.instance, c.fresh) {
                (Some(_), true) => true,
                (Some(i), false) => i.reset().is_ok(),
                (None, _) => false,
            };
            if !reuse {
                // A new instance: the first run, or one the FMU could not reset.
                c.instance = None;
                match c.fmu.instantiate(&c.name) {
                    Ok(instance) => c.instance = Some(instance),
                    Err(message) => {
                        c.instantiate_error = message;
                        return Err((k, Cause::Instantiate));
                    }
                }
            }
            c.fresh = false;
            let instance = c.instance.as_mut().expect("instantiated above");
            instance.setup_experiment(spec.start_time).map_err(|e| (k, Cause::Call(e)))?;
            instance.enter_initialization_mode().map_err(|e| (k, Cause::Call(e)))?;
            let mut values = c.bindings.clone();
            values.extend(spec.values.get(k).cloned().unwrap_or_default());
            instance.set_values(&values).map_err(|e| (k, Cause::Call(e)))?;
            instance.exit_initialization_mode().map_err(|e| (k, Cause::Call(e)))?;
        }
        Ok(())
    }

    /// Runs `spec`, handing the observer's values to it after every step.
    pub fn run(&mut self, spec: &RunSpec, observer: &mut dyn Observer) -> Outcome {
        let n = self.components.len();
        let watched = observer.watched();
        assert!(watched.len() <= n, "an observer asked for more components than the system has");
        if let Err((k, error)) = self.initialise(spec) {
            return Outcome { steps: 0, time: spec.start_time, failure: Some(self.failure(k, error, true)) };
        }
        let jacobi = spec.scheme == Scheme::Jacobi;
        // Direct feed-through in this run: through the inputs connections drive, and those this
        // run's tables and overrides drive (set at each point before the outputs are read).
        let feedthrough: Vec<bool> = (0..n)
            .map(|k| {
                let c = &self.components[k];
                let driven = |vr: &u32| {
                    spec.tables.iter().any(|t| t.component == k && t.value_references.contains(vr))
                        || spec.overrides.iter().any(|o| o.component == k && o.value_reference == *vr)
                };
                c.connected_feedthrough || c.source_feeds.iter().any(|feeds| feeds.iter().any(driven))
            })
            .collect();
        for (c, &f) in self.components.iter_mut().zip(&feedthrough) {
            c.feedthrough = f;
        }
        match gauss_seidel_order(&self.components.iter().map(Reader::of).collect::<Vec<_>>(), &feedthrough) {
            Ok(order) => self.order = order,
            Err(message) => {
                // A loop this run's tables or overrides close: named as the first component's
                // problem, before any step.
                let mut failure = self.failure(0, Cause::AlgebraicLoop, true);
                if let Some(problem) = failure.problems.first_mut() {
                    *problem = message;
                }
                return Outcome { steps: 0, time: spec.start_time, failure: Some(failure) };
            }
        }
        // After a step each component reads, in one call: its connection sources (unless it
        // has direct feed-through under Gauss-Seidel: those are read after its inputs are
        // set), then what the observer watches.
        let mut post: Vec<Vec<u32>> = vec![];
        let mut offsets = vec![];
        for (k, c) in self.components.iter().enumerate() {
            let mut vrs = if jacobi || !feedthrough[k] { c.sources.clone() } else { vec![] };
            offsets.push(vrs.len());
            vrs.extend(watched.get(k).cloned().unwrap_or_default());
            post.push(vrs);
        }
        let mut readings = Readings { buffers: post.iter().map(|v| vec![0.0; v.len()]).collect(), offsets };
        // The latest value of each connection source, per component (Jacobi: 0.0 at first).
        let mut sources: Vec<Vec<f64>> = self.components.iter().map(|c| vec![0.0; c.sources.len()]).collect();
        let mut next_sources = sources.clone();
        let mut input_values: Vec<Vec<f64>> = self.components.iter().map(|c| vec![0.0; c.inputs.len()]).collect();
        let input_vrs: Vec<Vec<u32>> = self.components.iter().map(|c| c.inputs.iter().map(|i| i.0).collect()).collect();
        // Overrides of inputs no connection drives are set on their own.
        let mut free_overrides: Vec<Vec<(u32, f64, f64)>> = vec![vec![]; n];
        let mut connected_overrides: Vec<Vec<(usize, f64, f64)>> = vec![vec![]; n];
        for o in &spec.overrides {
            match input_vrs[o.component].iter().position(|&vr| vr == o.value_reference) {
                Some(slot) => connected_overrides[o.component].push((slot, o.value, o.from)),
                None => free_overrides[o.component].push((o.value_reference, o.value, o.from)),
            }
        }
        let mut scratch_vrs: Vec<u32> = vec![];
        let mut scratch_values: Vec<f64> = vec![];
        let mut cursors = vec![0usize; spec.tables.len()];
        let mut table_values: Vec<f64> = vec![];

        // The tables' inputs at the start, so that the first readings see them.
        if let Err((k, e)) = self.set_tables(spec, spec.start_time, &mut cursors, &mut table_values) {
            return Outcome { steps: 0, time: spec.start_time, failure: Some(self.failure(k, Cause::Call(e), true)) };
        }
        // After initialisation: the sources (Gauss-Seidel reads them at each point) and the
        // observer's values.
        for k in 0..n {
            let instance = self.components[k].instance.as_mut().expect("initialised");
            if let Err(e) = instance.get_real(&post[k], &mut readings.buffers[k]) {
                return Outcome {
                    steps: 0,
                    time: spec.start_time,
                    failure: Some(self.failure(k, Cause::Call(e), true)),
                };
            }
            if !jacobi {
                let m = readings.offsets[k];
                sources[k][..m].copy_from_slice(&readings.buffers[k][..m]);
            }
        }
        observer.initial(&readings);

        let mut time = spec.start_time;
        for i in 0..spec.steps {
            // Inputs from tables first: no connection drives them, and a component with direct
            // feed-through is read after its inputs are set.
            if let Err((k, error)) = self.set_tables(spec, time, &mut cursors, &mut table_values) {
                return Outcome { steps: i, time, failure: Some(self.failure(k, Cause::Call(error), false)) };
            }
            let result = if jacobi {
                self.jacobi_step(
                    time,
                    spec.step,
                    &post,
                    &mut readings,
                    &mut sources,
                    &mut next_sources,
                    &mut input_values,
                    &input_vrs,
                    &connected_overrides,
                    &free_overrides,
                    (&mut scratch_vrs, &mut scratch_values),
                )
            } else {
                self.gauss_seidel_step(
                    time,
                    spec.step,
                    &post,
                    &mut readings,
                    &mut sources,
                    &mut input_values,
                    &input_vrs,
                    &connected_overrides,
                    &free_overrides,
                    (&mut scratch_vrs, &mut scratch_values),
                )
            };
            if let Err((k, error)) = result {
                return Outcome { steps: i, time, failure: Some(self.failure(k, Cause::Call(error), false)) };
            }
            // The communication points add the step each time (`t += h`), as FMPy's SSP master and
            // the package's Python masters count them: the FMUs see the time, so the masters give
            // the same bits only if they count alike.
            time += spec.step;
            observer.step(i, time, &readings);
        }
        Outcome { steps: spec.steps, time, failure: None }
    }

    /// Sets the inputs of the tables at `time`.
    fn set_tables(
        &mut self,
        spec: &RunSpec,
        time: f64,
        cursors: &mut [usize],
        values: &mut Vec<f64>,
    ) -> Result<(), (usize, CallError)> {
        for (table, cursor) in spec.tables.iter().zip(cursors.iter_mut()) {
            table.at(time, cursor, values);
            let instance = self.components[table.component].instance.as_mut().expect("initialised");
            instance.set_real(&table.value_references, values).map_err(|e| (table.component, e))?;
        }
        Ok(())
    }

    /// Sets component `k`'s connected inputs from `sources` (with the overrides active at
    /// `time`) and its free overrides.
    #[allow(clippy::too_many_arguments)]
    fn set_inputs(
        &mut self,
        k: usize,
        time: f64,
        sources: &[Vec<f64>],
        input_values: &mut [Vec<f64>],
        input_vrs: &[Vec<u32>],
        connected_overrides: &[Vec<(usize, f64, f64)>],
        free_overrides: &[Vec<(u32, f64, f64)>],
        scratch: (&mut Vec<u32>, &mut Vec<f64>),
    ) -> Result<(), CallError> {
        let c = &mut self.components[k];
        let instance = c.instance.as_mut().expect("initialised");
        if !c.inputs.is_empty() {
            let values = &mut input_values[k];
            for (slot, &(_, from, index)) in c.inputs.iter().enumerate() {
                values[slot] = sources[from][index];
            }
            for &(slot, value, from) in &connected_overrides[k] {
                if time >= from {
                    values[slot] = value;
                }
            }
            instance.set_real(&input_vrs[k], values)?;
        }
        if !free_overrides[k].is_empty() {
            let (vrs, values) = scratch;
            vrs.clear();
            values.clear();
            for &(vr, value, from) in &free_overrides[k] {
                if time >= from {
                    vrs.push(vr);
                    values.push(value);
                }
            }
            if !vrs.is_empty() {
                instance.set_real(vrs, values)?;
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn gauss_seidel_step(
        &mut self,
        time: f64,
        step: f64,
        post: &[Vec<u32>],
        readings: &mut Readings,
        sources: &mut [Vec<f64>],
        input_values: &mut [Vec<f64>],
        input_vrs: &[Vec<u32>],
        connected_overrides: &[Vec<(usize, f64, f64)>],
        free_overrides: &[Vec<(u32, f64, f64)>],
        scratch: (&mut Vec<u32>, &mut Vec<f64>),
    ) -> Result<(), (usize, CallError)> {
        let (scratch_vrs, scratch_values) = scratch;
        for o in 0..self.order.len() {
            let k = self.order[o];
            self.set_inputs(
                k,
                time,
                sources,
                input_values,
                input_vrs,
                connected_overrides,
                free_overrides,
                (&mut *scratch_vrs, &mut *scratch_values),
            )
            .map_err(|e| (k, e))?;
            let c = &mut self.components[k];
            if c.feedthrough {
                // Its outputs at this point follow the inputs just set.
                let instance = c.instance.as_mut().expect("initialised");
                instance.get_real(&c.sources, &mut sources[k]).map_err(|e| (k, e))?;
            }
        }
        for (k, c) in self.components.iter_mut().enumerate() {
            c.instance.as_mut().expect("initialised").do_step(time, step).map_err(|e| (k, e))?;
        }
        for (k, c) in self.components.iter_mut().enumerate() {
            let instance = c.instance.as_mut().expect("initialised");
            instance.get_real(&post[k], &mut readings.buffers[k]).map_err(|e| (k, e))?;
            let m = readings.offsets[k];
            if m > 0 {
                sources[k][..m].copy_from_slice(&readings.buffers[k][..m]);
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn jacobi_step(
        &mut self,
        time: f64,
        step: f64,
        post: &[Vec<u32>],
        readings: &mut Readings,
        sources: &mut Vec<Vec<f64>>,
        next_sources: &mut Vec<Vec<f64>>,
        input_values: &mut [Vec<f64>],
        input_vrs: &[Vec<u32>],
        connected_overrides: &[Vec<(usize, f64, f64)>],
        free_overrides: &[Vec<(u32, f64, f64)>],
        scratch: (&mut Vec<u32>, &mut Vec<f64>),
    ) -> Result<(), (usize, CallError)> {
        let (scratch_vrs, scratch_values) = scratch;
        for k in 0..self.components.len() {
            self.set_inputs(
                k,
                time,
                sources,
                input_values,
                input_vrs,
                connected_overrides,
                free_overrides,
                (&mut *scratch_vrs, &mut *scratch_values),
            )
            .map_err(|e| (k, e))?;
            let instance = self.components[k].instance.as_mut().expect("initialised");
            instance.do_step(time, step).map_err(|e| (k, e))?;
            instance.get_real(&post[k], &mut readings.buffers[k]).map_err(|e| (k, e))?;
            let m = readings.offsets[k];
            next_sources[k][..m].copy_from_slice(&readings.buffers[k][..m]);
        }
        std::mem::swap(sources, next_sources);
        Ok(())
    }
}
