//! Describing an FMU's variables once, in Rust, from which come the value-reference lookup,
//! the access rules, the model description XML and the HTML documentation.
//!
//! Arrays are declared as groups (`F` with shape `[6]`, `B` with shape `[6, 3]`); their
//! elements get consecutive value references in row-major order and FMI structured names
//! (`F[1]`, `B[2,3]`, 1-based). The continuous states follow from the derivative declarations
//! (`state_order.rs`: [`states`]).

mod state_order;
pub use state_order::{state_count, states};

/// FMI 2 causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
    Local,
    Independent,
}

impl Causality {
    pub fn xml(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

/// FMI 2 variability.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    Continuous,
}

impl Variability {
    pub fn xml(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

/// FMI 2 `initial` attribute (`None` = attribute omitted, as for inputs and the independent
/// variable).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
}

impl Initial {
    pub fn xml(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }
}

/// An enumeration type (`<TypeDefinitions>`), items numbered from 1.
#[derive(Debug)]
pub struct EnumerationType {
    pub name: &'static str,
    pub description: &'static str,
    /// `(item name, description)`; item `i` (0-based) has value `i + 1`.
    pub items: &'static [(&'static str, &'static str)],
}

/// Type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VariableType {
    Real,
    Integer,
    Boolean,
    Enumeration(&'static str),
    /// A text (a file name); `fmi2GetString`/`fmi3GetString` and the `Set` functions apply.
    String,
}

impl VariableType {
    /// Whether `fmi2GetBoolean`/`fmi2SetBoolean` apply.
    pub fn is_boolean(self) -> bool {
        self == VariableType::Boolean
    }
    /// Whether `fmi2GetReal`/`fmi2SetReal` (true) or the Integer functions apply.
    pub fn is_real(self) -> bool {
        self == VariableType::Real
    }
    /// Whether the String functions apply.
    pub fn is_string(self) -> bool {
        self == VariableType::String
    }
    pub fn is_integer_like(self) -> bool {
        matches!(self, VariableType::Integer | VariableType::Enumeration(_))
    }
}

/// A dependency of an unknown (in `<ModelStructure>`) on a group of knowns, named by its
/// index in the model's table (`group::R`, which `declare_variables!` generates: a name that
/// is not a variable does not compile).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dependency {
    /// Every element of the group.
    All(usize),
    /// The element of the group with the same index (e.g. `r[2]` on `r0[2]`).
    SameIndex(usize),
    /// Every dependency of a list: a concern's knowns (an actuator's parameters, the body's
    /// states), written once and named in every list they belong to.
    Each(&'static [Dependency]),
}

impl Dependency {
    /// Calls `f(group, same_index)` for every known of `deps` in order, lists flattened, each
    /// group an index into the model's table.
    pub fn each_known(deps: &[Dependency], f: &mut impl FnMut(usize, bool)) {
        for d in deps {
            match *d {
                Dependency::All(g) => f(g, false),
                Dependency::SameIndex(g) => f(g, true),
                Dependency::Each(list) => Dependency::each_known(list, f),
            }
        }
    }

    /// The knowns of `deps` as `(group, same_index)`, in order (lists flattened).
    pub fn knowns(deps: &[Dependency]) -> Vec<(usize, bool)> {
        let mut out = vec![];
        Dependency::each_known(deps, &mut |g, same| out.push((g, same)));
        out
    }
}

/// A scalar variable or an array of them.
#[derive(Debug)]
pub struct VariableGroup {
    /// Base name: `F`, `B`, `solver.relTol`.
    pub name: &'static str,
    /// Array shape; empty for a scalar.
    pub shape: &'static [usize],
    /// Value reference of the first element.
    pub first_vr: u32,
    pub var_type: VariableType,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Option<Initial>,
    /// Unit (must be in the model's unit table), or None for none.
    pub unit: Option<&'static str>,
    pub display_unit: Option<&'static str>,
    pub description: &'static str,
    /// For outputs: direct dependencies on inputs in `<Outputs>` (empty: none).
    pub output_dependencies: &'static [Dependency],
    /// For initial unknowns: what the value depends on in Initialization Mode.
    pub initial_dependencies: &'static [Dependency],
    /// `min` and `max` attributes (Real and Integer), if any.
    pub range: Option<(f64, f64)>,
    /// For a derivative variable: the name (table key) of the state group whose elements
    /// these are the time derivatives of, element by element (the `derivative` attribute).
    pub derivative_of: Option<&'static str>,
    /// For `<Derivatives>`: the knowns (states, inputs) the derivative depends on.
    pub derivative_dependencies: &'static [Dependency],
    /// FMI name of a derivative group's elements: `(base, order)` gives `der(base[i])` or
    /// `der(base[i],order)`; the group's `name` is then only a key in the table.
    pub display_base: Option<(&'static str, u8)>,
    /// Only in the FMI 3 model description (a variable FMI 2 expresses otherwise, such as
    /// the event indicators).
    pub fmi3_only: bool,
    /// For a state group of two dimensions: its elements are states column by column (the
    /// special form's `e_b` is column `b` of `R`), not in their row-major index order.
    pub state_by_columns: bool,
}

impl VariableGroup {
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The name of the whole variable (FMI 3, where arrays are variables): `F`, `der(v)`,
    /// `der(R,2)`.
    pub fn variable_name(&self) -> String {
        match self.display_base {
            Some((base, 1)) => format!("der({base})"),
            Some((base, order)) => format!("der({base},{order})"),
            None => self.name.to_string(),
        }
    }

