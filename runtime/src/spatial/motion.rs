use crate::spatial::Force;
use crate::Real;
use nalgebra::Vector3;

/// A spatial motion vector (velocity or acceleration) `[ω; v]`, the linear part taken at the frame origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion<T: Real> {
    /// Angular part `ω` (rad/s, or rad/s² for an acceleration).
    pub angular: Vector3<T>,
    /// Linear part `v` at the frame origin (m/s, or m/s²).
    pub linear: Vector3<T>,
}

impl<T: Real> Motion<T> {
    /// `[angular; linear]`.
    #[inline(always)]
    pub fn new(angular: Vector3<T>, linear: Vector3<T>) -> Self {
        Self { angular, linear }
    }
    /// The zero motion.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new(Vector3::zeros(), Vector3::zeros())
    }
    /// From `[ω; v]` as a 6-array.
    pub fn from_array(a: [T; 6]) -> Self {
        Self::new(
            Vector3::new(a[0], a[1], a[2]),
            Vector3::new(a[3], a[4], a[5]),
        )
    }
    /// As `[ω; v]`, a 6-array.
    pub fn to_array(&self) -> [T; 6] {
        let (w, v) = (&self.angular, &self.linear);
        [w.x, w.y, w.z, v.x, v.y, v.z]
    }
    /// Motion cross product `self ×ₘ m` (the paper's ad operator on motions).
    #[inline(always)]
    pub fn cross_motion(&self, m: &Motion<T>) -> Motion<T> {
        Motion::new(
            self.angular.cross(&m.angular),
            self.angular.cross(&m.linear) + self.linear.cross(&m.angular),
        )
    }
    /// Force cross product `self ×* f` (the dual of [`Motion::cross_motion`]).
    #[inline(always)]
    pub fn cross_force(&self, f: &Force<T>) -> Force<T> {
        Force::new(
            self.angular.cross(&f.angular) + self.linear.cross(&f.linear),
            self.angular.cross(&f.linear),
        )
    }
    /// The pairing `mᵀ f` (power).
    #[inline(always)]
    pub fn dot(&self, f: &Force<T>) -> T {
        self.angular.dot(&f.angular) + self.linear.dot(&f.linear)
    }
}

impl_spatial_vector_ops!(Motion);
