//! The scalar types the solver is generic over.
//!
//! `f64` is the working precision, `f32` the firmware precision, and [`DoubleDouble`] (about 106 bits of
//! mantissa) computes reference answers against which the other two are measured. nalgebra's `RealField`
//! is not used as the bound because a double-double type would have to implement several dozen methods
//! the solver never calls; [`Real`] asks only for what the dynamics needs.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use num_traits::{One, Zero};

#[cfg(feature = "std")]
pub use crate::double_double::DoubleDouble;

/// A real scalar the spatial algebra and the algorithms can run on.
pub trait Real:
    nalgebra::Scalar
    + Copy
    + Debug
    + PartialOrd
    + Zero
    + One
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Send
    + Sync
    + 'static
{
    /// Short name used in reports and benchmark tables (`"f64"`, `"f32"`, `"dd"`).
    const NAME: &'static str;
    /// Converts from `f64`, rounding to nearest where the type is narrower.
    fn from_f64(x: f64) -> Self;
    /// Converts to `f64`, rounding to nearest where the type is wider.
    fn to_f64(self) -> f64;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Sine (rad).
    fn sin(self) -> Self;
    /// Cosine (rad).
    fn cos(self) -> Self;
    /// Sine and cosine together.
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    /// Absolute value.
    fn abs(self) -> Self;
    /// The unit roundoff of the type (2⁻⁵² for f64).
    fn epsilon() -> Self;
    /// Whether the value is neither infinite nor NaN.
    fn is_finite(self) -> bool;

    /// The value, where one is known: always for numbers; for the code generator's traced scalar only for
    /// constants (a value computed from the generated function's inputs is unknown until run time).
    ///
    /// Every check on a computed value (a singular pivot, a singular loop, a non-finite input) goes through
    /// this, so that it is explicit what a check does while tracing: nothing — the generated function returns
    /// the measure (a pivot, a condition number) for its caller to check instead.
    #[inline(always)]
    fn value(self) -> Option<f64> {
        Some(self.to_f64())
    }

    /// `self > 0` and finite: false for zero, negatives, infinities and NaN (a usable pivot). A check:
    /// on a value unknown at generation time it is a generation-time error (see [`Real::value`]).
    #[inline(always)]
    fn is_positive_finite(self) -> bool {
        self > Self::zero() && self.is_finite()
    }

    /// Names this value for generated code: component `component` (`""` for a scalar) of `quantity`
    /// (`"v"`, `"qdd"`, …) of the body or joint `owner`. The code generator's traced scalar attaches the
    /// name to the operation that computed the value, and generated code calls it by that name
    /// (`thigh_v_ang_x`, `knee_qdd`); for numbers it is nothing at all. Names never change a value.
    #[inline(always)]
    fn named(self, _owner: &str, _quantity: &str, _component: &str) -> Self {
        self
    }

    /// `if self > other { then } else { otherwise }`: a data-dependent choice that generated code keeps
    /// (the tracing scalar records it as a select instead of answering the comparison at generation
    /// time). Every choice on a computed value in the algorithms is written with this, never with `if`:
    /// the tracing scalar refuses to answer a comparison of values it does not know.
    #[inline(always)]
    fn select_gt(self, other: Self, then: Self, otherwise: Self) -> Self {
        if self > other {
            then
        } else {
            otherwise
        }
    }

    /// The larger of two values (`other` where they are equal or either is NaN), as a select.
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        self.select_gt(other, self, other)
    }
    /// The smaller of two values (`other` where they are equal or either is NaN), as a select.
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        other.select_gt(self, self, other)
    }
}

// `num_traits::Float` is the platform's libm with `std` and the `libm` crate without it.
macro_rules! impl_real_for_float {
    ($t:ty, $name:literal) => {
        impl Real for $t {
            const NAME: &'static str = $name;
            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t as num_traits::Float>::sqrt(self)
            }
            #[inline(always)]
            fn sin(self) -> Self {
                <$t as num_traits::Float>::sin(self)
            }
            #[inline(always)]
            fn cos(self) -> Self {
                <$t as num_traits::Float>::cos(self)
            }
            #[inline(always)]
            fn sin_cos(self) -> (Self, Self) {
                <$t as num_traits::Float>::sin_cos(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn epsilon() -> Self {
                <$t>::EPSILON
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
        }
    };
}

impl_real_for_float!(f64, "f64");
impl_real_for_float!(f32, "f32");
