//! Checks of a `modelDescription.xml`, parsed with quick-xml (independently of the writer):
//! the rules FMPy's `validate_fmu`, fmusim and FMI Library enforce, so that a broken
//! description never leaves the build.

use std::collections::{BTreeSet, HashMap, HashSet};

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

pub struct Summary {
    pub guid: String,
    pub variables: usize,
    pub outputs: usize,
    pub initial_unknowns: usize,
}

#[derive(Default, Debug)]
struct Variable {
    name: String,
    vr: u32,
    causality: String,
    variability: String,
    initial: Option<String>,
    type_name: String,
    unit: Option<String>,
    display_unit: Option<String>,
    declared_type: Option<String>,
    has_start: bool,
    /// 1-based index of the state this variable is the derivative of.
    derivative: Option<usize>,
}

/// An element's attributes by name; a duplicate is an error (both FMI versions' checks).
pub fn attributes(e: &BytesStart) -> Result<HashMap<String, String>, String> {
    let mut out = HashMap::new();
    for a in e.attributes() {
        let a = a.map_err(|err| format!("bad attribute: {err}"))?;
        let key = a.key.as_ref().to_string();
        let value = a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map_err(|err| format!("bad attribute value: {err}"))?
            .into_owned();
        if out.insert(key.clone(), value).is_some() {
            return Err(format!("duplicate attribute {key}"));
        }
    }
    Ok(out)
}

