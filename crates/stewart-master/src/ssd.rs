//! An SSP system structure description (SSP 1.0 `SystemStructure.ssd`) as far as this master
//! runs it: one flat system of FMU components in element order, their connectors, their
//! inline parameter bindings (`ssd:ParameterBindings` with `ssv:Parameter` values) and the
//! connections between components. What it does not run (nested systems, connections to the
//! system's own connectors, parameter values in separate files) is refused by name.

use crate::xml::{self, Element};

#[derive(Clone, Debug, PartialEq)]
pub enum ParameterValue {
    Real(f64),
    Integer(i64),
    Boolean(bool),
}

#[derive(Clone, Debug)]
pub struct ComponentDescription {
    pub name: String,
    /// The FMU inside the SSP (`resources/StewartPlatform.fmu`).
    pub source: String,
    /// (name, kind) in document order.
    pub connectors: Vec<(String, String)>,
    pub parameters: Vec<(String, ParameterValue)>,
}

#[derive(Clone, Debug)]
pub struct ConnectionDescription {
    pub start_element: String,
    pub start_connector: String,
    pub end_element: String,
    pub end_connector: String,
}

#[derive(Clone, Debug)]
pub struct SystemDescription {
    pub name: String,
    pub components: Vec<ComponentDescription>,
    pub connections: Vec<ConnectionDescription>,
}

fn required<'a>(e: &'a Element, key: &str, what: &str) -> Result<&'a str, String> {
    e.attribute(key).ok_or_else(|| format!("{what} without the attribute {key}"))
}

fn parameters(component: &Element, name: &str) -> Result<Vec<(String, ParameterValue)>, String> {
    let mut out = vec![];
    for binding in component.children_named("ParameterBindings").flat_map(|b| b.children_named("ParameterBinding")) {
        if let Some(source) = binding.attribute("source") {
            return Err(format!(
                "component {name}: parameter values in a separate file ({source}) are not supported: write them inline"
            ));
        }
        if binding.attribute("prefix").is_some_and(|p| !p.is_empty()) {
            return Err(format!("component {name}: parameter bindings with a prefix are not supported"));
        }
        let sets = binding.children_named("ParameterValues").flat_map(|v| v.children_named("ParameterSet"));
        for parameter in sets.flat_map(|s| s.children_named("Parameters")).flat_map(|p| p.children_named("Parameter")) {
            let pname = required(parameter, "name", "a Parameter")?.to_string();
            let value_element = parameter.children.first().ok_or_else(|| format!("{name}.{pname}: no value"))?;
            let text = required(value_element, "value", &format!("{name}.{pname}"))?;
            let bad = || format!("{name}.{pname}: {text:?} is not a valid {} value", value_element.name);
            let value = match value_element.name.as_str() {
                "Real" => ParameterValue::Real(text.trim().parse().map_err(|_| bad())?),
                "Integer" | "Enumeration" => ParameterValue::Integer(text.trim().parse().map_err(|_| bad())?),
                "Boolean" => ParameterValue::Boolean(match text.trim() {
                    "true" | "1" => true,
                    "false" | "0" => false,
                    _ => return Err(bad()),
                }),
                other => return Err(format!("{name}.{pname}: {other} parameter values are not supported")),
            };
            out.push((pname, value));
        }
    }
    Ok(out)
}

impl SystemDescription {
    pub fn parse(text: &str) -> Result<SystemDescription, String> {
        let root = xml::parse(text).map_err(|e| format!("SystemStructure.ssd: {e}"))?;
        if root.name != "SystemStructureDescription" {
            return Err(format!("the root element is <{}>, not <ssd:SystemStructureDescription>", root.name));
        }
        let system = root.child("System").ok_or("the SSD has no <ssd:System>")?;
        let name = system.attribute("name").unwrap_or("").to_string();
        let mut components = vec![];
        for e in system.child("Elements").map(|e| e.children.as_slice()).unwrap_or_default() {
            let cname = required(e, "name", &format!("an element <{}>", e.name))?.to_string();
            match e.name.as_str() {
                "Component" => {}
                "System" => return Err(format!("element {cname}: nested systems are not supported")),
                other => return Err(format!("element {cname}: <{other}> elements are not supported")),
            }
            let kind = e.attribute("type").unwrap_or("application/x-fmu-sharedlibrary");
            if kind != "application/x-fmu-sharedlibrary" {
                return Err(format!(
                    "component {cname}: type {kind:?}: only FMUs (application/x-fmu-sharedlibrary) are supported"
                ));
            }
            let source = required(e, "source", &format!("component {cname}"))?.to_string();
            let connectors = e
                .child("Connectors")
                .map(|c| c.children_named("Connector").collect::<Vec<_>>())
                .unwrap_or_default()
                .into_iter()
                .map(|c| {
                    Ok((required(c, "name", "a Connector")?.to_string(), c.attribute("kind").unwrap_or("").to_string()))
                })
                .collect::<Result<Vec<_>, String>>()?;
            let parameters = parameters(e, &cname)?;
            components.push(ComponentDescription { name: cname, source, connectors, parameters });
        }
        let mut connections = vec![];
        for c in
            system.child("Connections").map(|c| c.children_named("Connection").collect::<Vec<_>>()).unwrap_or_default()
        {
            let start_connector = required(c, "startConnector", "a Connection")?.to_string();
            let end_connector = required(c, "endConnector", "a Connection")?.to_string();
            let (Some(start_element), Some(end_element)) = (c.attribute("startElement"), c.attribute("endElement"))
            else {
                return Err(format!(
                    "the connection {start_connector} -> {end_connector} joins a connector of the system itself: only \
                     connections between components are supported"
                ));
            };
            for element in [start_element, end_element] {
                if !components.iter().any(|k: &ComponentDescription| k.name == element) {
                    return Err(format!("a connection names the element {element:?}, which the system does not have"));
                }
            }
            connections.push(ConnectionDescription {
                start_element: start_element.to_string(),
                start_connector,
                end_element: end_element.to_string(),
                end_connector,
            });
        }
        Ok(SystemDescription { name, components, connections })
    }
}
