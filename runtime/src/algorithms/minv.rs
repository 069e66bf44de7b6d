//! The inverse mass matrix from the operator factorization of the paper's Eq. 6,
//! `ℳ⁻¹ = [I − Hψ𝒦]* 𝒟⁻¹ [I − Hψ𝒦]`, evaluated by two sweeps without forming or factoring `ℳ`.
//!
//! The backward sweep applies `𝒟⁻¹ [I − Hψ𝒦]` to the identity: row block `k` of the result needs only the
//! columns of `k`'s subtree, carried inward as spatial forces. The forward sweep applies
//! `[I − Hψ𝒦]*`, carrying one spatial acceleration per column outward. Cost O(N · nv).

use super::{check_len, DynamicsError, Workspace};
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place};
use crate::model::{JointType, Model};
use crate::spatial::{ArticulatedInertia, Force, Motion};
use crate::Real;
use nalgebra::{DMatrix, Matrix6};

/// `M(q)⁻¹`, symmetric, both triangles filled. Left in `ws.inverse_mass_matrix`.
pub fn mass_matrix_inverse<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    ws.reserve_inverse(model);
    let nv = model.nv();
    for (i, joint) in model.joints.iter().enumerate() {
        ws.parent_placement[i] = joint.placement.compose(&joint.joint_transform(q));
        ws.inertia[i] = ArticulatedInertia::from(model.bodies[i].inertia);
    }
    ws.minv_force.fill([T::zero(); 6]);
    ws.inverse_mass_matrix.fill(T::zero());
    let mut d6 = Matrix6::<T>::zeros();

    // Backward sweep: rows of 𝒟⁻¹[I − Hψ𝒦], restricted to each subtree's columns.
    for i in (0..model.nbodies()).rev() {
        let joint = &model.joints[i];
        let cols = model.subtree_v_range(i);
        let p = ws.inertia[i];
        match joint.joint_type {
            JointType::Floating => {
                let m = p.to_matrix();
                for r in 0..6 {
                    for c in 0..6 {
                        d6[(r, c)] = m[((r + 3) % 6, (c + 3) % 6)];
                    }
                }
                let pivot = cholesky_in_place(&mut d6);
                if !pivot.is_positive_finite() {
                    return Err(DynamicsError::SingularJoint {
                        joint: joint.name.clone(),
                        d: pivot.to_f64(),
                    });
                }
                for col in cols {
                    let f = Force::from_array(ws.minv_force[i * nv + col]);
                    // e_k − Sᵀ F (identity block on the joint's own columns).
                    let mut rhs = [
                        -f.linear.x,
                        -f.linear.y,
                        -f.linear.z,
                        -f.angular.x,
                        -f.angular.y,
                        -f.angular.z,
                    ];
                    if (joint.v_index..joint.v_index + 6).contains(&col) {
                        rhs[col - joint.v_index] += T::one();
                    }
                    cholesky_solve_in_place(&d6, &mut rhs);
                    for (k, x) in rhs.iter().enumerate() {
                        ws.inverse_mass_matrix[(joint.v_index + k, col)] = *x;
                    }
                }
                // A floating joint is a root: nothing to pass on.
            }
            _ => {
                let h = joint.subspace_column(0);
                let u = p.mul_motion(&h);
                let d_inv = T::one() / h.dot(&u);
                if !d_inv.is_positive_finite() {
                    return Err(DynamicsError::SingularJoint {
                        joint: joint.name.clone(),
                        d: (T::one() / d_inv).to_f64(),
                    });
                }
                let row = joint.v_index;
                ws.inverse_mass_matrix[(row, row)] = d_inv;
                for col in cols.start + 1..cols.end {
                    let f = Force::from_array(ws.minv_force[i * nv + col]);
                    ws.inverse_mass_matrix[(row, col)] = -d_inv * h.dot(&f);
                }
                if let Some(parent) = joint.parent {
                    let x = ws.parent_placement[i];
                    for col in cols {
                        let f = Force::from_array(ws.minv_force[i * nv + col])
                            + u * ws.inverse_mass_matrix[(row, col)];
                        let fp =
                            Force::from_array(ws.minv_force[parent * nv + col]) + x.act_force(&f);
                        ws.minv_force[parent * nv + col] = fp.to_array();
                    }
                    let mut p_plus = p;
                    p_plus.sub_rank_one(&u, d_inv);
                    ws.inertia[parent] += p_plus.act(&x);
                }
                ws.u[i] = u;
                ws.d_inv[i] = d_inv;
            }
        }
    }

    // Forward sweep: multiply by [I − Hψ𝒦]*, filling rows i for columns ≥ v_index(i).
    for (i, joint) in model.joints.iter().enumerate() {
        let start = joint.v_index;
        let x = ws.parent_placement[i];
        for col in start..nv {
            let a_parent = match joint.parent {
                Some(p) => x.inv_act_motion(&Motion::from_array(ws.minv_accel[p * nv + col])),
                None => Motion::zero(),
            };
            let mut a = a_parent;
            match joint.joint_type {
                JointType::Floating => {
                    for k in 0..6 {
                        a += joint.subspace_column(k) * ws.inverse_mass_matrix[(start + k, col)];
                    }
                }
                _ => {
                    if joint.parent.is_some() {
                        ws.inverse_mass_matrix[(start, col)] -=
                            ws.d_inv[i] * a_parent.dot(&ws.u[i]);
                    }
                    a += joint.subspace_column(0) * ws.inverse_mass_matrix[(start, col)];
                }
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
