use crate::spatial::{rotate_tensor, skew, Force, Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::{Matrix3, Matrix6};

/// A symmetric 6×6 inertia `[[A, B], [Bᵀ, C]]` in `[angular; linear]` order: the paper's articulated
/// inertia `P(k)` (and the composite inertia of CRBA), which is no longer a rigid-body inertia once a joint
/// has been articulated, so it keeps its three blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArticulatedInertia<T: Real> {
    /// Angular–angular block (symmetric).
    pub a: Matrix3<T>,
    /// Angular–linear block.
    pub b: Matrix3<T>,
    /// Linear–linear block (symmetric).
    pub c: Matrix3<T>,
}

impl<T: Real> ArticulatedInertia<T> {
    /// All three blocks zero.
    pub fn zero() -> Self {
        Self {
            a: Matrix3::zeros(),
            b: Matrix3::zeros(),
            c: Matrix3::zeros(),
        }
    }

    /// `P v`.
    #[inline(always)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        Force::new(
            self.a * v.angular + self.b * v.linear,
            self.b.tr_mul(&v.angular) + self.c * v.linear,
        )
    }

    /// `P − u uᵀ s`: the rank-one update that articulates a 1-DoF joint (`u = P h`, `s = 1/D`).
    #[inline(always)]
    pub fn sub_rank_one(&mut self, u: &Force<T>, s: T) {
        let (ua, ul) = (&u.angular, &u.linear);
        let sa = ua * s;
        let sl = ul * s;
        // A and C stay symmetric: six products each, mirrored.
        self.a -= symmetric(|i, j| sa[i] * ua[j]);
        self.b -= sa * ul.transpose();
        self.c -= symmetric(|i, j| sl[i] * ul[j]);
    }

    /// `P − a bᵀ` (one term of a symmetric low-rank update `Σ a_k b_kᵀ`; only the upper-right block of
    /// the pair is stored, so the caller must complete a symmetric sum).
    #[inline(always)]
    pub fn sub_outer(&mut self, a: &Force<T>, b: &Force<T>) {
        self.a -= a.angular * b.angular.transpose();
        self.b -= a.angular * b.linear.transpose();
        self.c -= a.linear * b.linear.transpose();
    }

    /// Zeroes the row and column of one spatial direction (angular or linear axis `k`): what an
    /// articulated inertia `τ̄ P` has exactly for a joint moving along that direction.
    pub fn clear_direction(&mut self, angular: bool, k: usize) {
        let z = T::zero();
        for m in 0..3 {
            if angular {
                self.a[(k, m)] = z;
                self.a[(m, k)] = z;
                self.b[(k, m)] = z;
            } else {
                self.c[(k, m)] = z;
                self.c[(m, k)] = z;
                self.b[(m, k)] = z;
            }
        }
    }

    /// The same inertia expressed in the parent frame of `x` (`Xᵀ P X` in Featherstone's notation).
    ///
    /// Rotate each block, then shift the reference point with `[p]×`; written in blocks so the cost is a few
    /// 3×3 products rather than two 6×6 ones.
    #[inline(always)]
    pub fn act(&self, x: &Transform<T>) -> ArticulatedInertia<T> {
        let r = &x.rotation;
        let a = rotate_tensor(r, &self.a);
        let b = r * self.b * r.transpose();
        let c = rotate_tensor(r, &self.c);
        let px = skew(&x.translation);
        let pxc = px * c;
        let bpx = b * px;
        // top-left: A − B[p]× + [p]×Bᵀ − [p]×C[p]×, where [p]×Bᵀ = −(B[p]×)ᵀ; top-right: B + [p]×C.
        // Symmetric: six entries, each a row of [p]×C times a column of [p]×.
        let a_new = symmetric(|i, j| {
            let pcp =
                pxc[(i, 0)] * px[(0, j)] + pxc[(i, 1)] * px[(1, j)] + pxc[(i, 2)] * px[(2, j)];
            a[(i, j)] - bpx[(i, j)] - bpx[(j, i)] - pcp
        });
        ArticulatedInertia {
            a: a_new,
            b: b + pxc,
            c,
        }
    }

    /// As a dense 6×6 matrix (for tests and for multi-DoF joints).
    pub fn to_matrix(&self) -> Matrix6<T> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
        m
    }
}

impl<T: Real> From<SpatialInertia<T>> for ArticulatedInertia<T> {
    fn from(i: SpatialInertia<T>) -> Self {
        ArticulatedInertia {
            a: i.rotational,
            b: skew(&i.first_moment),
            c: Matrix3::identity() * i.mass,
        }
    }
}

impl<T: Real> core::ops::AddAssign for ArticulatedInertia<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

/// The symmetric 3×3 matrix with upper-triangle entries `f(i, j)`, `i ≤ j` (six evaluations).
#[inline(always)]
fn symmetric<T: Real>(f: impl Fn(usize, usize) -> T) -> Matrix3<T> {
    let (xx, xy, xz, yy, yz, zz) = (f(0, 0), f(0, 1), f(0, 2), f(1, 1), f(1, 2), f(2, 2));
    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
}
