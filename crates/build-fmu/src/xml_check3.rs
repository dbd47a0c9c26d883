//! Checks of an FMI 3.0 `modelDescription.xml`, parsed with quick-xml (independently of the
//! writer): the rules FMPy's `validate_fmu` and FMI Library enforce for FMI 3.

use std::collections::{BTreeSet, HashMap, HashSet};

use quick_xml::Reader;
use quick_xml::events::Event;

use super::xml_check::attributes;

pub struct Summary {
    pub token: String,
    pub variables: usize,
    pub outputs: usize,
    pub states: usize,
    pub event_indicators: usize,
}

#[derive(Default, Debug)]
struct Variable {
    name: String,
    vr: u32,
    causality: String,
    variability: String,
    initial: Option<String>,
    element: String,
    unit: Option<String>,
    display_unit: Option<String>,
    start_count: Option<usize>,
    derivative: Option<u32>,
    dimensions: Vec<usize>,
}

impl Variable {
    fn size(&self) -> usize {
        self.dimensions.iter().product()
    }
}

const VARIABLE_ELEMENTS: [&str; 4] = ["Float64", "Int32", "Boolean", "String"];

pub fn check(xml: &str) -> Result<Summary, String> {
    let mut reader = Reader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut token = None;
    let mut units = HashSet::new();
    let mut display_units = HashSet::new();
    let mut variables: Vec<Variable> = vec![];
    let mut current: Option<Variable> = None;
    let mut structure: Vec<(String, u32, Option<String>)> = vec![];
    let mut current_unit = String::new();
    loop {
        let event = reader.read_event().map_err(|e| format!("XML error at {}: {e}", reader.buffer_position()))?;
        let (e, empty) = match &event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                let name = e.name().as_ref().to_string();
                if VARIABLE_ELEMENTS.contains(&name.as_str())
                    && let Some(v) = current.take()
                {
                    variables.push(v);
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = e.name().as_ref().to_string();
        let a = attributes(e)?;
        match name.as_str() {
            "fmiModelDescription" => {
                if a.get("fmiVersion").map(String::as_str) != Some("3.0") {
                    return Err("fmiVersion must be 3.0".into());
                }
                token = a.get("instantiationToken").cloned();
            }
            "Unit" => {
                current_unit = a.get("name").cloned().ok_or("Unit without name")?;
                units.insert(current_unit.clone());
            }
            "DisplayUnit" => {
                display_units.insert((current_unit.clone(), a.get("name").cloned().ok_or("DisplayUnit without name")?));
            }
            n if VARIABLE_ELEMENTS.contains(&n) => {
                let v = Variable {
                    name: a.get("name").cloned().ok_or("variable without name")?,
                    vr: a
                        .get("valueReference")
                        .ok_or("variable without valueReference")?
                        .parse()
                        .map_err(|_| "bad valueReference")?,
                    causality: a.get("causality").cloned().unwrap_or_else(|| "local".into()),
                    variability: a.get("variability").cloned().unwrap_or_else(|| "continuous".into()),
                    initial: a.get("initial").cloned(),
                    element: n.to_string(),
                    unit: a.get("unit").cloned(),
                    display_unit: a.get("displayUnit").cloned(),
                    start_count: a.get("start").map(|s| s.split_whitespace().count()),
                    derivative: match a.get("derivative") {
                        Some(d) => Some(d.parse().map_err(|_| "bad derivative attribute")?),
                        None => None,
                    },
                    dimensions: vec![],
                };
                if empty {
                    variables.push(v);
                } else {
                    current = Some(v);
                }
            }
            "Dimension" => {
                let n: usize = a
                    .get("start")
                    .ok_or("Dimension without start")?
                    .parse()
                    .map_err(|_| "Dimension start is not a size")?;
                current.as_mut().ok_or("Dimension outside a variable")?.dimensions.push(n);
            }
            // A String's start values are child elements, one per element.
            "Start" => {
                a.get("value").ok_or("Start without value")?;
                let v = current.as_mut().ok_or("Start outside a variable")?;
                v.start_count = Some(v.start_count.unwrap_or(0) + 1);
            }
            "Output" | "ContinuousStateDerivative" | "InitialUnknown" | "EventIndicator" => {
                let vr =
                    a.get("valueReference").ok_or("unknown without valueReference")?.parse().map_err(|_| "bad vr")?;
                structure.push((name.clone(), vr, a.get("dependencies").cloned()));
            }
            _ => {}
        }
    }
    let token = token.ok_or("no instantiationToken")?;
    let mut by_vr: HashMap<u32, &Variable> = HashMap::new();
    let mut names = HashSet::new();
    for v in &variables {
        if !names.insert(v.name.as_str()) {
            return Err(format!("variable name {} is not unique", v.name));
        }
        if by_vr.insert(v.vr, v).is_some() {
            return Err(format!("value reference {} is not unique", v.vr));
        }
        if let Some(u) = &v.unit
            && !units.contains(u)
        {
            return Err(format!("{}: unit {u} is not defined", v.name));
        }
        if let (Some(u), Some(d)) = (&v.unit, &v.display_unit)
            && !display_units.contains(&(u.clone(), d.clone()))
        {
            return Err(format!("{}: display unit {d} is not defined for {u}", v.name));
        }
        let needs_start = v.causality == "input" || matches!(v.initial.as_deref(), Some("exact" | "approx"));
        match (needs_start, v.start_count) {
            (true, None) => return Err(format!("{} has no start value", v.name)),
            (_, Some(n)) if n != v.size() => {
                return Err(format!("{} has {n} start values for {} elements", v.name, v.size()));
            }
            (false, Some(_)) if v.initial.as_deref() == Some("calculated") => {
                return Err(format!("{} is calculated but has a start value", v.name));
            }
            _ => {}
        }
        if v.element != "Float64" && v.variability == "continuous" {
            return Err(format!("{} of type {} cannot be continuous", v.name, v.element));
        }
    }
    if variables.iter().filter(|v| v.causality == "independent").count() != 1 {
        return Err("exactly one independent variable is required".into());
    }
    for (kind, vr, deps) in &structure {
        let v = by_vr.get(vr).ok_or_else(|| format!("{kind} references unknown value reference {vr}"))?;
        if kind == "ContinuousStateDerivative" {
            let state =
                v.derivative.ok_or_else(|| format!("{} is listed as a derivative without derivative=", v.name))?;
            let s = by_vr.get(&state).ok_or_else(|| format!("{}: derivative of unknown vr {state}", v.name))?;
            if s.size() != v.size() {
                return Err(format!("{} and its state {} differ in size", v.name, s.name));
            }
        }
        for d in deps.iter().flat_map(|d| d.split_whitespace()) {
            let d: u32 = d.parse().map_err(|_| format!("{}: bad dependency {d}", v.name))?;
            if !by_vr.contains_key(&d) {
                return Err(format!("{kind} {}: dependency on unknown value reference {d}", v.name));
            }
        }
    }
    let listed =
        |k: &str| -> BTreeSet<u32> { structure.iter().filter(|(n, ..)| n == k).map(|(_, vr, _)| *vr).collect() };
    let outputs: BTreeSet<u32> = variables.iter().filter(|v| v.causality == "output").map(|v| v.vr).collect();
    if listed("Output") != outputs {
        return Err("ModelStructure must list every output exactly once".into());
    }
    let mut expected_initial: BTreeSet<u32> = variables
        .iter()
        .filter(|v| v.causality == "output" && matches!(v.initial.as_deref(), Some("approx" | "calculated")))
        .map(|v| v.vr)
        .collect();
    for d in listed("ContinuousStateDerivative") {
        let derivative = by_vr[&d];
        for v in [Some(derivative), derivative.derivative.and_then(|s| by_vr.get(&s).copied())].into_iter().flatten() {
            if matches!(v.initial.as_deref(), Some("approx" | "calculated")) {
                expected_initial.insert(v.vr);
            }
        }
    }
    if listed("InitialUnknown") != expected_initial {
        return Err(format!(
            "ModelStructure/InitialUnknown lists {:?}, the standard expects {:?}",
            listed("InitialUnknown"),
            expected_initial
        ));
    }
    let states = listed("ContinuousStateDerivative").iter().map(|vr| by_vr[vr].size()).sum();
    let event_indicators = listed("EventIndicator").iter().map(|vr| by_vr[vr].size()).sum();
    Ok(Summary { token, variables: variables.len(), outputs: outputs.len(), states, event_indicators })
}
