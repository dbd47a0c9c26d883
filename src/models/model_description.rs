//! `modelDescription.xml`, the instantiation token (GUID) and `documentation/index.html`,
//! all generated from the models' variable tables, so that the XML, the binary and the
//! documentation cannot disagree. The committed copies under `modelDescription/` are checked
//! against this by the build program and by `cargo test`.

use std::collections::BTreeSet;
use std::fmt::Write;

use super::ModelKind;
use super::snapshot::fnv1a64;
use super::variables::{Causality, VariableTable, VariableType};
use crate::fmi2::logger::LogCategory;

/// Placeholder for the GUID while hashing the description.
const GUID_PLACEHOLDER: &str = "{00000000-0000-0000-0000-000000000000}";

/// The GUID of a model: a hash of its model description (with the GUID itself blanked), so
/// that any change of the interface changes the GUID.
pub fn instantiation_token(kind: ModelKind) -> String {
    let body = render(kind, GUID_PLACEHOLDER);
    let a = fnv1a64(body.as_bytes());
    let b = fnv1a64(&[body.as_bytes(), b"stewart_fmu"].concat());
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// The complete `modelDescription.xml` of a model.
pub fn model_description_xml(kind: ModelKind) -> String {
    render(kind, &instantiation_token(kind))
}

/// XML attribute escaping.
pub fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// A double that reads back to the same bits (`xs:double` syntax).
pub fn format_real(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) { format!("{x}") } else { format!("{x:e}") }
}

fn render(kind: ModelKind, guid: &str) -> String {
    let info = kind.info();
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
        info.event_indicators,
    );
    let directional = info.directional_derivatives;
    if info.model_exchange {
        let _ = writeln!(
            x,
            r#"  <ModelExchange modelIdentifier="{}" needsExecutionTool="false" completedIntegratorStepNotNeeded="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="{directional}"/>"#,
            info.model_identifier
        );
    }
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" needsExecutionTool="false" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true" maxOutputDerivativeOrder="1" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="{directional}"/>"#,
        info.model_identifier
    );

    let used_units: BTreeSet<&str> = info.groups.iter().filter_map(|g| g.unit).collect();
    let _ = writeln!(x, "  <UnitDefinitions>");
    for u in info.units.iter().filter(|u| used_units.contains(u.name)) {
        let _ = write!(x, r#"    <Unit name="{}">"#, xml_escape(u.name));
        let names = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];
        let exps: Vec<String> =
            names.iter().zip(u.base.iter()).filter(|(_, e)| **e != 0).map(|(n, e)| format!(r#" {n}="{e}""#)).collect();
        let _ = write!(x, "<BaseUnit{}/>", exps.concat());
        for (name, factor) in u.display_units {
            let _ = write!(x, r#"<DisplayUnit name="{}" factor="{}"/>"#, xml_escape(name), format_real(*factor));
        }
        let _ = writeln!(x, "</Unit>");
    }
    let _ = writeln!(x, "  </UnitDefinitions>");

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

    let _ = writeln!(x, "  <LogCategories>");
    for c in LogCategory::ALL {
        let _ = writeln!(x, r#"    <Category name="{}" description="{}"/>"#, c.name(), xml_escape(c.description()));
    }
    let _ = writeln!(x, "  </LogCategories>");
    let d = info.default_experiment;
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="{}" stopTime="{}" stepSize="{}"/>"#,
        format_real(d.start_time),
        format_real(d.stop_time),
        format_real(d.step_size)
    );

    let _ = writeln!(x, "  <ModelVariables>");
    for (n, g, i) in table.elements() {
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
    for (n, g, i) in table.elements().filter(|(_, g, _)| g.causality == Causality::Output) {
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
    for (n, g, i) in table.elements().filter(|(_, g, _)| g.is_initial_unknown()) {
        let deps = table.dependency_indices(g.initial_dependencies, i);
        let _ = writeln!(x, r#"      <Unknown index="{n}" dependencies="{}"/>"#, join(&deps));
    }
    let _ = writeln!(x, "    </InitialUnknowns>");
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

fn join(v: &[usize]) -> String {
    v.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
}

/// `documentation/index.html`: the variable table with units, starts and meanings, plus the
/// model's own notes.
pub fn documentation_html(kind: ModelKind) -> String {
    let info = kind.info();
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title>\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}}</style></head><body>\n\
         <h1>{0}</h1>\n<p>{1}</p>\n<p>FMI 2.0 Co-Simulation, model identifier <code>{2}</code>, GUID <code>{3}</code>, \
         version {4}.</p>",
        xml_escape(info.model_name),
        xml_escape(info.description),
        info.model_identifier,
        instantiation_token(kind),
        env!("CARGO_PKG_VERSION")
    );
    h.push_str(info.documentation);
    let _ = writeln!(
        h,
        "<h2>Variables</h2>\n<table><tr><th>name</th><th>value references</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>meaning</th></tr>"
    );
    for g in info.groups {
        let names = if g.len() == 1 {
            g.element_name(0)
        } else {
            format!("{} .. {}", g.element_name(0), g.element_name(g.len() - 1))
        };
        let vrs = if g.len() == 1 { g.first_vr.to_string() } else { format!("{}..{}", g.first_vr, g.vr(g.len() - 1)) };
        let starts = if g.has_start() {
            let vals: Vec<String> = (0..g.len())
                .filter_map(|i| table.lookup(g.vr(i)))
                .map(|(_, r)| {
                    if g.var_type.is_real() {
                        format_real(model.get_real(r))
                    } else if g.var_type.is_boolean() {
                        model.get_boolean(r).to_string()
                    } else {
                        model.get_integer(r).to_string()
                    }
                })
                .collect();
            vals.join(", ")
        } else {
            String::new()
        };
        let ty = match g.var_type {
            VariableType::Real => "Real".to_string(),
            VariableType::Integer => "Integer".to_string(),
            VariableType::Boolean => "Boolean".to_string(),
            VariableType::Enumeration(t) => format!("Enumeration {t}"),
        };
        let unit = match (g.unit, g.display_unit) {
            (Some(u), Some(d)) => format!("{u} (display {d})"),
            (Some(u), None) => u.to_string(),
            _ => String::new(),
        };
        let _ = writeln!(
            h,
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            xml_escape(&names),
            vrs,
            g.causality.xml(),
            g.variability.xml(),
            xml_escape(&ty),
            xml_escape(&unit),
            xml_escape(&starts),
            xml_escape(g.description)
        );
    }
    let _ = writeln!(h, "</table>");
    for e in info.enumerations {
        let _ = writeln!(h, "<h3>{}</h3><p>{}</p><ul>", xml_escape(e.name), xml_escape(e.description));
        for (i, (item, desc)) in e.items.iter().enumerate() {
            let _ = writeln!(h, "<li>{} = <code>{}</code>: {}</li>", i + 1, xml_escape(item), xml_escape(desc));
        }
        let _ = writeln!(h, "</ul>");
    }
    let _ = writeln!(h, "<h2>Log categories</h2><ul>");
    for c in LogCategory::ALL {
        let _ = writeln!(h, "<li><code>{}</code>: {}</li>", c.name(), xml_escape(c.description()));
    }
    let _ = writeln!(h, "</ul>\n</body></html>");
    h
}
