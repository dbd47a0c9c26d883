//! A model's variables declared once, each bound to where its value lives
//! (`declare_variables!`). From the one list come: the variable table
//! ([`VariableGroup`](crate::models::variables::VariableGroup): value references, causality,
//! variability, units, start values, descriptions; both model descriptions and the
//! documentation pages are rendered from it), the value-reference lookup, get and set of every
//! stored variable, the FMU state's bytes of the parameters and inputs (in declaration order),
//! the cache block of every output and the filling of the cache, and
//! the reading of outputs in any number type (their derivatives through duals).
//!
//! ```text
//! declare_variables! {
//!     model: PlatformModel,
//!     outputs: PlatformOutputs,            // optional: the generic type outputs are read from
//!     cache_blocks: [leg_outputs, outputs], // model methods, each returning one block's values
//!     variables: {
//!         F => V::input("F", &[6], 1, Some("N"), "..."); real(forces),
//!         M => V::parameter("M", &[], 10, Some("kg"), "..."); real(parameters.stand.mass),
//!         METHOD => V::parameter(...).integer(1, 2); integer(parameters.settings.method),
//!         STOPS => V::parameter(...).boolean(); boolean(parameters.stops_enabled),
//!         L => V::output("l", &[6], 121, ...); cached(leg_outputs.l),
//!         KAPPA => V::output(...); cached_apart(condition.kappa), // a block not in `outputs`
//!         DER_V => V::local(...).derivative(...); derivative,   // from the state's rate
//!         TIME => V::time(0); computed,                         // the model's own function
//!     }
//! }
//! ```
//!
//! Bindings: `real`, `integer`, `boolean` and `string` name a field of the model (a path)
//! holding the variable's value ([`RealStorage`], [`IntegerStorage`], `bool`, `String`); `cached(block.field)` is an
//! output read through the cache block `block` (the model method of that name returns the
//! block's values, `field` the variable's); `cached_apart(block.field)` the same for a value
//! that is not a field of the outputs type (its derivative is the model's own);
//! `cached_at(block.field, offset)` the elements of an array field from `offset` on (an
//! actuator's states in the actuators' part of the state); `derivative` a
//! state derivative
//! (`VariableGroup::derivative_of`), computed from the model's state rate; `computed` a value
//! the model computes itself ([`Binding::Computed`]).

use nalgebra::{Matrix3, Scalar, Vector3};

use super::snapshot::SnapshotError;

/// Where a variable's value comes from (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// A field of the model: a parameter or an input.
    Stored,
    /// An output read through cache block `block`.
    Cached { block: u8 },
    /// The time derivative of a state, from the model's state rate.
    Derivative,
    /// Computed by the model on request (the time, a value costly to compute).
    Computed,
}

/// A field holding a Real variable: its elements in the variable's row-major order.
pub trait RealStorage {
    fn element(&self, i: usize) -> Option<f64>;
    fn element_mut(&mut self, i: usize) -> Option<&mut f64>;
}

impl RealStorage for f64 {
    fn element(&self, i: usize) -> Option<f64> {
        (i == 0).then_some(*self)
    }
    fn element_mut(&mut self, i: usize) -> Option<&mut f64> {
        (i == 0).then_some(self)
    }
}

impl<const N: usize> RealStorage for [f64; N] {
    fn element(&self, i: usize) -> Option<f64> {
        self.get(i).copied()
    }
    fn element_mut(&mut self, i: usize) -> Option<&mut f64> {
        self.get_mut(i)
    }
}

impl RealStorage for Vector3<f64> {
    fn element(&self, i: usize) -> Option<f64> {
        self.get(i).copied()
    }
    fn element_mut(&mut self, i: usize) -> Option<&mut f64> {
        self.get_mut(i)
    }
}

/// One vector per row: `B[k,c]` is `base_joints[k-1][c-1]`.
impl<const N: usize> RealStorage for [Vector3<f64>; N] {
    fn element(&self, i: usize) -> Option<f64> {
        self.get(i / 3)?.get(i % 3).copied()
    }
    fn element_mut(&mut self, i: usize) -> Option<&mut f64> {
        self.get_mut(i / 3)?.get_mut(i % 3)
    }
}

