//! `stewart-master`: runs an SSP system from the command line (the same code the Python
//! extension runs).

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use crate::fmi2::Value;
use crate::record::Recorder;
use crate::system::{Given, Override, RunSpec, Scheme, System, convert};

pub const USAGE: &str = "\
usage: stewart-master run SYSTEM.ssp --stop-time T --step H [--scheme gauss-seidel|jacobi]
                          [--set COMPONENT.VARIABLE=VALUE ...] [--record COMPONENT.VARIABLE ...]
                          [--interval DT] [--fail COMPONENT.VARIABLE=VALUE@TIME ...]
                          [--input COMPONENT=TABLE.csv ...] [--out FILE.csv]
       stewart-master study SYSTEM.ssp --runs RUNS.txt [--out FILE.csv]
       stewart-master describe SYSTEM.ssp

run:      steps the system of the SSP file (FMI 2 Co-Simulation FMUs, connected as its
          SystemStructure.ssd says, its parameter bindings applied) from 0 to T at the
          communication step H; Gauss-Seidel by default (the Python master stewart_fmu.cosim's
          schemes). --set sets a parameter or input in initialisation mode (after the SSP's
          bindings); --record writes those outputs as CSV (to --out, or standard output) every
          DT (a multiple of H; default every step); --fail holds an input at VALUE from TIME on
          (a failed actuator); --input sets inputs of COMPONENT that no connection drives from a
          CSV table (a header row `time` and the inputs' names, then one row per time, s), linearly
          interpolated to each communication point and held after the last row (a vehicle's
          motion for StewartMotionSystem.ssp). A summary line (steps, time per step, status) goes to standard
          error. Exit status: 0 the run completed, 1 an FMU ended it early (discard or error;
          the FMU's message is printed), 2 the command was wrong.
study:    runs design-study points (stewart_fmu.study) on the system of the SSP file, its
          first component `platform`, closed by `controller` if it has one: RUNS.txt has one
          run a line, `STEPS STEP` then COMPONENT.VARIABLE=VALUE settings and
          COMPONENT.VARIABLE=VALUE@TIME held inputs, separated by spaces (`#` starts a comment
          line). Writes one CSV row a run (to --out, or standard output): status, discard_time,
          the metrics and the steps done as `stewart_fmu._master.System.study` returns them,
          then the message. Exit status: 0 every run was made (whatever its status), 2 the
          command or a line was wrong.
describe: the components, their FMUs, parameter bindings and the connections.";

/// Runs the command with `args` (without the program name); returns the exit status.
pub fn main(args: &[String]) -> i32 {
    match command(args) {
        Ok(status) => status,
        Err(message) => {
            eprintln!("stewart-master: {message}");
            2
        }
    }
}

/// A table's times and its named columns.
type Table = (Vec<f64>, Vec<(String, Vec<f64>)>);

/// A CSV table: a header row (`time`, then names), one row of numbers per time.
fn read_table(path: &Path) -> Result<Table, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| format!("{}: empty", path.display()))?
        .split(',')
        .map(|h| h.trim().to_string())
        .collect();
    if header.first().map(String::as_str) != Some("time") {
        return Err(format!("{}: the first column must be `time` (s), got {:?}", path.display(), header.first()));
    }
    let mut columns: Vec<Vec<f64>> = vec![vec![]; header.len()];
    for (row, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err(format!(
                "{}: row {} has {} cells for {} columns",
                path.display(),
                row + 2,
                cells.len(),
                header.len()
            ));
        }
        for (column, cell) in columns.iter_mut().zip(cells) {
            let x = cell
                .trim()
                .parse::<f64>()
                .map_err(|_| format!("{}: row {}: {cell:?} is not a number", path.display(), row + 2))?;
            column.push(x);
        }
    }
    let mut columns = columns.into_iter();
    let times = columns.next().unwrap_or_default();
    Ok((times, header.into_iter().skip(1).zip(columns).collect()))
}

fn parse_given(text: &str) -> Given {
    match text {
        "true" | "True" => Given::Bool(true),
        "false" | "False" => Given::Bool(false),
        _ => match text.parse::<i64>() {
            Ok(n) => Given::Int(n),
            Err(_) => text.parse::<f64>().map(Given::Float).unwrap_or(Given::Float(f64::NAN)),
        },
    }
}

/// `COMPONENT.VARIABLE=VALUE` (`--set`, a study line's setting): the component, the value
/// reference and the value of the variable's type.
fn setting(system: &System, text: &str) -> Result<(usize, u32, Value), String> {
    let (name, given) = text.split_once('=').ok_or_else(|| format!("{text}: write COMPONENT.VARIABLE=VALUE"))?;
    let (c, vr, kind) = system.resolve(name)?;
    let value =
        convert(kind, parse_given(given)).map_err(|expected| format!("{text}: {expected} is expected for {name}"))?;
    Ok((c, vr, value))
}

