//! The mass matrix by the composite-rigid-body algorithm: `ℳ = H φ M φ* H*` (Eq. 3).
//!
//! Composite inertias and joint axes are expressed in the world frame, so that the entry of joint `j` in
//! joint `i`'s column is one dot product `H(j) · (I_c(i) H*(i))` per ancestor, with no per-ancestor frame
//! change: the composite of a rigid subtree is itself a rigid-body inertia (10 numbers), so the sums are
//! cheap too.

use super::{check_len, DynamicsError, Workspace};
use crate::model::Model;
use crate::spatial::{Force, SpatialInertia};
use crate::Real;
use nalgebra::DMatrix;

/// The joint-space mass matrix `M(q)` (symmetric, both triangles filled). Left in `ws.mass_matrix`.
pub fn crba<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    check_len("q", q.len(), model.nq())?;
    let n = model.nbodies();
    // World poses, world-frame body inertias.
    for (i, joint) in model.joints.iter().enumerate() {
        let x = joint.placement.compose(&joint.joint_transform(q));
        let world = match joint.parent {
            Some(p) => ws.world_placement[p].compose(&x),
            None => x,
        };
        ws.parent_placement[i] = x;
        ws.world_placement[i] = world;
        ws.composite[i] = model.bodies[i].inertia.act(&world);
        for k in 0..joint.nv() {
            ws.world_subspace[joint.v_index + k] = world.act_motion(&joint.subspace_column(k));
        }
    }
    // Composite inertias, leaves first: in a common frame, a plain sum.
    for i in (0..n).rev() {
        if let Some(p) = model.joints[i].parent {
            let c = ws.composite[i];
            ws.composite[p] = ws.composite[p] + c;
        }
    }
    let m = &mut ws.mass_matrix;
    // Entries of joints on different branches are zero and never written below.
    m.as_mut_slice().fill(T::zero());
    let sw = &ws.world_subspace;
    for (i, joint) in model.joints.iter().enumerate() {
        for k in 0..joint.nv() {
            let col = joint.v_index + k;
            let f: Force<T> = SpatialInertia::mul_motion(&ws.composite[i], &sw[col]);
            // The joint's own block, mirrored so that M is exactly symmetric.
            for row in col..joint.v_index + joint.nv() {
                let val = sw[row].dot(&f);
                m[(row, col)] = val;
                m[(col, row)] = val;
            }
            let mut j = i;
            while let Some(p) = model.joints[j].parent {
                j = p;
                let jp = &model.joints[j];
                for row in jp.v_index..jp.v_index + jp.nv() {
                    let val = sw[row].dot(&f);
                    m[(row, col)] = val;
                    m[(col, row)] = val;
                }
            }
        }
    }
    Ok(&ws.mass_matrix)
}
