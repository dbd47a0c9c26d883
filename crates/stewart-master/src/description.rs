//! What a master needs of an FMI 2 model description: the GUID, the Co-Simulation model
//! identifier, the variables (name, value reference, type, causality) and, from the model
//! structure, which outputs depend directly on inputs (direct feed-through), which decides the
//! order of a Gauss-Seidel step.

use std::collections::HashMap;

use crate::xml;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Type {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration,
}

#[derive(Clone, Debug)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    pub kind: Type,
    pub causality: String,
    /// Outputs: the value references of the inputs the value depends on directly (empty: none).
    pub feeds_from: Vec<u32>,
}

#[derive(Clone, Debug)]
pub struct ModelDescription {
    pub model_name: String,
    pub guid: String,
    pub model_identifier: String,
    pub variables: Vec<Variable>,
    index: HashMap<String, usize>,
}

impl ModelDescription {
    pub fn parse(text: &str) -> Result<ModelDescription, String> {
        let root = xml::parse(text).map_err(|e| format!("modelDescription.xml: {e}"))?;
        if root.name != "fmiModelDescription" {
            return Err(format!(
                "modelDescription.xml: the root element is <{}>, not <fmiModelDescription>",
                root.name
            ));
        }
        let version = root.attribute("fmiVersion").unwrap_or("");
        if version != "2.0" {
            return Err(format!(
                "modelDescription.xml: fmiVersion {version:?}: this master imports FMI 2.0 Co-Simulation FMUs"
            ));
        }
        let model_name = root.attribute("modelName").unwrap_or("").to_string();
        let guid = root.attribute("guid").ok_or("modelDescription.xml: no guid")?.to_string();
        let model_identifier = root
            .child("CoSimulation")
            .and_then(|cs| cs.attribute("modelIdentifier"))
            .ok_or_else(|| format!("{model_name}: the FMU does not support Co-Simulation"))?
            .to_string();
        let mut variables = vec![];
        for v in root.child("ModelVariables").map(|m| m.children_named("ScalarVariable")).into_iter().flatten() {
            let name = v.attribute("name").ok_or("a ScalarVariable without a name")?.to_string();
            let value_reference = v
                .attribute("valueReference")
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| format!("{name}: no valid valueReference"))?;
            let kind = match v.children.first().map(|c| c.name.as_str()) {
                Some("Real") => Type::Real,
                Some("Integer") => Type::Integer,
                Some("Boolean") => Type::Boolean,
                Some("String") => Type::String,
                Some("Enumeration") => Type::Enumeration,
                other => return Err(format!("{name}: unknown type element {other:?}")),
            };
            let causality = v.attribute("causality").unwrap_or("local").to_string();
            variables.push(Variable { name, value_reference, kind, causality, feeds_from: vec![] });
        }
        // ModelStructure/Outputs: `dependencies` lists 1-based indices of the variables an
        // output depends on; without the attribute it may depend on all of them (FMI 2, 3.2.2.1).
        let inputs: Vec<u32> = variables.iter().filter(|v| v.causality == "input").map(|v| v.value_reference).collect();
        for u in root
            .child("ModelStructure")
            .and_then(|s| s.child("Outputs"))
            .map(|o| o.children_named("Unknown"))
            .into_iter()
            .flatten()
        {
            let Some(index) = u.attribute("index").and_then(|s| s.parse::<usize>().ok()).filter(|&i| i >= 1) else {
                continue;
            };
            let feeds_from = match u.attribute("dependencies") {
                None => inputs.clone(),
                Some(list) => list
                    .split_whitespace()
                    .filter_map(|s| s.parse::<usize>().ok())
                    .filter_map(|d| d.checked_sub(1).and_then(|d| variables.get(d)))
                    .filter(|v| v.causality == "input")
                    .map(|v| v.value_reference)
                    .collect(),
            };
            if let Some(v) = variables.get_mut(index - 1) {
                v.feeds_from = feeds_from;
            }
        }
        let index = variables.iter().enumerate().map(|(i, v)| (v.name.clone(), i)).collect();
        Ok(ModelDescription { model_name, guid, model_identifier, variables, index })
    }

    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.index.get(name).map(|&i| &self.variables[i])
    }

    /// The variable, or a message naming the model and the closest names.
    pub fn find(&self, name: &str) -> Result<&Variable, String> {
        self.variable(name).ok_or_else(|| {
            let stem = name.split('[').next().unwrap_or(name);
            let close: Vec<&str> = self
                .variables
                .iter()
                .map(|v| v.name.as_str())
                .filter(|n| n.split('[').next() == Some(stem))
                .take(3)
                .collect();
            let hint = if close.is_empty() { String::new() } else { format!(" (similar: {})", close.join(", ")) };
            format!("{} has no variable {name:?}{hint}", self.model_name)
        })
    }
}
