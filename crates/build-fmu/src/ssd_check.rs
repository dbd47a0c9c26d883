//! Checks of the system descriptions (`modelDescription/StewartSystem*.ssd`) with quick-xml:
//! well-formed, every component's source is one of our FMUs, every connector names a variable
//! of that model with the matching causality, every connection joins an output to an input,
//! every bound parameter value names a parameter of its component, of the type it declares.

use std::collections::HashMap;

use quick_xml::Reader;
use quick_xml::events::Event;
use stewart_fmu::models::ModelKind;
use stewart_fmu::models::variables::{Causality, VariableTable, VariableType};

/// Returns the FMU file names the system uses.
pub fn check(ssd: &str) -> Result<Vec<String>, String> {
    let mut reader = Reader::from_str(ssd);
    reader.config_mut().trim_text(true);
    // component name -> (model kind, connector name -> kind)
    let mut components: HashMap<String, (ModelKind, HashMap<String, String>)> = HashMap::new();
    let mut current: Option<String> = None;
    let mut connections = vec![];
    let mut sources = vec![];
    // The parameter whose value element comes next: component, name, FMI type.
    let mut parameter: Option<(String, String, &str)> = None;
    loop {
        let event = reader.read_event().map_err(|e| format!("not well-formed XML: {e}"))?;
        let e = match &event {
            Event::Start(e) | Event::Empty(e) => e.clone(),
            Event::Eof => break,
            _ => continue,
        };
        let mut attrs = HashMap::new();
        for a in e.attributes() {
            let a = a.map_err(|err| format!("bad attribute: {err}"))?;
            let value = a.normalized_value(quick_xml::XmlVersion::Implicit1_0).map_err(|err| format!("{err}"))?;
            attrs.insert(a.key.as_ref().to_string(), value.into_owned());
        }
        match e.name().as_ref() {
            "ssd:Component" => {
                let name = attrs.get("name").cloned().ok_or("Component without name")?;
                let source = attrs.get("source").cloned().ok_or("Component without source")?;
                let file = source.strip_prefix("resources/").ok_or(format!("{source}: not under resources/"))?;
                let kind = ModelKind::ALL
                    .into_iter()
                    .find(|k| format!("{}.fmu", k.info().model_identifier) == file)
                    .ok_or(format!("{source} is not one of this crate's FMUs"))?;
                sources.push(file.to_string());
                components.insert(name.clone(), (kind, HashMap::new()));
                current = Some(name);
            }
            "ssd:Connector" => {
                let component = current.as_ref().ok_or("Connector outside a Component")?;
                let name = attrs.get("name").cloned().ok_or("Connector without name")?;
                let kind = attrs.get("kind").cloned().ok_or("Connector without kind")?;
                let (model, connectors) = components.get_mut(component).ok_or("unknown component")?;
                let table = VariableTable::new(model.info().groups);
                let (group, _) = table
                    .elements()
                    .map(|(_, g, i)| (g, g.element_name(i)))
                    .find(|(_, n)| *n == name)
                    .ok_or(format!("{component}.{name} is not a variable of {}", model.info().model_identifier))?;
                let expected = match group.causality {
                    Causality::Input => "input",
                    Causality::Output => "output",
                    _ => "parameter",
                };
                if kind != expected {
                    return Err(format!("{component}.{name} is declared {kind} but is an {expected}"));
                }
                connectors.insert(name, kind);
            }
            "ssv:Parameter" => {
                let component = current.as_ref().ok_or("Parameter outside a Component")?;
                let name = attrs.get("name").cloned().ok_or("Parameter without name")?;
                let (model, _) = components.get(component).ok_or("unknown component")?;
                let table = VariableTable::new(model.info().groups);
                let (group, _) = table
                    .elements()
                    .map(|(_, g, i)| (g, g.element_name(i)))
                    .find(|(_, n)| *n == name)
                    .ok_or(format!("{component}: {name} is not a variable of {}", model.info().model_identifier))?;
                if group.causality != Causality::Parameter {
                    return Err(format!("{component}.{name} is bound a value but is not a parameter"));
                }
                let kind = match group.var_type {
                    VariableType::Real => "Real",
                    VariableType::Boolean => "Boolean",
                    VariableType::String => "String",
                    _ => "Integer",
                };
                parameter = Some((component.clone(), name, kind));
            }
            "ssv:Real" | "ssv:Integer" | "ssv:Boolean" | "ssv:String" => {
                let (component, name, kind) = parameter.take().ok_or("a value outside a Parameter")?;
                let element = e.name().as_ref().to_string();
                if element.strip_prefix("ssv:") != Some(kind) {
                    return Err(format!("{component}.{name} is a {kind} parameter, bound an {element}"));
                }
                attrs.get("value").ok_or(format!("{component}.{name}: value without value"))?;
            }
            "ssd:Connection" => {
                let get = |k: &str| attrs.get(k).cloned().ok_or(format!("Connection without {k}"));
                connections.push((
                    get("startElement")?,
                    get("startConnector")?,
                    get("endElement")?,
                    get("endConnector")?,
                ));
            }
            _ => {}
        }
    }
    for (se, sc, ee, ec) in &connections {
        let kind = |e: &String, c: &String| components.get(e).and_then(|(_, m)| m.get(c)).cloned();
        if kind(se, sc).as_deref() != Some("output") || kind(ee, ec).as_deref() != Some("input") {
            return Err(format!("connection {se}.{sc} -> {ee}.{ec} must join a declared output to a declared input"));
        }
    }
    if connections.is_empty() {
        return Err("no connections".into());
    }
    Ok(sources)
}
