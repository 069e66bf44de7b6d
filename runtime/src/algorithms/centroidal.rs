//! Centre of mass and centroidal momentum (Orin and Goswami): what balance controllers and centroidal
//! MPC read next to the dynamics.
//!
//! All of it reads the kinematics of the last forward kinematics call on the workspace and sums over
//! the model's bodies, which are the links that joints move (links fixed to the world are not bodies:
//! they are left out, as in Pinocchio). The centroidal momentum matrix `A_g` is Pinocchio's `ccrba`: each
//! joint's motion direction times the composite inertia of the subtree it carries, all in world axes,
//! the moment taken about the centre of mass.
//!
//! Each function checks that the workspace holds what it reads ([`Sweep`]: world placements, velocities,
//! accelerations without gravity) and fails with [`DynamicsError::KinematicsNotComputed`] otherwise. They
//! overwrite `ws.force` or `ws.composite`, never the kinematics, so any number of them can follow one sweep.

use super::{check_len, DynamicsError, Sweep, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::JointType;
use crate::model::Model;
use crate::spatial::{Force, SpatialInertia, Transform};
use crate::Real;
use nalgebra::{Matrix3, Matrix3xX, Matrix6xX, Vector3};

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
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics`](super::forward_kinematics)`(q, v)`
/// or [`forward_kinematics_acceleration`](super::forward_kinematics_acceleration) ran last on `ws`
/// ([`Sweep::Velocities`]).
pub fn center_of_mass<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
) -> Result<CenterOfMass<T>, DynamicsError> {
    ws.require("center_of_mass", Sweep::Velocities)?;
    let mut mass = T::zero();
    let mut moment = Vector3::zeros();
    let mut momentum = Vector3::zeros();
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        let inertia = &body.inertia;
        let v = &ws.velocity[i];
        mass += inertia.mass;
        moment += inertia.first_moment_in(x);
        // m × (velocity of the body's centre of mass) = m v + ω × h, in the body frame.
        momentum += x.rotation * (v.linear * inertia.mass + v.angular.cross(&inertia.first_moment));
    }
    let inv = inverse_mass(mass);
    Ok(CenterOfMass {
        mass,
        com: moment * inv,
        vcom: momentum * inv,
    })
}

/// `1/m`, or zero for a massless model (whose centre of mass is then the origin).
fn inverse_mass<T: Real>(mass: T) -> T {
    match mass.value() {
        Some(0.0) => T::zero(),
        _ => T::one() / mass,
    }
}

/// Each subtree's composite inertia in its own body frame, into `ws.composite` (CRBA's: the parent
/// placements are folded joint by joint, where a joint's constant placement and its axis keep most entries
/// of the transform exact zeros and ones); returns the whole model's in world axes about the world origin
/// (the roots' composites moved by their world placements).
fn body_composites<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) -> SpatialInertia<T> {
    for (i, body) in model.bodies.iter().enumerate() {
        ws.composite[i] = body.inertia;
    }
    let mut total = SpatialInertia::zero();
    for i in (0..model.nbodies()).rev() {
        let c = ws.composite[i].named(&model.bodies[i].name, "ic");
        ws.composite[i] = c;
        match model.joints[i].parent {
            Some(p) => ws.composite[p] = ws.composite[p] + c.act(&ws.parent_placement[i]),
            None => total = total + c.act(&ws.world_placement[i]),
        }
    }
    total
}

/// Each subtree's mass and first moment in world coordinates (into `ws.composite`, rotational inertia
/// left zero); returns the whole model's.
fn world_first_moments<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) -> SpatialInertia<T> {
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        let inertia = &body.inertia;
        ws.composite[i] = SpatialInertia {
            mass: inertia.mass,
            first_moment: inertia.first_moment_in(x),
            rotational: nalgebra::Matrix3::zeros(),
        };
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
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless a call that leaves world placements
/// ([`Sweep::Placements`], e.g. [`forward_kinematics`](super::forward_kinematics)) ran last on `ws`;
/// [`DynamicsError::WrongLength`] for a `jacobian` without `nv` columns.
pub fn com_jacobian<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    jacobian: &mut Matrix3xX<T>,
) -> Result<Vector3<T>, DynamicsError> {
    ws.require("com_jacobian", Sweep::Placements)?;
    check_len("J_com columns", jacobian.ncols(), model.nv())?;
    let total = world_first_moments(model, ws);
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
///
/// Column `k` is the momentum of the subtree joint `k` carries when only that coordinate moves: the
/// subtree's composite inertia times the joint's motion direction, formed in the joint's own body frame
/// (where the direction is a constant axis and the product picks a column of the inertia), then moved to
/// world axes and taken about the centre of mass.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless a call that leaves world placements
/// ([`Sweep::Placements`], e.g. [`forward_kinematics`](super::forward_kinematics)) ran last on `ws`;
/// [`DynamicsError::WrongLength`] for an `a_g` without `nv` columns.
pub fn centroidal_momentum_matrix<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    a_g: &mut Matrix6xX<T>,
) -> Result<Vector3<T>, DynamicsError> {
    ws.require("centroidal_momentum_matrix", Sweep::Placements)?;
    check_len("A_g columns", a_g.ncols(), model.nv())?;
    let total = body_composites(model, ws);
    let com = total.first_moment * inverse_mass(total.mass);
    let lone_free_flyer = lone_free_flyer(model);
    for (i, joint) in model.joints.iter().enumerate() {
        if lone_free_flyer == Some(i) {
            free_flyer_columns(&ws.composite[i], &ws.world_placement[i], a_g, joint.v_index);
            continue;
        }
        // The body's pose relative to a frame at the centre of mass with world axes: one transform takes
        // a body-frame momentum to the world's axes and about the centre of mass.
        let x = &ws.world_placement[i];
        let about_com = Transform::new(x.rotation, x.translation - com);
        for k in 0..joint.nv() {
            let local = ws.composite[i].mul_motion(&joint.subspace_column(k));
            let f = about_com.act_force(&local);
            super::frames::write_column(a_g, joint.v_index + k, &f.linear, &f.angular);
        }
    }
    Ok(com)
}

/// The free-flying root joint when it is the model's only root, so that its subtree is the whole model.
fn lone_free_flyer<T: Real>(model: &Model<T>) -> Option<usize> {
    let mut roots = model
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.parent.is_none());
    match (roots.next(), roots.next()) {
        (Some((i, j)), None) if j.joint_type == JointType::Floating => Some(i),
        _ => None,
    }
}

/// The six columns of `A_g` of a free flyer that carries the whole model, whose composite inertia in
/// the body frame is `whole` and whose pose is `x`. About the model's own centre of mass, the momentum
/// of the rigid whole moving with body velocity `(v, ω)` is `(m R v, R I_c ω)` with `c = h/m` the centre
/// of mass in the body frame and `I_c` the rotational inertia about it, plus the linear `R (ω × h)`: the
/// generic column (a full force transform, whose angular part for the linear velocities is a difference
/// of equal terms) costs about three times as much.
fn free_flyer_columns<T: Real>(
    whole: &SpatialInertia<T>,
    x: &Transform<T>,
    a_g: &mut Matrix6xX<T>,
    v_index: usize,
) {
    let r = &x.rotation;
    let h = &whole.first_moment;
    let c = h * inverse_mass(whole.mass);
    // I_c = I_o − m (|c|² 1 − c cᵀ) = I_o − ((h·c) 1 − h cᵀ), symmetric: six entries.
    let i_o = &whole.rotational;
    let xx = i_o[(0, 0)] - (h.y * c.y + h.z * c.z);
    let yy = i_o[(1, 1)] - (h.x * c.x + h.z * c.z);
    let zz = i_o[(2, 2)] - (h.x * c.x + h.y * c.y);
    let xy = i_o[(0, 1)] + h.x * c.y;
    let xz = i_o[(0, 2)] + h.x * c.z;
    let yz = i_o[(1, 2)] + h.y * c.z;
    let i_c = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
    let zero = Vector3::zeros();
    for k in 0..3 {
        // v = [v_lin; ω], the free flyer's order.
        let linear = r.column(k) * whole.mass;
        super::frames::write_column(a_g, v_index + k, &linear, &zero);
        let e = Vector3::ith(k, T::one());
        let linear = r * e.cross(h);
        let angular = r * i_c.column(k);
        super::frames::write_column(a_g, v_index + 3 + k, &linear, &angular);
    }
}

/// A world-axes force about the world origin, taken about the point `c` instead.
fn about_com<T: Real>(f: &Force<T>, c: &Vector3<T>) -> Force<T> {
    Force::new(f.angular - c.cross(&f.linear), f.linear)
}

/// The centroidal momentum `h_g = A_g v` (`[angular; linear]` as a spatial force: the linear momentum and
/// the angular momentum about the centre of mass, world axes), from the last forward kinematics, in O(N):
/// each body's momentum carried to its parent's frame (RNEA's inward sweep), the roots' moved to the world.
/// Overwrites `ws.force`.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics`](super::forward_kinematics)`(q, v)`
/// or [`forward_kinematics_acceleration`](super::forward_kinematics_acceleration) ran last on `ws`
/// ([`Sweep::Velocities`]).
pub fn centroidal_momentum<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
) -> Result<Force<T>, DynamicsError> {
    ws.require("centroidal_momentum", Sweep::Velocities)?;
    for (i, body) in model.bodies.iter().enumerate() {
        ws.force[i] = body.inertia.mul_motion(&ws.velocity[i]);
    }
    Ok(about_com(&carried_to_world(model, ws), &com_of(model, ws)))
}