/// A field holding an Integer variable: an enumeration coded as the variable's integers.
pub trait IntegerStorage {
    fn code(&self) -> i32;
    /// Takes the value coded `code`, or says why it is not one.
    fn set_code(&mut self, code: i32) -> Result<(), String>;
}

/// A switch as an Integer 0 (off) or 1 (on).
impl IntegerStorage for bool {
    fn code(&self) -> i32 {
        i32::from(*self)
    }
    fn set_code(&mut self, code: i32) -> Result<(), String> {
        match code {
            0 | 1 => {
                *self = code == 1;
                Ok(())
            }
            _ => Err(format!("{code} is neither 0 (off) nor 1 (on)")),
        }
    }
}

/// An output's values in the number type `T`, element by element in the variable's
/// row-major order.
pub trait OutputValues<T> {
    fn element(&self, i: usize) -> Option<T>;

    /// Every element into `slots` (as many as the variable has); `true` if one is NaN.
    #[inline]
    fn write(&self, slots: &mut [f64]) -> bool
    where
        T: Into<f64>,
    {
        let mut nan = false;
        for (i, slot) in slots.iter_mut().enumerate() {
            *slot = self.element(i).map_or(f64::NAN, Into::into);
            nan |= slot.is_nan();
        }
        nan
    }
}

impl<T: Copy> OutputValues<T> for T {
    fn element(&self, i: usize) -> Option<T> {
        (i == 0).then_some(*self)
    }
}

impl<T: Copy, const N: usize> OutputValues<T> for [T; N] {
    fn element(&self, i: usize) -> Option<T> {
        self.get(i).copied()
    }

    /// One copy (the legs' block is filled every step), then a check without early exit.
    #[inline]
    fn write(&self, slots: &mut [f64]) -> bool
    where
        T: Into<f64>,
    {
        self[..].write(slots)
    }
}

impl<T: Scalar + Copy> OutputValues<T> for Vector3<T> {
    fn element(&self, i: usize) -> Option<T> {
        self.get(i).copied()
    }

    /// The three components at once (a pose block is filled every step it is read).
    #[inline]
    fn write(&self, slots: &mut [f64]) -> bool
    where
        T: Into<f64>,
    {
        match slots.first_chunk_mut::<3>() {
            Some(s) => {
                *s = [self.x.into(), self.y.into(), self.z.into()];
                s.iter().fold(false, |nan, x| nan | x.is_nan())
            }
            None => false,
        }
    }
}

/// A part of an array of values (`cached_at`: the elements from an offset on), or a whole one.
impl<T: Copy> OutputValues<T> for [T] {
    fn element(&self, i: usize) -> Option<T> {
        self.get(i).copied()
    }

    /// One copy, then a check without early exit.
    #[inline]
    fn write(&self, slots: &mut [f64]) -> bool
    where
        T: Into<f64>,
    {
        for (slot, &x) in slots.iter_mut().zip(self) {
            *slot = x.into();
        }
        slots.iter().fold(false, |nan, x| nan | x.is_nan())
    }
}

/// One vector per row: `jointForce[k,c]` is `joint_force[k-1][c-1]`.
impl<T: Scalar + Copy, const N: usize> OutputValues<T> for [Vector3<T>; N] {
    fn element(&self, i: usize) -> Option<T> {
        self.get(i / 3)?.get(i % 3).copied()
    }
}

/// Row-major: `R[a,b]` is element `3 (a-1) + (b-1)`.
impl<T: Scalar + Copy> OutputValues<T> for Matrix3<T> {
    fn element(&self, i: usize) -> Option<T> {
        self.get((i / 3, i % 3)).copied()
    }

