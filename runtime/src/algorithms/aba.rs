//! The O(N) forward dynamics of the paper's Eq. 9 (the articulated-body algorithm).
//!
//! Names follow the paper: `P(k)` articulated inertia, `D(k) = H P H*`, `G(k) = P H* D⁻¹`,
//! `𝔷(k)` articulated bias force, `ε(k) = 𝒯(k) − H 𝔷(k)`, `ν(k) = D⁻¹ ε(k)`. The paper's tip-to-base
//! numbering is reversed here: the backward sweep runs from the leaves (high indices) to the root.

use super::{check_len, gravity_in, velocity_sweep, DynamicsError, Workspace};
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place};
use crate::model::{JointType, Model};
use crate::spatial::{ArticulatedInertia, Force, Motion};
use crate::Real;
use nalgebra::Vector3;

/// Forward dynamics `qdd = M(q)⁻¹ (τ − C(q, v) − g(q))`. The result is also left in `ws.qdd`.
///
/// ```
/// use embedyn_runtime::{aba, Model, JointType, SpatialInertia, Transform, Workspace};
/// use nalgebra::{Matrix3, Vector3};
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
    check_len("q", q.len(), model.nq())?;
    check_len("v", v.len(), model.nv())?;
    check_len("tau", tau.len(), model.nv())?;
    if model.has_constraints() {
        return super::embedded::aba(model, ws, q, v, tau);
    }
    articulate(model, ws, q, v, tau);
    for i in 0..model.nbodies() {
        forward_step(model, ws, i)?;
    }
    Ok(&ws.qdd)
}

/// The forward step of Eq. 9 for joint `i`: `θ̈ = D⁻¹(ε − Uᵀ a′)`, `a = a′ + H* θ̈`
/// (the paper's `ν(k) − K*(k+1,k) α(k+1)`).
pub(crate) fn forward_step<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    i: usize,
) -> Result<(), DynamicsError> {
    let joint = &model.joints[i];
    let x = &ws.parent_placement[i];
    let a_prime = match joint.parent {
        Some(p) => x.inv_act_motion(&ws.acceleration[p]),
        None => gravity_in(&model.gravity, x),
    } + ws.coriolis[i];
    let a = match joint.joint_type {
        JointType::Floating => {
            let pa = ws.inertia[i].mul_motion(&a_prime);
            let mut rhs = ws.floating_eps;
            let spa = to_v_order(&pa);
            for k in 0..6 {
                rhs[k] -= spa[k];
            }
            check_floating(joint, ws)?;
            cholesky_solve_in_place(&ws.floating_d, &mut rhs);
            ws.qdd[joint.v_index..joint.v_index + 6].copy_from_slice(&rhs);
            a_prime
                + Motion::new(
                    Vector3::new(rhs[3], rhs[4], rhs[5]),
                    Vector3::new(rhs[0], rhs[1], rhs[2]),
                )
        }
        _ => {
            let d_inv = ws.d_inv[i];
            if !d_inv.is_positive_finite() {
                return Err(DynamicsError::SingularJoint {
                    joint: joint.name.clone(),
                    d: (T::one() / d_inv).to_f64(),
                });
            }
            let qdd = (ws.epsilon[i] - a_prime.dot(&ws.u[i])) * d_inv;
            ws.qdd[joint.v_index] = qdd;
            a_prime + joint.subspace_column(0) * qdd
        }
    };
    ws.acceleration[i] = a;
    Ok(())
}

fn check_floating<T: Real>(
    joint: &crate::Joint<T>,
    ws: &Workspace<T>,
) -> Result<(), DynamicsError> {
    let d = floating_min_pivot(ws);
    if d.is_positive_finite() {
        Ok(())
    } else {
        Err(DynamicsError::SingularJoint {
            joint: joint.name.clone(),
            d: d.to_f64(),
        })
    }
}

/// The velocity sweep and the backward sweep of Eq. 9: `P(k)`, `D(k)`, `𝔷(k)`, `ε(k)` for every joint.
pub(crate) fn articulate<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
) {
    velocity_sweep(model, ws, q, v);
    init_articulated(model, ws);
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

/// The backward step of Eq. 9 for joint `i`: `D(k)`, `ε(k)`, and what passes to the parent,
/// `P(k+1) += φ τ̄ P φ*`, `𝔷(k+1) += φ (𝔷 + P⁺ a(k) + G ε)`.
pub(crate) fn backward_step<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, i: usize, tau: &[T]) {
    let joint = &model.joints[i];
    let p = ws.inertia[i];
    if joint.joint_type == JointType::Floating {
        // The floating joint is always a root (checked at build): nothing to pass on.
        let m = p.to_matrix();
        // Reorder [ω; v] rows and columns to the order of v = [v_lin; ω].
        let d = &mut ws.floating_d;
        for r in 0..6 {
            for c in 0..6 {
                d[(r, c)] = m[((r + 3) % 6, (c + 3) % 6)];
            }
        }
        let z = to_v_order(&ws.force[i]);
        for k in 0..6 {
            ws.floating_eps[k] = tau[joint.v_index + k] - z[k];
        }
        ws.floating_pivot = cholesky_in_place(d);
        return;
    }
    let h = joint.subspace_column(0);
    let u = p.mul_motion(&h);
    let d_inv = T::one() / h.dot(&u);
    let eps = tau[joint.v_index] - h.dot(&ws.force[i]);
    ws.u[i] = u;
    ws.d_inv[i] = d_inv;
    ws.epsilon[i] = eps;
    if let Some(parent) = joint.parent {
        // P⁺ = τ̄ P = P − U D⁻¹ Uᵀ;  𝔷⁺ = 𝔷 + P⁺ a(k) + G ε.
        let mut p_plus = p;
        p_plus.sub_rank_one(&u, d_inv);
        let mut z_plus = ws.force[i] + p_plus.mul_motion(&ws.coriolis[i]) + u * (eps * d_inv);
        // P⁺ H* = 0 and H 𝔷⁺ = 𝒯 exactly (τ̄ removes the joint's own direction). For an axis along a
        // coordinate axis that makes a row and column of P⁺ zero: set them exactly, which removes
        // rounding noise and, in generated code, every product with them.
        if let Some((angular, k)) = joint.coordinate_axis() {
            p_plus.clear_direction(angular, k);
            let sign = joint.axis[k];
            let tau_i = tau[joint.v_index] * sign;
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
}

/// The smallest pivot of the last floating-root `D` factorization (the 6-DoF analogue of `D(k)`).
pub(crate) fn floating_min_pivot<T: Real>(ws: &Workspace<T>) -> T {
    ws.floating_pivot
}

/// A force `[n; f]` in the order of `v` for a floating joint: `Hᵀ f = [f; n]`.
#[inline(always)]
fn to_v_order<T: Real>(f: &Force<T>) -> [T; 6] {
    [
        f.linear.x,
        f.linear.y,
        f.linear.z,
        f.angular.x,
        f.angular.y,
        f.angular.z,
    ]
}
