//! The load-time check that every joint's acceleration is determined: its articulated inertia about its
//! axis, `D(k)`, is positive at the scale of what the joint moves and the precision of the scalar type.
//!
//! Two comparisons, both relative (a milligram arm and a gram probe on a tonne carriage are valid
//! models; one absolute tolerance would refuse one or accept noise in the other):
//! - `M_kk`, the joint's composite inertia about its axis (the diagonal of the mass matrix: the links
//!   it moves, held rigid), against the size of that composite inertia in any direction (its mass for a
//!   translation, the largest entry of its rotational inertia for a rotation): a joint turning a needle
//!   about its own length, or a massless subtree, moves nothing.
//! - `D(k)` against what it is computed from, `R(k) = H (I_k + Σ_children φ P_c φ*) H*`: the body's own
//!   inertia plus its children's articulated inertias *before* each child's joint direction is taken out
//!   (`P⁺ = P − U D⁻¹ Uᵀ`). That subtraction is where `D`'s rounding error comes from, of order ε·`R`.
//!   Where the descendants' joints can absorb all of the inertia (a massless link carrying a coaxial
//!   joint), `D` is that rounding noise, positive or negative, and the acceleration is undetermined.
//!   (Not `M_kk`: the composite inertia carries the lever arms of the whole subtree, so along a long chain
//!   of free joints a perfectly determined `D` is a tiny fraction of it, and f32 would refuse a 100-link
//!   chain.)
//!
//! Both are judged at [`resolvable_fraction`] of the reference, i.e. in the precision of the scalar the
//! check runs in: [`crate::Model::try_cast`] runs it again in the target type.

use crate::algorithms::{aba, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::{Model, ModelError};
use crate::spatial::{ArticulatedInertia, SpatialInertia};
use crate::Real;

/// The smallest fraction of its reference a quantity must keep to be more than rounding in `T`: 1000 ε
/// (2.2e-13 in f64, 1.2e-4 in f32). Below it, fewer than three digits of the joint's acceleration
/// survive in `T` (the rule docs/conventions.md uses for a loop's conditioning, 1e-3/ε, read the other way).
fn resolvable_fraction<T: Real>() -> f64 {
    1e3 * T::epsilon().to_f64()
}

/// Whether joint `i`'s coordinate is a dependent one of an aggregate link (a loop, coupling or mimic
/// joint determines its acceleration from the independent ones).
fn is_dependent<T: Real>(model: &Model<T>, i: usize) -> bool {
    model.group_of(i).is_some() && !model.is_independent(i)
}

/// The articulated-body backward sweep, except that a dependent joint of an aggregate link is held
/// rigid: its body's articulated inertia joins its parent's unprojected. A dependent joint need not move
/// inertia of its own — a geared rotor of no axial inertia, a massless link of a four-bar — since the
/// constraint, not its own inertia, determines its acceleration; projecting along it would divide by
/// its zero pivot and poison every ancestor. Its inertia then counts for the independent joints above
/// it, as it does in the aggregate link.
fn articulate_with_dependent_rigid<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
) {
    if !model.has_constraints() {
        aba::articulate(model, ws, q, v, tau, &[]);
        return;
    }
    crate::algorithms::velocity_sweep(model, ws, q, v);
    aba::init_articulated(model, ws);
    for i in (0..model.nbodies()).rev() {
        if !is_dependent(model, i) {
            aba::backward_step(model, ws, i, tau);
            continue;
        }
        if let Some(parent) = model.joints[i].parent {
            let x = ws.parent_placement[i];
            let p = ws.inertia[i].act(&x);
            ws.inertia[parent] += p;
        }
    }
}

/// What one configuration says about one joint.
#[derive(Clone, Copy)]
struct JointVerdict {
    /// The joint moves inertia and `D` is resolved, at this configuration.
    regular: bool,
    /// `D` or `M` is not finite: the numbers overflowed when combined.
    overflow: bool,
    /// The pivot of `D` whose share of `M` is smallest (`D` itself for a 1-DoF joint).
    d: f64,
}

