//! Inverse dynamics by the recursive Newton–Euler algorithm (the paper's Eqs. 1–3), and its special
//! cases at rest: the generalized gravity `g(q)` and the nonlinear effects `C(q, v) v + g(q)`.

use super::{
    check_configuration, check_input, gravity_in, parent_placement, per_coordinate, velocity_sweep,
    DynamicsError, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::Motion;
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
    Ok(rnea_terms(model, ws, q, Some(v), Some(qdd), gravity))
}

/// The generalized gravity `g(q)`: the joint forces that hold the model still at `q` against the
/// model's gravity, [`rnea`] at `v = 0`, `qdd = 0` (Pinocchio's `computeGeneralizedGravity`). Left in
/// `ws.tau` too.
///
/// The velocity and acceleration terms are not computed at all (no velocity sweep, no armature, which
/// multiplies `qdd = 0`), so this costs a fraction of [`rnea`] and the generated `gravity` holds only the
/// placements, the gravity vector carried down the tree and the inward force sweep. For a model with
/// loops, couplings or mimic joints the result is the spanning tree's joint forces; only their
/// projection `Xᵀ g` ([`crate::embedding_map`]) acts on the independent coordinates.
///
/// Inputs are checked as [`rnea`]'s are.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{gravity, JointType, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// // At θ = 0.3 the pivot must carry the weight's moment: g(θ) = m g l sin θ.
/// let g = gravity(&model, &mut ws, &[0.3]).unwrap();
/// assert!((g[0] - 9.81 * 0.5 * 0.3f64.sin()).abs() < 1e-12);
/// ```
pub fn gravity<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w [T], DynamicsError> {
    check_configuration(model, q)?;
    Ok(rnea_terms(model, ws, q, None, None, true))
}

/// The nonlinear effects `C(q, v) v + g(q)`: Coriolis, centrifugal and gravity forces, [`rnea`] at
/// `qdd = 0` (Pinocchio's `nonLinearEffects`). Left in `ws.tau` too.
///
/// The acceleration terms are not computed (no armature, which multiplies `qdd = 0`). For a model with
/// loops, couplings or mimic joints, `v` must satisfy the velocity constraints (as for every call) and
/// the result is the spanning tree's joint forces; only `Xᵀ (C v + g)` acts on the independent
/// coordinates.
///
/// Inputs are checked as [`rnea`]'s are.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{nle, rnea, JointType, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// // A single pendulum swinging through θ = 0.3 has no Coriolis force: only gravity remains.
/// let h = nle(&model, &mut ws, &[0.3], &[2.0]).unwrap()[0];
/// assert!((h - 9.81 * 0.5 * 0.3f64.sin()).abs() < 1e-12);
/// assert_eq!(h, rnea(&model, &mut ws, &[0.3], &[2.0], &[0.0]).unwrap()[0]);
/// ```
pub fn nle<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
) -> Result<&'w [T], DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    Ok(rnea_terms(model, ws, q, Some(v), None, true))
}

/// The Newton–Euler sweeps with the terms of absent inputs left out rather than multiplied by zero:
/// without `v` no velocity sweep (only the placements) and no velocity products; without `qdd` no joint
/// accelerations and no armature. Inputs are checked by the caller.
#[inline(always)]
fn rnea_terms<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: Option<&[T]>,
    qdd: Option<&[T]>,
    gravity: bool,
) -> &'w [T] {
    match v {
        Some(v) => velocity_sweep(model, ws, q, v),
        None => {
            // At rest: the placements alone.
            for (i, joint) in model.joints.iter().enumerate() {
                ws.parent_placement[i] = parent_placement(joint, q);
                ws.velocity[i] = Motion::zero();
                ws.coriolis[i] = Motion::zero();
            }
        }
    }
    // Outward: α(k) = φ*(k+1,k) α(k+1) + H*(k) θ̈(k) + a(k), with the base accelerating at −g.
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = &ws.parent_placement[i];
        let mut a = match joint.parent {
            Some(p) => x.inv_act_motion(&ws.acceleration[p]),
            None if gravity => gravity_in(&model.gravity, x),
            None => Motion::zero(),
        };
        if let Some(qdd) = qdd {
            a = a + joint.joint_motion(qdd);
        }
        if v.is_some() {
            a = a + ws.coriolis[i];
        }
        let a = a.named(&body.name, "a");
        let inertia = &body.inertia;
        // f(k) = M(k) α(k) + b(k), b(k) = V ×* M V; children are added in the inward sweep.
        let mut f = inertia.mul_motion(&a);
        if v.is_some() {
            let vel = &ws.velocity[i];
            f = f + vel.cross_force(&inertia.mul_motion(vel));
        }
        ws.force[i] = f;
        ws.acceleration[i] = a;
    }
    // Inward: f(k) += φ(k,k−1) f(k−1);  𝒯(k) = H(k) f(k).
    for i in (0..model.nbodies()).rev() {
        let joint = &model.joints[i];
        let f = ws.force[i].named(&model.bodies[i].name, "f");
        let n = joint.nv();
        for k in 0..n {
            let mut tau = joint.subspace_column(k).dot(&f);
            if let Some(qdd) = qdd {
                if joint.has_armature() {
                    tau += joint.armature * qdd[joint.v_index + k];
                }
            }
            ws.tau[joint.v_index + k] = tau.named(&joint.name, per_coordinate(&TAU, n, k), "");
        }
        if let Some(p) = joint.parent {
            let fp = ws.parent_placement[i].act_force(&f);
            ws.force[p] += fp;
        }
    }
    &ws.tau
}

/// Names of the joint forces in generated code (see [`per_coordinate`]).
const TAU: [&str; 7] = ["tau", "tau0", "tau1", "tau2", "tau3", "tau4", "tau5"];
