use crate::spatial::{rotate_tensor, skew, Force, Motion, Transform};
use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// The spatial inertia of a rigid body about its frame origin, stored as
/// mass `m`, first moment `h = m c` (c: centre of mass) and rotational inertia `I_o` about the origin:
/// `M = [[I_o, [h]×], [[h]×ᵀ, m 1]]` (the paper's `M(k)` with `p(k) = c`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialInertia<T: Real> {
    /// Mass `m` (kg).
    pub mass: T,
    /// First moment `h = m c` (kg·m).
    pub first_moment: Vector3<T>,
    /// Rotational inertia `I_o` about the frame origin (kg·m²).
    pub rotational: Matrix3<T>,
}

impl<T: Real> SpatialInertia<T> {
    /// The inertia of nothing (all zero).
    pub fn zero() -> Self {
        Self {
            mass: T::zero(),
            first_moment: Vector3::zeros(),
            rotational: Matrix3::zeros(),
        }
    }

    /// From mass, centre of mass and rotational inertia about the centre of mass, all in this frame.
    pub fn from_com(mass: T, com: Vector3<T>, inertia_at_com: Matrix3<T>) -> Self {
        let h = com * mass;
        // Parallel-axis theorem: I_o = I_c + m ([c]×)ᵀ [c]× = I_c + m (|c|² 1 − c cᵀ).
        let cx = skew(&com);
        Self {
            mass,
            first_moment: h,
            rotational: inertia_at_com + cx.transpose() * cx * mass,
        }
    }

    /// The centre of mass (the origin for a massless body).
    pub fn com(&self) -> Vector3<T> {
        if self.mass > T::zero() {
            self.first_moment / self.mass
        } else {
            Vector3::zeros()
        }
    }

    /// Rotational inertia about the centre of mass.
    pub fn inertia_at_com(&self) -> Matrix3<T> {
        if self.mass > T::zero() {
            let c = self.com();
            let cx = skew(&c);
            self.rotational - cx.transpose() * cx * self.mass
        } else {
            self.rotational
        }
    }

    /// `M v`: the momentum of the body moving with `v`.
    #[inline(always)]
    pub fn mul_motion(&self, v: &Motion<T>) -> Force<T> {
        Force::new(
            self.rotational * v.angular + self.first_moment.cross(&v.linear),
            v.linear * self.mass - self.first_moment.cross(&v.angular),
        )
    }

    /// The first moment `m c` in the parent frame of `x`, about its origin (the body frame being `x`'s child
    /// frame): [`SpatialInertia::act`]'s first moment alone — what centre-of-mass sums and the weight of a
    /// subtree need.
    #[inline(always)]
    pub fn first_moment_in(&self, x: &Transform<T>) -> Vector3<T> {
        x.rotation * self.first_moment + x.translation * self.mass
    }

    /// The same inertia expressed in the parent frame of `x` (the body frame being `x`'s child frame).
    pub fn act(&self, x: &Transform<T>) -> SpatialInertia<T> {
        let r = &x.rotation;
        let p = &x.translation;
        let h_rot = r * self.first_moment;
        // I_o about the new origin: rotate, then shift the reference point by −p using
        // I_new = I_rot − [p]×[h]× − [h]×[p]× − m [p]×[p]× (h the rotated first moment), which with
        // [a]×[b]× = b aᵀ − (a·b) 1 is (2 p·h + m |p|²) 1 − h pᵀ − p hᵀ − m p pᵀ. The diagonal is written as
        // Σ_{j≠k} p_j (2 h_j + m p_j): no cancelling terms, so an offset along one axis leaves exact zeros.
        let m = self.mass;
        let h = &h_rot;
        let w = |j: usize| p[j] * (h[j] + h[j] + m * p[j]);
        let (w0, w1, w2) = (w(0), w(1), w(2));
        let s = |i: usize, j: usize| -(h[i] * p[j] + p[i] * h[j] + m * p[i] * p[j]);
        let (xy, xz, yz) = (s(0, 1), s(0, 2), s(1, 2));
        let shift = Matrix3::new(w1 + w2, xy, xz, xy, w0 + w2, yz, xz, yz, w0 + w1);
        let rot = rotate_tensor(r, &self.rotational) + shift;
        SpatialInertia {
            mass: self.mass,
            first_moment: h_rot + p * self.mass,
            rotational: rot,
        }
    }

    /// Kinetic energy ½ vᵀ M v.
    pub fn kinetic_energy(&self, v: &Motion<T>) -> T {
        let half = T::from_f64(0.5);
        v.dot(&self.mul_motion(v)) * half
    }

    /// The same inertia in scalar `U` (through f64).
    pub fn cast<U: Real>(&self) -> SpatialInertia<U> {
        SpatialInertia {
            mass: U::from_f64(self.mass.to_f64()),
            first_moment: self.first_moment.map(|x| U::from_f64(x.to_f64())),
            rotational: self.rotational.map(|x| U::from_f64(x.to_f64())),
        }
    }
}

impl<T: Real> core::ops::Add for SpatialInertia<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            mass: self.mass + o.mass,
            first_moment: self.first_moment + o.first_moment,
            rotational: self.rotational + o.rotational,
        }
    }
}
