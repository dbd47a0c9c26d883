//! The FMI 2.0 `modelDescription.xml`.

use std::fmt::Write;

use super::*;
use crate::models::ModelKind;
use crate::models::variables::{Causality, VariableTable, VariableType};

pub(super) fn render_fmi2(kind: ModelKind, guid: &str) -> String {
    let info = kind.info();
    let caps = info.capabilities;
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" author="stewart_fmu developers" version="{}" generationTool="stewart_fmu {} (build-fmu)" variableNamingConvention="structured" numberOfEventIndicators="{}">"#,
        xml_escape(info.model_name),
        guid,
        xml_escape(info.description),
        env!("CARGO_PKG_VERSION"),
        env!("CARGO_PKG_VERSION"),
        caps.event_indicators,
    );
    let directional = caps.directional_derivatives;
    if caps.model_exchange {
        let _ = writeln!(
            x,
            r#"  <ModelExchange modelIdentifier="{}" needsExecutionTool="false" completedIntegratorStepNotNeeded="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="{directional}"/>"#,
            info.model_identifier
        );
    }
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="{}" maxOutputDerivativeOrder="{}" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="{directional}"/>"#,
        info.model_identifier, caps.can_interpolate_inputs, caps.max_output_derivative_order
    );

    unit_definitions(&mut x, info, |g| !g.fmi3_only);

    if !info.enumerations.is_empty() {
        let _ = writeln!(x, "  <TypeDefinitions>");
        for e in info.enumerations {
            let _ = writeln!(
                x,
                r#"    <SimpleType name="{}" description="{}">"#,
                xml_escape(e.name),
                xml_escape(e.description)
            );
            let _ = writeln!(x, "      <Enumeration>");
            for (i, (item, desc)) in e.items.iter().enumerate() {
                let _ = writeln!(
                    x,
                    r#"        <Item name="{}" value="{}" description="{}"/>"#,
                    xml_escape(item),
                    i + 1,
                    xml_escape(desc)
                );
            }
            let _ = writeln!(x, "      </Enumeration>");
            let _ = writeln!(x, "    </SimpleType>");
        }
        let _ = writeln!(x, "  </TypeDefinitions>");
    }

    log_categories_and_experiment(&mut x, info);

    let _ = writeln!(x, "  <ModelVariables>");
    for (n, g, i) in table.elements().filter(|(_, g, _)| !g.fmi3_only) {
        let mut attrs = format!(
            r#"name="{}" valueReference="{}" description="{}" causality="{}" variability="{}""#,
            xml_escape(&g.element_name(i)),
            g.vr(i),
            xml_escape(g.description),
            g.causality.xml(),
            g.variability.xml()
        );
        if let Some(initial) = g.initial {
            let _ = write!(attrs, r#" initial="{}""#, initial.xml());
        }
        let start = if g.has_start() {
            let var = table.lookup(g.vr(i)).map(|(_, r)| r);
            match (g.var_type, var) {
                (VariableType::Real, Some(v)) => {
                    format!(r#" start="{}""#, format_real(model.get_real(v)))
                }
                (VariableType::Integer | VariableType::Enumeration(_), Some(v)) => {
                    format!(r#" start="{}""#, model.get_integer(v))
                }
                (VariableType::Boolean, Some(v)) => format!(r#" start="{}""#, model.get_boolean(v)),
                (VariableType::String, Some(v)) => {
                    format!(r#" start="{}""#, xml_escape(&model.get_string(v).unwrap_or_default()))
                }
                _ => String::new(),
            }
        } else {
            String::new()
        };
        let unit = g.unit.map(|u| format!(r#" unit="{}""#, xml_escape(u))).unwrap_or_default();
        let display = g.display_unit.map(|u| format!(r#" displayUnit="{}""#, xml_escape(u))).unwrap_or_default();
        let range = g
            .range
            .map(|(lo, hi)| format!(r#" min="{}" max="{}""#, format_real(lo), format_real(hi)))
            .unwrap_or_default();
        let derivative = g
            .derivative_of
            .and_then(|of| table.model_index(of, i))
            .map(|k| format!(r#" derivative="{k}""#))
            .unwrap_or_default();
        let element = match g.var_type {
            VariableType::Real => format!("<Real{unit}{display}{range}{derivative}{start}/>"),
            VariableType::Integer => format!("<Integer{range}{start}/>"),
            VariableType::Boolean => format!("<Boolean{start}/>"),
            VariableType::String => format!("<String{start}/>"),
            VariableType::Enumeration(t) => {
                format!(r#"<Enumeration declaredType="{}"{start}/>"#, xml_escape(t))
            }
        };
        let _ = writeln!(x, "    <!-- index {n} -->");
        let _ = writeln!(x, "    <ScalarVariable {attrs}>{element}</ScalarVariable>");
    }
    let _ = writeln!(x, "  </ModelVariables>");

    let _ = writeln!(x, "  <ModelStructure>");
    let _ = writeln!(x, "    <Outputs>");
    for (n, g, i) in table.elements().filter(|(_, g, _)| g.causality == Causality::Output && !g.fmi3_only) {
        let deps = table.dependency_indices(g.output_dependencies, i);
        let _ = writeln!(x, r#"      <Unknown index="{n}" dependencies="{}"/>"#, join(&deps));
    }
    let _ = writeln!(x, "    </Outputs>");
    if !info.states.is_empty() {
        let _ = writeln!(x, "    <Derivatives>");
        for (state_group, element) in info.states {
            let derivative = info.groups.iter().find(|g| g.derivative_of == Some(*state_group));
            if let Some(g) = derivative
                && let Some(n) = table.model_index(g.name, *element)
            {
                let deps = table.dependency_indices(g.derivative_dependencies, *element);
                let _ = writeln!(x, r#"      <Unknown index="{n}" dependencies="{}"/>"#, join(&deps));
            }
        }
        let _ = writeln!(x, "    </Derivatives>");
    }
    let _ = writeln!(x, "    <InitialUnknowns>");
    for (n, g, i) in table.elements().filter(|(_, g, _)| g.is_initial_unknown() && !g.fmi3_only) {
        let deps = table.dependency_indices(g.initial_dependencies, i);
        let _ = writeln!(x, r#"      <Unknown index="{n}" dependencies="{}"/>"#, join(&deps));
    }
    let _ = writeln!(x, "    </InitialUnknowns>");
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}
