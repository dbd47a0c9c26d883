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
use crate::models::variables::{Dependency, VariableGroup, VariableTable, VariableType};
use crate::models::{ModelInfo, ModelKind};

mod documentation;
mod fmi2;
mod fmi3;

pub use documentation::{documentation_html, interface_markdown, interface_table_begin, interface_table_end};
pub use fmi3::fmi3_state_order;

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
        // Each known as `All("r")` or `SameIndex("r0")`, in the order declared (lists flattened).
        for deps in [g.output_dependencies, g.initial_dependencies, g.derivative_dependencies] {
            Dependency::each_known(deps, &mut |known, same| {
                let name = info.groups.get(known).map_or("", |k| k.name);
                d.text(&format!("{}({name:?})", if same { "SameIndex" } else { "All" }));
            });
        }
        d.text(g.derivative_of.unwrap_or(""));
        d.text(&format!("{:?}{}", g.display_base, g.fmi3_only));
        if g.has_start() {
            for i in 0..g.len() {
                let Some((_, r)) = table.lookup(g.vr(i)) else { continue };
                let bits = match g.var_type {
                    VariableType::Real => model.get_real(r).to_bits(),
                    VariableType::Boolean => model.get_boolean(r) as u64,
                    VariableType::String => {
                        d.text(&model.get_string(r).unwrap_or_default());
                        0
                    }
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

/// The tokens, computed on first use (the digest reads every start value) and
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
        FmiVersion::Fmi2 => fmi2::render_fmi2(kind, token),
        FmiVersion::Fmi3 => fmi3::render_fmi3(kind, token),
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

pub(super) fn join<T: ToString>(v: &[T]) -> String {
    v.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
}

/// `<UnitDefinitions>` with the units the variables that `include` keeps use.
pub(super) fn unit_definitions(x: &mut String, info: &ModelInfo, include: impl Fn(&VariableGroup) -> bool) {
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

pub(super) fn log_categories_and_experiment(x: &mut String, info: &ModelInfo) {
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

/// `text` (a page of `docs/`) with the generated interface table of `kind` put in place of
/// the one between its markers; `None` if the markers are missing.
pub fn with_interface_table(text: &str, kind: ModelKind) -> Option<String> {
    let (begin, end) = (interface_table_begin(kind), interface_table_end(kind));
    let start = text.find(&begin)?;
    let stop = text[start..].find(&end)? + start + end.len() + 1;
    Some(format!("{}{}{}", &text[..start], interface_markdown(kind), text.get(stop..).unwrap_or("")))
}
