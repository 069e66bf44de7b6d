//! The O(N) forward dynamics of the paper's Eq. 9 (the articulated-body algorithm).
//!
//! Names follow the paper: `P(k)` articulated inertia, `D(k) = H P H*`, `G(k) = P H* D⁻¹`,
//! `𝔷(k)` articulated bias force, `ε(k) = 𝒯(k) − H 𝔷(k)`, `ν(k) = D⁻¹ ε(k)`. The paper's tip-to-base
//! numbering is reversed here: the backward sweep runs from the leaves (high indices) to the root.
//!
//! Every joint, whatever its number of velocity coordinates `n` (1 for revolute and prismatic joints, 6 for
//! a floating joint), takes the same steps on its own storage: `U = P H*` (n force columns), the `n × n`
//! factor of `D`, and `ε` (n entries). There is no shared "floating root" buffer, so a scene with several
//! free bodies is as correct as one robot.

use super::{
    check_configuration, check_input, gravity_in, per_coordinate, velocity_sweep, DynamicsError,
    Sweep, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place};
use crate::model::{Joint, Model};
use crate::spatial::{ArticulatedInertia, Force};
use crate::Real;
use nalgebra::DMatrixViewMut;

/// Forward dynamics `qdd = M(q)⁻¹ (τ − C(q, v) − g(q))`. The result is also left in `ws.qdd`.
///
/// Inputs are checked (lengths, NaN and infinities: [`DynamicsError`]); the result is not: finite inputs
/// whose result overflows the scalar give `Ok` with infinite or NaN entries (docs/conventions.md, "Errors").
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{aba, JointType, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// let qdd = aba(&model, &mut ws, &[0.3], &[0.0], &[0.0]).unwrap();
/// // θ̈ = −m g l sin θ / (m l² + I)
/// let expected = -9.81 * 0.5 * 0.3f64.sin() / (0.25 + 1e-3);
/// assert!((qdd[0] - expected).abs() < 1e-12);
/// ```
pub fn aba<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
) -> Result<&'w [T], DynamicsError> {
    forward_dynamics(model, ws, q, v, tau, &[])
}

/// [`aba`] and [`super::aba_ext`]: the inputs checked, then the sweeps of Eq. 9 (with the aggregate links
/// of a model with constraints), the wrenches `f_ext` in the bias forces.
pub(crate) fn forward_dynamics<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[super::LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    check_input("tau", tau, model.nv())?;
    super::wrenches::check_wrenches(model, f_ext)?;
    if model.has_constraints() {
        return super::embedded::aba(model, ws, q, v, tau, f_ext);
    }
    articulate(model, ws, q, v, tau, f_ext);
    for i in 0..model.nbodies() {
        forward_step(model, ws, i)?;
    }
    Ok(&ws.qdd)
}

/// The joint's block of `ws.d_factor` as an `n × n` matrix.
#[inline(always)]
pub(crate) fn d_block<'a, T: Real>(
    d_factor: &'a mut [T],
    d_offset: &[usize],
    i: usize,
    n: usize,
) -> DMatrixViewMut<'a, T> {
    let start = d_offset[i];
    DMatrixViewMut::from_slice(&mut d_factor[start..start + n * n], n, n)
}

/// Fails with the joint named where the last factorization of its `D` had a pivot that is not positive
/// (a value unknown at generation time passes: generated code carries no such check).
pub(crate) fn check_pivot<T: Real>(joint: &Joint<T>, pivot: T) -> Result<(), DynamicsError> {
    match pivot.value() {
        Some(d) if !(d > 0.0 && d.is_finite()) => Err(DynamicsError::SingularJoint {
            joint: joint.name.clone(),
            d,
        }),
        _ => Ok(()),
    }
}

