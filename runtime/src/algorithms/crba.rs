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
use crate::spatial::{SpatialInertia, Transform};
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
    // Entries of joints on different branches are zero and never written below.
    ws.mass_matrix.as_mut_slice().fill(T::zero());
    // Leaves first, in post-order: a body comes right after its subtree (its children follow it in index
    // order and come first to last), when its composite inertia is complete; it goes to the parent's, and
    // the body's columns are carried up right then. Generated code follows this order, so that only the
    // composites of the bodies on the current path are live: computing every composite before any column
    // kept them all live. The floating ANYmal B's generated `crba` takes 0.84× the time (G1 0.96–0.98×,
    // TALOS 1.04×, where the code's size rather than its live values sets the pace: BENCHMARKS.md).
    // Each composite is added to its parent's before its columns are walked: the other way round, the
    // pairing of TALOS's mirrored arms (its right gripper turned by π) found half the pairs.
    for last in 0..n {
        // The bodies whose subtree ends with `last`, deepest first.
        let mut i = last;
        while model.subtree_end(i) == last + 1 {
            crba_body(
                model,
                &mut ws.composite,
                &ws.parent_placement,
                &mut ws.mass_matrix,
                i,
            );
            match model.joints[i].parent {
                Some(p) => i = p,
                None => break,
            }
        }
    }
    Ok(&ws.mass_matrix)
}

/// Body `i`'s composite inertia (complete) added to its parent's, then its columns of `M`.
fn crba_body<T: Real>(
    model: &Model<T>,
    composites: &mut [SpatialInertia<T>],
    parent_placement: &[Transform<T>],
    m: &mut DMatrix<T>,
    i: usize,
) {
    let joint = &model.joints[i];
    let composite = composites[i].named(&model.bodies[i].name, "ic");
    if let Some(p) = joint.parent {
        let c = composite.act(&parent_placement[i]);
        composites[p] = composites[p] + c;
    }
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
            f = parent_placement[j].act_force(&f);
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
