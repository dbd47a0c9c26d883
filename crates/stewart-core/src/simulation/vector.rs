//! The door to the integrators compiled for AVX2 (the registers themselves are `crate::simd`'s).
//! A step computes the six legs and the three body axes side by side in vector registers
//! ([`Lanes`](crate::physics::legs::per_leg::Lanes)): SSE2 pairs everywhere (`Narrow`), or
//! where this build has the `avx2` feature (on by default) and the processor has AVX2 and FMA,
//! four lanes (`Wide`) with the integrators compiled for AVX2 around them. Both give the same
//! numbers to the bit (every lane operation is the scalar one, every sum in one fixed order;
//! Rust fuses no multiply-add by itself): the choice only changes the speed
//! (`tests/vector_extensions.rs`).

use crate::integration::{CrossingLog, IntegrationError, Integrator};
use crate::physics::actuators::LegForceLaw;
use crate::physics::error::PhysicsFault;
use crate::physics::legs::per_leg::Narrow;

use super::dynamics::PlatformDynamics;

/// Which registers a step computes in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VectorPath {
    /// SSE2 pairs: every x86-64 processor (and plain arrays elsewhere).
    Baseline,
    /// AVX2 lanes, the integrators compiled for AVX2. Only made by [`VectorPath::fastest`]
    /// (and accepted by [`VectorPath::checked`]) where the processor has it.
    Avx2,
}

impl VectorPath {
    /// The fastest path this build and processor allow.
    pub fn fastest() -> Self {
        if crate::simd::wide_available() { VectorPath::Avx2 } else { VectorPath::Baseline }
    }

    /// `path` if this build and processor allow it, else the baseline.
    pub fn checked(path: VectorPath) -> Self {
        if path == VectorPath::fastest() { path } else { VectorPath::Baseline }
    }
}

/// One call of the integrator: from `t0` to `t1` (or the first non-smooth point, with
/// `stop_at_restart`), the crossings met into `log`.
pub(super) struct Call<'a, const N: usize> {
    pub t0: f64,
    pub y: &'a mut [f64; N],
    pub t1: f64,
    pub log: &'a mut CrossingLog<N>,
    pub stop_at_restart: bool,
}

/// Integrates the platform's dynamics in the registers of `path`.
#[inline]
pub(super) fn integrate<L: LegForceLaw + ?Sized, const N: usize>(
    path: VectorPath,
    integrator: &mut Integrator,
    dynamics: &PlatformDynamics<'_, L, Narrow>,
    call: Call<'_, N>,
) -> Result<f64, IntegrationError<PhysicsFault>> {
    #[cfg(all(target_arch = "x86_64", feature = "avx2"))]
    if path == VectorPath::Avx2 {
        // SAFETY: `Avx2` is only made where the processor has AVX2 and FMA
        // (`VectorPath::fastest`, `VectorPath::checked`).
        return unsafe { integrate_avx2(integrator, dynamics, call) };
    }
    let _ = path;
    integrator.integrate_until_event(dynamics, call.t0, call.y, call.t1, call.log, call.stop_at_restart)
}

/// [`integrate`] compiled for AVX2: the integrator (inlined here) steps the dynamics in
/// `Wide` lanes; the legs the dynamics checked are handed back.
///
/// # Safety
/// The processor must have AVX2 and FMA.
#[cfg(all(target_arch = "x86_64", feature = "avx2"))]
#[target_feature(enable = "avx,avx2,fma")]
unsafe fn integrate_avx2<L: LegForceLaw + ?Sized, const N: usize>(
    integrator: &mut Integrator,
    dynamics: &PlatformDynamics<'_, L, Narrow>,
    call: Call<'_, N>,
) -> Result<f64, IntegrationError<PhysicsFault>> {
    let wide = dynamics.in_lanes::<crate::simd::Wide>();
    let result = integrator.integrate_until_event(&wide, call.t0, call.y, call.t1, call.log, call.stop_at_restart);
    dynamics.checked_legs.set(wide.checked_legs.get());
    dynamics.lowest_pressure.set(wide.lowest_pressure.get());
    result
}
