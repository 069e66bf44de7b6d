use super::{check_configuration, check_input, velocity_sweep, DynamicsError, Sweep, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::Transform;
use crate::Real;

/// Forward kinematics: each body's pose in the parent and world frames, and its spatial velocity
/// ([`Sweep::Velocities`]: what [`crate::frame_jacobian`], [`crate::frame_velocity`], the centre of mass
/// and the centroidal momentum read).
pub fn forward_kinematics<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    velocity_sweep(model, ws, q, v);
    world_placements(model, ws);
    ws.sweep = Sweep::Velocities;
    Ok(())
}

/// Each body's pose in the world from the parent placements in `ws`, root first.
pub(crate) fn world_placements<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) {
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        ws.world_placement[i] = match joint.parent {
            Some(p) => ws.world_placement[p].compose(&ws.parent_placement[i]),
            None => ws.parent_placement[i],
        }
        .named(&body.name, "pose");
    }
}

/// The world pose of every URDF link that rides on a moving body, from the poses of the last
/// [`forward_kinematics`] call: bodies in coordinate order, each body's links in the order of
/// [`Body::links`](crate::Body) (its own link first, then those merged into it through fixed joints).
/// Links fixed to the world have constant poses and are not listed. Never allocates.
pub fn link_poses<'a, T: Real>(
    model: &'a Model<T>,
    ws: &'a Workspace<T>,
) -> impl Iterator<Item = (&'a str, Transform<T>)> + 'a {
    model
        .bodies
        .iter()
        .zip(&ws.world_placement)
        .flat_map(|(body, world)| {
            body.links
                .iter()
                .zip(&body.link_placements)
                .map(move |(name, x)| (name.as_str(), world.compose(x)))
        })
}

/// Kinetic energy ½ vᵀ M(q) v, from the velocities of the last [`forward_kinematics`] call.
pub fn kinetic_energy<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> T {
    model
        .bodies
        .iter()
        .zip(&ws.velocity)
        .fold(T::zero(), |e, (b, v)| e + b.inertia.kinetic_energy(v))
}

/// Potential energy −Σ mᵢ gᵀ cᵢ in the model's gravity field, from the poses of the last
/// [`forward_kinematics`] call.
pub fn potential_energy<T: Real>(model: &Model<T>, ws: &Workspace<T>) -> T {
    model
        .bodies
        .iter()
        .zip(&ws.world_placement)
        .fold(T::zero(), |e, (b, x)| {
            let mc = b.inertia.first_moment_in(x);
            e - model.gravity.dot(&mc)
        })
}
