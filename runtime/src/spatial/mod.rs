//! Spatial (6-D) algebra in the convention of the paper: vectors are `[angular; linear]`.
//!
//! Transforms are stored as a rotation and a translation, inertias as (mass, first moment, rotational
//! inertia), never as dense 6×6 matrices: the algorithms apply them through the block formulas, which costs
//! a fraction of a 6×6 product and keeps the zero structure visible to the code generator later.

/// The vector-space operations shared by [`Motion`] and [`Force`] (both are a pair of 3-vectors).
macro_rules! impl_spatial_vector_ops {
    ($ty:ident) => {
        impl<T: Real> core::ops::Add for $ty<T> {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                Self::new(self.angular + o.angular, self.linear + o.linear)
            }
        }
        impl<T: Real> core::ops::Sub for $ty<T> {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                Self::new(self.angular - o.angular, self.linear - o.linear)
            }
        }
        impl<T: Real> core::ops::AddAssign for $ty<T> {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                self.angular += o.angular;
                self.linear += o.linear;
            }
        }
        impl<T: Real> core::ops::SubAssign for $ty<T> {
            #[inline(always)]
            fn sub_assign(&mut self, o: Self) {
                self.angular -= o.angular;
                self.linear -= o.linear;
            }
        }
        impl<T: Real> core::ops::Neg for $ty<T> {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                Self::new(-self.angular, -self.linear)
            }
        }
        impl<T: Real> core::ops::Mul<T> for $ty<T> {
            type Output = Self;
            #[inline(always)]
            fn mul(self, s: T) -> Self {
                Self::new(self.angular * s, self.linear * s)
            }
        }
    };
}

mod articulated;
mod force;
mod inertia;
mod motion;
mod names;
mod transform;

pub use articulated::ArticulatedInertia;
pub use force::Force;
pub use inertia::SpatialInertia;
pub use motion::Motion;
pub use transform::Transform;

use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// The skew-symmetric matrix `[x]×` with `[x]× y = x × y`.
#[inline(always)]
pub fn skew<T: Real>(x: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -x.z, x.y, x.z, z, -x.x, -x.y, x.x, z)
}

/// `R A Rᵀ` for a symmetric 3×3 `A`: the change of frame of a rotational inertia or a symmetric block.
/// Computes the six distinct entries only and mirrors them (exactly symmetric output).
#[inline(always)]
pub(crate) fn rotate_tensor<T: Real>(r: &Matrix3<T>, a: &Matrix3<T>) -> Matrix3<T> {
    // B = R A (27 products), then (B Rᵀ)_ij = row_i(B) · row_j(R) for i ≤ j (18 products).
    let b = r * a;
    let e =
        |i: usize, j: usize| b[(i, 0)] * r[(j, 0)] + b[(i, 1)] * r[(j, 1)] + b[(i, 2)] * r[(j, 2)];
    let (xx, xy, xz, yy, yz, zz) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
}

/// The unit vector along `v`, or `None` for a zero or non-finite vector. Scaled by its largest
/// component first, so that a direction written as `0 1e-200 0` or `0 1e200 0` is a direction: its
/// squared norm would underflow to zero or overflow to infinity.
#[cfg_attr(not(feature = "alloc"), allow(dead_code))]
pub(crate) fn unit_vector<T: Real>(v: &Vector3<T>) -> Option<Vector3<T>> {
    let largest = v.x.abs().max(v.y.abs()).max(v.z.abs());
    if !(v.iter().all(|x| x.is_finite()) && largest > T::zero()) {
        return None;
    }
    let scaled = v / largest;
    Some(scaled / scaled.dot(&scaled).sqrt())
}
