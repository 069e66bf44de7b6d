//! Centre of mass and centroidal momentum (Orin and Goswami): what balance controllers and centroidal
//! MPC read next to the dynamics.
//!
//! All of it reads the kinematics of the last forward kinematics call on the workspace and sums over
//! the model's bodies, which are the links that joints move (links fixed to the world are not bodies:
//! they are left out, as in Pinocchio). The centroidal momentum matrix `A_g` is Pinocchio's `ccrba`: each
//! joint's motion direction times the composite inertia of the subtree it carries, all in world axes,
//! the moment taken about the centre of mass.

use super::{check_len, DynamicsError, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::{Force, SpatialInertia};
use crate::Real;
use nalgebra::{Matrix3xX, Matrix6xX, Vector3};

/// The centre of mass of the model's bodies and its velocity, with their total mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CenterOfMass<T: Real> {
    /// Total mass of the bodies (kg).
    pub mass: T,
    /// Position in the world (m).
    pub com: Vector3<T>,
    /// Velocity in the world (m/s).
    pub vcom: Vector3<T>,
}

/// The centre of mass, its velocity and the total mass from the last
/// [`forward_kinematics`](super::forward_kinematics) (Pinocchio's `centerOfMass(q, v)`). A model without
/// mass has its centre of mass at the origin.
pub fn center_of_mass<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> CenterOfMass<T> {
    let mut mass = T::zero();
    let mut moment = Vector3::zeros();
    let mut momentum = Vector3::zeros();
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        let inertia = &body.inertia;
        let v = &ws.velocity[i];
        mass += inertia.mass;
        moment += x.rotation * inertia.first_moment + x.translation * inertia.mass;
        // m × (velocity of the body's centre of mass) = m v + ω × h, in the body frame.
        momentum += x.rotation * (v.linear * inertia.mass + v.angular.cross(&inertia.first_moment));
    }
    let inv = inverse_mass(mass);
    CenterOfMass {
        mass,
        com: moment * inv,
        vcom: momentum * inv,
    }
}

/// `1/m`, or zero for a massless model (whose centre of mass is then the origin).
fn inverse_mass<T: Real>(mass: T) -> T {
    match mass.value() {
        Some(0.0) => T::zero(),
        _ => T::one() / mass,
    }
}

/// Each subtree's composite inertia in world axes about the world origin, into `ws.composite`; returns
/// the whole model's (the sum over the roots).
fn world_composites<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) -> SpatialInertia<T> {
    for (i, body) in model.bodies.iter().enumerate() {
        ws.composite[i] = body.inertia.act(&ws.world_placement[i]);
    }
    let mut total = SpatialInertia::zero();
    for i in (0..model.nbodies()).rev() {
        let c = ws.composite[i];
        match model.joints[i].parent {
            Some(p) => ws.composite[p] = ws.composite[p] + c,
            None => total = total + c,
        }
    }
    total
}

/// The 3 × nv Jacobian of the centre of mass into `jacobian` (`vcom = J_com v`), from the poses of the
/// last forward kinematics (Pinocchio's `jacobianCenterOfMass`); returns the centre of mass. Column `k`
/// is the velocity of the centre of mass of the subtree joint `k` carries, weighted by that subtree's
/// share of the mass. Overwrites `ws.composite`; never allocates.
pub fn com_jacobian<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    jacobian: &mut Matrix3xX<T>,
) -> Result<Vector3<T>, DynamicsError> {
    check_len("J_com columns", jacobian.ncols(), model.nv())?;
    let total = world_composites(model, ws);
    let inv = inverse_mass(total.mass);
    for (i, joint) in model.joints.iter().enumerate() {
        let c = &ws.composite[i];
        for k in 0..joint.nv() {
            let s = ws.world_placement[i].act_motion(&joint.subspace_column(k));
            let col = (s.linear * c.mass + s.angular.cross(&c.first_moment)) * inv;
            for r in 0..3 {
                jacobian[(r, joint.v_index + k)] = col[r];
            }
        }
    }
    Ok(total.first_moment * inv)
}

/// The centroidal momentum matrix `A_g` (6 × nv, rows linear then angular; the momentum about the centre
/// of mass in world axes is `h_g = A_g v`) into `a_g`, from the poses of the last forward kinematics
/// (Pinocchio's `ccrba`); returns the centre of mass. Overwrites `ws.composite`; never allocates.
pub fn centroidal_momentum_matrix<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    a_g: &mut Matrix6xX<T>,
) -> Result<Vector3<T>, DynamicsError> {
    check_len("A_g columns", a_g.ncols(), model.nv())?;
    let total = world_composites(model, ws);
    let com = total.first_moment * inverse_mass(total.mass);
    for (i, joint) in model.joints.iter().enumerate() {
        for k in 0..joint.nv() {
            let s = ws.world_placement[i].act_motion(&joint.subspace_column(k));
            let f = about_com(&ws.composite[i].mul_motion(&s), &com);
            for r in 0..3 {
                a_g[(r, joint.v_index + k)] = f.linear[r];
                a_g[(r + 3, joint.v_index + k)] = f.angular[r];
            }
        }
    }
    Ok(com)
}

/// A world-axes force about the world origin, taken about the point `c` instead.
fn about_com<T: Real>(f: &Force<T>, c: &Vector3<T>) -> Force<T> {
    Force::new(f.angular - c.cross(&f.linear), f.linear)
}

/// The centroidal momentum `h_g = A_g v` (`[angular; linear]` as a spatial force: the linear momentum and
/// the angular momentum about the centre of mass, world axes), from the last forward kinematics, in O(N).
pub fn centroidal_momentum<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> Force<T> {
    let mut h = Force::zero();
    let mut mass = T::zero();
    let mut moment = Vector3::zeros();
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        h += x.act_force(&body.inertia.mul_motion(&ws.velocity[i]));
        mass += body.inertia.mass;
        moment += x.rotation * body.inertia.first_moment + x.translation * body.inertia.mass;
    }
    about_com(&h, &(moment * inverse_mass(mass)))
}

/// The rate of the centroidal momentum, `ḣ_g = A_g qdd + Ȧ_g v`, after
/// [`forward_kinematics_acceleration`](super::forward_kinematics_acceleration)`(q, v, qdd)`; with
/// `qdd = 0` it is `Ȧ_g v`, the bias centroidal MPC needs (Pinocchio's `dccrba` times `v`). It is the sum
/// of the bodies' momentum rates in world axes, the moment taken about the moving centre of mass
/// (`d/dt (n_O − c × p) = ṅ_O − c × ṗ`, since `ċ × p = ċ × m ċ = 0`). Gravity is not in it: for a robot
/// touched by nothing else, `ḣ_g = (m g, 0)`.
pub fn centroidal_momentum_rate<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> Force<T> {
    let mut rate = Force::zero();
    let mut mass = T::zero();
    let mut moment = Vector3::zeros();
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        let inertia = &body.inertia;
        let v = &ws.velocity[i];
        let f = inertia.mul_motion(&ws.acceleration[i]) + v.cross_force(&inertia.mul_motion(v));
        rate += x.act_force(&f);
        mass += inertia.mass;
        moment += x.rotation * inertia.first_moment + x.translation * inertia.mass;
    }
    about_com(&rate, &(moment * inverse_mass(mass)))
}
