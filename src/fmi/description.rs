//! `modelDescription.xml` of both FMI versions, the instantiation tokens and
//! `documentation/index.html`, all generated from the models' variable tables and
//! capabilities, so that the XML, the binary and the documentation cannot disagree. The
//! committed copies under `modelDescription/` (`fmi3/` for FMI 3) are checked against this by
//! the build program and by `cargo test`.

use std::collections::BTreeSet;
use std::fmt::Write;
use std::sync::OnceLock;

use super::FmiVersion;
use super::log::LogCategory;
use crate::models::variables::{Causality, Dependency, VariableGroup, VariableTable, VariableType};
use crate::models::{ModelInfo, ModelKind};

/// A digest of everything the model description of `kind` is made of (identity, every
/// variable with its attributes, dependencies and start value, units, capabilities, log
/// categories, crate and FMI version): any change of the interface changes it. Eight bytes at
/// a time, so that instantiation can afford it (a few microseconds).
fn digest(kind: ModelKind, version: FmiVersion) -> (u64, u64) {
    let info = kind.info();
    let table = VariableTable::new(info.groups);
    let mut model = kind.instantiate();
    let mut d = Digest::default();
    d.text(env!("CARGO_PKG_VERSION"));
    d.word(version as u64);
    d.text(info.model_name);
    d.text(info.model_identifier);
    d.text(info.description);
    let c = &info.capabilities;
    for flag in [c.model_exchange, c.directional_derivatives, c.adjoint_derivatives, c.can_interpolate_inputs] {
        d.word(flag as u64);
    }
    d.word(c.max_output_derivative_order as u64);
    d.word(c.event_indicators as u64);
    let e = info.default_experiment;
    for x in [e.start_time, e.stop_time, e.step_size] {
        d.word(x.to_bits());
    }
    for u in info.units {
        d.text(u.name);
        for b in u.base {
            d.word(b as u64);
        }
        for (name, factor) in u.display_units {
            d.text(name);
            d.word(factor.to_bits());
        }
    }
    for cat in LogCategory::ALL {
        d.text(cat.name());
        d.text(cat.description());
    }
    for (n, (group, element)) in info.states.iter().enumerate() {
        d.word(n as u64);
        d.text(group);
        d.word(*element as u64);
    }
    for g in info.groups {
        d.text(g.name);
        for &n in g.shape {
            d.word(n as u64);
        }
        d.word(g.first_vr as u64);
        d.text(&format!("{:?}{:?}{:?}{:?}{:?}", g.var_type, g.causality, g.variability, g.initial, g.range));
        d.text(g.unit.unwrap_or(""));
        d.text(g.display_unit.unwrap_or(""));
        d.text(g.description);
        for deps in [g.output_dependencies, g.initial_dependencies, g.derivative_dependencies] {
            for dep in deps {
                d.text(&format!("{dep:?}"));
            }
        }
        d.text(g.derivative_of.unwrap_or(""));
        d.text(&format!("{:?}{}", g.display_base, g.fmi3_only));
        if g.has_start() {
            for i in 0..g.len() {
                let Some((_, r)) = table.lookup(g.vr(i)) else { continue };
                let bits = match g.var_type {
                    VariableType::Real => model.get_real(r).to_bits(),
                    VariableType::Boolean => model.get_boolean(r) as u64,
                    _ => model.get_integer(r) as u64,
                };
                d.word(bits);
            }
        }
    }
    d.finish()
}

/// A word-at-a-time FNV-style hash in two lanes.
struct Digest {
    a: u64,
    b: u64,
}

impl Default for Digest {
    fn default() -> Self {
        Digest { a: 0xcbf2_9ce4_8422_2325, b: 0x8422_2325_cbf2_9ce4 }
    }
}

impl Digest {
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    fn word(&mut self, w: u64) {
        self.a = (self.a ^ w).wrapping_mul(Self::PRIME);
        self.b = (self.b ^ w.rotate_left(29)).wrapping_mul(Self::PRIME).rotate_left(7);
    }

    fn text(&mut self, s: &str) {
        let bytes = s.as_bytes();
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut w = [0u8; 8];
            w.copy_from_slice(c);
            self.word(u64::from_le_bytes(w));
        }
        let mut tail = [0u8; 8];
        for (t, b) in tail.iter_mut().zip(chunks.remainder()) {
            *t = *b;
        }
        self.word(u64::from_le_bytes(tail) ^ (bytes.len() as u64).rotate_left(56));
    }

    fn finish(&self) -> (u64, u64) {
        (self.a, self.b)
    }
}

