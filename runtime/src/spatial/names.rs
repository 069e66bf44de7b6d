//! Names of the components of spatial quantities for generated code ([`Real::named`]): a body's
//! velocity `v` becomes `thigh_v_ang_x … thigh_v_lin_z`, its articulated inertia `thigh_p_a00 …`.
//! For numbers every method here returns its argument unchanged and compiles to nothing.

use crate::spatial::{ArticulatedInertia, Force, Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// Components of a spatial vector, `[angular; linear]`.
const ANGULAR: [&str; 3] = ["ang_x", "ang_y", "ang_z"];
const LINEAR: [&str; 3] = ["lin_x", "lin_y", "lin_z"];

#[inline(always)]
fn name_vector<T: Real>(x: &mut Vector3<T>, owner: &str, quantity: &str, components: &[&str; 3]) {
    for (value, component) in x.iter_mut().zip(components) {
        *value = value.named(owner, quantity, component);
    }
}

/// Entries row-major, `components[3 r + c]` for entry `(r, c)`.
#[inline(always)]
fn name_matrix<T: Real>(m: &mut Matrix3<T>, owner: &str, quantity: &str, components: &[&str; 9]) {
    for r in 0..3 {
        for c in 0..3 {
            m[(r, c)] = m[(r, c)].named(owner, quantity, components[3 * r + c]);
        }
    }
}

impl<T: Real> Motion<T> {
    /// This motion named `quantity` of `owner` (see [`Real::named`]).
    #[inline(always)]
    pub fn named(mut self, owner: &str, quantity: &str) -> Self {
        name_vector(&mut self.angular, owner, quantity, &ANGULAR);
        name_vector(&mut self.linear, owner, quantity, &LINEAR);
        self
    }
}

impl<T: Real> Force<T> {
    /// This force named `quantity` of `owner` (see [`Real::named`]).
    #[inline(always)]
    pub fn named(mut self, owner: &str, quantity: &str) -> Self {
        name_vector(&mut self.angular, owner, quantity, &ANGULAR);
        name_vector(&mut self.linear, owner, quantity, &LINEAR);
        self
    }
}

impl<T: Real> Transform<T> {
    /// This transform named `quantity` of `owner`: rotation `r00 … r22`, translation `px py pz`.
    #[inline(always)]
    pub fn named(mut self, owner: &str, quantity: &str) -> Self {
        const ROTATION: [&str; 9] = [
            "r00", "r01", "r02", "r10", "r11", "r12", "r20", "r21", "r22",
        ];
        name_matrix(&mut self.rotation, owner, quantity, &ROTATION);
        name_vector(&mut self.translation, owner, quantity, &["px", "py", "pz"]);
        self
    }
}

impl<T: Real> ArticulatedInertia<T> {
    /// This inertia named `quantity` of `owner`: blocks `a`, `b`, `c` of `[[A, B], [Bᵀ, C]]`, entries
    /// `a00 … c22`.
    #[inline(always)]
    pub fn named(mut self, owner: &str, quantity: &str) -> Self {
        const A: [&str; 9] = [
            "a00", "a01", "a02", "a10", "a11", "a12", "a20", "a21", "a22",
        ];
        const B: [&str; 9] = [
            "b00", "b01", "b02", "b10", "b11", "b12", "b20", "b21", "b22",
        ];
        const C: [&str; 9] = [
            "c00", "c01", "c02", "c10", "c11", "c12", "c20", "c21", "c22",
        ];
        name_matrix(&mut self.a, owner, quantity, &A);
        name_matrix(&mut self.b, owner, quantity, &B);
        name_matrix(&mut self.c, owner, quantity, &C);
        self
    }
}

impl<T: Real> SpatialInertia<T> {
    /// This inertia named `quantity` of `owner`: mass `m`, first moment `hx hy hz`, rotational inertia
    /// `i00 … i22`.
    #[inline(always)]
    pub fn named(mut self, owner: &str, quantity: &str) -> Self {
        const ROTATIONAL: [&str; 9] = [
            "i00", "i01", "i02", "i10", "i11", "i12", "i20", "i21", "i22",
        ];
        self.mass = self.mass.named(owner, quantity, "m");
        name_vector(&mut self.first_moment, owner, quantity, &["hx", "hy", "hz"]);
        name_matrix(&mut self.rotational, owner, quantity, &ROTATIONAL);
        self
    }
}
