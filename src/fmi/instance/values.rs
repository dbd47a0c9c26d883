//! Getting and setting variables: element by element through the model, or outputs through
//! the value cache, which a step fills again for the blocks the host reads (a read of the
//! same outputs every step is a copy).

use super::Instance;
use super::access::*;
use crate::fmi::{FmiVersion, Status};
use crate::models::AnyModel;
use crate::models::snapshot::{ByteReader, ByteWriter};
use crate::models::variables::VariableRef;
use crate::physics::body::state::all_finite;

impl Instance {
    #[inline(always)]
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        // The fast path once per version, so that each has only its own run check inline.
        let fast = match self.version {
            FmiVersion::Fmi2 => self.get_fresh_run(FmiVersion::Fmi2, vrs, values),
            FmiVersion::Fmi3 => self.get_fresh_run(FmiVersion::Fmi3, vrs, values),
        };
        match fast {
            Some(status) => status,
            None => self.get_real_elementwise(vrs, values),
        }
    }

    /// The fast path of [`Instance::get_real`]: consecutive elements of one cache block (the
    /// legs' lengths and rates) that the step has computed already, one copy. `None`: the
    /// general path (which fills a stale block first). A get that fails leaves its values
    /// undefined (FMI 2.0 section 2.1.3, FMI 3.0 section 2.2.6), so nothing needs validating
    /// before the first is written.
    #[inline(always)]
    pub(super) fn get_fresh_run(&mut self, version: FmiVersion, vrs: &[u32], values: &mut [f64]) -> Option<Status> {
        let (first, block) = self.cached_run(version, vrs, values.len())?;
        let bit = 1u32 << block;
        if self.fresh & bit == 0 {
            return None;
        }
        self.read_since_step |= bit;
        copy_f64(values, self.value_cache.get(first..first + values.len())?);
        Some(if self.nan & bit == 0 { Status::Ok } else { self.check_nan(vrs, values) })
    }

    /// A read of several runs, each of consecutive elements of one cache block that the step
    /// has computed already (the legs and the pose: a few copies, no look-up per element). A
    /// host reads the same references every step: the runs of the last such read are kept
    /// ([`ReadPlan`]), so that the next is a comparison of its references and the copies.
    /// `None`: the general path, which fills a stale block first (the values written so far are
    /// written again).
    #[inline(always)]
    fn get_fresh_runs(&mut self, vrs: &[u32], values: &mut [f64]) -> Option<Status> {
        let plan = &self.read_plan;
        let blocks = if plan.reads(vrs, values.len()) {
            let mut filled = 0;
            for &(first, width) in plan.runs.get(..plan.count)? {
                let (first, width) = (first as usize, width as usize);
                copy_f64(values.get_mut(filled..filled + width)?, self.value_cache.get(first..first + width)?);
                filled += width;
            }
            (self.fresh & plan.blocks == plan.blocks).then_some(plan.blocks)?
        } else {
            self.resolve_runs(vrs, values)?
        };
        self.read_since_step |= blocks;
        Some(if self.nan & blocks == 0 { Status::Ok } else { self.check_nan(vrs, values) })
    }

    /// [`Instance::get_fresh_runs`] of references not read before: each run looked up, copied,
    /// and the runs kept for the next read; the blocks read, or `None`.
    #[inline(never)]
    fn resolve_runs(&mut self, vrs: &[u32], values: &mut [f64]) -> Option<u32> {
        let mut plan = ReadPlan::NONE;
        let (mut at, mut filled, mut blocks) = (0, 0, 0u32);
        while let Some(&vr) = vrs.get(at) {
            let first = vr as usize;
            let CachedElement { block, run } = *self.cached.get(first)?;
            let run = usize::from(run);
            let (width, references) = match self.version {
                FmiVersion::Fmi2 => {
                    // The references from `at` that go on consecutively within the run: all of
                    // them (one comparison), or up to the first that does not.
                    let refs = vrs.get(at..at + run.min(vrs.len() - at))?;
                    let n = if consecutive(refs) {
                        refs.len()
                    } else {
                        refs.iter().zip(first..).take_while(|&(&r, v)| r as usize == v).count()
                    };
                    (n, n)
                }
                FmiVersion::Fmi3 => (self.variable_width.get(first).map_or(0, |&w| w as usize), 1),
            };
            let bit = 1u32.checked_shl(block.into())?;
            if width == 0 || width > run || self.fresh & bit == 0 {
                return None;
            }
            copy_f64(values.get_mut(filled..filled + width)?, self.value_cache.get(first..first + width)?);
            // A run that goes on where the last ended (FMI 3's `l` then `ldot`) extends it.
            match plan.count.checked_sub(1).and_then(|last| plan.runs.get_mut(last)) {
                Some((start, n)) if *start as usize + *n as usize == first => *n += width as u32,
                _ => {
                    if let Some(slot) = plan.runs.get_mut(plan.count) {
                        *slot = (vr, width as u32);
                    }
                    plan.count += 1;
                }
            }
            (at, filled, blocks) = (at + references, filled + width, blocks | bit);
        }
        if filled != values.len() {
            return None;
        }
        if let Some(references) = plan.references.get_mut(..vrs.len())
            && plan.count <= plan.runs.len()
        {
            references.copy_from_slice(vrs);
            (plan.len, plan.values, plan.blocks) = (vrs.len(), filled, blocks);
            self.read_plan = plan;
        }
        Some(blocks)
    }

    /// Fills the cache blocks in `blocks` from the model and notes which hold a NaN.
    #[inline(never)]
    pub(super) fn refresh(&mut self, blocks: u32) {
        let mut rest = blocks;
        while rest != 0 {
            let block = rest.trailing_zeros();
            let nan = self.model.fill_cache(block as u8, &mut self.value_cache);
            debug_assert_eq!(nan, self.block_holds_nan(block), "fill_cache's NaN report, block {block}");
            self.nan = (self.nan & !(1 << block)) | (u32::from(nan) << block);
            rest &= rest - 1;
        }
        self.fresh |= blocks;
    }

    /// Whether an element of cache block `block` is NaN (the check of the models' reports).
    pub(super) fn block_holds_nan(&self, block: u32) -> bool {
        let values = self.value_cache.iter().zip(&self.cached);
        values.filter(|&(_, c)| u32::from(c.block) == block).any(|(x, _)| x.is_nan())
    }

    /// The end of a get whose block holds a NaN somewhere: an error if one was read.
    #[cold]
    pub(super) fn check_nan(&self, vrs: &[u32], values: &[f64]) -> Status {
        if values.iter().any(|x| x.is_nan()) { self.nan_error(vrs, values) } else { Status::Ok }
    }

    /// [`Instance::get_real`] reference by reference (and any read of a stale block). Out of
    /// line, so that the fast path above keeps few registers.
    #[inline(never)]
    pub(super) fn get_real_elementwise(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        if let Some(status) = self.get_fresh_runs(vrs, values) {
            return status;
        }
        if self.version == FmiVersion::Fmi2 && vrs.len() == values.len() {
            // One element per reference: the cache block of each comes from one table. Loops
            // without calls (so the tables stay in registers): which blocks the references
            // need, fill the stale ones, copy. Only a reference outside the cache (or unknown)
            // takes the element-by-element path, alone: a host that reads `kappa` with the leg
            // lengths still gets the lengths copied.
            let cached = &self.cached;
            let uncached = 1u32.wrapping_shl(NO_CACHE.into());
            let mut needed = 0u32;
            for &vr in vrs {
                let block = cached.get(vr as usize).map_or(NO_CACHE, |c| c.block);
                needed |= 1u32.wrapping_shl(block.into());
            }
            let blocks = needed & !uncached;
            self.refresh(blocks & !self.fresh);
            self.read_since_step |= blocks;
            let mut nan = false;
            if needed & uncached == 0 {
                let cache = &self.value_cache;
                for (slot, &vr) in values.iter_mut().zip(vrs) {
                    *slot = cache.get(vr as usize).copied().unwrap_or(f64::NAN);
                    nan |= slot.is_nan();
                }
            } else {
                for (slot, &vr) in values.iter_mut().zip(vrs) {
                    let in_cache = self.cached.get(vr as usize).is_some_and(|c| c.block != NO_CACHE);
                    if in_cache {
                        *slot = self.value_cache.get(vr as usize).copied().unwrap_or(f64::NAN);
                    } else if let Err(s) = self.read_real(vrs, vr, std::slice::from_mut(slot), 0) {
                        return s;
                    }
                    nan |= slot.is_nan();
                }
            }
            return if nan { self.nan_error(vrs, values) } else { Status::Ok };
        }
        let mut filled = 0;
        for &vr in vrs {
            match self.read_real(vrs, vr, values, filled) {
                Ok(width) => filled += width,
                Err(s) => return s,
            }
        }
        if filled != values.len() {
            return self.count_error(vrs, BaseType::Real, values.len());
        }
        if values.iter().any(|x| x.is_nan()) {
            return self.nan_error(vrs, values);
        }
        Status::Ok
    }

    /// When `vrs` address `n` consecutive elements of one cache block (FMI 2: consecutive
    /// references; FMI 3: consecutive variables), the first element's value reference (its
    /// place in the value cache) and the block. `version` is the instance's, passed as a
    /// constant where the caller knows it.
    #[inline(always)]
    pub(super) fn cached_run(&self, version: FmiVersion, vrs: &[u32], n: usize) -> Option<(usize, u8)> {
        let first = *vrs.first()? as usize;
        let CachedElement { block, run } = *self.cached.get(first)?;
        // `&`, not `&&`: one branch for the usual case (a run outside the cache has run 0).
        let fits = (n != 0) & (n <= usize::from(run));
        let whole = match version {
            // (A read longer than the run, of several blocks, compares no references here.)
            FmiVersion::Fmi2 => fits && (vrs.len() == n) & consecutive(vrs),
            FmiVersion::Fmi3 => fits && self.consecutive_variables(vrs, n),
        };
        (fits & whole).then_some((first, block))
    }

    /// FMI 3: whether `vrs` are whole variables, each right after the last, `n` elements in
    /// all.
    #[inline(always)]
    pub(super) fn consecutive_variables(&self, vrs: &[u32], n: usize) -> bool {
        let Some(&first) = vrs.first() else { return false };
        let mut next = first as usize;
        for &vr in vrs {
            // 0 for an element inside a variable or an unknown reference: the general path.
            let width = self.variable_width.get(vr as usize).map_or(0, |&w| w as usize);
            if (vr as usize != next) | (width == 0) {
                return false;
            }
            next += width;
        }
        next == first as usize + n
    }

    /// Reads the values of one reference into `values[filled..]`: from the value cache
    /// (filling its block if stale) or through the model. Returns the number of values read.
    /// Out of line, so that the loops of [`Instance::get_real_elementwise`] keep their
    /// registers.
    #[inline(never)]
    pub(super) fn read_real(
        &mut self,
        vrs: &[u32],
        vr: u32,
        values: &mut [f64],
        filled: usize,
    ) -> Result<usize, Status> {
        let a = self.access(vr, BaseType::Real)?;
        let Some(out) = values.get_mut(filled..filled + a.width) else {
            return Err(self.count_error(vrs, BaseType::Real, values.len()));
        };
        if a.cache == NO_CACHE {
            for (i, slot) in out.iter_mut().enumerate() {
                *slot = self.model.get_real(VariableRef { group: a.group, index: a.index + i });
            }
            return Ok(a.width);
        }
        let bit = 1u32 << a.cache;
        if self.fresh & bit == 0 {
            self.refresh(bit);
        }
        self.read_since_step |= bit;
        let first = vr as usize;
        match self.value_cache.get(first..first + out.len()) {
            // Element by element: a handful of values, no memcpy call.
            Some(cached) => {
                for (slot, &x) in out.iter_mut().zip(cached) {
                    *slot = x;
                }
            }
            None => out.fill(f64::NAN),
        }
        Ok(a.width)
    }

    /// The error of a get whose references address more or fewer values than given.
    #[cold]
    pub(super) fn count_error(&self, vrs: &[u32], want: BaseType, n_values: usize) -> Status {
        match self.check_values(vrs, want, n_values, false) {
            Err(s) => s,
            Ok(()) => self.error("the value references and nValues disagree"),
        }
    }

    /// The error of a get that read a NaN (an output undefined with the current parameters).
    #[cold]
    pub(super) fn nan_error(&self, vrs: &[u32], values: &[f64]) -> Status {
        let i = values.iter().position(|x| x.is_nan()).unwrap_or(0);
        let r = elements(&self.access, vrs).nth(i).unwrap_or(VariableRef { group: usize::MAX, index: 0 });
        let reason = self.model.undefined_reason().unwrap_or_else(|| "with the current parameters".into());
        self.error(&format!("{} is not a number: {reason}", self.element_name(r)))
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        // The run check once per version, so that each has only its own inline.
        let run = match self.version {
            FmiVersion::Fmi2 => self.settable_run(FmiVersion::Fmi2, vrs, values),
            FmiVersion::Fmi3 => self.settable_run(FmiVersion::Fmi3, vrs, values),
        };
        if let Some(a) = run {
            // Consecutive elements of one array (the leg forces): checked in one pass, stored
            // in one call; only the cached values that depend on the input go stale (all the
            // elements share the entry's `stales`, as `stale_after_set` would find).
            self.fresh &= !a.stales;
            self.set_since_step |= a.stales;
            return match self.model.set_real_run(VariableRef { group: a.group, index: a.index }, values) {
                Ok(()) => Status::Ok,
                Err(m) => self.error(&m),
            };
        }
        self.set_real_elementwise(vrs, values)
    }

    /// FMI 2: whether `vrs` fall into runs that each pass [`Instance::settable_run`] (a
    /// controller's measured lengths and rates in one call); else the element-by-element path
    /// decides.
    #[inline]
    pub(super) fn settable_runs(&self, vrs: &[u32], values: &[f64]) -> bool {
        if self.version != FmiVersion::Fmi2 || vrs.len() != values.len() {
            return false;
        }
        let mut at = 0;
        while let Some(a) = vrs.get(at).and_then(|&vr| self.access.get(vr as usize).copied().flatten()) {
            let end = at + a.run.min(vrs.len() - at);
            if self.settable_run(FmiVersion::Fmi2, &vrs[at..end], &values[at..end]).is_none() {
                return false;
            }
            at = end;
        }
        at == vrs.len()
    }

    /// [`Instance::set_real`] reference by reference, out of line as for gets.
    #[inline(never)]
    pub(super) fn set_real_elementwise(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if self.settable_runs(vrs, values) {
            // Checked: each run stored in one call, as the single-run path stores it.
            self.stale_after_set(vrs);
            let mut at = 0;
            while let Some(a) = vrs.get(at).and_then(|&vr| self.access.get(vr as usize).copied().flatten()) {
                let n = a.run.min(vrs.len() - at);
                if let Err(m) =
                    self.model.set_real_run(VariableRef { group: a.group, index: a.index }, &values[at..at + n])
                {
                    return self.error(&m);
                }
                at += n;
            }
            return Status::Ok;
        }
        // Two passes, no allocation: validate every reference and value, then store (all or
        // nothing).
        if let Err(s) = self.check_set_real(vrs, values) {
            return s;
        }
        self.stale_after_set(vrs);
        let access = &self.access;
        let result = if self.version == FmiVersion::Fmi2 {
            // One element per reference (checked above).
            let element = |(&vr, &x): (&u32, &f64)| {
                let a = access.get(vr as usize).copied().flatten()?;
                Some((VariableRef { group: a.group, index: a.index }, x))
            };
            self.model.set_reals(vrs.iter().zip(values).map_while(element))
        } else {
            self.model.set_reals(elements(access, vrs).zip(values.iter().copied()))
        };
        match result {
            Ok(()) => Status::Ok,
            Err(m) => self.error(&m),
        }
    }

    /// Marks stale the cached values a set of `vrs` changes ([`Access::stales`]); an unknown
    /// reference (refused before anything is set) counts as changing everything.
    pub(super) fn stale_after_set(&mut self, vrs: &[u32]) {
        let stale = vrs.iter().fold(0u32, |mask, &vr| {
            mask | self.access.get(vr as usize).copied().flatten().map_or(u32::MAX, |a| a.stales)
        });
        self.fresh &= !stale;
        self.set_since_step |= stale;
    }

    /// When `vrs` address consecutive elements of one settable Real group (FMI 2:
    /// consecutive references; FMI 3: one variable) and every value is finite, the first
    /// element's access entry. `version` is the instance's, as in [`Instance::cached_run`].
    #[inline(always)]
    pub(super) fn settable_run(&self, version: FmiVersion, vrs: &[u32], values: &[f64]) -> Option<Access> {
        let a = (*self.access.get(*vrs.first()? as usize)?)?;
        let addressed = match version {
            FmiVersion::Fmi2 => vrs.len() == values.len() && values.len() <= a.run && consecutive(vrs),
            FmiVersion::Fmi3 => vrs.len() == 1 && values.len() == a.width,
        };
        let finite = all_finite(values);
        (addressed && finite && a.base == BaseType::Real && a.settable_in & self.state.bit() != 0).then_some(a)
    }

    /// The first pass of [`Instance::set_real`]: references, states and values. FMI 2's
    /// one element per reference is checked in one tight loop; anything else, or a failure,
    /// takes the general check that names the problem.
    #[inline]
    pub(super) fn check_set_real(&self, vrs: &[u32], values: &[f64]) -> Result<(), Status> {
        let state = self.state.bit();
        let plain = self.version == FmiVersion::Fmi2
            && vrs.len() == values.len()
            && vrs.iter().zip(values).all(|(&vr, x)| {
                matches!(self.access.get(vr as usize), Some(Some(a))
                    if a.base == BaseType::Real && a.settable_in & state != 0 && x.is_finite())
            });
        if plain { Ok(()) } else { self.check_set_real_slowly(vrs, values) }
    }

    #[cold]
    pub(super) fn check_set_real_slowly(&self, vrs: &[u32], values: &[f64]) -> Result<(), Status> {
        self.check_values(vrs, BaseType::Real, values.len(), true)?;
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            let r = elements(&self.access, vrs).nth(i).unwrap_or(VariableRef { group: usize::MAX, index: 0 });
            return Err(self.error(&format!(
                "{} = {} refused: values must be finite",
                self.element_name(r),
                values[i]
            )));
        }
        Ok(())
    }

    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Status {
        self.get_elements(vrs, values, BaseType::Integer, |model, r| model.get_integer(r))
    }

    /// A get of Integer or Boolean values, each read through the model and written as the C
    /// type of the calling FMI version.
    pub(super) fn get_elements<T>(
        &mut self,
        vrs: &[u32],
        values: &mut [T],
        base: BaseType,
        read: impl Fn(&mut AnyModel, VariableRef) -> T,
    ) -> Status {
        if let Err(s) = self.check_values(vrs, base, values.len(), false) {
            return s;
        }
        for (slot, r) in values.iter_mut().zip(elements(&self.access, vrs)) {
            *slot = read(&mut self.model, r);
        }
        Status::Ok
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::Integer, values.len(), true) {
            return s;
        }
        // Validate every value on a copy first: all or nothing.
        let mut trial = self.copy_model();
        for (r, &x) in elements(&self.access, vrs).zip(values) {
            if let Err(m) = trial.set_integer(r, x) {
                return self.error(&format!("{} = {x} refused: {m}", self.element_name(r)));
            }
        }
        self.replace_model(trial);
        Status::Ok
    }

    /// Booleans as the calling version's C type `T`: `encode` turns a value into it.
    pub fn get_boolean<T>(&mut self, vrs: &[u32], values: &mut [T], encode: impl Fn(bool) -> T) -> Status {
        self.get_elements(vrs, values, BaseType::Boolean, |model, r| encode(model.get_boolean(r)))
    }

    /// Booleans given as the calling version's C type `T`: `decode` reads one.
    pub fn set_boolean<T: Copy>(&mut self, vrs: &[u32], values: &[T], decode: impl Fn(T) -> bool) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::Boolean, values.len(), true) {
            return s;
        }
        self.stale_after_set(vrs);
        for (r, &x) in elements(&self.access, vrs).zip(values) {
            if let Err(m) = self.model.set_boolean(r, decode(x)) {
                return self.error(&m);
            }
        }
        Status::Ok
    }

    /// Strings: each read through the model into the instance's own buffer, which holds them
    /// until the next get of Strings (the FMI rule for the returned pointers); `each` receives
    /// them in order.
    pub fn get_string(&mut self, vrs: &[u32], count: usize, mut each: impl FnMut(usize, &std::ffi::CStr)) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::String, count, false) {
            return s;
        }
        self.strings.clear();
        for r in elements(&self.access, vrs) {
            let text = self.model.get_string(r).unwrap_or_default();
            // A text with a NUL cannot be a C string: cut it there (the model never stores one:
            // set_string refuses it).
            let bytes: Vec<u8> = text.into_bytes().into_iter().take_while(|&b| b != 0).collect();
            self.strings.push(std::ffi::CString::new(bytes).unwrap_or_default());
        }
        for (i, s) in self.strings.iter().enumerate() {
            each(i, s);
        }
        Status::Ok
    }

    /// Strings given as UTF-8 texts (`None`: not one), all or nothing.
    pub fn set_string(&mut self, vrs: &[u32], values: &[Option<&str>]) -> Status {
        if let Err(s) = self.check_values(vrs, BaseType::String, values.len(), true) {
            return s;
        }
        let mut trial = self.copy_model();
        for (r, x) in elements(&self.access, vrs).zip(values) {
            let Some(x) = x else {
                return self.error(&format!("{} refused: the value is not UTF-8 text", self.element_name(r)));
            };
            if let Err(m) = trial.set_string(r, x) {
                return self.error(&format!("{} = {x:?} refused: {m}", self.element_name(r)));
            }
        }
        self.replace_model(trial);
        Status::Ok
    }

    /// A deep copy of the model through its own serialization (models are not `Clone`
    /// through `AnyModel`).
    pub(super) fn copy_model(&self) -> AnyModel {
        let mut w = ByteWriter::default();
        self.model.save(&mut w);
        let mut r = ByteReader::new(&w.bytes);
        AnyModel::restore(self.kind, &mut r).unwrap_or_else(|_| self.kind.instantiate())
    }

    /// A get or set of a type the model has no variables of: every reference is unknown.
    pub fn no_variables_of_type(&self, vrs: &[u32], type_name: &str) -> Status {
        match vrs.first() {
            None => Status::Ok,
            Some(vr) => self
                .error(&format!("value reference {vr}: {} has no {type_name} variables", self.kind.info().model_name)),
        }
    }
}

/// The runs of the last read of several cache blocks' elements (see
/// [`Instance::get_fresh_runs`]): its references, and each run's first element (its place in
/// the value cache) and width.
#[derive(Clone, Copy, Debug)]
pub(super) struct ReadPlan {
    references: [u32; 32],
    /// How many references (`usize::MAX`: none kept).
    len: usize,
    runs: [(u32, u32); 8],
    count: usize,
    /// How many values the runs give, and the blocks they lie in.
    values: usize,
    blocks: u32,
}

impl ReadPlan {
    pub(super) const NONE: ReadPlan =
        ReadPlan { references: [0; 32], len: usize::MAX, runs: [(0, 0); 8], count: 0, values: 0, blocks: 0 };

    /// Whether this is the plan of a read of `vrs` into `n` values.
    #[inline(always)]
    fn reads(&self, vrs: &[u32], n: usize) -> bool {
        vrs.len() == self.len && n == self.values && self.references.get(..self.len) == Some(vrs)
    }
}
