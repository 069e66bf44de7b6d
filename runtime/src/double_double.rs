//! Double-double arithmetic: a real number stored as the unevaluated sum of two `f64`s.
//!
//! [`DoubleDouble`] carries about 106 bits of mantissa (≈ 32 decimal digits) while using only hardware
//! `f64` operations, which makes it cheap enough to run the whole dynamics solver on and accurate enough
//! that its answers serve as the reference against which `f64` and `f32` runs are measured.
//!
//! The algorithms are the classical ones: Knuth's two-sum and Dekker's fast two-sum for exact sums, an
//! FMA-based exact product, and the "accurate" double-double operations of Bailey's QD library as
//! analysed by Joldes, Muller and Popescu ("Tight and rigorous error bounds for basic building blocks of
//! double-word arithmetic", ACM TOMS 2017). The cheaper "sloppy" addition of QD is deliberately not used:
//! it loses all relative accuracy when the operands nearly cancel, which is exactly what happens inside
//! the dynamics (inertia differences, residual forces).
//!
//! Measured in the tests below: `+ - * /` and `sqrt` are within about 5·10⁻³² relative error, and
//! `sin`/`cos` within about 10⁻³¹ absolute error for any |x| up to 10¹⁵ (the argument reduction is
//! exact there; see `reduce_half_pi` for larger arguments).
//!
//! Non-finite values are not tracked carefully: an overflow, an infinite operand or a division by zero
//! generally produces NaN rather than ±∞ (the error terms become `∞ − ∞`). Either way
//! [`DoubleDouble::is_finite`] reports `false`, which is all the solver looks at.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
use core::fmt;
use core::iter::Sum;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

use num_traits::{One, Zero};

use crate::scalar::Real;

/// A double-double number: the value is `hi + lo` exactly, with `|lo| ≤ ulp(hi)/2`.
///
/// Every constructor and operation returns a normalized pair (`hi` is `hi + lo` rounded to nearest),
/// which is what makes the derived lexicographic `PartialOrd` and `PartialEq` correct.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Default)]
pub struct DoubleDouble {
    hi: f64,
    lo: f64,
}

/// `π/2` split into four doubles whose exact sum is within 3·10⁻⁶⁶ of `π/2`. The extra terms keep
/// the subtraction of `k·π/2` during argument reduction accurate to the double-double level even for
/// large multiples `k` (the products `k·term` of the first three are formed exactly with [`two_prod`]).
const FRAC_PI_2_PARTS: [f64; 4] = [
    core::f64::consts::FRAC_PI_2,
    6.123_233_995_736_766e-17,
    -1.497_384_904_859_169_8e-33,
    5.562_271_104_316_826e-50,
];

/// Upper bound on reduction passes: each pass shrinks the argument by a factor of about 2⁵², so even
/// `f64::MAX` is reduced in ~20 passes. It also guarantees termination for pathological inputs.
const MAX_REDUCTION_PASSES: usize = 24;

/// Taylor terms smaller than this (relative to the leading term) are dropped; 2⁻¹¹⁰ is below the
/// double-double rounding error, so truncation never dominates.
const SERIES_TOLERANCE: f64 = 7.7e-34;

/// Hard cap on the number of Taylor levels, reached only if the reduced argument were far outside
/// `[-π/4, π/4]` (for which ~14 levels suffice).
const MAX_SERIES_LEVELS: u32 = 40;

/// Largest number of digits after the decimal point that [`fmt::Display`] will print; digits beyond the
/// ~32nd are noise anyway.
const MAX_DISPLAY_PRECISION: usize = 40;

/// Exact sum of two doubles (Knuth's two-sum): returns `(s, e)` with `s = fl(a + b)` and `s + e = a + b`
/// exactly, for any ordering of magnitudes (6 flops, no branch).
#[inline]
pub fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let b_virtual = s - a;
    let a_virtual = s - b_virtual;
    let e = (a - a_virtual) + (b - b_virtual);
    (s, e)
}

/// Exact sum of two doubles when `|a| ≥ |b|` (or `a == 0`) (Dekker's fast two-sum): returns `(s, e)`
/// with `s = fl(a + b)` and `s + e = a + b` exactly, in 3 flops. Used to renormalize a pair whose
/// ordering is already known.
#[inline]
pub fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let e = b - (s - a);
    (s, e)
}

/// Exact product of two doubles: returns `(p, e)` with `p = fl(a·b)` and `p + e = a·b` exactly
/// (barring overflow and underflow).
///
/// The rounding error of a product is itself a double, and a fused multiply-add computes `a·b − p`
/// with a single rounding, so `mul_add` yields it exactly in one operation, where Dekker's splitting
/// needs 17 flops and a careful argument about overflow. `f64::mul_add` is correctly rounded on every
/// target: it is the FMA instruction where the target enables it (e.g. `-C target-cpu=native`) and the
/// C library's exact `fma` otherwise, so correctness never depends on CPU features, only speed does.
#[inline]
pub fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let e = a.mul_add(b, -p);
    (p, e)
}

impl DoubleDouble {
    /// Zero.
    pub const ZERO: Self = Self { hi: 0.0, lo: 0.0 };
    /// One.
    pub const ONE: Self = Self { hi: 1.0, lo: 0.0 };
    /// Not a number (`hi` is NaN).
    pub const NAN: Self = Self {
        hi: f64::NAN,
        lo: f64::NAN,
    };
    /// π to double-double precision.
    pub const PI: Self = Self {
        hi: core::f64::consts::PI,
        lo: 1.224_646_799_147_353_2e-16,
    };
    /// 2π to double-double precision.
    pub const TAU: Self = Self {
        hi: core::f64::consts::TAU,
        lo: 2.449_293_598_294_706_4e-16,
    };
    /// π/2 to double-double precision.
    pub const FRAC_PI_2: Self = Self {
        hi: FRAC_PI_2_PARTS[0],
        lo: FRAC_PI_2_PARTS[1],
    };
    /// 2⁻¹⁰⁴: the double-double analogue of `f64::EPSILON` (the square of it). Correctly implemented
    /// operations are accurate to a small multiple of 2⁻¹⁰⁶, comfortably inside this.
    pub const EPSILON: Self = Self {
        hi: f64::EPSILON * f64::EPSILON,
        lo: 0.0,
    };