/// The forward step of Eq. 9 for joint `i`: `θ̈ = D⁻¹(ε − Uᵀ a′)`, `a = a′ + H* θ̈`
/// (the paper's `ν(k) − K*(k+1,k) α(k+1)`).
pub(crate) fn forward_step<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    i: usize,
) -> Result<(), DynamicsError> {
    let joint = &model.joints[i];
    check_pivot(joint, ws.d_pivot[i])?;
    // Accelerations with gravity.
    ws.sweep = Sweep::None;
    let x = &ws.parent_placement[i];
    let a_prime = match joint.parent {
        Some(p) => x.inv_act_motion(&ws.acceleration[p]),
        None => gravity_in(&model.gravity, x),
    } + ws.coriolis[i];
    let (v0, n) = (joint.v_index, joint.nv());
    let qdd = &mut ws.qdd[v0..v0 + n];
    for (k, x) in qdd.iter_mut().enumerate() {
        *x = ws.epsilon[v0 + k] - a_prime.dot(&ws.u[v0 + k]);
    }
    cholesky_solve_in_place(&d_block(&mut ws.d_factor, &ws.d_offset, i, n), qdd);
    for (k, x) in qdd.iter_mut().enumerate() {
        *x = x.named(&joint.name, per_coordinate(&QDD, n, k), "");
    }
    let mut a = a_prime;
    for (k, &x) in qdd.iter().enumerate() {
        a += joint.subspace_column(k) * x;
    }
    ws.acceleration[i] = a.named(&model.bodies[i].name, "a");
    Ok(())
}

/// The velocity sweep and the backward sweep of Eq. 9: `P(k)`, `D(k)`, `𝔷(k)`, `ε(k)` for every joint,
/// with the external wrenches `f_ext` in the bias forces.
pub(crate) fn articulate<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[super::LinkWrench<T>],
) {
    velocity_sweep(model, ws, q, v);
    init_articulated(model, ws);
    super::wrenches::subtract_wrenches(model, ws, f_ext);
    for i in (0..model.nbodies()).rev() {
        backward_step(model, ws, i, tau);
    }
}

/// `P(k) = M(k)` and `𝔷(k) = b(k) = V ×* M V` for every body, before the backward sweep adds children.
pub(crate) fn init_articulated<T: Real>(model: &Model<T>, ws: &mut Workspace<T>) {
    for (i, body) in model.bodies.iter().enumerate() {
        let inertia = &body.inertia;
        let vel = &ws.velocity[i];
        ws.force[i] = vel.cross_force(&inertia.mul_motion(vel));
        ws.inertia[i] = ArticulatedInertia::from(*inertia);
    }
}

/// `U = P H*`, the factor of `D = H P H*` and its smallest pivot, for joint `i` with articulated inertia
/// `p` (shared by the forward dynamics and the operator inverse of Eq. 6).
pub(crate) fn factor_joint<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, i: usize) {
    let joint = &model.joints[i];
    ws.inertia[i] = ws.inertia[i].named(&model.bodies[i].name, "p");
    let p = &ws.inertia[i];
    let (v0, n) = (joint.v_index, joint.nv());
    for k in 0..n {
        ws.u[v0 + k] = p
            .mul_motion(&joint.subspace_column(k))
            .named(&joint.name, per_coordinate(&U, n, k));
    }
    let mut d = d_block(&mut ws.d_factor, &ws.d_offset, i, n);
    // The lower triangle is what the factorization reads.
    for r in 0..n {
        let h = joint.subspace_column(r);
        for c in 0..=r {
            d[(r, c)] = h.dot(&ws.u[v0 + c]);
        }
        if joint.has_armature() {
            // The rotor's inertia along the joint: D = H P H* + armature.
            d[(r, r)] += joint.armature;
        }
    }
    ws.d_pivot[i] = cholesky_in_place(&mut d).named(&joint.name, "d", "");
    if n == 1 {
        // The factor of a 1 × 1 `D` is its inverse.
        d[(0, 0)] = d[(0, 0)].named(&joint.name, "d_inv", "");
    }
}

/// Names of the per-coordinate quantities of a joint in generated code (see [`per_coordinate`]).
const QDD: [&str; 7] = ["qdd", "qdd0", "qdd1", "qdd2", "qdd3", "qdd4", "qdd5"];
const U: [&str; 7] = ["u", "u0", "u1", "u2", "u3", "u4", "u5"];
const EPSILON: [&str; 7] = ["eps", "eps0", "eps1", "eps2", "eps3", "eps4", "eps5"];