/// `COMPONENT.VARIABLE=VALUE@TIME` (`--fail`, a study line's held input): an input held at
/// VALUE from TIME on.
fn held_input(system: &System, text: &str) -> Result<Override, String> {
    let parsed = text.split_once('=').and_then(|(n, rest)| rest.split_once('@').map(|(v, t)| (n, v, t)));
    let (name, v, t) = parsed.ok_or_else(|| format!("{text}: write COMPONENT.VARIABLE=VALUE@TIME"))?;
    let (component, value_reference, _) = system.resolve(name)?;
    // Only an input can be held (an output belongs to its FMU).
    let variable = name.split_once('.').map(|(_, v)| v).unwrap_or(name);
    let causality = &system.fmu(component).description.find(variable)?.causality;
    if causality != "input" {
        return Err(format!("{text}: {name} is {causality}, not an input"));
    }
    let (Ok(value), Ok(from)) = (v.parse::<f64>(), t.parse::<f64>()) else {
        return Err(format!("{text}: VALUE and TIME must be numbers"));
    };
    Ok(Override { component, value_reference, value, from })
}

/// Where `--out` sends the rows: the file, or standard output.
fn output(out: &Option<String>) -> Result<Box<dyn Write>, String> {
    Ok(match out {
        Some(file) => {
            Box::new(std::io::BufWriter::new(std::fs::File::create(file).map_err(|e| format!("--out {file}: {e}"))?))
        }
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    })
}

fn positive(text: Option<&String>, option: &str) -> Result<f64, String> {
    let text = text.ok_or_else(|| format!("{option} needs a value"))?;
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("{option} {text}: a positive number of seconds is expected")),
    }
}

fn command(args: &[String]) -> Result<i32, String> {
    let Some(verb) = args.first() else {
        println!("{USAGE}");
        return Ok(2);
    };
    if verb == "--help" || verb == "-h" || verb == "help" {
        println!("{USAGE}");
        return Ok(0);
    }
    let path = args.get(1).ok_or_else(|| format!("{verb}: the SSP file is missing\n{USAGE}"))?;
    if !matches!(verb.as_str(), "run" | "study" | "describe") {
        return Err(format!("unknown command {verb:?}\n{USAGE}"));
    }
    let (mut system, description) = crate::ssp::open(Path::new(path))?;
    if verb == "describe" {
        println!("system {} ({})", description.name, path);
        for (k, c) in description.components.iter().enumerate() {
            let fmu = system.fmu(k);
            println!(
                "  component {}: {} ({}, {} variables), {} connectors",
                c.name,
                c.source,
                fmu.description.model_name,
                fmu.description.variables.len(),
                c.connectors.len()
            );
            for (name, value) in &c.parameters {
                println!("    bound {name} = {value:?}");
            }
        }
        for c in &description.connections {
            println!("  {}.{} -> {}.{}", c.start_element, c.start_connector, c.end_element, c.end_connector);
        }
        return Ok(0);
    }
    if verb == "study" {
        return study(&mut system, &args[2..]);
    }
    let (mut stop, mut step, mut scheme, mut interval, mut out) = (None, None, Scheme::GaussSeidel, None, None);
    let mut values = vec![vec![]; system.component_count()];
    let (mut record, mut overrides, mut tables) = (vec![], vec![], vec![]);
    let mut i = 2;
    while i < args.len() {
        let option = args[i].as_str();
        let value = args.get(i + 1);
        match option {
            "--stop-time" => stop = Some(positive(value, option)?),
            "--step" => step = Some(positive(value, option)?),
            "--interval" => interval = Some(positive(value, option)?),
            "--scheme" => scheme = Scheme::parse(value.ok_or("--scheme needs a value")?)?,
            "--out" => out = Some(value.ok_or("--out needs a file name")?.clone()),
            "--record" => record.push(value.ok_or("--record needs a variable")?.clone()),
            "--set" => {
                let text = value.ok_or("--set needs COMPONENT.VARIABLE=VALUE")?;
                let (c, vr, value) = setting(&system, text).map_err(|e| format!("--set {e}"))?;
                values[c].push((vr, value));
            }
            "--input" => {
                let text = value.ok_or("--input needs COMPONENT=TABLE.csv")?;
                let (component, file) =
                    text.split_once('=').ok_or_else(|| format!("--input {text}: write COMPONENT=TABLE.csv"))?;
                let (times, columns) = read_table(Path::new(file))?;
                tables.push(system.input_table(component, times, columns).map_err(|e| format!("--input {text}: {e}"))?);
            }
            "--fail" => {
                let text = value.ok_or("--fail needs COMPONENT.VARIABLE=VALUE@TIME")?;
                overrides.push(held_input(&system, text).map_err(|e| format!("--fail {e}"))?);
            }
            _ => return Err(format!("unknown option {option:?}\n{USAGE}")),
        }
        i += 2;
    }
    let stop = stop.ok_or("--stop-time is required")?;
    let step = step.ok_or("--step is required")?;
    let steps = (stop / step).round();
    if steps < 1.0 {
        return Err(format!("--step {step} is longer than --stop-time {stop}: no step would run"));
    }
    let every = match interval {
        None => 1,
        Some(dt) => {
            let k = (dt / step).round();
            if k < 1.0 || ((k * step - dt).abs() > 1e-9 * dt) {
                return Err(format!("--interval {dt}: a whole multiple of --step {step} is expected"));
            }
            k as usize
        }
    };
    let mut recorder = Recorder::new(&system, &record, every)?;
    let spec = RunSpec { start_time: 0.0, step, steps: steps as usize, scheme, values, overrides, tables };
    let started = Instant::now();
    let outcome = system.run(&spec, &mut recorder);
    let seconds = started.elapsed().as_secs_f64();
    if !record.is_empty() {
        let mut writer = output(&out)?;
        let io = |e: std::io::Error| format!("writing the results: {e}");
        writeln!(writer, "time,{}", record.join(",")).map_err(io)?;
        let width = recorder.width();
        for (r, t) in recorder.times.iter().enumerate() {
            let row: Vec<String> =
                recorder.values[r * width..(r + 1) * width].iter().map(|x| format!("{x:?}")).collect();
            writeln!(writer, "{t:?},{}", row.join(",")).map_err(io)?;
        }
        writer.flush().map_err(io)?;
    }
    let per_step = seconds / outcome.steps.max(1) as f64;
    match &outcome.failure {
        None => {
            eprintln!(
                "stewart-master: {} steps of {step} s in {seconds:.3} s ({:.3} us a step); ok",
                outcome.steps,
                per_step * 1e6
            );
            Ok(0)
        }
        Some(f) => {
            let name = system.component_names()[f.component].clone();
            let problem = f.problems.get(f.component).filter(|p| !p.is_empty()).cloned().unwrap_or_default();
            eprintln!(
                "stewart-master: {} steps of {step} s in {seconds:.3} s; ended at t = {} by {name}: {}{}",
                outcome.steps,
                outcome.time,
                f.cause,
                if problem.is_empty() { String::new() } else { format!(" {problem}") }
            );
            Ok(1)
        }
    }
}