    /// Builds `hi + lo`, normalizing the pair, so any two doubles are accepted (their sum is then
    /// represented exactly unless it overflows).
    #[inline]
    pub fn new(hi: f64, lo: f64) -> Self {
        let (s, e) = two_sum(hi, lo);
        if s.is_finite() {
            Self { hi: s, lo: e }
        } else {
            // Keep ±∞ / NaN in `hi` with a clean `lo` instead of the NaN the error term would be.
            Self { hi: s, lo: 0.0 }
        }
    }

    /// Converts a double exactly.
    #[inline]
    pub const fn from_f64(x: f64) -> Self {
        Self { hi: x, lo: 0.0 }
    }

    /// The leading component: the value rounded to the nearest double.
    #[inline]
    pub const fn hi(self) -> f64 {
        self.hi
    }

    /// The trailing component: the rounding error of [`hi`](Self::hi).
    #[inline]
    pub const fn lo(self) -> f64 {
        self.lo
    }

    /// Rounds to the nearest double (`hi + lo`, which for a normalized pair is `hi` except in ties).
    #[inline]
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// `true` if neither component is infinite or NaN.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.hi.is_finite() && self.lo.is_finite()
    }

    /// Absolute value (exact).
    #[inline]
    pub fn abs(self) -> Self {
        if self.hi.is_sign_negative() {
            -self
        } else {
            self
        }
    }

    /// `self²`, slightly cheaper than `self * self`.
    #[inline]
    pub fn square(self) -> Self {
        let (p, e) = two_prod(self.hi, self.hi);
        let cross = 2.0 * self.hi * self.lo;
        let e = self.lo.mul_add(self.lo, cross + e);
        let (hi, lo) = quick_two_sum(p, e);
        Self { hi, lo }
    }

    /// `1 / self`.
    #[inline]
    pub fn recip(self) -> Self {
        Self::ONE / self
    }

    /// Square root; NaN for negative arguments, `±0` for `±0`.
    ///
    /// One Newton step from the `f64` root: with `s = √hi`, the exact residual `self − s²` (the square
    /// is formed exactly with `two_prod`) divided by `2s` is the correction. Newton doubles the number
    /// of correct bits, so 53 become ~106; the neglected second-order term is `(correction)²/(2s)`,
    /// about 2⁻¹⁰⁷ relative.
    pub fn sqrt(self) -> Self {
        if self.hi.is_nan() || self.hi < 0.0 {
            return Self::NAN;
        }
        if self.hi == 0.0 || self.hi == f64::INFINITY {
            return Self::from_f64(self.hi);
        }
        let s = self.hi.sqrt();
        let (p, e) = two_prod(s, s);
        let residual = self - Self { hi: p, lo: e };
        let correction = residual.hi / (2.0 * s);
        let (hi, lo) = quick_two_sum(s, correction);
        Self { hi, lo }
    }

    /// Sine. NaN for non-finite arguments.
    pub fn sin(self) -> Self {
        if !self.is_finite() {
            return Self::NAN;
        }
        let (r, quadrant) = reduce_half_pi(self);
        match quadrant {
            0 => sin_kernel(r),
            1 => cos_kernel(r),
            2 => -sin_kernel(r),
            _ => -cos_kernel(r),
        }
    }

    /// Cosine. NaN for non-finite arguments.
    pub fn cos(self) -> Self {
        if !self.is_finite() {
            return Self::NAN;
        }
        let (r, quadrant) = reduce_half_pi(self);
        match quadrant {
            0 => cos_kernel(r),
            1 => -sin_kernel(r),
            2 => -cos_kernel(r),
            _ => sin_kernel(r),
        }
    }

    /// `(sin, cos)` sharing one argument reduction. NaN for non-finite arguments.
    pub fn sin_cos(self) -> (Self, Self) {
        if !self.is_finite() {
            return (Self::NAN, Self::NAN);
        }
        let (r, quadrant) = reduce_half_pi(self);
        let (s, c) = (sin_kernel(r), cos_kernel(r));
        match quadrant {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    /// Largest integer not above `self` (used by the decimal formatter).
    fn floor(self) -> Self {
        let hi = self.hi.floor();
        if hi == self.hi {
            // `hi` is already an integer, so the fractional part (if any) lives in `lo`.
            let (hi, lo) = quick_two_sum(hi, self.lo.floor());
            Self { hi, lo }
        } else {
            Self { hi, lo: 0.0 }
        }
    }

    /// `self + b` for a double `b` (Joldes–Muller–Popescu "DWPlusFP", relative error ≤ 2u²).
    #[inline]
    fn add_f64(self, b: f64) -> Self {
        let (s, e) = two_sum(self.hi, b);
        let (hi, lo) = quick_two_sum(s, e + self.lo);
        Self { hi, lo }
    }

    /// `self · b` for a double `b`: the leading product exactly, the trailing one fused in
    /// ("DWTimesFP3", relative error ≤ 2u²).
    #[inline]
    fn mul_f64(self, b: f64) -> Self {
        let (p, e) = two_prod(self.hi, b);
        let e = self.lo.mul_add(b, e);
        let (hi, lo) = quick_two_sum(p, e);
        Self { hi, lo }
    }

    /// `self / b` for a double `b`: the first quotient digit, its exact back-product, and one
    /// correction from the remainder ("DWDivFP3", relative error ≤ 3u²).
    #[inline]
    fn div_f64(self, b: f64) -> Self {
        let q1 = self.hi / b;
        let (p, e) = two_prod(q1, b);
        // `self.hi − p` is exact (Sterbenz) since `p` is within an ulp of `self.hi`.
        let remainder = (self.hi - p - e) + self.lo;
        let (hi, lo) = quick_two_sum(q1, remainder / b);
        Self { hi, lo }
    }
}

/// Reduces `x` to `r = x − k·π/2` with `|r| ≲ π/4`, returning `r` and `k mod 4`.
///
/// `k·π/2` is subtracted one exact partial product at a time (`k` is an integer-valued double, and
/// [`two_prod`] makes each `k·part` exact), so the only rounding errors are those of the accurate
/// double-double subtractions, which are relative to their results: the cancellation is harmless, and
/// the four-term π/2 (truncated at 3·10⁻⁶⁶) contributes nothing measurable. This gives full accuracy
/// (~10⁻³² absolute) while `k` is exact, i.e. for `|x|` below 2⁵³·π/2 ≈ 1.4·10¹⁶. Beyond that `k` is
/// coarser than 1, a second pass is needed, and the intermediate remainder (up to `ulp(k)·π/2`) is
/// rounded at the double-double level, so the error grows with `|x|` (5·10⁻²⁸ measured at 10²²). Each
/// pass shrinks the argument by about 2⁵², so the loop ends quickly even for `f64::MAX`.
fn reduce_half_pi(x: DoubleDouble) -> (DoubleDouble, u8) {
    let [part1, part2, part3, part4] = FRAC_PI_2_PARTS;
    let mut r = x;
    let mut quadrant = 0.0_f64;
    for _ in 0..MAX_REDUCTION_PASSES {
        let mut k = (r.hi / part1).round();
        if k == 0.0 {
            break;
        }
        let (mut p, mut e) = two_prod(k, part1);
        if !p.is_finite() {
            // Only within an ulp of `f64::MAX` can `k·π/2` overflow; back `k` off by one part in 2⁵²
            // (it stays an integer) and let the next pass take the rest.
            k *= 1.0 - f64::EPSILON;
            (p, e) = two_prod(k, part1);
        }
        r -= DoubleDouble { hi: p, lo: e };
        let (p, e) = two_prod(k, part2);
        r -= DoubleDouble { hi: p, lo: e };
        let (p, e) = two_prod(k, part3);
        r -= DoubleDouble { hi: p, lo: e };
        r = r.add_f64(-k * part4);
        // Exact: `k` is an integer-valued double, and so is its remainder modulo 4.
        quadrant = (quadrant + k.rem_euclid(4.0)).rem_euclid(4.0);
    }
    (r, quadrant as u8)
}

/// Number of nested Taylor levels needed for `|r|² = r2` so that the first dropped term,
/// `r^(2n+2)/(2n+2)!`, is below [`SERIES_TOLERANCE`] (the sine's first dropped term is smaller still).
/// About 14 at `|r| = π/4`, fewer for small arguments.
fn series_levels(r2: f64) -> u32 {
    let mut term = 1.0_f64;
    let mut n = 0;
    while n < MAX_SERIES_LEVELS {
        let k = f64::from(2 * n + 1);
        term *= r2 / (k * (k + 1.0));
        if term.is_nan() || term < SERIES_TOLERANCE {
            break;
        }
        n += 1;
    }
    n
}

/// `sin r` for `|r| ≲ π/4`, Taylor series in nested (Horner) form:
/// `r·(1 − r²/(2·3)·(1 − r²/(4·5)·(1 − …)))`.
///
/// Evaluating from the innermost level outwards needs no factorial table (each level divides by an
/// exactly representable integer), and every level's rounding error is damped by the factor
/// `r²/((2j)(2j+1)) ≤ 0.11` of the levels outside it, so the total error is a few u²·|sin r|.
fn sin_kernel(r: DoubleDouble) -> DoubleDouble {
    let r2 = r.square();
    let mut acc = DoubleDouble::ONE;
    for j in (1..=series_levels(r2.hi)).rev() {
        let k = f64::from(2 * j);
        acc = (-(acc * r2).div_f64(k * (k + 1.0))).add_f64(1.0);
    }
    r * acc
}

/// `cos r` for `|r| ≲ π/4`, nested Taylor series `1 − r²/(1·2)·(1 − r²/(3·4)·(1 − …))`; see
/// [`sin_kernel`]. On this interval `cos r ≥ 0.7`, so the final `1 − …` does not cancel.
fn cos_kernel(r: DoubleDouble) -> DoubleDouble {
    let r2 = r.square();
    let mut acc = DoubleDouble::ONE;
    for j in (1..=series_levels(r2.hi)).rev() {
        let k = f64::from(2 * j);
        acc = (-(acc * r2).div_f64((k - 1.0) * k)).add_f64(1.0);
    }
    acc
}

/// `10ⁿ` for `n ≥ 0` by binary powering. Exact up to `10²²` (the powers are exact doubles there), and
/// within a few u² beyond.
fn pow10(mut n: u32) -> DoubleDouble {
    let mut result = DoubleDouble::ONE;
    let mut base = DoubleDouble::from_f64(10.0);
    while n > 0 {
        if n & 1 == 1 {
            result *= base;
        }
        n >>= 1;
        if n > 0 {
            base = base.square();
        }
    }
    result
}

impl From<f64> for DoubleDouble {
    #[inline]
    fn from(x: f64) -> Self {
        Self::from_f64(x)
    }
}

impl Neg for DoubleDouble {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Add for DoubleDouble {
    type Output = Self;
    /// Accurate addition (QD's `ieee_add`, "AccurateDWPlusDW"): the high and low parts are summed
    /// separately with exact two-sums and the four partial results renormalized twice. Relative error
    /// ≤ 3u² even under cancellation.
    #[inline]
    fn add(self, b: Self) -> Self {
        let (s_hi, s_lo) = two_sum(self.hi, b.hi);
        let (t_hi, t_lo) = two_sum(self.lo, b.lo);
        let (v_hi, v_lo) = quick_two_sum(s_hi, s_lo + t_hi);
        let (hi, lo) = quick_two_sum(v_hi, v_lo + t_lo);
        Self { hi, lo }
    }
}

impl Sub for DoubleDouble {
    type Output = Self;
    #[inline]
    fn sub(self, b: Self) -> Self {
        self + (-b)
    }
}

impl Mul for DoubleDouble {
    type Output = Self;
    /// Product of the high parts exactly, cross terms folded in with fused multiply-adds
    /// ("DWTimesDW3"): relative error ≤ 5u².
    #[inline]
    fn mul(self, b: Self) -> Self {
        let (p, e) = two_prod(self.hi, b.hi);
        let cross = self.hi.mul_add(b.lo, self.lo * b.lo);
        let cross = self.lo.mul_add(b.hi, cross);
        let (hi, lo) = quick_two_sum(p, e + cross);
        Self { hi, lo }
    }
}

impl Div for DoubleDouble {
    type Output = Self;
    /// Long division with a correction (QD's `accurate_div`): three quotient "digits", each the `f64`
    /// quotient of the current remainder's leading part, the remainder being updated with accurate
    /// double-double arithmetic. The third digit corrects the error of the first two, which makes this
    /// as accurate as multiplication.
    #[inline]
    fn div(self, b: Self) -> Self {
        let q1 = self.hi / b.hi;
        let r = self - b.mul_f64(q1);
        let q2 = r.hi / b.hi;
        let r = r - b.mul_f64(q2);
        let q3 = r.hi / b.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        Self { hi, lo }.add_f64(q3)
    }
}

impl Add<f64> for DoubleDouble {
    type Output = Self;
    #[inline]
    fn add(self, b: f64) -> Self {
        self.add_f64(b)
    }
}

impl Sub<f64> for DoubleDouble {
    type Output = Self;
    #[inline]
    fn sub(self, b: f64) -> Self {
        self.add_f64(-b)
    }
}

impl Mul<f64> for DoubleDouble {
    type Output = Self;
    #[inline]
    fn mul(self, b: f64) -> Self {
        self.mul_f64(b)
    }
}

impl Div<f64> for DoubleDouble {
    type Output = Self;
    #[inline]
    fn div(self, b: f64) -> Self {
        self.div_f64(b)
    }
}

macro_rules! impl_assign_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for DoubleDouble {
            #[inline]
            fn $method(&mut self, b: Self) {
                *self = *self $op b;
            }
        }
        impl $trait<f64> for DoubleDouble {
            #[inline]
            fn $method(&mut self, b: f64) {
                *self = *self $op b;
            }
        }
    };
}