/// Rejects a model in which some joint's `D(k)` is not resolved (see the module documentation) at two
/// unrelated configurations (then it is unresolved everywhere but on a null set: the joint moves no
/// inertia, e.g. a massless leaf, and ABA would divide by rounding noise), or in which the inertias
/// overflow when the algorithms combine them.
pub(crate) fn check_articulated_inertia<T: Real>(model: &Model<T>) -> Result<(), ModelError> {
    let n = model.nbodies();
    if n == 0 {
        return Ok(());
    }
    let mut ws = Workspace::new(model);
    let q0 = model.neutral_configuration();
    let mut q1 = q0.clone();
    // A fixed, irrational-looking configuration: no symmetry of a hand-written model lines up with it.
    for (k, x) in q1.iter_mut().enumerate() {
        *x += T::from_f64(0.37 + 0.61 * ((k as f64) * 1.618_033_988_749).sin());
    }
    model.normalize_configuration(&mut q1);
    let v = vec![T::zero(); model.nv()];
    let tau = v.clone();
    let mut composite: Vec<SpatialInertia<T>> = Vec::with_capacity(n);
    let mut regular = vec![false; n];
    let mut last = vec![
        JointVerdict {
            regular: false,
            overflow: false,
            d: 0.0
        };
        n
    ];
    let mut unprojected: Vec<ArticulatedInertia<T>> = Vec::with_capacity(n);
    for q in [&q0, &q1] {
        articulate_with_dependent_rigid(model, &mut ws, q, &v, &tau);
        // Composite inertias, leaves first, from the placements the sweep left in `ws`; and each body's
        // inertia plus its children's articulated inertias before their joints are taken out (`ws.inertia`
        // keeps every body's `P` as it was before its own projection).
        composite.clear();
        composite.extend(model.bodies.iter().map(|b| b.inertia));
        unprojected.clear();
        unprojected.extend(
            model
                .bodies
                .iter()
                .map(|b| ArticulatedInertia::from(b.inertia)),
        );
        for i in (0..n).rev() {
            if let Some(p) = model.joints[i].parent {
                let x = &ws.parent_placement[i];
                let c = composite[i].act(x);
                composite[p] = composite[p] + c;
                unprojected[p] += ws.inertia[i].act(x);
            }
        }
        for i in 0..n {
            if is_dependent(model, i) {
                // Its acceleration follows from the constraints; its inertia was judged with its
                // independent joints (rigidly attached, see `articulate_with_dependent_rigid`).
                regular[i] = true;
                continue;
            }
            last[i] = judge_joint(model, &ws, &composite[i], &unprojected[i], i);
            regular[i] |= last[i].regular;
        }
    }
    // A singular joint poisons its ancestors (D = NaN there): report the last one in depth-first
    // order, which has no singular descendant and is the cause.
    let Some(i) = regular.iter().rposition(|r| !r) else {
        return Ok(());
    };
    let joint = model.joints[i].name.clone();
    if last[i].overflow {
        // The largest inertia in the joint's subtree is the one to blame.
        let magnitude = |b: usize| {
            let inertia = &model.bodies[b].inertia;
            let largest = |m: f64, x: &T| m.max(x.to_f64().abs());
            let m = inertia
                .first_moment
                .iter()
                .fold(inertia.mass.to_f64().abs(), largest);
            inertia.rotational.iter().fold(m, largest)
        };
        let body = (i..model.subtree_end(i))
            .max_by(|&a, &b| magnitude(a).total_cmp(&magnitude(b)))
            .unwrap_or(i);
        return Err(ModelError::InertiaOverflow {
            joint,
            body: model.bodies[body].name.clone(),
            magnitude: magnitude(body),
        });
    }
    Err(ModelError::NoInertiaAboutAxis {
        joint,
        d: last[i].d,
    })
}

/// The verdict on joint `i` from its articulated inertia (in `ws` after the backward sweep), its
/// composite inertia and the unprojected sum `D` is computed from (see the module documentation), all in
/// its body frame.
fn judge_joint<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
    composite: &SpatialInertia<T>,
    unprojected: &ArticulatedInertia<T>,
    i: usize,
) -> JointVerdict {
    let joint = &model.joints[i];
    let nv = joint.nv();
    let resolvable = resolvable_fraction::<T>();
    let articulated = &ws.inertia[i];
    // D = Sᵀ P S and M = Sᵀ I_c S (≤ 6 × 6), in f64: their entries are what T computed.
    let mut d = [[0.0f64; 6]; 6];
    let mut m = [[0.0f64; 6]; 6];
    let mut reference = [0.0f64; 6];
    let mut moves_inertia = true;
    // The largest entry, not the trace: a sum could overflow where every entry is finite.
    let rotational_size = composite
        .rotational
        .iter()
        .fold(0.0f64, |m, x| m.max(x.to_f64().abs()));
    let mass = composite.mass.to_f64().abs();
    for r in 0..nv {
        let s_r = joint.subspace_column(r);
        for c in 0..nv {
            let s_c = joint.subspace_column(c);
            d[r][c] = s_r.dot(&articulated.mul_motion(&s_c)).to_f64();
            m[r][c] = s_r.dot(&composite.mul_motion(&s_c)).to_f64();
        }
        reference[r] = s_r.dot(&unprojected.mul_motion(&s_r)).to_f64();
        // The composite's size along any direction of this kind of motion.
        let squared = |v: &nalgebra::Vector3<T>| v.dot(v).to_f64();
        let size = squared(&s_r.angular) * rotational_size + squared(&s_r.linear) * mass;
        moves_inertia &= m[r][r] > resolvable * size;
    }
    let finite = d[..nv]
        .iter()
        .chain(&m[..nv])
        .all(|row| row[..nv].iter().all(|x| x.is_finite()));
    if !finite {
        return JointVerdict {
            regular: false,
            overflow: true,
            d: f64::NAN,
        };
    }
    // The Cholesky pivots of D scaled by diag(R)^(-1/2) on both sides: each is the share of R_kk that D
    // keeps in direction k after the earlier directions (1-DoF: D / R_kk), unit-free for a floating joint
    // whose directions mix kg and kg·m².
    let mut smallest_share = f64::INFINITY;
    let mut d_at_smallest = d[0][0];
    for k in 0..nv {
        // Gaussian elimination without pivoting: the pivots of D's LDLᵀ factorization, in order.
        let pivot = d[k][k];
        let share = pivot / reference[k];
        if share < smallest_share || share.is_nan() {
            smallest_share = share;
            d_at_smallest = pivot;
        }
        if !pivot.is_positive_finite() {
            break;
        }
        let row_k = d[k];
        for row in d.iter_mut().take(nv).skip(k + 1) {
            let factor = row[k] / pivot;
            for (x, &y) in row.iter_mut().zip(&row_k).take(nv).skip(k + 1) {
                *x -= factor * y;
            }
        }
    }
    JointVerdict {
        // NaN compares false: an undetermined share is not regular.
        regular: moves_inertia && smallest_share > resolvable,
        overflow: false,
        d: d_at_smallest,
    }
}