pub fn check(xml: &str) -> Result<Summary, String> {
    let mut reader = Reader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut guid = None;
    let mut units = HashSet::new();
    let mut display_units = HashSet::new();
    let mut types = HashSet::new();
    let mut variables: Vec<Variable> = vec![];
    let mut current: Option<Variable> = None;
    let mut section = String::new();
    let mut outputs: Vec<(usize, Vec<usize>)> = vec![];
    let mut initial_unknowns: Vec<(usize, Vec<usize>)> = vec![];
    let mut derivatives: Vec<(usize, Vec<usize>)> = vec![];
    let mut depth = 0usize;
    let mut saw_cosimulation = false;
    loop {
        let event = reader
            .read_event()
            .map_err(|e| format!("not well-formed XML at byte {}: {e}", reader.buffer_position()))?;
        let (e, empty) = match &event {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(e) => {
                depth = depth.saturating_sub(1);
                let name = e.name().as_ref().to_string();
                if name == "ScalarVariable" {
                    variables.push(current.take().ok_or("unbalanced ScalarVariable")?);
                }
                if name == section {
                    section.clear();
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        if !empty {
            depth += 1;
        }
        let name = e.name().as_ref().to_string();
        let attrs = attributes(&e)?;
        let get = |k: &str| attrs.get(k).cloned();
        match name.as_str() {
            "fmiModelDescription" => {
                if get("fmiVersion").as_deref() != Some("2.0") {
                    return Err("fmiVersion must be 2.0".into());
                }
                guid = get("guid");
            }
            "CoSimulation" => {
                saw_cosimulation = true;
                if get("modelIdentifier").is_none() {
                    return Err("CoSimulation without modelIdentifier".into());
                }
            }
            "Unit" => {
                units.insert(get("name").ok_or("Unit without name")?);
            }
            "DisplayUnit" => {
                display_units.insert(get("name").ok_or("DisplayUnit without name")?);
            }
            "SimpleType" => {
                types.insert(get("name").ok_or("SimpleType without name")?);
            }
            "ScalarVariable" => {
                let vr = get("valueReference").ok_or("ScalarVariable without valueReference")?;
                current = Some(Variable {
                    name: get("name").ok_or("ScalarVariable without name")?,
                    vr: vr.parse().map_err(|_| format!("valueReference {vr} is not an unsigned integer"))?,
                    causality: get("causality").unwrap_or_else(|| "local".into()),
                    variability: get("variability").unwrap_or_else(|| "continuous".into()),
                    initial: get("initial"),
                    ..Default::default()
                });
                if empty {
                    return Err("ScalarVariable without a type element".into());
                }
            }
            "Real" | "Integer" | "Boolean" | "String" | "Enumeration" => {
                if let Some(v) = current.as_mut() {
                    v.type_name = name.clone();
                    v.unit = get("unit");
                    v.display_unit = get("displayUnit");
                    v.declared_type = get("declaredType");
                    v.has_start = attrs.contains_key("start");
                    v.derivative = match get("derivative") {
                        Some(d) => Some(d.parse().map_err(|_| format!("bad derivative attribute {d}"))?),
                        None => None,
                    };
                }
            }
            "Outputs" | "InitialUnknowns" | "Derivatives" => {
                section = name.clone();
            }
            "Unknown" => {
                let index: usize =
                    get("index").ok_or("Unknown without index")?.parse().map_err(|_| "bad Unknown index")?;
                let deps: Vec<usize> = match get("dependencies") {
                    Some(d) => d
                        .split_whitespace()
                        .map(|s| s.parse().map_err(|_| format!("bad dependency {s}")))
                        .collect::<Result<_, _>>()?,
                    None => return Err(format!("Unknown {index}: dependencies must be explicit")),
                };
                if let Some(kinds) = get("dependenciesKind")
                    && kinds.split_whitespace().count() != deps.len()
                {
                    return Err(format!("Unknown {index}: dependenciesKind and dependencies differ in length"));
                }
                match section.as_str() {
                    "Outputs" => outputs.push((index, deps)),
                    "InitialUnknowns" => initial_unknowns.push((index, deps)),
                    "Derivatives" => derivatives.push((index, deps)),
                    _ => {}
                }
            }
            _ => {}
        }
    }
    if depth != 0 {
        return Err("unbalanced elements".into());
    }
    if !saw_cosimulation {
        return Err("no CoSimulation element".into());
    }
    let guid = guid.ok_or("no guid")?;

    let mut names = HashSet::new();
    let mut vrs = HashSet::new();
    let n = variables.len();
    for v in &variables {
        if !names.insert(v.name.clone()) {
            return Err(format!("variable name {} is not unique", v.name));
        }
        if !vrs.insert(v.vr) {
            return Err(format!("value reference {} of {} is not unique", v.vr, v.name));
        }
        if v.type_name.is_empty() {
            return Err(format!("{} has no type element", v.name));
        }
        if v.type_name != "Real" && v.variability == "continuous" {
            return Err(format!("{} is {} and cannot be continuous", v.name, v.type_name));
        }
        for u in [&v.unit, &v.display_unit].into_iter().flatten() {
            if !units.contains(u) && !display_units.contains(u) {
                return Err(format!("{}: unit {u} is not defined in UnitDefinitions", v.name));
            }
        }
        if let Some(t) = &v.declared_type
            && !types.contains(t)
        {
            return Err(format!("{}: declaredType {t} is not defined", v.name));
        }
        let needs_start = v.causality == "input" || matches!(v.initial.as_deref(), Some("exact" | "approx"));
        let forbids_start = v.causality == "independent" || v.initial.as_deref() == Some("calculated");
        if needs_start && !v.has_start {
            return Err(format!("{} needs a start value", v.name));
        }
        if forbids_start && v.has_start {
            return Err(format!("{} must not have a start value", v.name));
        }
    }
    let index_of = |i: usize| -> Result<&Variable, String> {
        if i >= 1 && i <= n {
            Ok(&variables[i - 1])
        } else {
            Err(format!("ModelStructure index {i} is out of range 1..={n}"))
        }
    };
    let expected_outputs: BTreeSet<usize> = (1..=n).filter(|&i| variables[i - 1].causality == "output").collect();
    let listed_outputs: BTreeSet<usize> = outputs.iter().map(|o| o.0).collect();
    if expected_outputs != listed_outputs {
        return Err(format!(
            "ModelStructure/Outputs lists {listed_outputs:?}, expected every output {expected_outputs:?}"
        ));
    }
    // States: the variables some derivative refers to.
    let mut states = BTreeSet::new();
    for v in &variables {
        if let Some(s) = v.derivative {
            index_of(s)?;
            states.insert(s);
        }
    }
    let derivative_indices: BTreeSet<usize> = (1..=n).filter(|&i| variables[i - 1].derivative.is_some()).collect();
    let listed_derivatives: BTreeSet<usize> = derivatives.iter().map(|d| d.0).collect();
    if listed_derivatives != derivative_indices {
        return Err(format!(
            "ModelStructure/Derivatives lists {listed_derivatives:?}, expected {derivative_indices:?}"
        ));
    }
    for (i, deps) in outputs.iter().chain(derivatives.iter()) {
        for d in deps {
            let v = index_of(*d)?;
            if v.causality != "input" && !states.contains(d) {
                return Err(format!(
                    "{} depends on {}, which is neither an input nor a state",
                    index_of(*i)?.name,
                    v.name
                ));
            }
        }
    }
    let calculated = |i: usize| matches!(variables[i - 1].initial.as_deref(), Some("approx" | "calculated"));
    let expected_initial: BTreeSet<usize> = (1..=n)
        .filter(|&i| {
            calculated(i)
                && (variables[i - 1].causality == "output" || states.contains(&i) || derivative_indices.contains(&i))
        })
        .collect();
    let listed_initial: BTreeSet<usize> = initial_unknowns.iter().map(|o| o.0).collect();
    if expected_initial != listed_initial {
        return Err(format!("ModelStructure/InitialUnknowns lists {listed_initial:?}, expected {expected_initial:?}"));
    }
    for (i, deps) in &initial_unknowns {
        for d in deps {
            let v = index_of(*d)?;
            let known = v.causality == "input" || v.initial.as_deref() == Some("exact") || v.causality == "independent";
            if !known {
                return Err(format!(
                    "initial unknown {} depends on {}, which is not known in Initialization Mode",
                    index_of(*i)?.name,
                    v.name
                ));
            }
        }
    }
    Ok(Summary { guid, variables: n, outputs: listed_outputs.len(), initial_unknowns: listed_initial.len() })
}
