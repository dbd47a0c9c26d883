//! What a value reference addresses: the per-instance tables a get or set checks a reference
//! against with one read, and the copies and comparisons of short runs on the fast paths.

use crate::fmi::{FmiVersion, ModelState};
use crate::models::variables::{
    Causality, Dependency, Initial, Variability, VariableGroup, VariableRef, VariableTable, VariableType,
};

/// The base type a get/set function works on (FMI 2 Real/Integer/Boolean, FMI 3
/// Float64/Int32/Boolean).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
    String,
}

impl BaseType {
    pub(super) fn matches(self, t: VariableType) -> bool {
        match self {
            BaseType::Real => t.is_real(),
            BaseType::Integer => t.is_integer_like(),
            BaseType::Boolean => t.is_boolean(),
            BaseType::String => t.is_string(),
        }
    }

    pub(super) fn name(self, version: FmiVersion) -> &'static str {
        match (self, version) {
            (BaseType::Real, FmiVersion::Fmi2) => "Real",
            (BaseType::Real, FmiVersion::Fmi3) => "Float64",
            (BaseType::Integer, FmiVersion::Fmi2) => "Integer",
            (BaseType::Integer, FmiVersion::Fmi3) => "Int32",
            (BaseType::Boolean, _) => "Boolean",
            (BaseType::String, _) => "String",
        }
    }
}

/// What a value reference addresses, precomputed per instance so that a get or set checks a
/// reference with one table read: the element (FMI 2) or the variable's first element and its
/// number of values (FMI 3), its base type, and the states in which it may be set.
#[derive(Clone, Copy, Debug)]
pub(super) struct Access {
    pub(super) group: usize,
    pub(super) index: usize,
    pub(super) width: usize,
    pub(super) base: BaseType,
    /// Bit set over [`ModelState`]: where `fmi2Set*`/`fmi3Set*` may change it.
    pub(super) settable_in: u16,
    /// The block of the value cache a Real variable is read through, or [`NO_CACHE`].
    pub(super) cache: u8,
    /// How many elements of the group, from this one on, consecutive value references
    /// address (FMI 2: to the end of the array; FMI 3: the variable's own width): the
    /// longest run a set of consecutive references may store in one call to the model.
    pub(super) run: usize,
    /// The cache blocks a set of this variable makes stale: for an input, those holding a
    /// value that depends on it (`<ModelStructure>`: the dependencies of outputs, initial
    /// unknowns and derivatives); for anything else every block (parameters change the whole
    /// model).
    pub(super) stales: u32,
}

/// [`Access::cache`] of a variable read through the model element by element.
pub(super) const NO_CACHE: u8 = u8::MAX;

pub(super) fn base_type(t: VariableType) -> BaseType {
    if t.is_real() {
        BaseType::Real
    } else if t.is_boolean() {
        BaseType::Boolean
    } else if t.is_string() {
        BaseType::String
    } else {
        BaseType::Integer
    }
}

/// The access table of a model for one FMI version, indexed by value reference.
/// `cache_block` gives the model's cache block of each group ([`AnyModel::cache_block`]).
pub(super) fn access_table(
    table: &VariableTable,
    version: FmiVersion,
    cache_block: impl Fn(usize) -> Option<u8>,
) -> Vec<Option<Access>> {
    let max_vr = table.groups.iter().map(|g| g.vr(g.len().saturating_sub(1))).max().unwrap_or(0);
    let blocks: Vec<Option<u8>> = (0..table.groups.len()).map(cache_block).collect();
    // The cache blocks holding a value that depends on an input group, by the model's
    // declared structure: outputs, initial unknowns and derivatives.
    let dependants = |input: usize| {
        let on_input = |deps: &[Dependency]| Dependency::knowns(deps).iter().any(|&(g, _)| g == input);
        table.groups.iter().zip(&blocks).fold(0u32, |mask, (g, block)| {
            let knowns = [g.output_dependencies, g.initial_dependencies, g.derivative_dependencies];
            match block {
                Some(b) if knowns.into_iter().any(on_input) => mask | 1 << b,
                _ => mask,
            }
        })
    };
    // Per group: what a set of it makes stale.
    let stales: Vec<u32> = (table.groups.iter().enumerate())
        .map(|(i, g)| if g.causality == Causality::Input { dependants(i) } else { u32::MAX })
        .collect();
    (0..=max_vr)
        .map(|vr| {
            let (g, r) = match version {
                FmiVersion::Fmi2 => table.lookup(vr).filter(|(g, _)| !g.fmi3_only)?,
                FmiVersion::Fmi3 => table.lookup_variable(vr)?,
            };
            let settable_in =
                ModelState::ALL.iter().filter(|&&s| settable_in_state(g, s)).fold(0u16, |m, s| m | s.bit());
            let width = match version {
                FmiVersion::Fmi2 => 1,
                FmiVersion::Fmi3 => g.len(),
            };
            let base = base_type(g.var_type);
            let cache = if base == BaseType::Real { blocks.get(r.group).copied().flatten() } else { None };
            let stales = stales.get(r.group).copied().unwrap_or(u32::MAX);
            Some(Access {
                group: r.group,
                index: r.index,
                width,
                base,
                settable_in,
                cache: cache.unwrap_or(NO_CACHE),
                run: g.len() - r.index,
                stales,
            })
        })
        .collect()
}