/// A study line: `STEPS STEP` then settings and held inputs.
fn study_point(system: &System, line: &str) -> Result<RunSpec, String> {
    let mut words = line.split_whitespace();
    let steps = words.next().and_then(|w| w.parse::<usize>().ok()).ok_or("STEPS (a whole number) first")?;
    let step = positive(words.next().map(str::to_string).as_ref(), "STEP")?;
    let (mut values, mut overrides) = (vec![vec![]; system.component_count()], vec![]);
    for word in words {
        if word.split_once('=').is_some_and(|(_, v)| v.contains('@')) {
            overrides.push(held_input(system, word)?);
        } else {
            let (c, vr, value) = setting(system, word)?;
            values[c].push((vr, value));
        }
    }
    Ok(RunSpec { start_time: 0.0, step, steps, scheme: Scheme::GaussSeidel, values, overrides, tables: vec![] })
}

/// `study SYSTEM.ssp --runs RUNS.txt [--out FILE.csv]` on the opened system.
fn study(system: &mut System, options: &[String]) -> Result<i32, String> {
    let (mut runs, mut out) = (None, None);
    for pair in options.chunks(2) {
        let value = pair.get(1).cloned();
        match pair[0].as_str() {
            "--runs" => runs = Some(value.ok_or("--runs needs a file")?),
            "--out" => out = Some(value.ok_or("--out needs a file name")?),
            option => return Err(format!("unknown option {option:?}\n{USAGE}")),
        }
    }
    let runs = runs.ok_or("--runs is required")?;
    let text = std::fs::read_to_string(&runs).map_err(|e| format!("cannot read {runs}: {e}"))?;
    if system.component_index("platform")? != 0 {
        return Err("study: the system's first component must be `platform`".into());
    }
    let controller = system.component_index("controller").ok();
    let mut specs = vec![];
    for (n, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#')) {
        specs.push(study_point(system, line).map_err(|e| format!("{runs}, line {}: {e}", n + 1))?);
    }
    let mut writer = output(&out)?;
    let io = |e: std::io::Error| format!("writing the rows: {e}");
    writeln!(
        writer,
        "status,discard_time,max_leg_error,max_pose_error,min_kappa,max_stop_force,energy_residual,\
         peak_deceleration,final_z,min_supply_pressure,landing_deceleration,steps,message"
    )
    .map_err(io)?;
    for spec in &specs {
        let r = crate::study::run(system, controller, spec)?;
        let metrics = [
            r.discard_time,
            r.max_leg_error,
            r.max_pose_error,
            r.min_kappa,
            r.max_stop_force,
            r.energy_residual,
            r.peak_deceleration,
            r.final_z,
            r.min_supply_pressure,
            r.landing_deceleration,
        ];
        let metrics: Vec<String> = metrics.iter().map(|x| format!("{x:?}")).collect();
        let message = format!("\"{}\"", r.message.replace('"', "\"\""));
        writeln!(writer, "{},{},{},{message}", r.status, metrics.join(","), r.steps).map_err(io)?;
    }
    writer.flush().map_err(io)?;
    Ok(0)
}
