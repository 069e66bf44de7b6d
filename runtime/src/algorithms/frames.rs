//! Frame kinematics: the pose, velocity, classical acceleration and 6 × nv Jacobian of any link, in the
//! three references Pinocchio defines (docs/conventions.md, "Contacts, frames and momentum").
//!
//! Every function here reads the kinematics of the last [`forward_kinematics`](super::forward_kinematics)
//! (poses, velocities) or [`forward_kinematics_acceleration`] (also accelerations, without gravity) call
//! on the workspace, as Pinocchio's frame functions read `data`: one sweep serves any number of frames.
//! Unlike Pinocchio's, each checks that the workspace holds what it reads ([`Sweep`]) and fails with
//! [`DynamicsError::KinematicsNotComputed`] where a call is missing (a new workspace, or another
//! algorithm ran since), rather than return another state's numbers.

use super::{
    check_configuration, check_input, forward_kinematics, DynamicsError, Sweep, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::{FrameId, Model};
use crate::spatial::{Motion, Transform};
use crate::Real;
use nalgebra::{Matrix6xX, Vector3};

/// Where a frame quantity is expressed (Pinocchio's `ReferenceFrame`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Reference {
    /// The frame's own axes, about its origin (`LOCAL`).
    Local,
    /// The world's axes, about the frame's origin (`LOCAL_WORLD_ALIGNED`): the linear part is the
    /// velocity of the frame's origin in world coordinates.
    #[default]
    LocalWorldAligned,
    /// The world's axes, about the world's origin (`WORLD`): the linear part is the velocity of the body
    /// point passing through the world origin.
    World,
}

impl Reference {
    /// The name the command line and docs/conventions.md use (`local`, `local_world_aligned`, `world`).
    pub fn as_str(self) -> &'static str {
        match self {
            Reference::Local => "local",
            Reference::LocalWorldAligned => "local_world_aligned",
            Reference::World => "world",
        }
    }

    /// The reference named `name` (see [`Reference::as_str`]).
    pub fn from_name(name: &str) -> Option<Reference> {
        [
            Reference::Local,
            Reference::LocalWorldAligned,
            Reference::World,
        ]
        .into_iter()
        .find(|r| r.as_str() == name)
    }
}

/// Poses and velocities as [`forward_kinematics`](super::forward_kinematics), and each body's spatial
/// acceleration for the joint accelerations `qdd` in `ws.acceleration` (body frames, no gravity: the
/// motion an observer in the world sees). With `qdd = 0` the accelerations are the velocity-product
/// terms, from which [`frame_classical_acceleration`] gives the bias `J̇ v`.
pub fn forward_kinematics_acceleration<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: &[T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    check_input("qdd", qdd, model.nv())?;
    forward_kinematics(model, ws, q, v)?;
    for (i, joint) in model.joints.iter().enumerate() {
        let a = match joint.parent {
            Some(p) => ws.parent_placement[i].inv_act_motion(&ws.acceleration[p]),
            None => Motion::zero(),
        } + ws.coriolis[i]
            + joint.joint_motion(qdd);
        ws.acceleration[i] = a.named(&model.bodies[i].name, "a");
    }
    ws.sweep = Sweep::Accelerations;
    Ok(())
}

/// The frame's pose in its body (in the world for a link fixed to the world, `frame.body == None`); an
/// error for a frame of another model.
fn in_body<T: Real>(model: &Model<T>, frame: FrameId) -> Result<&Transform<T>, DynamicsError> {
    model
        .frame_in_body(frame)
        .ok_or(DynamicsError::UnknownFrame { index: 0, frame })
}

/// The world pose of a frame, from the last forward kinematics.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics`](super::forward_kinematics) (or
/// another call that leaves world placements, [`Sweep::Placements`]) ran last on `ws`;
/// [`DynamicsError::UnknownFrame`] for a frame of another model.
pub fn frame_placement<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    frame: FrameId,
) -> Result<Transform<T>, DynamicsError> {
    ws.require("frame_placement", Sweep::Placements)?;
    let in_body = in_body(model, frame)?;
    Ok(match frame.body {
        Some(b) => ws.world_placement[b].compose(in_body),
        None => *in_body,
    })
}

/// A body-frame motion of `frame`'s body, as the frame's motion in `reference` (`m` in the body frame).
fn express<T: Real>(
    body: &Transform<T>,
    in_body: &Transform<T>,
    m: &Motion<T>,
    reference: Reference,
) -> Motion<T> {
    match reference {
        Reference::World => body.act_motion(m),
        Reference::Local => in_body.inv_act_motion(m),
        Reference::LocalWorldAligned => {
            let local = in_body.inv_act_motion(m);
            let r = body.rotation * in_body.rotation;
            Motion::new(r * local.angular, r * local.linear)
        }
    }
}

