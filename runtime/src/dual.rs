//! Forward-mode dual numbers with `N` tangent directions: a scalar the whole solver runs on, so that one
//! pass of an algorithm gives its value and its derivatives along `N` directions of its inputs.
//!
//! `Dual { re, eps }` stands for `re + Σₖ eps[k] εₖ` with `εⱼ εₖ = 0`: sums add the tangents, products
//! follow the product rule, and `sqrt`, `sin`, `cos` the chain rule. The derivatives of the dynamics
//! ([`crate::aba_derivatives`], [`crate::rnea_derivatives`]) seed the inputs' tangents with the directions
//! they differentiate along and read the outputs' tangents; they are exact to rounding, with no step size.
//!
//! Comparisons, [`Real::select_gt`] and the checks on computed values look at the value `re` only: a
//! derivative is that of the branch taken, as it is everywhere but on a branch boundary.

use crate::Real;
use core::fmt::Debug;
use core::iter::Sum;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use num_traits::{One, Zero};

/// `re + Σₖ eps[k] εₖ`: a value and its derivatives along `N` directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<T: Real, const N: usize> {
    /// The value.
    pub re: T,
    /// The derivative along each direction.
    pub eps: [T; N],
}

impl<T: Real, const N: usize> Dual<T, N> {
    /// A constant: no derivative along any direction.
    #[inline(always)]
    pub fn constant(re: T) -> Self {
        Self {
            re,
            eps: [T::zero(); N],
        }
    }

    /// The value `re` varying with unit rate along direction `k` (the seed of an input).
    #[inline(always)]
    pub fn variable(re: T, k: usize) -> Self {
        let mut eps = [T::zero(); N];
        eps[k] = T::one();
        Self { re, eps }
    }

    /// `f(re) + f'(re) · tangent`: the chain rule for a function with value `f` and derivative `df` at `re`.
    #[inline(always)]
    fn chain(self, f: T, df: T) -> Self {
        let mut eps = self.eps;
        for e in &mut eps {
            *e *= df;
        }
        Self { re: f, eps }
    }
}

impl<T: Real, const N: usize> PartialOrd for Dual<T, N> {
    /// Orders by value (a dual with equal values and different tangents is neither less nor greater).
    fn partial_cmp(&self, other: &Self) -> Option<core::cmp::Ordering> {
        self.re.partial_cmp(&other.re)
    }
}

impl<T: Real, const N: usize> Add for Dual<T, N> {
    type Output = Self;
    #[inline(always)]
    fn add(mut self, o: Self) -> Self {
        self.re += o.re;
        for k in 0..N {
            self.eps[k] += o.eps[k];
        }
        self
    }
}

impl<T: Real, const N: usize> Sub for Dual<T, N> {
    type Output = Self;
    #[inline(always)]
    fn sub(mut self, o: Self) -> Self {
        self.re -= o.re;
        for k in 0..N {
            self.eps[k] -= o.eps[k];
        }
        self
    }
}

impl<T: Real, const N: usize> Mul for Dual<T, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let mut eps = [T::zero(); N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = self.eps[k] * o.re + self.re * o.eps[k];
        }
        Self {
            re: self.re * o.re,
            eps,
        }
    }
}

impl<T: Real, const N: usize> Div for Dual<T, N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        // (a/b)' = (a' − (a/b) b') / b
        let re = self.re / o.re;
        let mut eps = [T::zero(); N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = (self.eps[k] - re * o.eps[k]) / o.re;
        }
        Self { re, eps }
    }
}

impl<T: Real, const N: usize> Neg for Dual<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            re: -self.re,
            eps: self.eps.map(|e| -e),
        }
    }
}

macro_rules! assign_from_binary {
    ($tr:ident, $method:ident, $op:tt) => {
        impl<T: Real, const N: usize> $tr for Dual<T, N> {
            #[inline(always)]
            fn $method(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}
assign_from_binary!(AddAssign, add_assign, +);
assign_from_binary!(SubAssign, sub_assign, -);
assign_from_binary!(MulAssign, mul_assign, *);
assign_from_binary!(DivAssign, div_assign, /);

impl<T: Real, const N: usize> Zero for Dual<T, N> {
    fn zero() -> Self {
        Self::constant(T::zero())
    }
    fn is_zero(&self) -> bool {
        self.re.is_zero() && self.eps.iter().all(|e| e.is_zero())
    }
}

impl<T: Real, const N: usize> One for Dual<T, N> {
    fn one() -> Self {
        Self::constant(T::one())
    }
}

impl<T: Real, const N: usize> Sum for Dual<T, N> {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::zero(), |a, b| a + b)
    }
}

impl<'a, T: Real, const N: usize> Sum<&'a Dual<T, N>> for Dual<T, N> {
    fn sum<I: Iterator<Item = &'a Self>>(iter: I) -> Self {
        iter.fold(Self::zero(), |a, b| a + *b)
    }
}

