//! Spatial (6-D) algebra in the convention of the paper: vectors are `[angular; linear]`.
//!
//! Transforms are stored as a rotation and a translation, inertias as (mass, first moment, rotational
//! inertia), never as dense 6×6 matrices: the algorithms apply them through the block formulas, which costs
//! a fraction of a 6×6 product and keeps the zero structure visible to the code generator later.

mod articulated;
mod force;
mod inertia;
mod motion;
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

/// `R A Rᵀ` for a 3×3 `A`: the change of frame of a rotational inertia or a tensor block.
#[inline(always)]
pub(crate) fn rotate_tensor<T: Real>(r: &Matrix3<T>, a: &Matrix3<T>) -> Matrix3<T> {
    r * a * r.transpose()
}