/// The spatial velocity of a frame in `reference` (from the last forward kinematics): `[angular; linear]`,
/// the linear part as [`Reference`] says. Zero for a link fixed to the world.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics`](super::forward_kinematics)`(q, v)`
/// or [`forward_kinematics_acceleration`] ran last on `ws` ([`Sweep::Velocities`]);
/// [`DynamicsError::UnknownFrame`] for a frame of another model.
pub fn frame_velocity<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    frame: FrameId,
    reference: Reference,
) -> Result<Motion<T>, DynamicsError> {
    ws.require("frame_velocity", Sweep::Velocities)?;
    let in_body = in_body(model, frame)?;
    Ok(match frame.body {
        Some(b) => express(&ws.world_placement[b], in_body, &ws.velocity[b], reference),
        None => Motion::zero(),
    })
}

/// The classical acceleration of a frame in `reference` after [`forward_kinematics_acceleration`]: the
/// spatial acceleration with `ω × v` added to its linear part, i.e. the second time derivative of the
/// position of the point the linear part refers to (the frame's origin for `Local` and
/// `LocalWorldAligned`). After `forward_kinematics_acceleration(q, v, 0)` it is the bias of the frame's
/// acceleration, `a = J qdd + bias` (in `LocalWorldAligned`, `bias = J̇ v`); Pinocchio's
/// `getFrameClassicalAcceleration`. Zero for a link fixed to the world.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics_acceleration`] (or
/// [`crate::constraint_kinematics`], its `qdd = 0`) ran last on `ws` ([`Sweep::Accelerations`]): after
/// [`forward_kinematics`](super::forward_kinematics) there are no accelerations, after [`crate::aba`]
/// they include gravity; [`DynamicsError::UnknownFrame`] for a frame of another model.
pub fn frame_classical_acceleration<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    frame: FrameId,
    reference: Reference,
) -> Result<Motion<T>, DynamicsError> {
    ws.require("frame_classical_acceleration", Sweep::Accelerations)?;
    let in_body = in_body(model, frame)?;
    let Some(b) = frame.body else {
        return Ok(Motion::zero());
    };
    let body = &ws.world_placement[b];
    let vel = express(body, in_body, &ws.velocity[b], reference);
    let acc = express(body, in_body, &ws.acceleration[b], reference);
    Ok(Motion::new(
        acc.angular,
        acc.linear + vel.angular.cross(&vel.linear),
    ))
}

/// The 6 × nv Jacobian of a frame in `reference` into `jacobian` (rows linear then angular, as Pinocchio's;
/// columns in `v` order), from the poses of the last forward kinematics: `J v` is the frame's velocity
/// ([`frame_velocity`]). Columns of joints that do not carry the frame are zero; so is the whole Jacobian
/// of a link fixed to the world. For a model with loops, couplings or mimic joints the columns are over
/// the spanning tree's coordinates; `J X` ([`crate::embedding_map_in`]) is the Jacobian over the
/// independent ones. Never allocates.
///
/// # Errors
/// [`DynamicsError::KinematicsNotComputed`] unless [`forward_kinematics`](super::forward_kinematics) (or
/// another call that leaves world placements, [`Sweep::Placements`]) ran last on `ws`;
/// [`DynamicsError::WrongLength`] for a `jacobian` without `nv` columns; [`DynamicsError::UnknownFrame`].
pub fn frame_jacobian<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    frame: FrameId,
    reference: Reference,
    jacobian: &mut Matrix6xX<T>,
) -> Result<(), DynamicsError> {
    ws.require("frame_jacobian", Sweep::Placements)?;
    super::check_len("jacobian columns", jacobian.ncols(), model.nv())?;
    jacobian.fill(T::zero());
    let in_body = in_body(model, frame)?;
    let Some(b) = frame.body else {
        return Ok(());
    };
    let world = ws.world_placement[b].compose(in_body);
    let origin = world.translation;
    for i in core::iter::once(b).chain(model.ancestors(b)) {
        let joint = &model.joints[i];
        let x = &ws.world_placement[i];
        for k in 0..joint.nv() {
            // The joint's motion direction in world coordinates, about the world origin.
            let s = x.act_motion(&joint.subspace_column(k));
            let col = match reference {
                Reference::World => s,
                Reference::LocalWorldAligned => {
                    Motion::new(s.angular, s.linear + s.angular.cross(&origin))
                }
                Reference::Local => world.inv_act_motion(&s),
            };
            write_column(jacobian, joint.v_index + k, &col.linear, &col.angular);
        }
    }
    Ok(())
}

/// Writes a six-vector as column `c` of a 6 × nv matrix, linear rows first (the layout of Jacobians and `A_g`).
pub(super) fn write_column<T: Real>(
    matrix: &mut Matrix6xX<T>,
    c: usize,
    linear: &Vector3<T>,
    angular: &Vector3<T>,
) {
    for r in 0..3 {
        matrix[(r, c)] = linear[r];
        matrix[(r + 3, c)] = angular[r];
    }
}
