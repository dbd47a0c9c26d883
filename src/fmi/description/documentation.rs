//! `documentation/index.html` of each FMU.

use std::fmt::Write;

use super::*;
use crate::fmi::FmiVersion;
use crate::fmi::log::LogCategory;
use crate::models::variables::{Causality, VariableGroup, VariableTable, VariableType};
use crate::models::{AnyModel, ModelKind};

/// `documentation/index.html`: the variable table with units, starts and meanings, plus the
/// model's own notes.
pub fn documentation_html(kind: ModelKind, version: FmiVersion) -> String {
    let info = kind.info();
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut h = String::new();
    let interfaces =
        if info.capabilities.model_exchange { "Co-Simulation and Model Exchange" } else { "Co-Simulation" };
    let (standard, token_name) = match version {
        FmiVersion::Fmi2 => ("FMI 2.0", "GUID"),
        FmiVersion::Fmi3 => ("FMI 3.0", "instantiation token"),
    };
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title>\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}}</style></head><body>\n\
         <h1>{0}</h1>\n<p>{1}</p>\n<p>{standard} {interfaces}, model identifier <code>{2}</code>, {token_name} \
         <code>{3}</code>, version {4}.</p>",
        xml_escape(info.model_name),
        xml_escape(info.description),
        info.model_identifier,
        instantiation_token(kind, version),
        env!("CARGO_PKG_VERSION")
    );
    h.push_str(info.documentation);
    let _ = writeln!(
        h,
        "<h2>Variables</h2>\n<table><tr><th>name</th><th>value references</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th><th>meaning</th></tr>"
    );
    for g in info.groups.iter().filter(|g| version == FmiVersion::Fmi3 || !g.fmi3_only) {
        let names = match version {
            FmiVersion::Fmi2 if g.len() == 1 => g.element_name(0),
            FmiVersion::Fmi2 => format!("{} .. {}", g.element_name(0), g.element_name(g.len() - 1)),
            FmiVersion::Fmi3 if g.shape.is_empty() => g.variable_name(),
            FmiVersion::Fmi3 => format!("{}{:?}", g.variable_name(), g.shape),
        };
        let vrs = match version {
            FmiVersion::Fmi2 if g.len() > 1 => format!("{}..{}", g.first_vr, g.vr(g.len() - 1)),
            _ => g.first_vr.to_string(),
        };
        let starts = start_values(&mut model, &table, g).join(", ");
        let ty = type_name(g);
        let unit = unit_text(g);
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

/// The start values of a variable's elements as text (none without a start value).
fn start_values(model: &mut AnyModel, table: &VariableTable, g: &VariableGroup) -> Vec<String> {
    if !g.has_start() {
        return vec![];
    }
    (0..g.len())
        .filter_map(|i| table.lookup(g.vr(i)))
        .map(|(_, r)| {
            if g.var_type.is_real() {
                format_real(model.get_real(r))
            } else if g.var_type.is_boolean() {
                model.get_boolean(r).to_string()
            } else if g.var_type.is_string() {
                format!("{:?}", model.get_string(r).unwrap_or_default())
            } else {
                model.get_integer(r).to_string()
            }
        })
        .collect()
}

fn type_name(g: &VariableGroup) -> String {
    match g.var_type {
        VariableType::Real => "Real".to_string(),
        VariableType::Integer => "Integer".to_string(),
        VariableType::Boolean => "Boolean".to_string(),
        VariableType::String => "String".to_string(),
        VariableType::Enumeration(t) => format!("Enumeration {t}"),
    }
}

fn unit_text(g: &VariableGroup) -> String {
    match (g.unit, g.display_unit) {
        (Some(u), Some(d)) => format!("{u} (display {d})"),
        (Some(u), None) => u.to_string(),
        _ => String::new(),
    }
}

/// The first line of the generated interface table of `kind` in `docs/model.md`.
pub fn interface_table_begin(kind: ModelKind) -> String {
    format!(
        "<!-- the variables of {0}: generated from src/models/*/variables.rs by `build-fmu --update-model-description`; \
         do not edit -->",
        kind.info().model_identifier
    )
}

/// The last line of the generated interface table of `kind` in `docs/model.md`.
pub fn interface_table_end(kind: ModelKind) -> String {
    format!("<!-- end of the variables of {} -->", kind.info().model_identifier)
}

/// The interface table of `kind` for `docs/model.md` (Markdown, between the markers): every
/// variable with its FMI 2 names, causality, type, unit, start and meaning, from the
/// declarations.
pub fn interface_markdown(kind: ModelKind) -> String {
    let info = kind.info();
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut md = String::new();
    let _ = writeln!(md, "{}", interface_table_begin(kind));
    let _ = writeln!(md, "| name | causality | type | unit | start | meaning |");
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    // Inputs, parameters, outputs, locals, each in declaration order.
    let rank = |g: &&VariableGroup| match g.causality {
        Causality::Input => 0,
        Causality::Parameter => 1,
        Causality::Output => 2,
        Causality::Local => 3,
        Causality::Independent => 4,
    };
    let mut groups: Vec<&VariableGroup> = info.groups.iter().collect();
    groups.sort_by_key(rank);
    for g in groups {
        let ranges: Vec<String> = g.shape.iter().map(|n| format!("1..{n}")).collect();
        let base = g.display_base.map_or(g.name, |(b, _)| b);
        let element = if ranges.is_empty() { base.to_string() } else { format!("{base}[{}]", ranges.join(",")) };
        let name = match g.display_base {
            Some((_, 1)) => format!("der({element})"),
            Some((_, order)) => format!("der({element},{order})"),
            None => element,
        };
        let mut causality = g.causality.xml().to_string();
        if g.variability == crate::models::variables::Variability::Tunable {
            causality = format!("tunable {causality}");
        }
        if g.fmi3_only {
            causality.push_str(" (FMI 3 only)");
        }
        let starts = start_values(&mut model, &table, g);
        let start = match starts.as_slice() {
            [] => String::new(),
            [first, rest @ ..] if rest.iter().all(|x| x == first) && !rest.is_empty() => format!("{first} (each)"),
            values if values.len() <= 6 => values.join(", "),
            values => format!("{} values (the FMU's documentation page lists them)", values.len()),
        };
        let _ = writeln!(
            md,
            "| `{name}` | {causality} | {} | {} | {start} | {} |",
            type_name(g),
            unit_text(g),
            g.description.replace('|', "\\|")
        );
    }
    let _ = writeln!(md, "{}", interface_table_end(kind));
    md
}