impl_assign_op!(AddAssign, add_assign, +);
impl_assign_op!(SubAssign, sub_assign, -);
impl_assign_op!(MulAssign, mul_assign, *);
impl_assign_op!(DivAssign, div_assign, /);

impl Zero for DoubleDouble {
    #[inline]
    fn zero() -> Self {
        Self::ZERO
    }
    #[inline]
    fn is_zero(&self) -> bool {
        self.hi == 0.0
    }
}

impl One for DoubleDouble {
    #[inline]
    fn one() -> Self {
        Self::ONE
    }
}

impl Sum for DoubleDouble {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::ZERO, Add::add)
    }
}

impl<'a> Sum<&'a DoubleDouble> for DoubleDouble {
    fn sum<I: Iterator<Item = &'a Self>>(iter: I) -> Self {
        iter.copied().sum()
    }
}

/// Scientific notation with 32 significant digits by default (`3.3333333333333333333333333333333e-1`
/// for 1/3); a precision (`{:.5}`) sets the digits after the point, capped at 40. The last digit may
/// be off by one, as the decimal scaling itself rounds at the 10⁻³² level. Zero, non-finite values and
/// magnitudes beyond 10^±290 (where the scaling could overflow) are printed through `f64`'s `{:e}`.
impl fmt::Display for DoubleDouble {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let after_point = f.precision().unwrap_or(31).min(MAX_DISPLAY_PRECISION);
        let magnitude = self.hi.abs();
        if !self.is_finite() || magnitude == 0.0 || !(1e-290..=1e290).contains(&magnitude) {
            return fmt::LowerExp::fmt(&self.to_f64(), f);
        }

