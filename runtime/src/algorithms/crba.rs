//! The mass matrix by the composite-rigid-body algorithm: `ℳ = H φ M φ* H*` (Eq. 3).
//!
//! Everything stays in body frames: the composite inertia of each subtree (a rigid-body inertia, 10
//! numbers) is carried to the parent frame, and each column `I_c(i) H*(i)` is carried up the ancestors as
//! a spatial force, one frame change per ancestor. Body frames keep the zero structure of axis-aligned
//! joints, which generated code exploits; world frames would fill it in.

use super::{check_configuration, DynamicsError, Sweep, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::Real;
use nalgebra::DMatrix;

/// The joint-space mass matrix `M(q)` (symmetric, both triangles filled). Left in `ws.mass_matrix`.
///
/// Inputs are checked (lengths, NaN and infinities: [`DynamicsError`]); the result is not: finite inputs
/// whose result overflows the scalar give `Ok` with infinite or NaN entries (docs/conventions.md, "Errors").
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{crba, JointType, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// // m l² + I about the pivot.
/// let m = crba(&model, &mut ws, &[0.3]).unwrap();
/// assert!((m[(0, 0)] - (0.25 + 1e-3)).abs() < 1e-12);
/// ```
pub fn crba<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    check_configuration(model, q)?;
    ws.reserve_mass_matrix(model);
    // Parent placements only.
    ws.sweep = Sweep::None;
    let n = model.nbodies();
    for (i, joint) in model.joints.iter().enumerate() {
        ws.parent_placement[i] = joint.placement.compose(&joint.joint_transform(q));
        ws.composite[i] = model.bodies[i].inertia;
    }
    // Composite inertias, leaves first.
    for i in (0..n).rev() {
        if let Some(p) = model.joints[i].parent {
            let c = ws.composite[i].act(&ws.parent_placement[i]);
            ws.composite[p] = ws.composite[p] + c;
        }
    }
    let m = &mut ws.mass_matrix;
    // Entries of joints on different branches are zero and never written below.
    m.as_mut_slice().fill(T::zero());
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let composite = ws.composite[i].named(&body.name, "ic");
        for k in 0..joint.nv() {
            let col = joint.v_index + k;
            let mut f = composite.mul_motion(&joint.subspace_column(k));
            // The joint's own block, mirrored so that M is exactly symmetric.
            for r in k..joint.nv() {
                let mut val = joint.subspace_column(r).dot(&f);
                if r == k && joint.has_armature() {
                    val += joint.armature;
                }
                m[(joint.v_index + r, col)] = val;
                m[(col, joint.v_index + r)] = val;
            }
            let mut j = i;
            while let Some(p) = model.joints[j].parent {
                f = ws.parent_placement[j].act_force(&f);
                j = p;
                let jp = &model.joints[j];
                for r in 0..jp.nv() {
                    let row = jp.v_index + r;
                    let val = jp.subspace_column(r).dot(&f);
                    m[(row, col)] = val;
                    m[(col, row)] = val;
                }
            }
        }
    }
    Ok(&ws.mass_matrix)
}
