//! The one scalar type parameter used throughout gait-core.
//!
//! Every model computation is generic over [`Real`], so the same code runs in
//! `f32` on the Cortex-M4F (whose FPU is single precision) and in `f64` on the
//! host (optimiser, simulator, reference tests).

use nalgebra::RealField;

/// A real scalar: nalgebra's `RealField` plus the few operations the model
/// needs in a form we control on the target.
pub trait Real: RealField + Copy + core::fmt::Debug + PartialOrd {
    /// Converts a constant written in `f64` (model data, tolerances).
    fn lit(x: f64) -> Self;

    /// Converts back to `f64` for reporting and comparisons across precisions.
    fn to_f64(self) -> f64;

    /// Sine and cosine of one angle, computed together.
    ///
    /// On `f32` this is our own routine (see [`sin_cos_f32`]); on `f64` it is
    /// libm's correctly rounded pair.
    fn sin_cos_fast(self) -> (Self, Self);

    /// `true` when the value is neither NaN nor infinite.
    fn finite(self) -> bool;

    /// atan2(self, x) by the `libm` crate on every platform: the host's std
    /// links the system's libm, which rounds some results differently from
    /// the target's, and the firmware's commands must equal the host's bit
    /// for bit (`cargo xtask qemu`).
    fn atan2_portable(self, x: Self) -> Self;

    /// √ε of the type, as a constant: the same value as
    /// `default_epsilon().sqrt()`, which on the M4F is libm's software
    /// `sqrtf` (some 60 instructions) every time a solver is made.
    fn sqrt_epsilon() -> Self;
}

impl Real for f64 {
    #[inline]
    fn lit(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn sin_cos_fast(self) -> (Self, Self) {
        (libm::sin(self), libm::cos(self))
    }
    #[inline]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline]
    fn atan2_portable(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline]
    fn sqrt_epsilon() -> Self {
        // ε = 2⁻⁵², √ε = 2⁻²⁶ exactly.
        1.490_116_119_384_765_6e-8
    }
}

impl Real for f32 {
    #[inline]
    fn lit(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn sin_cos_fast(self) -> (Self, Self) {
        sin_cos_f32(self)
    }
    #[inline]
    fn finite(self) -> bool {
        self.is_finite()
    }
    #[inline]
    fn atan2_portable(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
    #[inline]
    fn sqrt_epsilon() -> Self {
        // ε = 2⁻²³, √ε = 2⁻¹¹·⁵ rounded to f32 (checked against sqrtf).
        3.452_669_8e-4
    }
}

/// Beyond this magnitude the single-step Cody–Waite reduction loses accuracy;
/// joint angles never get there, so such inputs go to libm.
const FAST_RANGE_RAD: f32 = 512.0;

/// Sine and cosine of an `f32` angle, all in single precision.
///
/// Why this is hand-written: libm's `sinf`/`cosf` reduce the argument and
/// evaluate the polynomial in `f64`, which the M4F's single-precision FPU runs
/// in software (measured at about 1,600 instructions per call, see
/// `shared/notes/cross-build.md`), and the model needs five sine/cosine pairs
/// per sample. This routine is a Cody–Waite reduction by π/2 in two parts
/// followed by Taylor polynomials on [−π/4, π/4] (degree 9 for sine, 8 for
/// cosine; truncation error below 3e-8), so the result is within a few ulp of
/// the true value over the joint-angle range. Non-finite or huge arguments
/// fall back to libm, so NaN still propagates.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if x.is_nan() || x.abs() > FAST_RANGE_RAD {
        return (libm::sinf(x), libm::cosf(x));
    }
    const TWO_OVER_PI: f32 = core::f32::consts::FRAC_2_PI;
    // π/2 split in two: PIO2_HI = 201/128 has 8 significant bits, so
    // `k * PIO2_HI` is exact for every |k| ≤ 326 reached here.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_LO: f32 = 4.838_268e-4;
    let kf = round_f32(x * TWO_OVER_PI);
    let r = (x - kf * PIO2_HI) - kf * PIO2_LO;
    let r2 = r * r;
    // sin r = r (1 - r²/3! + r⁴/5! - r⁶/7! + r⁸/9!)
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0)))));
    // cos r = 1 - r²/2! + r⁴/4! - r⁶/6! + r⁸/8!
    let c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0))));
    // The quadrant is k mod 4; |k| ≤ 326 here, so the cast is exact.
    match (kf as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Round half away from zero without libm (the argument is already bounded).
#[inline]
fn round_f32(x: f32) -> f32 {
    let t = x + if x >= 0.0 { 0.5 } else { -0.5 };
    // Truncation toward zero; |t| < 2^23 so the cast round-trips.
    (t as i32) as f32
}

/// `x` limited to `[lo, hi]`, with no panic path.
///
/// `f32::clamp` panics when `lo > hi` or either bound is NaN; with bounds
/// computed at run time (a derated torque limit, a slew step) the optimiser
/// cannot remove that branch, and the firmware image must hold no panic path
/// (`docs/safety.md`). Here a NaN `x` stays NaN (the supervisor's finiteness
/// checks see it), and inverted bounds give `hi`.
#[inline]
#[must_use]
pub fn clamp_f32(x: f32, lo: f32, hi: f32) -> f32 {
    if x > hi {
        hi
    } else if x < lo {
        lo
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrt_epsilon_is_the_rounded_square_root_of_epsilon() {
        assert_eq!(f32::sqrt_epsilon(), libm::sqrtf(f32::EPSILON));
        assert_eq!(f32::sqrt_epsilon(), f32::EPSILON.sqrt());
        assert_eq!(f64::sqrt_epsilon(), f64::EPSILON.sqrt());
        fn generic<T: Real>() -> T {
            T::default_epsilon().sqrt()
        }
        assert_eq!(f32::sqrt_epsilon(), generic::<f32>());
        assert_eq!(f64::sqrt_epsilon(), generic::<f64>());
    }

    #[test]
    fn f32_sin_cos_matches_f64_over_joint_range() {
        let mut worst = 0.0_f64;
        let mut x = -20.0_f64;
        while x <= 20.0 {
            let (s, c) = sin_cos_f32(x as f32);
            let xs = f64::from(x as f32);
            worst = worst.max((f64::from(s) - xs.sin()).abs());
            worst = worst.max((f64::from(c) - xs.cos()).abs());
            x += 0.000_37;
        }
        assert!(worst < 3.0e-7, "worst abs error {worst}");
    }

    #[test]
    fn f32_sin_cos_quadrant_boundaries() {
        for k in -8..=8 {
            let x = k as f32 * core::f32::consts::FRAC_PI_4;
            let (s, c) = sin_cos_f32(x);
            assert!((f64::from(s) - f64::from(x).sin()).abs() < 3.0e-7);
            assert!((f64::from(c) - f64::from(x).cos()).abs() < 3.0e-7);
        }
    }

    #[test]
    fn f32_sin_cos_non_finite_propagates() {
        let (s, c) = sin_cos_f32(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, _) = sin_cos_f32(f32::INFINITY);
        assert!(s.is_nan());
        let (s, c) = sin_cos_f32(1000.0);
        assert!((f64::from(s) - 1000.0_f64.sin()).abs() < 1e-6);
        assert!((f64::from(c) - 1000.0_f64.cos()).abs() < 1e-6);
    }
}