        // Scale into [1, 10); the log10 estimate may be off by one either way, hence the fix-ups.
        let mut exponent = magnitude.log10().floor() as i32;
        let mut x = self.abs();
        x = if exponent >= 0 {
            x / pow10(exponent.unsigned_abs())
        } else {
            x * pow10(exponent.unsigned_abs())
        };
        while x.hi >= 10.0 {
            x /= 10.0;
            exponent += 1;
        }
        while x.hi < 1.0 {
            x *= 10.0;
            exponent -= 1;
        }

        // Leading digit, `after_point` digits, and one guard digit for rounding. Each digit is the
        // integer part of the remainder, so it lies in 0..=10 (10 only through rounding in `x * 10`),
        // which the carry pass below absorbs.
        let count = after_point + 2;
        let mut digits: Vec<u8> = Vec::with_capacity(count);
        for _ in 0..count {
            let d = x.floor();
            digits.push(d.to_f64() as u8);
            x = (x - d) * 10.0;
        }
        let guard = digits.pop().unwrap_or(0);
        if guard >= 5 {
            if let Some(last) = digits.last_mut() {
                *last += 1;
            }
        }
        for i in (1..digits.len()).rev() {
            if digits[i] >= 10 {
                digits[i] -= 10;
                digits[i - 1] += 1;
            }
        }
        if digits[0] >= 10 {
            // Rounded up to the next power of ten: 9.99… → 10.0… → 1.00…e(n+1).
            digits[0] -= 10;
            digits.insert(0, 1);
            digits.pop();
            exponent += 1;
        }

        let mut text = String::with_capacity(count + 8);
        if self.hi < 0.0 {
            text.push('-');
        }
        text.push(char::from(b'0' + digits[0]));
        if after_point > 0 {
            text.push('.');
            text.extend(digits[1..].iter().map(|&d| char::from(b'0' + d)));
        }
        text.push('e');
        text.push_str(&exponent.to_string());
        f.write_str(&text)
    }
}

