use crate::Real;
use nalgebra::Vector3;

/// A spatial force vector `[n; f]`: moment about the frame origin, then force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Force<T: Real> {
    /// Moment `n` about the frame origin (N·m).
    pub angular: Vector3<T>,
    /// Force `f` (N).
    pub linear: Vector3<T>,
}

impl<T: Real> Force<T> {
    /// `[angular; linear]`.
    #[inline(always)]
    pub fn new(angular: Vector3<T>, linear: Vector3<T>) -> Self {
        Self { angular, linear }
    }
    /// The zero force.
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new(Vector3::zeros(), Vector3::zeros())
    }
    /// From `[n; f]` as a 6-array.
    pub fn from_array(a: [T; 6]) -> Self {
        Self::new(
            Vector3::new(a[0], a[1], a[2]),
            Vector3::new(a[3], a[4], a[5]),
        )
    }
    /// The pairing `fᵀ m` (power), as [`crate::Motion::dot`] from the force side.
    #[inline(always)]
    pub fn dot_motion(&self, m: &crate::Motion<T>) -> T {
        self.angular.dot(&m.angular) + self.linear.dot(&m.linear)
    }
    /// As `[n; f]`, a 6-array.
    pub fn to_array(&self) -> [T; 6] {
        let (n, f) = (&self.angular, &self.linear);
        [n.x, n.y, n.z, f.x, f.y, f.z]
    }
}

impl_spatial_vector_ops!(Force);