/// Length of a token: `{8-4-4-4-12}` hexadecimal digits.
const TOKEN_LEN: usize = 38;

/// The tokens, computed on first use (the digest reads every start value, about 27 us) and
/// then only read: a write-once cache per model and FMI version, without heap memory, so
/// `fmi2Instantiate`/`fmi3Instantiate*` compare against a fixed string.
static TOKENS: [[OnceLock<[u8; TOKEN_LEN]>; 2]; ModelKind::ALL.len()] =
    [const { [const { OnceLock::new() }; 2] }; ModelKind::ALL.len()];

/// The instantiation token (FMI 2 GUID) of a model: `{aaaaaaaa-aaaa-KKVV-bbbb-bbbbbbbbbbbb}`
/// from the digest of its description, with the model's kind code `KK` and the FMI version
/// `VV` in the middle group, so that the binary finds the model of a token without trying
/// every model.
pub fn instantiation_token(kind: ModelKind, version: FmiVersion) -> &'static str {
    let v: u8 = match version {
        FmiVersion::Fmi2 => 2,
        FmiVersion::Fmi3 => 3,
    };
    let slot = &TOKENS[kind as usize][usize::from(v - 2)];
    let bytes = slot.get_or_init(|| {
        let (a, b) = digest(kind, version);
        let text = format!(
            "{{{:08x}-{:04x}-{:02x}{:02x}-{:04x}-{:012x}}}",
            a >> 32,
            (a >> 16) & 0xffff,
            kind.code(),
            v,
            b >> 48,
            b & 0xffff_ffff_ffff
        );
        let mut out = [0u8; TOKEN_LEN];
        out.copy_from_slice(&text.as_bytes()[..TOKEN_LEN]);
        out
    });
    // Hexadecimal digits, dashes and braces only: always UTF-8.
    std::str::from_utf8(bytes).unwrap_or_default()
}

/// The model an importer's token belongs to, if it is one of this binary's for `version`.
pub fn model_of_token(token: &str, version: FmiVersion) -> Option<ModelKind> {
    let code = token.get(15..17).and_then(|k| u8::from_str_radix(k, 16).ok())?;
    let kind = ModelKind::ALL.iter().copied().find(|k| k.code() == code)?;
    (instantiation_token(kind, version) == token).then_some(kind)
}

/// The complete `modelDescription.xml` of a model for an FMI version.
pub fn model_description_xml(kind: ModelKind, version: FmiVersion) -> String {
    let token = instantiation_token(kind, version);
    match version {
        FmiVersion::Fmi2 => render_fmi2(kind, token),
        FmiVersion::Fmi3 => render_fmi3(kind, token),
    }
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

fn render_fmi2(kind: ModelKind, guid: &str) -> String {
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

fn join<T: ToString>(v: &[T]) -> String {
    v.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
}

/// `<UnitDefinitions>` with the units the variables that `include` keeps use.
fn unit_definitions(x: &mut String, info: &ModelInfo, include: impl Fn(&VariableGroup) -> bool) {
    let used_units: BTreeSet<&str> = info.groups.iter().filter(|g| include(g)).filter_map(|g| g.unit).collect();
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
}

fn log_categories_and_experiment(x: &mut String, info: &ModelInfo) {
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
}

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
fn fmi3_state_groups(info: &ModelInfo) -> Vec<&'static str> {
    let mut groups: Vec<&'static str> = vec![];
    for (name, _) in info.states {
        if !groups.contains(name) {
            groups.push(name);
        }
    }
    groups
}

/// Value references of the variables a dependency list names (FMI 3: whole variables).
fn dependency_vrs(info: &ModelInfo, deps: &[Dependency]) -> Vec<u32> {
    let mut out: Vec<u32> = deps
        .iter()
        .filter_map(|d| {
            let name = match d {
                Dependency::All(n) | Dependency::SameIndex(n) => *n,
            };
            info.groups.iter().find(|g| g.name == name).map(|g| g.first_vr)
        })
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The FMI 3 model description: arrays where FMI 2 has structured names.
fn render_fmi3(kind: ModelKind, token: &str) -> String {
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
        if g.has_start() {
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
        if g.shape.is_empty() {
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
