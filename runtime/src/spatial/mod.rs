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
pub use transform::{quarter_turn, Transform, QUARTER_TURN_TOLERANCE};

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
    if let Some((k, flip)) = fixed_axis(r) {
        return rotate_tensor_about(k, flip, r, a);
    }
    // B = R A (27 products), then (B Rᵀ)_ij = row_i(B) · row_j(R) for i ≤ j (18 products).
    let b = r * a;
    let e =
        |i: usize, j: usize| b[(i, 0)] * r[(j, 0)] + b[(i, 1)] * r[(j, 1)] + b[(i, 2)] * r[(j, 2)];
    let (xx, xy, xz, yy, yz, zz) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
}

/// The coordinate axis `k` that `r` keeps fixed or reverses, if its row and column `k` are known to be
/// `±e_k` (a joint rotating about a coordinate axis, its origin not rotated or turned by a half turn about
/// another axis; in generated code the entries are constants there), and whether it reverses it. Such a
/// rotation is `[[c, −s], [s, c]]` in the other two axes, or that with its second row negated.
#[inline(always)]
fn fixed_axis<T: Real>(r: &Matrix3<T>) -> Option<(usize, bool)> {
    (0..3).find_map(|k| {
        let off_axis_zero = (0..3)
            .filter(|&m| m != k)
            .all(|m| r[(k, m)].value() == Some(0.0) && r[(m, k)].value() == Some(0.0));
        match r[(k, k)].value() {
            Some(d) if off_axis_zero && d == 1.0 => Some((k, false)),
            Some(d) if off_axis_zero && d == -1.0 => Some((k, true)),
            _ => None,
        }
    })
}

/// `R A Rᵀ` for a rotation `R` about coordinate axis `k` by the angle θ (`c = cos θ`, `s = sin θ` read
/// from `R`), in the double angle: with `(i, j)` the other two axes, `a = (A_ii + A_jj)/2` and
/// `d = (A_ii − A_jj)/2`, the plane block becomes `a ± (d cos 2θ − A_ij sin 2θ)` on the diagonal and
/// `d sin 2θ + A_ij cos 2θ` off it, and the axis row `A_ki, A_kj` rotates like a vector. About 25
/// operations where the general product takes 33 or more even after the zeros of `R` fold away.
///
/// Where `R` reverses axis `k` (`flip`) it is `D Q`, `D = diag` with −1 at `k` and `j`, `Q` a rotation
/// about `k` read from `R` (`c = R_ii`, `s = −R_ji`), and `R A Rᵀ = D (Q A Qᵀ) D` negates the entries
/// that join `i` to `k` or `j`. So a joint behind a half turn (TALOS's right gripper, turned by π about
/// its wrist where the left one is not) is computed as its mirror partner is, up to signs.
#[inline(always)]
fn rotate_tensor_about<T: Real>(
    k: usize,
    flip: bool,
    r: &Matrix3<T>,
    a: &Matrix3<T>,
) -> Matrix3<T> {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let (c, s) = if flip {
        (r[(i, i)], -r[(j, i)])
    } else {
        (r[(i, i)], r[(j, i)])
    };
    let cos2 = c * c - s * s;
    let sc = s * c;
    let sin2 = sc + sc;
    let half = T::from_f64(0.5);
    // Halved before the sum: A_ii + A_jj may overflow where the rotated entries do not.
    let (ii, jj) = (a[(i, i)] * half, a[(j, j)] * half);
    let (mean, diff) = (ii + jj, ii - jj);
    let t = diff * cos2 - a[(i, j)] * sin2;
    let mut out = Matrix3::zeros();
    out[(k, k)] = a[(k, k)];
    out[(i, i)] = mean + t;
    out[(j, j)] = mean - t;
    let ij = diff * sin2 + a[(i, j)] * cos2;
    let ki = c * a[(k, i)] - s * a[(k, j)];
    let kj = s * a[(k, i)] + c * a[(k, j)];
    out[(i, j)] = ij;
    out[(j, i)] = ij;
    out[(k, i)] = ki;
    out[(i, k)] = ki;
    out[(k, j)] = kj;
    out[(j, k)] = kj;
    if flip {
        for (m, n) in [(i, j), (j, i), (i, k), (k, i)] {
            out[(m, n)] = -out[(m, n)];
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The double-angle rotation about a coordinate axis against the plain product `R A Rᵀ`, for each
    /// axis, angles across the circle and a symmetric `A` with every entry non-zero and of mixed signs
    /// (the articulated inertia's blocks are not positive).
    #[test]
    fn rotation_about_a_coordinate_axis_matches_the_full_product() {
        let a = Matrix3::new(2.5, -0.3, 0.7, -0.3, 1.1, 0.45, 0.7, 0.45, -0.8);
        for k in 0..3 {
            for step in 0..16 {
                let angle = -3.0 + 0.41 * step as f64;
                let axis = nalgebra::Unit::new_normalize(Vector3::ith(k, 1.0));
                let r = *nalgebra::Rotation3::from_axis_angle(&axis, angle).matrix();
                // Rotation3 writes exact zeros and ones in row and column k.
                assert_eq!(fixed_axis(&r), Some((k, false)));
                // Behind a half turn about either other axis (exact: a quarter-turn reading), k reverses.
                let half_turns = [(k + 1) % 3, (k + 2) % 3].map(|other| {
                    let mut h = Matrix3::from_diagonal_element(-1.0);
                    h[(other, other)] = 1.0;
                    h * r
                });
                for (r, flip) in [(r, false), (half_turns[0], true), (half_turns[1], true)] {
                    assert_eq!(fixed_axis(&r), Some((k, flip)));
                    let fast = rotate_tensor(&r, &a);
                    let full = r * a * r.transpose();
                    assert!(
                        (fast - full).abs().max() < 1e-15 * a.abs().max(),
                        "axis {k}, angle {angle}, reversed {flip}"
                    );
                    assert_eq!(fast, fast.transpose());
                }
            }
        }
        // A rotation that keeps no coordinate axis takes the general product.
        let r = *nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.9).matrix();
        assert_eq!(fixed_axis(&r), None);
        assert!((rotate_tensor(&r, &a) - r * a * r.transpose()).abs().max() < 1e-15 * 4.0);
    }
}