    /// Structured name of element `index` (row-major, 0-based).
    pub fn element_name(&self, index: usize) -> String {
        let base = self.display_base.map_or(self.name, |(b, _)| b);
        let plain = match self.shape {
            [] => base.to_string(),
            [_] => format!("{base}[{}]", index + 1),
            [_, cols] => format!("{base}[{},{}]", index / cols + 1, index % cols + 1),
            _ => format!("{base}[{}]", index + 1),
        };
        match self.display_base {
            Some((_, 1)) => format!("der({plain})"),
            Some((_, order)) => format!("der({plain},{order})"),
            None => plain,
        }
    }

    pub fn vr(&self, index: usize) -> u32 {
        self.first_vr + index as u32
    }

    /// Whether this variable is an initial unknown (listed in `<InitialUnknowns>`): an
    /// output with `initial` approx or calculated (no calculated parameters or ME states here).
    pub fn is_initial_unknown(&self) -> bool {
        matches!(self.causality, Causality::Output | Causality::Local)
            && matches!(self.initial, Some(Initial::Approx | Initial::Calculated))
    }

    /// Whether a start value is written (and must be burned in): exact/approx or inputs.
    pub fn has_start(&self) -> bool {
        self.causality == Causality::Input || matches!(self.initial, Some(Initial::Exact | Initial::Approx))
    }
}

/// A unit: name and SI base-unit exponents `(kg, m, s, A, K, mol, cd, rad)`, with an
/// optional display unit `(name, factor)`.
#[derive(Debug)]
pub struct UnitDefinition {
    pub name: &'static str,
    pub base: [i8; 8],
    pub display_units: &'static [(&'static str, f64)],
}

/// Where the value of a variable comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VariableRef {
    pub group: usize,
    pub index: usize,
}

/// All variables of a model, with an O(1) lookup by value reference.
#[derive(Debug)]
pub struct VariableTable {
    pub groups: &'static [VariableGroup],
    by_vr: Vec<Option<VariableRef>>,
}

impl VariableTable {
    pub fn new(groups: &'static [VariableGroup]) -> Self {
        let max_vr = groups.iter().map(|g| g.first_vr as usize + g.len()).max().unwrap_or(0);
        let mut by_vr = vec![None; max_vr];
        for (gi, g) in groups.iter().enumerate() {
            for i in 0..g.len() {
                if let Some(slot) = by_vr.get_mut(g.vr(i) as usize) {
                    *slot = Some(VariableRef { group: gi, index: i });
                }
            }
        }
        VariableTable { groups, by_vr }
    }

    #[inline]
    pub fn lookup(&self, vr: u32) -> Option<(&'static VariableGroup, VariableRef)> {
        let r = (*self.by_vr.get(vr as usize)?)?;
        Some((self.groups.get(r.group)?, r))
    }

    /// A whole variable by the value reference of its first element (FMI 3 addressing).
    #[inline]
    pub fn lookup_variable(&self, vr: u32) -> Option<(&'static VariableGroup, VariableRef)> {
        let (g, r) = self.lookup(vr)?;
        (r.index == 0).then_some((g, r))
    }

    pub fn group(&self, name: &str) -> Option<(usize, &'static VariableGroup)> {
        self.groups.iter().enumerate().find(|(_, g)| g.name == name)
    }