impl Real for DoubleDouble {
    const NAME: &'static str = "dd";
    #[inline]
    fn from_f64(x: f64) -> Self {
        DoubleDouble::from_f64(x)
    }
    #[inline]
    fn to_f64(self) -> f64 {
        DoubleDouble::to_f64(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        DoubleDouble::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        DoubleDouble::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        DoubleDouble::cos(self)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        DoubleDouble::sin_cos(self)
    }
    #[inline]
    fn abs(self) -> Self {
        DoubleDouble::abs(self)
    }
    #[inline]
    fn epsilon() -> Self {
        Self::EPSILON
    }
    #[inline]
    fn is_finite(self) -> bool {
        DoubleDouble::is_finite(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Dd = DoubleDouble;

    /// The crate's deterministic generator, so failures reproduce, with this module's draws on top.
    struct Rng(crate::random::SplitMix64);

    impl Rng {
        fn new(seed: u64) -> Rng {
            Rng(crate::random::SplitMix64::new(seed))
        }
        fn next_u64(&mut self) -> u64 {
            self.0.next_u64()
        }
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0.uniform(lo, hi)
        }
        /// A double-double with a random (full) trailing part, magnitude in [lo, hi).
        fn dd(&mut self, lo: f64, hi: f64) -> Dd {
            let h = self.uniform(lo, hi);
            Dd::new(h, h * f64::EPSILON * self.uniform(-0.5, 0.5))
        }
        /// An integer in [2^(bits-1), 2^bits), with random sign.
        fn int(&mut self, bits: u32) -> i128 {
            let random = i128::from(self.next_u64()) << 64 | i128::from(self.next_u64());
            let n = random & ((1 << bits) - 1) | (1 << (bits - 1));
            if self.next_u64() & 1 == 0 {
                n
            } else {
                -n
            }
        }
    }

    /// Exact conversion of an integer below 2¹⁰⁶ in magnitude.
    fn from_i128(n: i128) -> Dd {
        let hi = n as f64;
        let lo = (n - hi as i128) as f64;
        let x = Dd::new(hi, lo);
        assert_eq!(to_i128(x), n, "{n} is not representable");
        x
    }

    /// Exact conversion of an integer-valued double-double whose trailing part is an integer too.
    fn to_i128(x: Dd) -> i128 {
        assert!(x.lo().fract() == 0.0, "{x:?} is not an integer pair");
        x.hi() as i128 + x.lo() as i128
    }

    /// Parses a plain decimal such as `-0.8414709848078965066525023216302989996226` (test helper: the
    /// digits are accumulated exactly until 2¹⁰⁶ and then rounded at the u² level, and the final scaling
    /// by a power of ten adds a few u² more, so the parse is good to ~10⁻³¹ relative).
    fn parse(s: &str) -> Dd {
        let (negative, body) = match s.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, s),
        };
        let mut value = Dd::ZERO;
        let mut decimals = 0u32;
        let mut seen_point = false;
        for c in body.chars() {
            if c == '.' {
                seen_point = true;
                continue;
            }
            let digit = c.to_digit(10).expect("decimal digit");
            value = value * 10.0 + f64::from(digit);
            if seen_point {
                decimals += 1;
            }
        }
        let value = value / pow10(decimals);
        if negative {
            -value
        } else {
            value
        }
    }

    fn abs_err(a: Dd, b: Dd) -> f64 {
        (a - b).abs().to_f64()
    }

    fn rel_err(a: Dd, b: Dd) -> f64 {
        abs_err(a, b) / b.abs().to_f64()
    }

    #[test]
    fn error_free_transformations_are_exact() {
        let mut rng = Rng::new(0x1234_5678_9abc_def1);
        for _ in 0..10_000 {
            // Products of integers below 2^53: exact in i128, must equal p + e exactly.
            let a = rng.int(53);
            let b = rng.int(53);
            let (p, e) = two_prod(a as f64, b as f64);
            assert_eq!(p as i128 + e as i128, a * b);
            assert!(e.abs() <= p.abs() * f64::EPSILON / 2.0);

            // Sums of integers of very different sizes, in both orders.
            // 53 significant bits shifted up 27, so both operands are exact doubles.
            let c = rng.int(53) << 27;
            let d = rng.int(30);
            for (x, y) in [(c, d), (d, c)] {
                let (s, e) = two_sum(x as f64, y as f64);
                assert_eq!(s as i128 + e as i128, x + y);
            }
            let (s, e) = quick_two_sum(c as f64, d as f64);
            assert_eq!(s as i128 + e as i128, c + d);
        }
    }

    #[test]
    fn new_normalizes_and_accessors_round_trip() {
        let x = Dd::new(1.0, 1.0);
        assert_eq!((x.hi(), x.lo()), (2.0, 0.0));
        let tiny = f64::EPSILON / 4.0;
        let y = Dd::new(tiny, 1.0);
        assert_eq!((y.hi(), y.lo()), (1.0, tiny));
        assert_eq!(y.to_f64(), 1.0);
        assert_eq!(Dd::from_f64(0.1).to_f64(), 0.1);
        assert_eq!(Dd::from(0.1), Dd::from_f64(0.1));
        assert_eq!(Dd::new(f64::INFINITY, 1.0).hi(), f64::INFINITY);
        assert!(!Dd::new(f64::NAN, 0.0).is_finite());
        assert_eq!(Dd::default(), Dd::ZERO);
    }

    #[test]
    fn ordering_follows_the_value() {
        let one = Dd::ONE;
        let above = Dd::new(1.0, 1e-20);
        let below = Dd::new(1.0, -1e-20);
        assert!(below < one && one < above);
        assert!(Dd::from(-2.0) < below);
        assert!(above > Dd::from(0.999_999_999_999_999_9));
        assert_eq!(Dd::new(1.0, 1e-20).partial_cmp(&Dd::NAN), None);
    }

    #[test]
    fn add_and_sub_match_integer_arithmetic() {
        let mut rng = Rng::new(0x0dd0_0dd0_0dd0_0dd1);
        for _ in 0..10_000 {
            let a = rng.int(100);
            let bits = rng.next_u64() as u32 % 100 + 1;
            let b = rng.int(bits);
            let exact = a + b;
            let sum = from_i128(a) + from_i128(b);
            // The exact sum fits in 106 bits, so an accurate addition must produce it exactly.
            assert_eq!(to_i128(sum), exact, "{a} + {b}");
            assert_eq!(to_i128(from_i128(a) - from_i128(b)), a - b, "{a} - {b}");
        }
    }

