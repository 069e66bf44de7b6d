use crate::Real;
use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};
use nalgebra::Vector3;

/// A spatial force vector `[n; f]`: moment about the frame origin, then force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Force<T: Real> {
    pub angular: Vector3<T>,
    pub linear: Vector3<T>,
}

impl<T: Real> Force<T> {
    #[inline(always)]
    pub fn new(angular: Vector3<T>, linear: Vector3<T>) -> Self {
        Self { angular, linear }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::new(Vector3::zeros(), Vector3::zeros())
    }
    pub fn from_array(a: [T; 6]) -> Self {
        Self::new(
            Vector3::new(a[0], a[1], a[2]),
            Vector3::new(a[3], a[4], a[5]),
        )
    }
    pub fn to_array(&self) -> [T; 6] {
        let (n, f) = (&self.angular, &self.linear);
        [n.x, n.y, n.z, f.x, f.y, f.z]
    }
}

impl<T: Real> Add for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.angular + o.angular, self.linear + o.linear)
    }
}
impl<T: Real> Sub for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.angular - o.angular, self.linear - o.linear)
    }
}
impl<T: Real> AddAssign for Force<T> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        self.angular += o.angular;
        self.linear += o.linear;
    }
}
impl<T: Real> SubAssign for Force<T> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        self.angular -= o.angular;
        self.linear -= o.linear;
    }
}
impl<T: Real> Neg for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.angular, -self.linear)
    }
}
impl<T: Real> Mul<T> for Force<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: T) -> Self {
        Self::new(self.angular * s, self.linear * s)
    }
}