/// The rate of the centroidal momentum, `ḣ_g = A_g qdd + Ȧ_g v`, after
/// [`forward_kinematics_acceleration`](super::forward_kinematics_acceleration)`(q, v, qdd)`; with
/// `qdd = 0` it is `Ȧ_g v`, the bias centroidal MPC needs (Pinocchio's `dccrba` times `v`). It is the sum
/// of the bodies' momentum rates `I a + v ×* I v` (RNEA's body forces without gravity) in world axes, the
/// moment taken about the moving centre of mass (`d/dt (n_O − c × p) = ṅ_O − c × ṗ`, since
/// `ċ × p = ċ × m ċ = 0`). Gravity is not in it: for a robot touched by nothing else, `ḣ_g = (m g, 0)`.
/// Overwrites `ws.force`.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless
/// [`forward_kinematics_acceleration`](super::forward_kinematics_acceleration) (or
/// [`crate::constraint_kinematics`], its `qdd = 0`) ran last on `ws` ([`Sweep::Accelerations`]): after
/// [`forward_kinematics`](super::forward_kinematics) there are no accelerations, after [`crate::aba`]
/// they include gravity.
pub fn centroidal_momentum_rate<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
) -> Result<Force<T>, DynamicsError> {
    ws.require("centroidal_momentum_rate", Sweep::Accelerations)?;
    for (i, body) in model.bodies.iter().enumerate() {
        let inertia = &body.inertia;
        let v = &ws.velocity[i];
        ws.force[i] =
            inertia.mul_motion(&ws.acceleration[i]) + v.cross_force(&inertia.mul_motion(v));
    }
    Ok(about_com(&carried_to_world(model, ws), &com_of(model, ws)))
}

/// The sum of the per-body forces in `ws.force` (body frames) in world axes about the world origin,
/// carried leaves first to each parent's frame and the roots' moved to the world.
fn carried_to_world<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) -> Force<T> {
    let mut total = Force::zero();
    for i in (0..model.nbodies()).rev() {
        let f = ws.force[i].named(&model.bodies[i].name, "f");
        match model.joints[i].parent {
            Some(p) => {
                let fp = ws.parent_placement[i].act_force(&f);
                ws.force[p] += fp;
            }
            None => total += ws.world_placement[i].act_force(&f),
        }
    }
    total
}

/// The centre of mass from the last forward kinematics (the origin for a massless model).
fn com_of<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> Vector3<T> {
    let mut mass = T::zero();
    let mut moment = Vector3::zeros();
    for (i, body) in model.bodies.iter().enumerate() {
        let x = &ws.world_placement[i];
        mass += body.inertia.mass;
        moment += body.inertia.first_moment_in(x);
    }
    moment * inverse_mass(mass)
}
