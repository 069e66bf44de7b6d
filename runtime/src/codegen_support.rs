// The helpers generated code calls: sine and cosine (a range-reduced polynomial, branch-light and at full
// f64 accuracy; much faster than the platform libm for the angles a robot sees) and the square root.
// `no_std`, no allocation, no panics. The same text is compiled into embedyn-runtime and copied into every
// standalone crate `embedyn generate` writes, so both paths compute bit-identical results.

/// The scalar operations generated code needs, for `f64` and `f32`.
pub trait Float: Copy {
    fn sincos(self) -> (Self, Self);
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
}

/// Sine and cosine of `x` together.
#[inline(always)]
pub fn sincos<S: Float>(x: S) -> (S, S) {
    x.sincos()
}

#[inline(always)]
pub fn sqrt<S: Float>(x: S) -> S {
    x.sqrt()
}

#[inline(always)]
pub fn abs<S: Float>(x: S) -> S {
    x.abs()
}

impl Float for f64 {
    #[inline(always)]
    fn sincos(self) -> (f64, f64) {
        sincos_f64(self)
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        libm::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> f64 {
        libm::fabs(self)
    }
}

impl Float for f32 {
    /// Evaluated in f64 and rounded once: accurate to the last f32 bit.
    #[inline(always)]
    fn sincos(self) -> (f32, f32) {
        let (s, c) = sincos_f64(self as f64);
        (s as f32, c as f32)
    }
    #[inline(always)]
    fn sqrt(self) -> f32 {
        libm::sqrtf(self)
    }
    #[inline(always)]
    fn abs(self) -> f32 {
        libm::fabsf(self)
    }
}

/// sin and cos of `x`: Cody–Waite reduction by π/2 in three parts (exact products for |k| < 2²⁰), then
/// minimax polynomials on [−π/4, π/4] (the classic fdlibm kernels' coefficients). Beyond |x| ≈ 8e5 it
/// defers to libm's full reduction.
#[inline(always)]
#[allow(clippy::excessive_precision)]
pub fn sincos_f64(x: f64) -> (f64, f64) {
    const TWO_OVER_PI: f64 = core::f64::consts::FRAC_2_PI;
    const PIO2_1: f64 = 1.570_796_326_734_125_6e0;
    const PIO2_2: f64 = 6.077_100_506_303_966e-11;
    const PIO2_3: f64 = 2.022_266_248_711_166_5e-21;
    // Rounds to the nearest integer without `f64::round` (not in core): adding and removing 1.5·2⁵².
    const SHIFTER: f64 = 6_755_399_441_055_744.0;
    if x.is_nan() || libm::fabs(x) >= 823_550.0 {
        return (libm::sin(x), libm::cos(x));
    }
    let k = (x * TWO_OVER_PI + SHIFTER) - SHIFTER;
    let r = ((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3;
    let n = (k as i64) & 3;
    let z = r * r;
    // sin kernel.
    const S1: f64 = -1.666_666_666_666_663_2e-1;
    const S2: f64 = 8.333_333_333_322_49e-3;
    const S3: f64 = -1.984_126_982_985_795e-4;
    const S4: f64 = 2.755_731_370_707_006_8e-6;
    const S5: f64 = -2.505_076_025_340_686_3e-8;
    const S6: f64 = 1.589_690_995_211_55e-10;
    let sr = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let s = r + z * r * (S1 + z * sr);
    // cos kernel, with the fdlibm correction that keeps 1 − z/2 exact.
    const C1: f64 = 4.166_666_666_666_660_2e-2;
    const C2: f64 = -1.388_888_888_887_411e-3;
    const C3: f64 = 2.480_158_728_947_673e-5;
    const C4: f64 = -2.755_731_435_139_066_3e-7;
    const C5: f64 = 2.087_572_321_298_175e-9;
    const C6: f64 = -1.135_964_755_778_819_5e-11;
    let cr = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + z * cr);
    // Quadrant: (s, c), (c, −s), (−s, −c), (−c, s).
    let swap = n & 1 == 1;
    let (a, b) = if swap { (c, s) } else { (s, c) };
    let sin_sign = if n & 2 == 2 { -1.0 } else { 1.0 };
    let cos_sign = if (n + 1) & 2 == 2 { -1.0 } else { 1.0 };
    (sin_sign * a, cos_sign * b)
}
