use crate::spatial::{Force, Motion};
use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// How far (rad) an URDF `rpy` angle may be from a multiple of π/2 and still be read as that exact
/// quarter turn.
pub const QUARTER_TURN_TOLERANCE: f64 = 1e-10;

/// The exact sine and cosine (each 0 or ±1) of an angle within [`QUARTER_TURN_TOLERANCE`] of a multiple
/// of π/2, or `None`.
///
/// Why: model files write quarter turns rounded (`1.57079632679`, `4.71238898038`: π/2 and 3π/2 to 11
/// digits), and even π/2 to full f64 precision has a cosine of 6.1e-17. Taken literally, these leave
/// residues of 1e-11 to 1e-17 in the rotations, which change no result that matters (5e-12 rad at most)
/// but are numbers the generated code must multiply by where the exact turn has a zero, and they make
/// mirrored branches differ (TALOS's right gripper is turned by π - 9.8e-12 about its wrist, its left
/// by exactly 0), so that the branches' code no longer pairs. The tolerance is ten times the rounding of
/// an 11-digit angle; an angle meant to be 1e-10 rad off a quarter turn is not a model anyone writes.
pub fn quarter_turn(angle: f64) -> Option<(f64, f64)> {
    if !angle.is_finite() || angle.abs() > 1e3 {
        return None;
    }
    let turns = libm::round(angle / core::f64::consts::FRAC_PI_2);
    if (angle - turns * core::f64::consts::FRAC_PI_2).abs() > QUARTER_TURN_TOLERANCE {
        return None;
    }
    Some(match (turns as i64).rem_euclid(4) {
        0 => (0.0, 1.0),
        1 => (1.0, 0.0),
        2 => (0.0, -1.0),
        _ => (-1.0, 0.0),
    })
}

/// A rigid transform: the pose of a child frame in a parent frame.
///
/// `rotation` has the child's axes as columns, in parent coordinates; `translation` is the child origin in
/// parent coordinates (Pinocchio's `SE3` placement; Featherstone's `X` from parent to child is the motion
/// map [`Transform::inv_act_motion`]). Points map child → parent as `p_parent = R p_child + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform<T: Real> {
    /// The child's axes as columns, in parent coordinates.
    pub rotation: Matrix3<T>,
    /// The child origin in parent coordinates (m).
    pub translation: Vector3<T>,
}

impl<T: Real> Transform<T> {
    /// From rotation and translation as [`Transform`] defines them.
    #[inline(always)]
    pub fn new(rotation: Matrix3<T>, translation: Vector3<T>) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// The child frame coincides with the parent.
    pub fn identity() -> Self {
        Self::new(Matrix3::identity(), Vector3::zeros())
    }