/// `P⁺ = τ̄ P = P − U D⁻¹ Uᵀ` for joint `i` (after [`factor_joint`]), and `G ε = U D⁻¹ ε` for the `ε` given
/// (zeros where only `P⁺` is wanted).
pub(crate) fn articulated_inertia_plus<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    i: usize,
    epsilon: &[T],
) -> (ArticulatedInertia<T>, Force<T>) {
    let joint = &model.joints[i];
    let (v0, n) = (joint.v_index, joint.nv());
    let mut p_plus = ws.inertia[i];
    if n == 1 {
        // The common case as a rank-one update (six products per symmetric block).
        let d_inv = ws.d_factor[ws.d_offset[i]];
        let u = ws.u[v0];
        p_plus.sub_rank_one(&u, d_inv);
        return (p_plus, u * (epsilon[0] * d_inv));
    }
    let mut g_eps = Force::zero();
    let mut unit = [T::zero(); 6];
    for k in 0..n {
        // w_k = U D⁻¹ e_k; Σ_k u_k w_kᵀ = U D⁻¹ Uᵀ is symmetric, as `sub_outer` requires.
        unit[..n].fill(T::zero());
        unit[k] = T::one();
        cholesky_solve_in_place(
            &d_block(&mut ws.d_factor, &ws.d_offset, i, n),
            &mut unit[..n],
        );
        let mut w = Force::zero();
        for (l, &x) in unit[..n].iter().enumerate() {
            w += ws.u[v0 + l] * x;
        }
        p_plus.sub_outer(&ws.u[v0 + k], &w);
        g_eps += w * epsilon[k];
    }
    (p_plus, g_eps)
}

/// The backward step of Eq. 9 for joint `i`: `D(k)`, `ε(k)`, and what passes to the parent,
/// `P(k+1) += φ τ̄ P φ*`, `𝔷(k+1) += φ (𝔷 + P⁺ a(k) + G ε)`.
pub(crate) fn backward_step<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, i: usize, tau: &[T]) {
    factor_joint(model, ws, i);
    let joint = &model.joints[i];
    let (v0, n) = (joint.v_index, joint.nv());
    ws.force[i] = ws.force[i].named(&model.bodies[i].name, "z");
    for k in 0..n {
        ws.epsilon[v0 + k] = (tau[v0 + k] - joint.subspace_column(k).dot(&ws.force[i])).named(
            &joint.name,
            per_coordinate(&EPSILON, n, k),
            "",
        );
    }
    let Some(parent) = joint.parent else {
        return;
    };
    // P⁺ = τ̄ P = P − U D⁻¹ Uᵀ;  𝔷⁺ = 𝔷 + P⁺ a(k) + G ε with G = U D⁻¹.
    let mut epsilon = [T::zero(); 6];
    epsilon[..n].copy_from_slice(&ws.epsilon[v0..v0 + n]);
    let (mut p_plus, g_eps) = articulated_inertia_plus(model, ws, i, &epsilon[..n]);
    let mut z_plus = ws.force[i] + p_plus.mul_motion(&ws.coriolis[i]) + g_eps;
    // P⁺ H* = 0 and H 𝔷⁺ = 𝒯 exactly (τ̄ removes the joint's own direction). For an axis along a
    // coordinate axis that makes a row and column of P⁺ zero: set them exactly, which removes
    // rounding noise and, in generated code, every product with them. (Not with armature: the
    // rotor takes part of 𝒯, and P⁺ H* = U D⁻¹ armature.)
    if let Some((angular, k)) = joint.coordinate_axis().filter(|_| !joint.has_armature()) {
        p_plus.clear_direction(angular, k);
        let sign = joint.axis[k];
        let tau_i = tau[v0] * sign;
        if angular {
            z_plus.angular[k] = tau_i;
        } else {
            z_plus.linear[k] = tau_i;
        }
    }
    let x = ws.parent_placement[i];
    ws.inertia[parent] += p_plus.act(&x);
    let zf = x.act_force(&z_plus);
    ws.force[parent] += zf;
}