/// By element value reference: the cache block each Real element is read through, or
/// [`NO_CACHE`].
pub(super) fn element_blocks(access: &[Option<Access>]) -> Vec<u8> {
    let mut blocks = vec![NO_CACHE; access.len()];
    for (vr, a) in access.iter().enumerate() {
        if let Some(a) = a
            && a.base == BaseType::Real
            && let Some(elements) = blocks.get_mut(vr..vr + a.width)
        {
            elements.fill(a.cache);
        }
    }
    blocks
}

/// By element value reference: the length of the run of elements from it in the same cache
/// block (0 for an element not cached).
pub(super) fn cache_runs(blocks: &[u8]) -> Vec<u16> {
    let mut runs = vec![0u16; blocks.len()];
    for vr in (0..blocks.len()).rev() {
        if blocks[vr] != NO_CACHE {
            let rest = if blocks.get(vr + 1) == Some(&blocks[vr]) { runs[vr + 1] } else { 0 };
            runs[vr] = rest.saturating_add(1);
        }
    }
    runs
}

/// What the fast paths of a get know of a Real element, by element value reference (FMI 2's
/// numbering, the value cache's index): one table, so that a read looks its first reference up
/// once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct CachedElement {
    /// The element's cache block, or [`NO_CACHE`].
    pub(super) block: u8,
    /// How many consecutive elements from this one lie in its cache block (0: not cached).
    pub(super) run: u16,
}

pub(super) fn cached_elements(access: &[Option<Access>]) -> Vec<CachedElement> {
    let blocks = element_blocks(access);
    let runs = cache_runs(&blocks);
    blocks.into_iter().zip(runs).map(|(block, run)| CachedElement { block, run }).collect()
}

/// `0, 1, 2, ...`: a run of consecutive value references is a slice of it.
pub(super) static COUNTING: [u32; 1024] = {
    let mut c = [0; 1024];
    let mut i = 0;
    while i < c.len() {
        c[i] = i as u32;
        i += 1;
    }
    c
};

/// Whether value references are consecutive (`vrs[i] = vrs[0] + i`, wrapping): compared with
/// the run of [`COUNTING`] that starts at `vrs[0]`, beyond it with the counting itself (a
/// table read is cheaper than counts built in registers).
#[inline(always)]
pub(super) fn consecutive(vrs: &[u32]) -> bool {
    let Some(&first) = vrs.first() else { return false };
    match COUNTING.get(first as usize..first as usize + vrs.len()) {
        Some(run) => same_u32(run, vrs),
        None => vrs.iter().enumerate().fold(0, |diff, (i, &vr)| diff | (vr ^ first.wrapping_add(i as u32))) == 0,
    }
}

/// `a == b` for slices of one length. From 4 to 16 elements (a dozen references in a read
/// or set), two overlapping fixed-size comparisons of the ends, without early exit, as libc's
/// `memcmp` does inside but without its call.
#[inline(always)]
pub(super) fn same_u32(a: &[u32], b: &[u32]) -> bool {
    match a.len() {
        8..=16 => ends_equal::<8>(a, b),
        4..=7 => ends_equal::<4>(a, b),
        _ => a == b,
    }
}

/// Whether the first and the last `K` elements of `a` and `b` (of one length, at least `K`)
/// agree.
#[inline(always)]
pub(super) fn ends_equal<const K: usize>(a: &[u32], b: &[u32]) -> bool {
    match (a.first_chunk::<K>(), b.first_chunk::<K>(), a.last_chunk::<K>(), b.last_chunk::<K>()) {
        // `&`, not `&&`: both compared without a branch between them.
        (Some(a0), Some(b0), Some(a1), Some(b1)) => (a0 == b0) & (a1 == b1),
        _ => false,
    }
}

/// `to.copy_from_slice(from)`. From 2 to 16 values (a read of a dozen outputs), two
/// overlapping fixed-size copies of the ends, as libc's `memcpy` does inside but without its
/// call.
#[inline(always)]
pub(super) fn copy_f64(to: &mut [f64], from: &[f64]) {
    match to.len() {
        8..=16 => copy_ends::<8>(to, from),
        4..=7 => copy_ends::<4>(to, from),
        2..=3 => copy_ends::<2>(to, from),
        _ => to.copy_from_slice(from),
    }
}

/// Copies the first and the last `K` values of `from` into `to` (of one length, at least `K`).
#[inline(always)]
pub(super) fn copy_ends<const K: usize>(to: &mut [f64], from: &[f64]) {
    if let (Some(t), Some(f)) = (to.first_chunk_mut::<K>(), from.first_chunk::<K>()) {
        *t = *f;
    }
    if let (Some(t), Some(f)) = (to.last_chunk_mut::<K>(), from.last_chunk::<K>()) {
        *t = *f;
    }
}