    /// The URDF `<origin xyz rpy>` transform, computed in `T` from the file's numbers (so that a
    /// higher-precision scalar evaluates the trigonometry in its own precision).
    /// URDF's rpy are fixed-axis roll about x, then pitch about y, then yaw about z: `R = Rz Ry Rx`.
    /// An angle within [`QUARTER_TURN_TOLERANCE`] of a multiple of π/2 is read as that exact quarter
    /// turn (see [`quarter_turn`]).
    pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        let sin_cos = |angle: f64| match quarter_turn(angle) {
            Some((s, c)) => (T::from_f64(s), T::from_f64(c)),
            None => T::from_f64(angle).sin_cos(),
        };
        let (sr, cr) = sin_cos(rpy[0]);
        let (sp, cp) = sin_cos(rpy[1]);
        let (sy, cy) = sin_cos(rpy[2]);
        let rotation = Matrix3::new(
            cy * cp,
            cy * sp * sr - sy * cr,
            cy * sp * cr + sy * sr,
            sy * cp,
            sy * sp * sr + cy * cr,
            sy * sp * cr - cy * sr,
            -sp,
            cp * sr,
            cp * cr,
        );
        let t = Vector3::new(
            T::from_f64(xyz[0]),
            T::from_f64(xyz[1]),
            T::from_f64(xyz[2]),
        );
        Self::new(rotation, t)
    }

    /// Rotation by `angle` about the unit vector `axis` (Rodrigues), no translation.
    #[inline(always)]
    pub fn rotation_about(axis: &Vector3<T>, angle: T) -> Self {
        let (s, c) = angle.sin_cos();
        Self::new(rotation_matrix(axis, s, c), Vector3::zeros())
    }

    /// Translation by `d` along the unit vector `axis`, no rotation.
    #[inline(always)]
    pub fn translation_along(axis: &Vector3<T>, d: T) -> Self {
        Self::new(Matrix3::identity(), axis * d)
    }

    /// `self ∘ other`: the pose of `other`'s child frame in `self`'s parent frame.
    #[inline(always)]
    pub fn compose(&self, other: &Transform<T>) -> Transform<T> {
        Transform::new(
            self.rotation * other.rotation,
            self.translation + self.rotation * other.translation,
        )
    }

    /// The pose of the parent frame in the child frame.
    pub fn inverse(&self) -> Transform<T> {
        let rt = self.rotation.transpose();
        Transform::new(rt, -(rt * self.translation))
    }

    /// Maps a point from child to parent coordinates.
    #[inline(always)]
    pub fn act_point(&self, p: &Vector3<T>) -> Vector3<T> {
        self.rotation * p + self.translation
    }

    /// A motion in child coordinates expressed in parent coordinates.
    #[inline(always)]
    pub fn act_motion(&self, m: &Motion<T>) -> Motion<T> {
        let w = self.rotation * m.angular;
        let v = self.rotation * m.linear + self.translation.cross(&w);
        Motion::new(w, v)
    }

    /// A motion in parent coordinates expressed in child coordinates (Featherstone's `X m`).
    #[inline(always)]
    pub fn inv_act_motion(&self, m: &Motion<T>) -> Motion<T> {
        let v = m.linear - self.translation.cross(&m.angular);
        Motion::new(self.rotation.tr_mul(&m.angular), self.rotation.tr_mul(&v))
    }

    /// A force in child coordinates expressed in parent coordinates (Featherstone's `Xᵀ f`).
    #[inline(always)]
    pub fn act_force(&self, f: &Force<T>) -> Force<T> {
        let lin = self.rotation * f.linear;
        let ang = self.rotation * f.angular + self.translation.cross(&lin);
        Force::new(ang, lin)
    }

    /// A force in parent coordinates expressed in child coordinates.
    #[inline(always)]
    pub fn inv_act_force(&self, f: &Force<T>) -> Force<T> {
        let n = f.angular - self.translation.cross(&f.linear);
        Force::new(self.rotation.tr_mul(&n), self.rotation.tr_mul(&f.linear))
    }

    /// Converts every entry to another scalar type.
    pub fn cast<U: Real>(&self) -> Transform<U> {
        Transform::new(
            self.rotation.map(|x| U::from_f64(x.to_f64())),
            self.translation.map(|x| U::from_f64(x.to_f64())),
        )
    }
}

/// Rodrigues' formula `R = c I + s [a]× + (1 − c) a aᵀ` from a unit axis and the angle's sine and cosine.
/// An axis along ±x, ±y or ±z gives the exact elementary rotation (its 1 stays exactly 1, and generated
/// code sees its zeros).
#[inline(always)]
pub fn rotation_matrix<T: Real>(a: &Vector3<T>, s: T, c: T) -> Matrix3<T> {
    let (o, z) = (T::one(), T::zero());
    let unit = |v: T| v == o || v == -o;
    if unit(a.x) && a.y == z && a.z == z {
        let s = s * a.x;
        return Matrix3::new(o, z, z, z, c, -s, z, s, c);
    }
    if unit(a.y) && a.x == z && a.z == z {
        let s = s * a.y;
        return Matrix3::new(c, z, s, z, o, z, -s, z, c);
    }
    if unit(a.z) && a.x == z && a.y == z {
        let s = s * a.z;
        return Matrix3::new(c, -s, z, s, c, z, z, z, o);
    }
    rodrigues(a, s, c)
}

#[inline(always)]
fn rodrigues<T: Real>(a: &Vector3<T>, s: T, c: T) -> Matrix3<T> {
    let t = T::one() - c;
    let (x, y, z) = (a.x, a.y, a.z);
    Matrix3::new(
        c + t * x * x,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        c + t * y * y,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        c + t * z * z,
    )
}
