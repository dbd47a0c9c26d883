//! How the physics' per-leg and per-axis values are held side by side in vector registers, and
//! whether the wide registers may be used (the code compiled for them is entered through
//! `crate::simulation::vector`).
//!
//! - [`Lanes`]: six values, one per leg. `Narrow` is three SSE2 pairs (every x86-64
//!   processor); `Wide` is legs 1-4 and 5-6 in two AVX registers (only where
//!   [`wide_available`] says so: the steps' AVX2 path, `crate::simulation::vector`).
//! - [`AxisLanes`]: three values, one per body axis (and a padding lane): `Pair` (SSE2) and
//!   `Quad` (AVX2).
//!
//! `Plain` is six plain values with the same operations (`portable.rs`): the checks at the end
//! of a step use it (except on the AVX2 path, which checks in `Wide`), and on others than
//! x86-64 (aarch64) it is `Narrow` and `Wide` too, as plain arrays are the axes' lanes there.
//! Every operation is per lane and exactly rounded (IEEE 754 `+ - * / sqrt`, no fused
//! multiply-add), and every sum adds in one fixed order, so all forms give the same bits. The
//! physics never names a register: it is written once over `crate::physics::number::Number`,
//! which `f64`, dual numbers and the per-leg lanes (`PerLeg`) implement.
//!
//! The intrinsics are written out by hand, rather than leaving loops over arrays to the
//! compiler, because that keeps the values in registers: the vectoriser splits such loops
//! into scalars and shuffles as soon as a branch or a padded lane appears (the measurements
//! are in the git log and `benches/results/`).
//!
//! The wide forms are behind the cargo feature `avx2` (on by default) and the one run-time
//! check [`wide_available`] (AVX2 and FMA together, as the AVX2 path is compiled for both).

#[cfg(target_arch = "x86_64")]
mod axes_x86_64;
#[cfg(target_arch = "x86_64")]
mod legs_x86_64;
mod portable;

#[cfg(target_arch = "x86_64")]
pub use axes_x86_64::Pair;
// Crate-private: its operations execute AVX2 instructions.
#[cfg(target_arch = "x86_64")]
#[cfg_attr(not(feature = "avx2"), allow(unused_imports))]
pub(crate) use axes_x86_64::Quad;
#[cfg(target_arch = "x86_64")]
pub use legs_x86_64::Narrow;
// Crate-private: its operations execute AVX instructions, so only the steps' AVX2 path
// (behind `unsafe fn integrate_avx2`) may make one.
#[cfg(target_arch = "x86_64")]
#[cfg_attr(not(feature = "avx2"), allow(unused_imports))]
pub(crate) use legs_x86_64::Wide;
pub use portable::Plain;
#[cfg(not(target_arch = "x86_64"))]
pub use portable::{Pair, Plain as Narrow};
#[cfg(not(target_arch = "x86_64"))]
#[allow(unused_imports)] // named only by the AVX2 path, which is x86-64 only
pub(crate) use portable::{Plain as Wide, Quad};

/// For the tests that compare the wide forms with the narrow ones: whether they run here. On
/// an x86-64 build with `avx2` whose processor lacks AVX2 or FMA the comparison would test
/// nothing, so this fails there unless `STEWART_FMU_NO_WIDE=1` says that is expected (a
/// skipped comparison must not pass as one made).
#[doc(hidden)]
pub fn wide_testable() -> bool {
    if wide_available() {
        return true;
    }
    let built_in = cfg!(all(target_arch = "x86_64", feature = "avx2"));
    assert!(
        !built_in || std::env::var("STEWART_FMU_NO_WIDE").is_ok_and(|v| v == "1"),
        "this processor lacks AVX2 or FMA: the wide forms cannot be compared with the narrow ones here (set \
         STEWART_FMU_NO_WIDE=1 to run the other tests)"
    );
    eprintln!("the wide forms are not compared: this build or processor has none");
    false
}