/// Whether a variable may be set in a state (FMI 2.0 conditions 1, 3, 6 of the CS table; 1, 3,
/// 4, 5 of the ME table; the same rules in FMI 3).
pub(super) fn settable_in_state(g: &VariableGroup, state: ModelState) -> bool {
    if g.variability == Variability::Constant || g.causality == Causality::Independent {
        return false;
    }
    let exact_or_approx = matches!(g.initial, Some(Initial::Exact | Initial::Approx));
    match state {
        ModelState::Instantiated => exact_or_approx || g.causality == Causality::Input,
        ModelState::InitializationMode => g.initial == Some(Initial::Exact) || g.causality == Causality::Input,
        ModelState::StepComplete | ModelState::EventMode => {
            g.causality == Causality::Input
                || (g.causality == Causality::Parameter && g.variability == Variability::Tunable)
        }
        ModelState::ContinuousTimeMode => g.causality == Causality::Input && g.variability == Variability::Continuous,
        _ => false,
    }
}

/// The elements addressed by `vrs` in order: one per reference in FMI 2, every element of
/// each referenced variable in FMI 3. Unknown references are skipped (callers check first).
pub(super) fn elements<'a>(access: &'a [Option<Access>], vrs: &'a [u32]) -> impl Iterator<Item = VariableRef> + 'a {
    // A plain state machine rather than `flat_map`: this runs on every get and set.
    let mut refs = vrs.iter();
    let mut current: Option<(Access, usize)> = None;
    std::iter::from_fn(move || {
        loop {
            if let Some((a, i)) = current.as_mut()
                && *i < a.width
            {
                *i += 1;
                return Some(VariableRef { group: a.group, index: a.index + *i - 1 });
            }
            current = access.get(*refs.next()? as usize).copied().flatten().map(|a| (a, 0));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::ModelKind;

    /// The cache blocks a set of the named group's first element makes stale, for a model
    /// whose groups `cached` (by name) sit in the given blocks.
    fn stales(kind: ModelKind, cached: &[(&str, u8)], set: &str) -> u32 {
        let table = VariableTable::new(kind.info().groups);
        let block = |g: usize| cached.iter().find(|(name, _)| table.groups[g].name == *name).map(|&(_, b)| b);
        let access = access_table(&table, FmiVersion::Fmi2, block);
        let (_, g) = table.group(set).expect("group");
        access[g.first_vr as usize].expect("access").stales
    }

    #[test]
    fn a_set_makes_stale_exactly_the_cached_values_that_depend_on_it() {
        // The platform's leg lengths and rates depend on the state only; its accelerations
        // (Model Exchange derivatives) on the leg forces too; a parameter changes everything.
        let platform = [("l", 0), ("ldot", 0), ("der(v)", 3)];
        assert_eq!(stales(ModelKind::Platform, &platform, "F"), 1 << 3);
        assert_eq!(stales(ModelKind::Platform, &platform[..2], "F"), 0);
        assert_eq!(stales(ModelKind::Platform, &platform, "M"), u32::MAX);
        // The controller's force command feeds its inputs through.
        assert_eq!(stales(ModelKind::Controller, &[("F", 0)], "l"), 1 << 0);
        assert_eq!(stales(ModelKind::Controller, &[("F", 0), ("rp", 1)], "pose.r"), (1 << 0) | (1 << 1));
    }

    #[test]
    fn copies_of_every_length_copy_every_value() {
        for n in 0..=20 {
            let from: Vec<f64> = (0..n).map(|i| i as f64 + 0.5).collect();
            let mut to = vec![f64::NAN; n];
            copy_f64(&mut to, &from);
            assert_eq!(to, from, "{n} values");
        }
    }

    #[test]
    fn runs_of_cached_elements_and_consecutive_references() {
        assert_eq!(cache_runs(&[NO_CACHE, 0, 0, 1, NO_CACHE, 1]), vec![0, 2, 1, 1, 0, 1]);
        assert!(consecutive(&[7, 8, 9, 10, 11, 12, 13, 14, 15, 16]));
        assert!(!consecutive(&[7, 8, 9, 10, 11, 12, 13, 14, 16, 15]));
        assert!(!consecutive(&[]));
        // Past the counting table's end: the element-by-element pass.
        assert!(consecutive(&[1020, 1021, 1022, 1023, 1024, 1025]));
        assert!(!consecutive(&[1020, 1021, 1022, 1023, 1024, 1024]));
        assert!(consecutive(&[u32::MAX, 0, 1]));
        assert!(!consecutive(&[u32::MAX, 1]));
        // Every length up to 20 (the fixed-size halves from 4 to 16, overlapping from 9), and
        // one wrong reference at every place.
        for n in 1..=20u32 {
            for start in [0, 1020, u32::MAX - 5] {
                let run: Vec<u32> = (0..n).map(|i| start.wrapping_add(i)).collect();
                assert!(consecutive(&run), "{run:?}");
                for k in 1..n as usize {
                    let mut wrong = run.clone();
                    wrong[k] = wrong[k].wrapping_add(1);
                    assert!(!consecutive(&wrong), "{wrong:?}");
                }
            }
        }
    }
}
