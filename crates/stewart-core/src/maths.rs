//! The elementary functions, one implementation on every platform.
//!
//! IEEE 754 rounds `+ - * /` and `sqrt` exactly, so every platform computes them alike; it
//! does not fix `sin`, `exp`, `pow` and the others, and the C libraries differ in their last
//! bits (glibc against Windows' `msvcrt.dll`). An adaptive integrator turns one such bit into
//! another step size, and a moving run then differs by far more than a bit. So the model's
//! path takes every such function from here: the `libm` crate (the Rust port of musl's libm),
//! compiled into the FMU, the same code on Linux, Windows and macOS, x86-64 and aarch64.
//! nalgebra's own calls (the SVD's `hypot`) go to the same crate through its `libm-force`
//! feature. `build-fmu` refuses a binary that takes any of them from a C library, imported or
//! linked in (`crates/build-fmu/src/file_check.rs`), and `tests/python/test_platforms.py`
//! compares the platforms' results bit for bit.
//!
//! Rust never fuses a multiply and an add by itself, so no platform's fused multiply-add can
//! change a result either.

#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `(sin x, cos x)` from one argument reduction.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}

#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

#[inline]
pub fn atan(x: f64) -> f64 {
    libm::atan(x)
}

/// The angle of `(x, y)`, `y` first as in C.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `exp(x) - 1`, accurate for small `x`.
#[inline]
pub fn exp_m1(x: f64) -> f64 {
    libm::expm1(x)
}

#[inline]
pub fn tanh(x: f64) -> f64 {
    libm::tanh(x)
}

/// `x` to the power `y`.
#[inline]
pub fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// The natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

#[inline]
pub fn log2(x: f64) -> f64 {
    libm::log2(x)
}

/// The largest integer not above `x` (exact everywhere; `f64::floor` is a C library's call on
/// x86-64 without SSE4.1).
#[inline]
pub fn floor(x: f64) -> f64 {
    libm::floor(x)
}

#[cfg(test)]
mod tests {
    /// The crate's functions against the platform's C library: the same to an ulp or two
    /// (they are not the same bits everywhere, which is why the crate's are used).
    #[test]
    fn the_portable_functions_agree_with_the_c_library_to_an_ulp_or_two() {
        let ulps = |a: f64, b: f64| (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs();
        let mut worst = 0;
        for i in 0..20_000 {
            let x = -7.0 + 14.0 * (i as f64 + 0.37) / 20_000.0;
            let u = x / 7.5;
            let pairs = [
                (super::sin(x), x.sin()),
                (super::cos(x), x.cos()),
                (super::sin_cos(x).0, x.sin()),
                (super::sin_cos(x).1, x.cos()),
                (super::asin(u), u.asin()),
                (super::acos(u), u.acos()),
                (super::atan(x), x.atan()),
                (super::atan2(x, u - 0.3), x.atan2(u - 0.3)),
                (super::exp(x), x.exp()),
                (super::exp_m1(u), u.exp_m1()),
                (super::tanh(x), x.tanh()),
                (super::pow(x.abs() + 0.1, u), (x.abs() + 0.1).powf(u)),
                (super::log2(x.abs() + 1e-3), (x.abs() + 1e-3).log2()),
            ];
            for (ours, theirs) in pairs {
                worst = worst.max(ulps(ours, theirs));
            }
        }
        println!("largest difference from the C library: {worst} ulp");
        assert!(worst <= 2, "{worst} ulp");
        // Exact cases every implementation gets right.
        assert_eq!(super::sin_cos(0.0), (0.0, 1.0));
        assert_eq!(super::sin_cos(-0.0).0.to_bits(), (-0.0f64).to_bits());
        assert_eq!(super::exp(0.0), 1.0);
        assert_eq!(super::pow(2.0, 10.0), 1024.0);
    }
}