    /// Every element of FMI 2's `<ModelVariables>` (the variables only FMI 3 declares left out)
    /// in declaration order, with its 1-based index there.
    pub fn elements(&self) -> impl Iterator<Item = (usize, &'static VariableGroup, usize)> + '_ {
        self.groups
            .iter()
            .filter(|g| !g.fmi3_only)
            .flat_map(|g| (0..g.len()).map(move |i| (g, i)))
            .enumerate()
            .map(|(n, (g, i))| (n + 1, g, i))
    }

    /// 1-based index of an element in FMI 2's `<ModelVariables>` (`None` for a variable only
    /// FMI 3 declares).
    pub fn model_index(&self, group_name: &str, index: usize) -> Option<usize> {
        let mut n = 0;
        for g in self.groups.iter().filter(|g| !g.fmi3_only) {
            if g.name == group_name {
                return if index < g.len() { Some(n + index + 1) } else { None };
            }
            n += g.len();
        }
        None
    }

    /// `<ModelStructure>` dependency indices of element `index` of `group`.
    pub fn dependency_indices(&self, deps: &[Dependency], index: usize) -> Vec<usize> {
        let mut out = vec![];
        Dependency::each_known(deps, &mut |g, same| {
            let Some(name) = self.groups.get(g).map(|g| g.name) else { return };
            match same {
                false => out.extend((0..self.groups[g].len()).filter_map(|i| self.model_index(name, i))),
                true => out.extend(self.model_index(name, index)),
            }
        });
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// Constructors for the variable tables (usable in `static` items).
impl VariableGroup {
    /// A fixed Real parameter (`initial="exact"`).
    pub const fn parameter(
        name: &'static str,
        shape: &'static [usize],
        first_vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
    ) -> Self {
        VariableGroup {
            name,
            shape,
            first_vr,
            var_type: VariableType::Real,
            causality: Causality::Parameter,
            variability: Variability::Fixed,
            initial: Some(Initial::Exact),
            unit,
            display_unit: None,
            description,
            output_dependencies: &[],
            initial_dependencies: &[],
            range: None,
            derivative_of: None,
            derivative_dependencies: &[],
            display_base: None,
            fmi3_only: false,
            state_by_columns: false,
        }
    }

    /// A continuous Real input.
    pub const fn input(
        name: &'static str,
        shape: &'static [usize],
        first_vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
    ) -> Self {
        VariableGroup {
            causality: Causality::Input,
            variability: Variability::Continuous,
            initial: None,
            ..Self::parameter(name, shape, first_vr, unit, description)
        }
    }

    /// A continuous Real output, calculated; `initial_dependencies` are the knowns it
    /// depends on in Initialization Mode.
    pub const fn output(
        name: &'static str,
        shape: &'static [usize],
        first_vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
        initial_dependencies: &'static [Dependency],
    ) -> Self {
        VariableGroup {
            causality: Causality::Output,
            variability: Variability::Continuous,
            initial: Some(Initial::Calculated),
            initial_dependencies,
            ..Self::parameter(name, shape, first_vr, unit, description)
        }
    }

    /// The independent variable `time` (no start value).
    pub const fn time(first_vr: u32) -> Self {
        VariableGroup {
            causality: Causality::Independent,
            variability: Variability::Continuous,
            initial: None,
            ..Self::parameter("time", &[], first_vr, Some("s"), "Simulation time")
        }
    }

    pub const fn display(self, display_unit: &'static str) -> Self {
        VariableGroup { display_unit: Some(display_unit), ..self }
    }

    /// An Integer parameter with a range instead of a Real one.
    pub const fn integer(self, min: i32, max: i32) -> Self {
        VariableGroup { var_type: VariableType::Integer, unit: None, range: Some((min as f64, max as f64)), ..self }
    }

    /// A String parameter instead of a Real one.
    pub const fn string(self) -> Self {
        VariableGroup { var_type: VariableType::String, unit: None, ..self }
    }

    /// A Boolean parameter instead of a Real one.
    pub const fn boolean(self) -> Self {
        VariableGroup { var_type: VariableType::Boolean, unit: None, ..self }
    }

    /// A value that changes only at communication points and events (a Boolean output).
    pub const fn discrete(self) -> Self {
        VariableGroup { variability: Variability::Discrete, ..self }
    }

    /// A parameter that may be changed between steps.
    pub const fn tunable(self) -> Self {
        VariableGroup { variability: Variability::Tunable, ..self }
    }

    /// A calculated local variable (a Model Exchange state or derivative that is not an
    /// output).
    pub const fn local(
        name: &'static str,
        shape: &'static [usize],
        first_vr: u32,
        unit: Option<&'static str>,
        description: &'static str,
        initial_dependencies: &'static [Dependency],
    ) -> Self {
        VariableGroup {
            causality: Causality::Local,
            ..Self::output(name, shape, first_vr, unit, description, initial_dependencies)
        }
    }

    /// Marks the group as the time derivative (order `order` of `base`) of the state group
    /// `of`, depending on `dependencies` in `<Derivatives>`.
    pub const fn derivative(
        self,
        of: &'static str,
        base: &'static str,
        order: u8,
        dependencies: &'static [Dependency],
    ) -> Self {
        VariableGroup {
            derivative_of: Some(of),
            display_base: Some((base, order)),
            derivative_dependencies: dependencies,
            ..self
        }
    }

    /// Marks a plainly named group (e.g. `v`) as the derivative of the state group `of`.
    pub const fn derivative_named(self, of: &'static str, dependencies: &'static [Dependency]) -> Self {
        VariableGroup { derivative_of: Some(of), derivative_dependencies: dependencies, ..self }
    }

    /// A two-dimensional state group whose elements are states column by column.
    pub const fn state_by_columns(self) -> Self {
        VariableGroup { state_by_columns: true, ..self }
    }

    /// Only in the FMI 3 model description.
    pub const fn fmi3_only(self) -> Self {
        VariableGroup { fmi3_only: true, ..self }
    }

    /// Direct dependencies of an output on inputs (`<Outputs>`).
    pub const fn depends_on(self, output_dependencies: &'static [Dependency]) -> Self {
        VariableGroup { output_dependencies, ..self }
    }
}
