//! The FMI 3.0 `modelDescription.xml`, and the order of its continuous states.

use std::fmt::Write;

use super::*;
use crate::models::variables::{Causality, Dependency, VariableTable, VariableType};
use crate::models::{ModelInfo, ModelKind};

/// FMI 3's continuous states in the order of its `<ContinuousStateDerivative>` elements:
/// the state variables of `info.states` in order of first appearance, each whole (arrays
/// row-major). Returns, for each position, the index in the model's state vector.
pub fn fmi3_state_order(info: &ModelInfo) -> Vec<usize> {
    let mut order = Vec::with_capacity(info.states.len());
    for group in fmi3_state_groups(info) {
        let Some(g) = info.groups.iter().find(|g| g.name == group) else { continue };
        for element in 0..g.len() {
            if let Some(i) = info.states.iter().position(|&(name, e)| name == group && e == element) {
                order.push(i);
            }
        }
    }
    order
}

/// The state variables in order of first appearance in `info.states`.
pub(super) fn fmi3_state_groups(info: &ModelInfo) -> Vec<&'static str> {
    let mut groups: Vec<&'static str> = vec![];
    for (name, _) in info.states {
        if !groups.contains(name) {
            groups.push(name);
        }
    }
    groups
}

/// Value references of the variables a dependency list names (FMI 3: whole variables).
pub(super) fn dependency_vrs(info: &ModelInfo, deps: &[Dependency]) -> Vec<u32> {
    let mut out: Vec<u32> =
        Dependency::knowns(deps).iter().filter_map(|&(g, _)| info.groups.get(g)).map(|g| g.first_vr).collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The FMI 3 model description: arrays where FMI 2 has structured names.
pub(super) fn render_fmi3(kind: ModelKind, token: &str) -> String {
    let info = kind.info();
    let caps = info.capabilities;
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="3.0" modelName="{}" instantiationToken="{}" description="{}" author="stewart_fmu developers" version="{}" generationTool="stewart_fmu {} (build-fmu)" variableNamingConvention="structured">"#,
        xml_escape(info.model_name),
        token,
        xml_escape(info.description),
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_VERSION"),
    );
    let directional = caps.directional_derivatives;
    let adjoint = caps.adjoint_derivatives;
    if caps.model_exchange {
        let _ = writeln!(
            x,
            r#"  <ModelExchange modelIdentifier="{}" needsExecutionTool="false" canBeInstantiatedOnlyOncePerProcess="false" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="{directional}" providesAdjointDerivatives="{adjoint}" needsCompletedIntegratorStep="true"/>"#,
            info.model_identifier
        );
    }
    let events = caps.event_indicators > 0;
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" needsExecutionTool="false" canBeInstantiatedOnlyOncePerProcess="false" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="{directional}" providesAdjointDerivatives="{adjoint}" canHandleVariableCommunicationStepSize="true" maxOutputDerivativeOrder="{}" providesIntermediateUpdate="{events}" canReturnEarlyAfterIntermediateUpdate="{events}" hasEventMode="{events}"/>"#,
        info.model_identifier, caps.max_output_derivative_order
    );
    unit_definitions(&mut x, info, |_| true);
    log_categories_and_experiment(&mut x, info);

    let _ = writeln!(x, "  <ModelVariables>");
    for g in info.groups {
        let element = match g.var_type {
            VariableType::Real => "Float64",
            VariableType::Integer | VariableType::Enumeration(_) => "Int32",
            VariableType::Boolean => "Boolean",
            VariableType::String => "String",
        };
        let mut attrs = format!(
            r#"name="{}" valueReference="{}" description="{}" causality="{}" variability="{}""#,
            xml_escape(&g.variable_name()),
            g.first_vr,
            xml_escape(g.description),
            g.causality.xml(),
            g.variability.xml()
        );
        if let Some(initial) = g.initial {
            let _ = write!(attrs, r#" initial="{}""#, initial.xml());
        }
        if let Some(u) = g.unit {
            let _ = write!(attrs, r#" unit="{}""#, xml_escape(u));
        }
        if let Some(u) = g.display_unit {
            let _ = write!(attrs, r#" displayUnit="{}""#, xml_escape(u));
        }
        if let Some((lo, hi)) = g.range {
            let _ = write!(attrs, r#" min="{}" max="{}""#, format_real(lo), format_real(hi));
        }
        if let Some(of) = g.derivative_of
            && let Some((_, state)) = table.group(of)
        {
            let _ = write!(attrs, r#" derivative="{}""#, state.first_vr);
        }
        // FMI 3 gives a String's start as child elements, not as an attribute.
        let mut string_starts = Vec::new();
        if g.has_start() && g.var_type == VariableType::String {
            for i in 0..g.len() {
                if let Some((_, r)) = table.lookup(g.vr(i)) {
                    string_starts.push(model.get_string(r).unwrap_or_default());
                }
            }
        } else if g.has_start() {
            let values: Vec<String> = (0..g.len())
                .filter_map(|i| table.lookup(g.vr(i)))
                .map(|(_, r)| match g.var_type {
                    VariableType::Real => format_real(model.get_real(r)),
                    VariableType::Boolean => model.get_boolean(r).to_string(),
                    _ => model.get_integer(r).to_string(),
                })
                .collect();
            let _ = write!(attrs, r#" start="{}""#, values.join(" "));
        }
        if !string_starts.is_empty() {
            let _ = write!(x, "    <{element} {attrs}>");
            for n in g.shape {
                let _ = write!(x, r#"<Dimension start="{n}"/>"#);
            }
            for s in &string_starts {
                let _ = write!(x, r#"<Start value="{}"/>"#, xml_escape(s));
            }
            let _ = writeln!(x, "</{element}>");
        } else if g.shape.is_empty() {
            let _ = writeln!(x, "    <{element} {attrs}/>");
        } else {
            let _ = write!(x, "    <{element} {attrs}>");
            for n in g.shape {
                let _ = write!(x, r#"<Dimension start="{n}"/>"#);
            }
            let _ = writeln!(x, "</{element}>");
        }
    }
    let _ = writeln!(x, "  </ModelVariables>");

    let _ = writeln!(x, "  <ModelStructure>");
    for g in info.groups.iter().filter(|g| g.causality == Causality::Output) {
        let deps = dependency_vrs(info, g.output_dependencies);
        let _ = writeln!(x, r#"    <Output valueReference="{}" dependencies="{}"/>"#, g.first_vr, join(&deps));
    }
    let state_groups = fmi3_state_groups(info);
    for state in &state_groups {
        if let Some(d) = info.groups.iter().find(|g| g.derivative_of == Some(*state)) {
            let deps = dependency_vrs(info, d.derivative_dependencies);
            let _ = writeln!(
                x,
                r#"    <ContinuousStateDerivative valueReference="{}" dependencies="{}"/>"#,
                d.first_vr,
                join(&deps)
            );
        }
    }
    // Initial unknowns: outputs calculated in Initialization Mode, and the continuous states
    // and their derivatives.
    for g in info.groups.iter().filter(|g| {
        g.is_initial_unknown()
            && (g.causality == Causality::Output || state_groups.contains(&g.name) || g.derivative_of.is_some())
    }) {
        let deps = dependency_vrs(info, g.initial_dependencies);
        let _ = writeln!(x, r#"    <InitialUnknown valueReference="{}" dependencies="{}"/>"#, g.first_vr, join(&deps));
    }
    if caps.event_indicators > 0
        && let Some(g) = info.groups.iter().find(|g| g.name == EVENT_INDICATORS)
    {
        let _ = writeln!(x, r#"    <EventIndicator valueReference="{}"/>"#, g.first_vr);
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

/// Name of the FMI 3 variable that holds a model's event indicators.
pub const EVENT_INDICATORS: &str = "eventIndicators";