    /// The nine elements at once, row by row.
    #[inline]
    fn write(&self, slots: &mut [f64]) -> bool
    where
        T: Into<f64>,
    {
        match slots.first_chunk_mut::<9>() {
            Some(s) => {
                *s = std::array::from_fn(|i| self[(i / 3, i % 3)].into());
                s.iter().fold(false, |nan, x| nan | x.is_nan())
            }
            None => false,
        }
    }
}

/// Writes every element of an output into the value cache from `first` on; `true` if one of
/// them is NaN.
#[inline]
pub fn fill<V: OutputValues<f64> + ?Sized>(cache: &mut [f64], first: u32, len: usize, values: &V) -> bool {
    let Some(slots) = cache.get_mut(first as usize..first as usize + len) else { return false };
    values.write(slots)
}

/// A stored value of an FMU state that is not one of the variable's.
pub fn refused(name: &str, why: String) -> SnapshotError {
    SnapshotError(format!("{name}: {why}"))
}

/// See the module documentation.
macro_rules! declare_variables {
    (
        model: $model:ty,
        outputs: $outputs:ident,
        cache_blocks: [$($block:ident),* $(,)?],
        variables: { $($id:ident => $def:expr ; $kind:ident $(($($arg:tt)*))?),* $(,)? }
    ) => {
        $crate::models::declare::declare_variables! {
            model: $model,
            cache_blocks: [$($block),*],
            variables: { $($id => $def ; $kind $(($($arg)*))?),* }
        }

        /// An output's element in any number type: the value, or through duals its derivative
        /// (every cache block's values carry the fields of the outputs type under the same
        /// names).
        #[allow(dead_code)]
        pub fn output_element<T: $crate::physics::number::Real>(
            o: &$outputs<T>,
            var: $crate::models::variables::VariableRef,
        ) -> Option<T> {
            $($crate::models::declare::declare_variables!(@element o, var, $id, $kind $(($($arg)*))?);)*
            None
        }
    };

    (
        model: $model:ty,
        cache_blocks: [$($block:ident),* $(,)?],
        variables: { $($id:ident => $def:expr ; $kind:ident $(($($arg:tt)*))?),* $(,)? }
    ) => {
        /// Indices into [`GROUPS`] and [`BINDINGS`], matched on by the model.
        pub mod group {
            #[allow(non_camel_case_types, clippy::upper_case_acronyms, dead_code)]
            #[repr(usize)]
            enum Index { $($id),* }
            $(pub const $id: usize = Index::$id as usize;)*
        }

        /// The cache blocks, numbered in the order of `cache_blocks`.
        #[allow(non_upper_case_globals, dead_code)]
        pub mod cache_block {
            #[allow(non_camel_case_types)]
            #[repr(u8)]
            enum Index { $($block,)* _End }
            $(pub const $block: u8 = Index::$block as u8;)*
        }

        /// The variables, in declaration order.
        pub static GROUPS: &[$crate::models::variables::VariableGroup] = TABLE;
        const TABLE: &[$crate::models::variables::VariableGroup] = &[$($def),*];

        /// The continuous states in the order of the state vector, from the declarations (the
        /// state groups in the order of their derivatives): `(group name, flat element index)`.
        pub static STATES: &[(&str, usize)] =
            &$crate::models::variables::states::<{ $crate::models::variables::state_count(TABLE) }>(TABLE);

        /// Where each variable's value comes from.
        pub static BINDINGS: &[$crate::models::declare::Binding] =
            &[$($crate::models::declare::declare_variables!(@binding $kind $(($($arg)*))?)),*];

        // A model without Booleans or cache blocks leaves some arguments unused.
        #[allow(unused_variables, unused_mut)]
        impl $crate::models::declare::Variables for $model {
            fn real_slot(&mut self, var: $crate::models::variables::VariableRef) -> Option<&mut f64> {
                $($crate::models::declare::declare_variables!(@real_slot self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn real_stored(&self, var: $crate::models::variables::VariableRef) -> Option<f64> {
                $($crate::models::declare::declare_variables!(@real_get self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn integer(&self, var: $crate::models::variables::VariableRef) -> Option<i32> {
                $($crate::models::declare::declare_variables!(@int_get self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn set_integer_code(&mut self, var: $crate::models::variables::VariableRef, code: i32) -> Option<Result<(), String>> {
                $($crate::models::declare::declare_variables!(@int_set self, var, code, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn boolean_slot(&mut self, var: $crate::models::variables::VariableRef) -> Option<&mut bool> {
                $($crate::models::declare::declare_variables!(@bool_slot self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn string_value(&self, var: $crate::models::variables::VariableRef) -> Option<&str> {
                $($crate::models::declare::declare_variables!(@string_get self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn string_slot(&mut self, var: $crate::models::variables::VariableRef) -> Option<&mut String> {
                $($crate::models::declare::declare_variables!(@string_slot self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            fn output_value(&mut self, var: $crate::models::variables::VariableRef) -> Option<f64> {
                $($crate::models::declare::declare_variables!(@output self, var, $id, $kind $(($($arg)*))?);)*
                None
            }

            #[inline]
            fn fill_block(&mut self, block: u8, cache: &mut [f64]) -> bool {
                // One function per block (the block's variables alone, out of line).
                match block {
                    $(cache_block::$block => self.fill_block_out_of_line::<{ cache_block::$block }>(cache),)*
                    _ => false,
                }
            }

            fn save_variables(&self, w: &mut $crate::models::snapshot::ByteWriter) {
                $($crate::models::declare::declare_variables!(@save self, w, $id, $kind $(($($arg)*))?);)*
            }

            fn restore_variables(
                &mut self,
                r: &mut $crate::models::snapshot::ByteReader,
            ) -> Result<(), $crate::models::snapshot::SnapshotError> {
                $($crate::models::declare::declare_variables!(@restore self, r, $id, $kind $(($($arg)*))?);)*
                Ok(())
            }
        }

        #[allow(unused_variables, unused_mut, dead_code)]
        impl $model {
            /// The values of cache block `B` into the cache at their value references; `true` if
            /// one is NaN. Inlined where `B` is known (the block a step's cycle fills every time).
            #[inline(always)]
            pub(crate) fn fill_block_values<const B: u8>(&mut self, cache: &mut [f64]) -> bool {
                let mut nan = false;
                $($crate::models::declare::declare_variables!(@fill self, B, cache, nan, $id, $kind $(($($arg)*))?);)*
                nan
            }

            /// [`Self::fill_block_values`] out of line, one function per block (inlined into one
            /// function, every block's addresses were prepared for any).
            #[inline(never)]
            fn fill_block_out_of_line<const B: u8>(&mut self, cache: &mut [f64]) -> bool {
                self.fill_block_values::<B>(cache)
            }
        }

    };

    (@binding real($($p:tt)*)) => { $crate::models::declare::Binding::Stored };
    (@binding integer($($p:tt)*)) => { $crate::models::declare::Binding::Stored };
    (@binding boolean($($p:tt)*)) => { $crate::models::declare::Binding::Stored };
    (@binding string($($p:tt)*)) => { $crate::models::declare::Binding::Stored };
    (@binding cached($block:ident . $field:ident)) => {
        $crate::models::declare::Binding::Cached { block: cache_block::$block }
    };
    // `cached_apart` is `cached` in every arm but `@element` (none: not in the outputs type).
    (@binding cached_apart($($p:tt)*)) => { $crate::models::declare::declare_variables!(@binding cached($($p)*)) };
    (@binding cached_at($block:ident . $field:ident, $at:expr)) => {
        $crate::models::declare::declare_variables!(@binding cached($block . $field))
    };
    (@binding derivative) => { $crate::models::declare::Binding::Derivative };
    (@binding computed) => { $crate::models::declare::Binding::Computed };

    (@real_slot $s:ident, $var:ident, $id:ident, real($($p:ident).+)) => {
        if $var.group == group::$id {
            return $crate::models::declare::RealStorage::element_mut(&mut $s.$($p).+, $var.index);
        }
    };
    (@real_slot $($rest:tt)*) => {};

    (@real_get $s:ident, $var:ident, $id:ident, real($($p:ident).+)) => {
        if $var.group == group::$id {
            return $crate::models::declare::RealStorage::element(&$s.$($p).+, $var.index);
        }
    };
    (@real_get $($rest:tt)*) => {};

    (@int_get $s:ident, $var:ident, $id:ident, integer($($p:ident).+)) => {
        if $var.group == group::$id {
            return Some($crate::models::declare::IntegerStorage::code(&$s.$($p).+));
        }
    };
    (@int_get $($rest:tt)*) => {};

    (@int_set $s:ident, $var:ident, $code:ident, $id:ident, integer($($p:ident).+)) => {
        if $var.group == group::$id {
            return Some($crate::models::declare::IntegerStorage::set_code(&mut $s.$($p).+, $code));
        }
    };
    (@int_set $($rest:tt)*) => {};

    (@bool_slot $s:ident, $var:ident, $id:ident, boolean($($p:ident).+)) => {
        if $var.group == group::$id {
            return Some(&mut $s.$($p).+);
        }
    };
    (@bool_slot $($rest:tt)*) => {};

    (@string_get $s:ident, $var:ident, $id:ident, string($($p:ident).+)) => {
        if $var.group == group::$id {
            return Some($s.$($p).+.as_str());
        }
    };
    (@string_get $($rest:tt)*) => {};

    (@string_slot $s:ident, $var:ident, $id:ident, string($($p:ident).+)) => {
        if $var.group == group::$id {
            return Some(&mut $s.$($p).+);
        }
    };
    (@string_slot $($rest:tt)*) => {};

    (@output $s:ident, $var:ident, $id:ident, cached($block:ident . $field:ident)) => {
        if $var.group == group::$id {
            return $crate::models::declare::OutputValues::<f64>::element(&$s.$block().$field, $var.index);
        }
    };
    (@output $s:ident, $var:ident, $id:ident, cached_apart($($p:tt)*)) => {
        $crate::models::declare::declare_variables!(@output $s, $var, $id, cached($($p)*))
    };
    (@output $s:ident, $var:ident, $id:ident, cached_at($block:ident . $field:ident, $at:expr)) => {
        if $var.group == group::$id {
            return $crate::models::declare::OutputValues::<f64>::element(&$s.$block().$field[..], $at + $var.index);
        }
    };
    (@output $($rest:tt)*) => {};

    // (`$want` is a constant: only the block's own variables are left.)
    (@fill $s:ident, $want:ident, $cache:ident, $nan:ident, $id:ident, cached($block:ident . $field:ident)) => {
        if cache_block::$block == $want {
            let g = &GROUPS[group::$id];
            $nan |= $crate::models::declare::fill($cache, g.first_vr, g.len(), &$s.$block().$field);
        }
    };
    (@fill $s:ident, $want:ident, $cache:ident, $nan:ident, $id:ident, cached_apart($($p:tt)*)) => {
        $crate::models::declare::declare_variables!(@fill $s, $want, $cache, $nan, $id, cached($($p)*))
    };
    (@fill $s:ident, $want:ident, $cache:ident, $nan:ident, $id:ident, cached_at($block:ident . $field:ident, $at:expr)) => {
        if cache_block::$block == $want {
            let g = &GROUPS[group::$id];
            if let Some(values) = $s.$block().$field.get($at..$at + g.len()) {
                $nan |= $crate::models::declare::fill($cache, g.first_vr, g.len(), values);
            }
        }
    };
    (@fill $($rest:tt)*) => {};

    (@save $s:ident, $w:ident, $id:ident, real($($p:ident).+)) => {
        for i in 0..GROUPS[group::$id].len() {
            $w.f64($crate::models::declare::RealStorage::element(&$s.$($p).+, i).unwrap_or(f64::NAN));
        }
    };
    (@save $s:ident, $w:ident, $id:ident, integer($($p:ident).+)) => {
        $w.i32($crate::models::declare::IntegerStorage::code(&$s.$($p).+));
    };
    (@save $s:ident, $w:ident, $id:ident, boolean($($p:ident).+)) => {
        $w.bool($s.$($p).+);
    };
    (@save $s:ident, $w:ident, $id:ident, string($($p:ident).+)) => {
        $w.str(&$s.$($p).+);
    };
    (@save $($rest:tt)*) => {};

    (@restore $s:ident, $r:ident, $id:ident, real($($p:ident).+)) => {
        let g = &GROUPS[group::$id];
        for i in 0..g.len() {
            let x = $r.finite(g.name)?;
            if let Some(slot) = $crate::models::declare::RealStorage::element_mut(&mut $s.$($p).+, i) {
                *slot = x;
            }
        }
    };
    (@restore $s:ident, $r:ident, $id:ident, integer($($p:ident).+)) => {
        let code = $r.i32()?;
        $crate::models::declare::IntegerStorage::set_code(&mut $s.$($p).+, code)
            .map_err(|why| $crate::models::declare::refused(GROUPS[group::$id].name, why))?;
    };
    (@restore $s:ident, $r:ident, $id:ident, boolean($($p:ident).+)) => {
        $s.$($p).+ = $r.bool()?;
    };
    (@restore $s:ident, $r:ident, $id:ident, string($($p:ident).+)) => {
        $s.$($p).+ = $r.string(GROUPS[group::$id].name)?;
    };
    (@restore $($rest:tt)*) => {};

    (@element $o:ident, $var:ident, $id:ident, cached($block:ident . $field:ident)) => {
        if $var.group == group::$id {
            return $crate::models::declare::OutputValues::element(&$o.$field, $var.index);
        }
    };
    (@element $o:ident, $var:ident, $id:ident, cached_at($block:ident . $field:ident, $at:expr)) => {
        if $var.group == group::$id {
            return $crate::models::declare::OutputValues::element(&$o.$field[..], $at + $var.index);
        }
    };
    (@element $($rest:tt)*) => {};
}

pub(crate) use declare_variables;

/// What `declare_variables!` derives for a model from its declarations.
pub trait Variables {
    /// The storage of an element of a stored Real variable (parameter or input).
    fn real_slot(&mut self, var: super::variables::VariableRef) -> Option<&mut f64>;
    /// The value of an element of a stored Real variable.
    fn real_stored(&self, var: super::variables::VariableRef) -> Option<f64>;
    /// The code of a stored Integer variable.
    fn integer(&self, var: super::variables::VariableRef) -> Option<i32>;
    /// Sets a stored Integer variable by its code; `None` if `var` is none.
    fn set_integer_code(&mut self, var: super::variables::VariableRef, code: i32) -> Option<Result<(), String>>;
    /// The storage of a stored Boolean variable.
    fn boolean_slot(&mut self, var: super::variables::VariableRef) -> Option<&mut bool>;
    /// The value of a stored String variable.
    fn string_value(&self, var: super::variables::VariableRef) -> Option<&str>;
    /// The storage of a stored String variable.
    fn string_slot(&mut self, var: super::variables::VariableRef) -> Option<&mut String>;
    /// The current value of an output element (`cached` or `cached_apart`).
    fn output_value(&mut self, var: super::variables::VariableRef) -> Option<f64>;
    /// Writes the values of cache block `block` into the cache at their value references;
    /// `true` if one is NaN.
    fn fill_block(&mut self, block: u8, cache: &mut [f64]) -> bool;
    /// Every stored variable's value, in declaration order.
    fn save_variables(&self, w: &mut super::snapshot::ByteWriter);
    /// Reads what [`Variables::save_variables`] wrote.
    fn restore_variables(&mut self, r: &mut super::snapshot::ByteReader) -> Result<(), SnapshotError>;
}

/// The cache block of a group, from its binding.
pub fn cache_block_of(bindings: &[Binding], group: usize) -> Option<u8> {
    match bindings.get(group) {
        Some(Binding::Cached { block }) => Some(*block),
        _ => None,
    }
}
