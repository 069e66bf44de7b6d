//! Inverse dynamics by the recursive Newton–Euler algorithm (the paper's Eqs. 1–3), and its special
//! cases at rest: the generalized gravity `g(q)` and the nonlinear effects `C(q, v) v + g(q)`.

use super::{
    check_configuration, check_input, gravity_in, parent_placement, per_coordinate, velocity_sweep,
    DynamicsError, Sweep, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::{Force, Motion, SpatialInertia};
use crate::Real;
use nalgebra::{Matrix3, Vector3};

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
    inverse_dynamics(model, ws, q, v, Some(qdd), gravity, &[])
}

/// [`rnea_with_gravity`], [`nle`] and their forms with wrenches ([`super::rnea_ext`],
/// [`super::nle_ext`]): the inputs checked (`qdd` where given), then [`rnea_terms`].
pub(crate) fn inverse_dynamics<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: Option<&[T]>,
    gravity: bool,
    f_ext: &[super::LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    if let Some(qdd) = qdd {
        check_input("qdd", qdd, model.nv())?;
    }
    super::wrenches::check_wrenches(model, f_ext)?;
    Ok(rnea_terms(model, ws, q, v, qdd, gravity, f_ext))
}

/// The generalized gravity `g(q)`: the joint forces that hold the model still at `q` against the
/// model's gravity, [`rnea`] at `v = 0`, `qdd = 0` (Pinocchio's `computeGeneralizedGravity`). Left in
/// `ws.tau` too.
///
/// At rest every body accelerates at `−g` and nothing else, so the force a joint carries is the weight
/// of the subtree it holds: the outward sweep carries only the gravity vector down the tree (no velocity
/// sweep, no joint accelerations, no armature, which multiplies `qdd = 0`), and the inward sweep carries
/// each subtree's mass and first moment `h = m c` up, `h(parent) += R h + m p`, instead of a spatial force.
/// The joint force is then `Sᵀ (h × a, m a)` with `a = −g` in the body frame. This is a fraction of
/// [`rnea`]'s arithmetic (on the 7-DoF z1 arm the generated `gravity` has about a tenth of `rnea`'s
/// operations). For a model with loops, couplings or mimic joints the result is the spanning tree's joint
/// forces; only their projection `Xᵀ g` ([`crate::embedding_map`]) acts on the independent coordinates.
///
/// Inputs are checked as [`rnea`]'s are. `ws.acceleration` holds `−g` in each body frame afterwards, and
/// `ws.composite` each subtree's mass and first moment (its rotational inertia zero).
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
    // Parent placements and accelerations with gravity, no world placements.
    ws.sweep = Sweep::None;
    // Outward: ᵖX_i(q) and a(i) = −g in body i's frame, a pure linear acceleration (`Rᵀ a(parent)`).
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = parent_placement(joint, q);
        let a = match joint.parent {
            Some(p) => x.rotation.tr_mul(&ws.acceleration[p].linear),
            None => gravity_in(&model.gravity, &x).linear,
        };
        ws.acceleration[i] = Motion::new(Vector3::zeros(), a).named(&body.name, "a");
        ws.velocity[i] = Motion::zero();
        ws.coriolis[i] = Motion::zero();
        ws.parent_placement[i] = x;
        ws.composite[i] = SpatialInertia {
            rotational: Matrix3::zeros(),
            ..body.inertia
        };
    }
    // Inward: the subtree's weight f(k) = (h × a, m a) about the body origin, 𝒯(k) = H(k) f(k); its mass
    // and first moment join the parent's.
    for i in (0..model.nbodies()).rev() {
        let (joint, body) = (&model.joints[i], &model.bodies[i]);
        let c = ws.composite[i].named(&body.name, "ic");
        let a = &ws.acceleration[i].linear;
        let f = Force::new(c.first_moment.cross(a), a * c.mass).named(&body.name, "f");
        ws.force[i] = f;
        let n = joint.nv();
        for k in 0..n {
            let tau = joint.subspace_column(k).dot(&f);
            ws.tau[joint.v_index + k] = tau.named(&joint.name, per_coordinate(&TAU, n, k), "");
        }
        if let Some(p) = joint.parent {
            let x = &ws.parent_placement[i];
            let h = c.first_moment_in(x);
            ws.composite[p].mass += c.mass;
            ws.composite[p].first_moment += h;
        }
    }
    Ok(&ws.tau)
}

/// The nonlinear effects `C(q, v) v + g(q)`: Coriolis, centrifugal and gravity forces, [`rnea`] at
/// `qdd = 0` (Pinocchio's `nonLinearEffects`). Left in `ws.tau` too.
///
/// The acceleration terms are not computed (no joint accelerations, no armature, which multiplies
/// `qdd = 0`). For a model with
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
    inverse_dynamics(model, ws, q, v, None, true, &[])
}

/// The Newton–Euler sweeps; without `qdd` its terms are left out rather than multiplied by zero (no
/// joint accelerations, no armature). The environment's wrenches `f_ext` take their part of each body's
/// force. Inputs are checked by the caller.
#[inline(always)]
fn rnea_terms<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: Option<&[T]>,
    gravity: bool,
    f_ext: &[super::LinkWrench<T>],
) -> &'w [T] {
    velocity_sweep(model, ws, q, v);
    // Outward: α(k) = φ*(k+1,k) α(k+1) + H*(k) θ̈(k) + a(k), with the base accelerating at −g.
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = &ws.parent_placement[i];
        let mut a = match joint.parent {
            Some(p) => x.inv_act_motion(&ws.acceleration[p]),
            None if gravity => gravity_in(&model.gravity, x),
            None => Motion::zero(),
        };
        if let Some(qdd) = qdd {
            a += joint.joint_motion(qdd);
        }
        let a = (a + ws.coriolis[i]).named(&body.name, "a");
        let inertia = &body.inertia;
        let vel = &ws.velocity[i];
        // f(k) = M(k) α(k) + b(k), b(k) = V ×* M V; children are added in the inward sweep.
        ws.force[i] = inertia.mul_motion(&a) + vel.cross_force(&inertia.mul_motion(vel));
        ws.acceleration[i] = a;
    }
    super::wrenches::subtract_wrenches(model, ws, f_ext);
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