    #[test]
    fn add_is_accurate_under_cancellation() {
        // When the leading parts cancel, the result is the sum of the two trailing parts, which must
        // be kept exactly: QD's cheaper "sloppy" addition rounds it to one double and fails here with
        // relative errors near 10⁻¹⁶.
        let x = Dd::new(1.0, 1e-20);
        let y = Dd::new(-1.0, 1e-25);
        assert_eq!(x + y, Dd::new(1e-20, 1e-25));
        let mut rng = Rng::new(0x5107_5107);
        for _ in 0..10_000 {
            let a = rng.dd(-1e6, 1e6);
            let c = a.hi() * f64::EPSILON * rng.uniform(-0.5, 0.5);
            let b = Dd::new(-a.hi(), c);
            let exact = Dd::new(a.lo(), c);
            assert!(rel_err(a + b, exact) <= 1e-31, "{a:?} + {b:?}");
            assert!(rel_err(a - (-b), exact) <= 1e-31, "{a:?} - {:?}", -b);
        }
    }

    #[test]
    fn mul_matches_integer_arithmetic() {
        let mut rng = Rng::new(0xfeed_beef_cafe_f00d);
        let mut worst = 0.0_f64;
        for _ in 0..10_000 {
            // Exact: two 53-bit factors give a 106-bit product.
            let a = rng.int(53);
            let b = rng.int(53);
            assert_eq!(to_i128(from_i128(a) * from_i128(b)), a * b);

            // Rounded: two 62-bit factors (with nonzero trailing parts) give a 124-bit product.
            let a = rng.int(62);
            let b = rng.int(62);
            let product = from_i128(a) * from_i128(b);
            let exact = a * b;
            let err = (to_i128(product) - exact).abs() as f64 / (exact as f64).abs();
            worst = worst.max(err);
        }
        // The error bound of this multiplication is 5u² ≈ 6·10⁻³²; 3.7·10⁻³² is measured.
        assert!(worst <= 6e-32, "worst relative product error {worst:e}");
    }

    #[test]
    fn div_matches_integer_arithmetic() {
        let mut rng = Rng::new(0xabad_1dea_5eed_0001);
        let mut worst = 0.0_f64;
        for _ in 0..10_000 {
            // Exact quotients must come back exactly.
            let a = rng.int(60);
            let b = rng.int(45);
            let quotient = from_i128(a * b) / from_i128(b);
            assert_eq!(to_i128(quotient), a, "{a} * {b} / {b}");

            // Inexact: n / d = q + rem/d with the integer division of i128.
            let n = rng.int(104);
            let bits = rng.next_u64() as u32 % 60 + 2;
            let d = rng.int(bits);
            let (q, rem) = (n / d, n % d);
            let quotient = from_i128(n) / from_i128(d);
            let fraction = quotient - from_i128(q);
            let expected = from_i128(rem) / from_i128(d);
            let err = abs_err(fraction, expected) / quotient.abs().to_f64();
            worst = worst.max(err);
        }
        // 1.8·10⁻³² is measured; without the third quotient digit it would be 4.7·10⁻³².
        assert!(worst <= 3e-32, "worst relative quotient error {worst:e}");
    }

    #[test]
    fn one_third_times_three_is_one() {
        let third = Dd::ONE / Dd::from(3.0);
        assert!(abs_err(third * Dd::from(3.0), Dd::ONE) <= 1e-31);
        assert_eq!(third.hi(), 1.0 / 3.0);
        assert!(
            third.lo() != 0.0,
            "the trailing part carries the extra digits"
        );
        let seventh = Dd::from(22.0) / Dd::from(7.0);
        assert!(abs_err(seventh * 7.0, Dd::from(22.0)) <= 1e-30);
        assert!(abs_err(Dd::from(2.0).recip() * 2.0, Dd::ONE) == 0.0);
    }

    #[test]
    fn random_round_trips_are_accurate() {
        let mut rng = Rng::new(42);
        let (mut worst_div, mut worst_add) = (0.0_f64, 0.0_f64);
        for _ in 0..10_000 {
            let a = rng.dd(-1e3, 1e3);
            let b = rng.dd(1e-3, 1e3);
            worst_div = worst_div.max(rel_err((a / b) * b, a));
            // The rounding of `a + b` is relative to |a + b| ≤ |a| + |b|, so measure against that.
            let scale = a.abs().to_f64() + b.abs().to_f64();
            worst_add = worst_add.max(abs_err((a + b) - b, a) / scale);
            let mut c = a;
            c += b;
            c -= b;
            c *= b;
            c /= b;
            assert!(rel_err(c, a) <= 1e-29 || abs_err(c, a) <= 1e-29 * b.abs().to_f64());
        }
        assert!(worst_div <= 1e-31, "worst (a/b)*b error {worst_div:e}");
        assert!(worst_add <= 1e-31, "worst (a+b)-b error {worst_add:e}");
    }

    #[test]
    fn sqrt_is_accurate() {
        let two = Dd::from(2.0);
        let root = two.sqrt();
        assert!(abs_err(root * root, two) <= 1e-31);
        let reference = parse("1.41421356237309504880168872420969807856967188");
        assert!(rel_err(root, reference) <= 1e-31);

        let mut rng = Rng::new(7);
        let mut worst = 0.0_f64;
        for _ in 0..10_000 {
            let x = rng.dd(1e-10, 1e10);
            let r = x.sqrt();
            worst = worst.max(rel_err(r.square(), x));
            // Perfect squares of 53-bit integers have exact roots.
            let n = rng.int(53).abs();
            assert_eq!(to_i128(from_i128(n * n).sqrt()), n);
        }
        assert!(worst <= 1e-31, "worst sqrt(x)^2 error {worst:e}");
        assert_eq!(Dd::ZERO.sqrt(), Dd::ZERO);
        assert!(Dd::from(-1.0).sqrt().hi().is_nan());
        assert!(Dd::NAN.sqrt().hi().is_nan());
        assert_eq!(Dd::from(f64::INFINITY).sqrt().hi(), f64::INFINITY);
    }