/// The number of lanes of a [`Lanes`] value: one per leg.
pub const LANES: usize = 6;

/// Whether this build and processor may run the wide forms (`Wide`, `Quad`) and the code
/// compiled for them (`#[target_feature(enable = "avx,avx2,fma")]`): the `avx2` feature is
/// built in and the processor has AVX2 and FMA. The one run-time check of the crate.
#[inline]
pub fn wide_available() -> bool {
    #[cfg(all(target_arch = "x86_64", feature = "avx2"))]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        return true;
    }
    false
}

/// How six per-leg values are held and operated on: [`Narrow`] (SSE2 pairs, every x86-64)
/// or `Wide` (AVX: legs 1-4 and 5-6 in two 256-bit registers). Both give the same bits:
/// every operation is per leg, and the sum adds in one fixed order.
pub trait Lanes: Copy {
    /// The same registers for three per-axis values ([`AxisLanes`]).
    type Axes: AxisLanes;
    /// The lanes the checks at the end of a step compute the legs in: these, where they are
    /// cheaper for it than plain arrays, else [`Plain`] (see
    /// [`crate::physics::legs::geometry::JointArrays::kinematics_in`]); the same bits either way.
    type Checks: Lanes;
    /// Whether these are AVX registers (code in them runs only where [`wide_available`] said
    /// so).
    const AVX: bool;
    fn new(x: &[f64; LANES]) -> Self;
    fn splat(x: f64) -> Self;
    fn add(self, other: Self) -> Self;
    fn sub(self, other: Self) -> Self;
    fn mul(self, other: Self) -> Self;
    fn div(self, other: Self) -> Self;
    fn sqrt(self) -> Self;
    /// A mask: every bit set in the lanes where `self > other`, clear elsewhere (and where
    /// either is NaN).
    fn greater(self, other: Self) -> Self;
    /// `yes` in the lanes where the mask `self` (from [`Lanes::greater`]) is set, else `no`.
    fn select(self, yes: Self, no: Self) -> Self;
    fn where_positive(self, value: Self) -> Self;
    fn select_positive(self, positive: Self, otherwise: Self) -> Self;
    fn clamp(self, lower: Self, upper: Self) -> Self;
    fn any_outside(self, lower: Self, upper: Self) -> bool;
    fn sum(self) -> f64;
    /// Four sums at once, each in [`Lanes::sum`]'s order (so the same bits).
    #[inline(always)]
    fn sum4(values: [Self; 4]) -> [f64; 4] {
        values.map(Self::sum)
    }
    /// [`Lanes::sum4`], each sum then multiplied by `factor`.
    #[inline(always)]
    fn sum4_times(values: [Self; 4], factor: f64) -> [f64; 4] {
        Self::sum4(values).map(|x| x * factor)
    }
    fn to_array(self) -> [f64; LANES];
}

/// How three per-axis values (lane `a` for axis `a+1`, and a padding lane that takes part in
/// the arithmetic and is never read) are held and operated on: `Pair` (SSE2, every x86-64)
/// or `Quad` (AVX2). Both give the same bits.
pub trait AxisLanes: Copy {
    fn new(x: [f64; 3]) -> Self;
    /// Four lanes read as they are stored (for per-axis constants kept padded).
    fn load(x: &[f64; 4]) -> Self;
    fn splat(x: f64) -> Self;
    fn add(self, other: Self) -> Self;
    fn sub(self, other: Self) -> Self;
    fn mul(self, other: Self) -> Self;
    /// Lane `a` takes the value of axis `a+1` (mod 3): `[x2, x3, x1]` for axes 1, 2, 3.
    fn next(self) -> Self;
    /// Lane `a` takes the value of axis `a-1` (mod 3): `[x3, x1, x2]`.
    fn previous(self) -> Self;
    /// `(x1 + x2) + x3`.
    fn sum3(self) -> f64;
    /// The lanes, padding last.
    fn to_array(self) -> [f64; 4];
}
