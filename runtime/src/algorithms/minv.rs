//! The inverse mass matrix from the operator factorization of the paper's Eq. 6,
//! `ℳ⁻¹ = [I − Hψ𝒦]* 𝒟⁻¹ [I − Hψ𝒦]`, evaluated by two sweeps without forming or factoring `ℳ`.
//!
//! The backward sweep applies `𝒟⁻¹ [I − Hψ𝒦]` to the identity: row block `k` of the result needs only the
//! columns of `k`'s subtree, carried inward as spatial forces. The forward sweep applies
//! `[I − Hψ𝒦]*`, carrying one spatial acceleration per column outward. Cost O(N · nv).

use super::aba::{articulated_inertia_plus, check_pivot, d_block, factor_joint};
use super::{check_configuration, DynamicsError, Sweep, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::linalg::cholesky_solve_in_place;
use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Motion};
use crate::Real;
use nalgebra::DMatrix;

/// `M(q)⁻¹`, symmetric, both triangles filled. Left in `ws.inverse_mass_matrix`.
pub fn mass_matrix_inverse<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    check_configuration(model, q)?;
    ws.reserve_inverse(model);
    // Parent placements only.
    ws.sweep = Sweep::None;
    let nv = model.nv();
    for (i, joint) in model.joints.iter().enumerate() {
        ws.parent_placement[i] = joint.placement.compose(&joint.joint_transform(q));
        ws.inertia[i] = ArticulatedInertia::from(model.bodies[i].inertia);
    }
    ws.minv_force.fill([T::zero(); 6]);
    ws.inverse_mass_matrix.fill(T::zero());
    let zeros = [T::zero(); 6];

    // Backward sweep: rows of 𝒟⁻¹[I − Hψ𝒦], restricted to each subtree's columns. Each joint works on its
    // own `n × n` block of `D` (n = 1 or 6), as in the forward dynamics.
    for i in (0..model.nbodies()).rev() {
        let joint = &model.joints[i];
        let (v0, n) = (joint.v_index, joint.nv());
        let cols = model.subtree_v_range(i);
        factor_joint(model, ws, i);
        check_pivot(joint, ws.d_pivot[i])?;
        for col in cols.clone() {
            let f = Force::from_array(ws.minv_force[i * nv + col]);
            if n == 1 {
                // The common case, with −D⁻¹ formed once per row: D⁻¹ on the joint's own column,
                // −D⁻¹ H F on the columns of its descendants.
                let d_inv = ws.d_factor[ws.d_offset[i]];
                ws.inverse_mass_matrix[(v0, col)] = if col == v0 {
                    d_inv
                } else {
                    -d_inv * joint.subspace_column(0).dot(&f)
                };
                continue;
            }
            // Row block of the joint: D⁻¹ (e − Hᵀ F), the identity on the joint's own columns.
            let mut rhs = [T::zero(); 6];
            for (k, r) in rhs[..n].iter_mut().enumerate() {
                let e = if col == v0 + k { T::one() } else { T::zero() };
                *r = e - joint.subspace_column(k).dot(&f);
            }
            cholesky_solve_in_place(
                &d_block(&mut ws.d_factor, &ws.d_offset, i, n),
                &mut rhs[..n],
            );
            for (k, x) in rhs[..n].iter().enumerate() {
                ws.inverse_mass_matrix[(v0 + k, col)] = *x;
            }
        }
        if let Some(parent) = joint.parent {
            let x = ws.parent_placement[i];
            for col in cols {
                let mut f = Force::from_array(ws.minv_force[i * nv + col]);
                for k in 0..n {
                    f += ws.u[v0 + k] * ws.inverse_mass_matrix[(v0 + k, col)];
                }
                let fp = Force::from_array(ws.minv_force[parent * nv + col]) + x.act_force(&f);
                ws.minv_force[parent * nv + col] = fp.to_array();
            }
            let (p_plus, _) = articulated_inertia_plus(model, ws, i, &zeros[..n]);
            ws.inertia[parent] += p_plus.act(&x);
        }
    }

    // Forward sweep: multiply by [I − Hψ𝒦]*, filling rows of joint i for columns ≥ v_index(i).
    for (i, joint) in model.joints.iter().enumerate() {
        let (start, n) = (joint.v_index, joint.nv());
        let x = ws.parent_placement[i];
        for col in start..nv {
            let a_parent = match joint.parent {
                Some(p) => x.inv_act_motion(&Motion::from_array(ws.minv_accel[p * nv + col])),
                None => Motion::zero(),
            };
            if joint.parent.is_some() {
                // Rows −= D⁻¹ Uᵀ a_parent.
                let mut y = [T::zero(); 6];
                for (k, y) in y[..n].iter_mut().enumerate() {
                    *y = a_parent.dot(&ws.u[start + k]);
                }
                cholesky_solve_in_place(
                    &d_block(&mut ws.d_factor, &ws.d_offset, i, n),
                    &mut y[..n],
                );
                for (k, y) in y[..n].iter().enumerate() {
                    ws.inverse_mass_matrix[(start + k, col)] -= *y;
                }
            }
            let mut a = a_parent;
            for k in 0..n {
                a += joint.subspace_column(k) * ws.inverse_mass_matrix[(start + k, col)];
            }
            ws.minv_accel[i * nv + col] = a.to_array();
        }
    }
    // Mirror the upper triangle.
    for c in 0..nv {
        for r in c + 1..nv {
            ws.inverse_mass_matrix[(r, c)] = ws.inverse_mass_matrix[(c, r)];
        }
    }
    Ok(&ws.inverse_mass_matrix)
}