    #[test]
    fn pythagorean_identity_holds() {
        let points = [
            0.0, 1e-20, 0.1, 0.5, 1.0, 3.0, 10.0, 100.0, -7.5, 1e3, -1e3, 1e6,
        ];
        for x in points {
            let (s, c) = Dd::from(x).sin_cos();
            let err = abs_err(s.square() + c.square(), Dd::ONE);
            assert!(err <= 1e-30, "sin²+cos²−1 = {err:e} at {x}");
        }
        let mut rng = Rng::new(99);
        for _ in 0..2_000 {
            let x = rng.dd(-20.0, 20.0);
            let (s, c) = x.sin_cos();
            assert!(
                abs_err(s.square() + c.square(), Dd::ONE) <= 1e-30,
                "at {x:?}"
            );
        }
    }

    #[test]
    fn sin_cos_agree_with_f64() {
        let mut rng = Rng::new(2024);
        for _ in 0..20_000 {
            let x = rng.uniform(-1e3, 1e3);
            let (s, c) = Dd::from(x).sin_cos();
            assert!((s.to_f64() - x.sin()).abs() <= 2e-16, "sin({x})");
            assert!((c.to_f64() - x.cos()).abs() <= 2e-16, "cos({x})");
            assert_eq!(Dd::from(x).sin(), s);
            assert_eq!(Dd::from(x).cos(), c);
        }
        // Far beyond any joint angle, the reduction still works.
        assert!((Dd::from(1e22).sin().to_f64() - 1e22_f64.sin()).abs() <= 2e-16);
    }

    #[test]
    fn special_angles() {
        let sixth = Dd::PI / 6.0;
        assert!(abs_err(sixth.sin(), Dd::from(0.5)) <= 1e-31);
        assert!(abs_err((Dd::PI / 3.0).cos(), Dd::from(0.5)) <= 1e-31);
        assert!(abs_err((Dd::PI / 4.0).sin().square(), Dd::from(0.5)) <= 1e-31);
        assert!(abs_err(Dd::FRAC_PI_2.sin(), Dd::ONE) <= 1e-31);
        // The double-double π/2 falls short of π/2 by δ = part₃ + part₄ + 3e-66, so its cosine is
        // sin δ = δ to 10⁻⁹⁹: this checks the reduction to full relative precision at 10⁻³³.
        let [_, _, part3, part4] = FRAC_PI_2_PARTS;
        let delta = Dd::new(part3, part4);
        let residue = Dd::FRAC_PI_2.cos();
        assert!(rel_err(residue, delta) <= 1e-31, "{residue:?}");
        assert!(rel_err(Dd::PI.sin(), delta * 2.0) <= 1e-31);
        assert!(abs_err(Dd::PI.cos(), -Dd::ONE) <= 1e-31);
        assert!(abs_err(Dd::TAU.cos(), Dd::ONE) <= 1e-31);
        assert!(abs_err(Dd::TAU, Dd::PI * 2.0) == 0.0);
        assert_eq!(Dd::ZERO.sin(), Dd::ZERO);
        assert_eq!(Dd::ZERO.cos(), Dd::ONE);
        let tiny = Dd::from(1e-20);
        assert!(rel_err(tiny.sin(), tiny - Dd::from(1e-60) / 6.0) <= 1e-31);
    }

    #[test]
    fn sin_cos_symmetries() {
        let mut rng = Rng::new(5);
        for _ in 0..1_000 {
            let x = rng.dd(0.0, 50.0);
            assert_eq!((-x).sin(), -x.sin());
            assert_eq!((-x).cos(), x.cos());
        }
    }

    #[test]
    fn sin_cos_satisfy_multiple_angle_identities() {
        // Independent of any tabulated constant: each identity ties values at different arguments,
        // which go through different quadrants and reduction multiples.
        let mut points: Vec<Dd> = [1.0, 0.5, 0.1, 2.5, 7.0, -3.3]
            .iter()
            .map(|&x| Dd::from(x))
            .collect();
        let mut rng = Rng::new(11);
        points.extend((0..500).map(|_| rng.dd(-10.0, 10.0)));
        let mut worst = 0.0_f64;
        for x in points {
            let (s, c) = x.sin_cos();
            let (s2, c2) = (x * 2.0).sin_cos();
            let (s3, c3) = (x * 3.0).sin_cos();
            let errs = [
                abs_err(s2, s * c * 2.0),
                abs_err(c2, c.square() * 2.0 - 1.0),
                abs_err(s3, s * 3.0 - s * s.square() * 4.0),
                abs_err(c3, c * c.square() * 4.0 - c * 3.0),
            ];
            for err in errs {
                worst = worst.max(err);
            }
        }
        assert!(worst <= 1e-30, "worst identity error {worst:e}");
        // sin(1) = 2 sin(½) cos(½), to the full precision.
        let (s, c) = Dd::from(0.5).sin_cos();
        assert!(abs_err(Dd::ONE.sin(), s * c * 2.0) <= 1e-31);
    }

