//! Inverse dynamics by the recursive Newton–Euler algorithm (the paper's Eqs. 1–3).

use super::{
    check_configuration, check_input, gravity_in, per_coordinate, velocity_sweep, DynamicsError,
    Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::Real;

/// Inverse dynamics `τ = M(q) qdd + C(q, v) + g(q)` with the model's gravity. Left in `ws.tau` too.
///
/// Inputs are checked (lengths, NaN and infinities: [`DynamicsError`]); the result is not: finite inputs
/// whose result overflows the scalar give `Ok` with infinite or NaN entries (docs/conventions.md, "Errors").
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{rnea, JointType, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// // Held still at θ = 0.3 the pivot carries the weight's moment: τ = m g l sin θ.
/// let tau = rnea(&model, &mut ws, &[0.3], &[0.0], &[0.0]).unwrap();
/// assert!((tau[0] - 9.81 * 0.5 * 0.3f64.sin()).abs() < 1e-12);
/// ```
pub fn rnea<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: &[T],
) -> Result<&'w [T], DynamicsError> {
    rnea_with_gravity(model, ws, q, v, qdd, true)
}

/// [`rnea`] with gravity switched on or off (off gives `M qdd + C v`; with `v = 0`, `M qdd`).
pub fn rnea_with_gravity<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: &[T],
    gravity: bool,
) -> Result<&'w [T], DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    check_input("qdd", qdd, model.nv())?;
    velocity_sweep(model, ws, q, v);
    // Outward: α(k) = φ*(k+1,k) α(k+1) + H*(k) θ̈(k) + a(k), with the base accelerating at −g.
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = &ws.parent_placement[i];
        let a_parent = match joint.parent {
            Some(p) => x.inv_act_motion(&ws.acceleration[p]),
            None if gravity => gravity_in(&model.gravity, x),
            None => crate::spatial::Motion::zero(),
        };
        let a = (a_parent + joint.joint_motion(qdd) + ws.coriolis[i]).named(&body.name, "a");
        let inertia = &body.inertia;
        let vel = &ws.velocity[i];
        // f(k) = M(k) α(k) + b(k), b(k) = V ×* M V; children are added in the inward sweep.
        ws.force[i] = inertia.mul_motion(&a) + vel.cross_force(&inertia.mul_motion(vel));
        ws.acceleration[i] = a;
    }
    // Inward: f(k) += φ(k,k−1) f(k−1);  𝒯(k) = H(k) f(k).
    for i in (0..model.nbodies()).rev() {
        let joint = &model.joints[i];
        let f = ws.force[i].named(&model.bodies[i].name, "f");
        let n = joint.nv();
        for k in 0..n {
            let mut tau = joint.subspace_column(k).dot(&f);
            if joint.has_armature() {
                tau += joint.armature * qdd[joint.v_index + k];
            }
            ws.tau[joint.v_index + k] = tau.named(&joint.name, per_coordinate(&TAU, n, k), "");
        }
        if let Some(p) = joint.parent {
            let fp = ws.parent_placement[i].act_force(&f);
            ws.force[p] += fp;
        }
    }
    Ok(&ws.tau)
}

/// Names of the joint forces in generated code (see [`per_coordinate`]).
const TAU: [&str; 7] = ["tau", "tau0", "tau1", "tau2", "tau3", "tau4", "tau5"];