impl<T: Real, const N: usize> Real for Dual<T, N> {
    const NAME: &'static str = "dual";

    fn from_f64(x: f64) -> Self {
        Self::constant(T::from_f64(x))
    }

    fn to_f64(self) -> f64 {
        self.re.to_f64()
    }

    fn sqrt(self) -> Self {
        let root = self.re.sqrt();
        // d√x = dx / (2√x). At x = 0 a zero tangent stays zero (no 0 · ∞): the norm of a vector that
        // passes through zero (a rotation angle at the identity) has a zero tangent there. A select, not
        // a test of the tangent, decides it: in traced code a tangent like 2 w · dw is a computed value,
        // zero only at run time, and 0 · ∞ there was NaN (generated `step_derivatives` of a floating
        // base: the step's rotation against itself is the identity). A non-zero tangent at x = 0, whose
        // derivative does not exist, gets 0 too instead of ±∞.
        let half_inverse = root.select_gt(T::zero(), T::from_f64(0.5) / root, T::zero());
        let mut eps = self.eps;
        for e in &mut eps {
            if !e.is_zero() {
                *e *= half_inverse;
            }
        }
        Self { re: root, eps }
    }

    fn sin(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(s, c)
    }

    fn cos(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(c, -s)
    }

    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.re.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }

    fn abs(self) -> Self {
        // d|x| = sign(x) dx, the sign as a select so that traced code keeps it.
        let sign = T::zero().select_gt(self.re, -T::one(), T::one());
        self.chain(self.re.abs(), sign)
    }

    /// Lane by lane: the value and each derivative of the branch the values choose.
    fn select_gt(self, other: Self, then: Self, otherwise: Self) -> Self {
        let mut eps = [T::zero(); N];
        for (k, e) in eps.iter_mut().enumerate() {
            *e = self.re.select_gt(other.re, then.eps[k], otherwise.eps[k]);
        }
        Self {
            re: self.re.select_gt(other.re, then.re, otherwise.re),
            eps,
        }
    }

    fn epsilon() -> Self {
        Self::constant(T::epsilon())
    }

    fn is_finite(self) -> bool {
        self.re.is_finite() && self.eps.iter().all(|e| e.is_finite())
    }

    /// Known only for a constant (every tangent exactly zero): the algorithms use a known value to skip
    /// work on exact zeros and ones (a joint axis, a rotation about a coordinate axis), which would drop
    /// the derivative of an entry that is 0 or 1 now but moves along a direction.
    fn value(self) -> Option<f64> {
        if self.eps.iter().all(|e| e.is_zero()) {
            self.re.value()
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type D = Dual<f64, 2>;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-14 * (1.0 + b.abs())
    }

    /// Each rule against the derivative worked by hand, at a point where every term matters.
    #[test]
    fn rules_match_hand_derivatives() {
        let x = D::variable(0.7, 0);
        let y = D::variable(-1.3, 1);
        let f = (x * y + x.sin()) / (y.cos() + D::from_f64(2.0)) - x.sqrt() * y;
        // ∂/∂x and ∂/∂y of (x y + sin x)/(cos y + 2) − √x y.
        let (a, b) = (0.7f64, -1.3f64);
        let den = b.cos() + 2.0;
        let dx = (b + a.cos()) / den - 0.5 / a.sqrt() * b;
        let dy = a / den + (a * b + a.sin()) * b.sin() / (den * den) - a.sqrt();
        assert!(close(f.re, (a * b + a.sin()) / den - a.sqrt() * b));
        assert!(close(f.eps[0], dx), "{} vs {dx}", f.eps[0]);
        assert!(close(f.eps[1], dy), "{} vs {dy}", f.eps[1]);
        let n = -x;
        assert_eq!((n.re, n.eps), (-0.7, [-1.0, 0.0]));
        assert_eq!(y.abs().eps, [0.0, -1.0]);
    }

    /// A constant is known; a value that moves is not; √0 of a constant keeps a zero tangent.
    #[test]
    fn value_is_known_only_for_constants() {
        assert_eq!(D::from_f64(1.0).value(), Some(1.0));
        assert_eq!(D::variable(1.0, 1).value(), None);
        let root = D::constant(0.0).sqrt();
        assert_eq!(root.eps, [0.0, 0.0]);
        assert!(D::variable(1.0, 0) < D::variable(2.0, 1));
    }
}