    #[test]
    fn sin_cos_match_high_precision_values() {
        // Columns: x, sin x, cos x, and the absolute tolerance x is held to. The digits come from an
        // independent 400-bit computation (mpmath), rounded to 40 places. Up to 2⁵³ the reduction is
        // exact and the error is that of the series (~10⁻³²); beyond, see `reduce_half_pi`.
        const TABLE: &str = "
            1    0.8414709848078965066525023216302989996226  0.5403023058681397174009366074429766037323 1e-31
            0.5  0.4794255386042030002732879352155713880818  0.8775825618903727161162815826038296519916 1e-31
            3    0.1411200080598672221007448028081102798469 -0.9899924966004454572715727947312613023937 1e-31
            10  -0.5440211108893698134047476618513772816836 -0.8390715290764524522588639478240648345199 1e-31
            -7.5 -0.9379999767747388579484637981490472364318 0.3466353178350258109716193361718955783718 1e-31
            100 -0.5063656411097587936565576104597854320650  0.8623188722876839341019385139508425355101 1e-31
            1000 0.8268795405320025602558874291092181412127  0.5623790762907029910782492266053959687558 1e-31
            1e6 -0.3499935021712929521176524867807714690614  0.9367521275331447869385325350749187757081 1e-31
            1e15 0.8582727931702358355238863908484066466002 -0.5131937377869702522345361364231649295882 1e-31
            1e18 -0.9929693207404050762095530172636302708600 0.1183719902187107326119543333310430207098 1e-29
            1e22 -0.8522008497671888017727058937530293682618 0.5232147853951389454975944733847094921409 1e-27";
        for line in TABLE.lines().filter(|l| !l.trim().is_empty()) {
            let fields: Vec<&str> = line.split_whitespace().collect();
            let [x, sin_ref, cos_ref, tol] = fields[..] else {
                panic!("malformed line {line:?}");
            };
            let tol: f64 = tol.parse().unwrap();
            let (s, c) = Dd::from(x.parse::<f64>().unwrap()).sin_cos();
            let (es, ec) = (abs_err(s, parse(sin_ref)), abs_err(c, parse(cos_ref)));
            let message = format!("x = {x}: sin error {es:e}, cos error {ec:e}");
            assert!(es <= tol && ec <= tol, "{message}");
        }
    }

    #[test]
    fn non_finite_arguments_give_nan() {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let x = Dd::from(x);
            assert!(x.sin().hi().is_nan());
            assert!(x.cos().hi().is_nan());
            let (s, c) = x.sin_cos();
            assert!(s.hi().is_nan() && c.hi().is_nan());
            assert!(!x.is_finite());
        }
        // Huge finite arguments do not panic and stay on the unit circle.
        for x in [1e300, -f64::MAX, f64::MAX] {
            let (s, c) = Dd::from(x).sin_cos();
            assert!(s.is_finite() && c.is_finite());
            assert!(abs_err(s.square() + c.square(), Dd::ONE) <= 1e-30);
        }
        assert!(!(Dd::ONE / Dd::ZERO).is_finite());
        assert!(!(Dd::from(f64::MAX) * 2.0).is_finite());
    }

    #[test]
    fn display_prints_32_significant_digits() {
        let third = Dd::ONE / Dd::from(3.0);
        assert_eq!(third.to_string(), "3.3333333333333333333333333333333e-1");
        // The double-double nearest 2/3 is 0.66666666666666666666666666666666461…, so the 32nd digit
        // correctly stays a 6; √2 = 1.41421356237309504880168872420969807… checks rounding up.
        assert_eq!(
            (third * 2.0).to_string(),
            "6.6666666666666666666666666666666e-1"
        );
        assert_eq!(
            (-third * 2.0).to_string(),
            "-6.6666666666666666666666666666666e-1"
        );
        assert_eq!(format!("{:.4}", Dd::from(-2.5)), "-2.5000e0");
        assert_eq!(format!("{:.0}", Dd::from(123.0)), "1e2");
        assert_eq!(format!("{:.2}", Dd::from(9.999)), "1.00e1");
        assert_eq!(
            Dd::from(1e10).to_string(),
            "1.0000000000000000000000000000000e10"
        );
        // The exact binary value of the double nearest 0.1.
        assert_eq!(
            Dd::from(0.1).to_string(),
            "1.0000000000000000555111512312578e-1"
        );
        assert_eq!(Dd::PI.to_string(), "3.1415926535897932384626433832795e0");
        assert_eq!(
            Dd::from(2.0).sqrt().to_string(),
            "1.4142135623730950488016887242097e0"
        );
        assert_eq!(Dd::ZERO.to_string(), "0e0");
        assert_eq!(Dd::NAN.to_string(), "NaN");
        assert_eq!(Dd::from(1e-300).to_string(), format!("{:e}", 1e-300));
    }

    #[test]
    fn num_traits_and_sum() {
        assert!(Dd::zero().is_zero());
        assert!(!Dd::new(0.0, 0.0).is_zero() || Dd::new(0.0, 0.0) == Dd::ZERO);
        assert_eq!(Dd::one(), Dd::ONE);
        // 0.1 summed ten times, exactly as ten copies of the double 0.1 add up.
        let tenths = [Dd::from(0.1); 10];
        let total: Dd = tenths.iter().sum();
        assert!(abs_err(total, Dd::from(0.1) * 10.0) <= 1e-32);
        let owned: Dd = tenths.into_iter().sum();
        assert_eq!(owned, total);
        // Catastrophic cancellation in a sum: big terms cancel exactly, the small one survives.
        let terms = [
            Dd::from(1e20),
            Dd::from(1.0),
            Dd::from(-1e20),
            Dd::from(1e-15),
        ];
        let total: Dd = terms.iter().sum();
        assert!(abs_err(total, Dd::from(1.0) + 1e-15) <= 1e-31);
    }

    fn hypot<T: Real>(a: T, b: T) -> T {
        (a * a + b * b).sqrt()
    }

    #[test]
    fn implements_real() {
        assert_eq!(<Dd as Real>::NAME, "dd");
        assert_eq!(<Dd as Real>::epsilon().to_f64(), 2f64.powi(-104));
        assert_eq!(<Dd as Real>::from_f64(0.3).to_f64(), 0.3);
        let h = hypot(Dd::from(3.0), Dd::from(4.0));
        assert_eq!(h, Dd::from(5.0));
        let one = Dd::ONE;
        assert_eq!(Real::max(one, Dd::ZERO), one);
        assert_eq!(Real::min(one, Dd::ZERO), Dd::ZERO);
        let (s, c) = Real::sin_cos(Dd::from(0.25));
        assert_eq!(
            (s, c),
            (Real::sin(Dd::from(0.25)), Real::cos(Dd::from(0.25)))
        );
        assert_eq!(Real::abs(Dd::from(-2.0)), Dd::from(2.0));
        assert!(Real::is_finite(one) && !Real::is_finite(Dd::NAN));
    }
}
