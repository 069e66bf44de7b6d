//! Derivatives of inverse dynamics by a recursion over the tree in world-aligned frames, and of forward
//! dynamics from them (`∂q̈ = −M⁻¹ ∂τ`): the analytical alternative to the dual numbers of
//! [`super::derivatives`], for models without loops, couplings or mimic joints.
//!
//! Why: forward mode costs every input direction a pass through the whole algorithm, `O(nv²)` tangent
//! work with a large constant; here each pair of related coordinates (one an ancestor of the other)
//! costs a few dot products, and each coordinate a few spatial products, `O(nv · depth)`.
//!
//! # The recursion
//!
//! Everything is in one inertial frame per root body: the world's axes at that body's origin at `q` (any
//! inertial frame serves, and this one keeps the numbers of the robot's size: about the world origin a
//! body `d` away has inertia entries of `m d²` that the dot products cancel back, losing digits as `ε d²`,
//! so that a robot 100 m out had 1e-11 in f64 and 4 % in f32; subtrees of different roots never meet).
//! In it: `Jₖ` the columns of joint `k`'s motion subspace, `v_i` and `a_i` the
//! bodies' spatial velocities and accelerations (the root's parent accelerating at `−g`), `I_i` their
//! inertias, `h_i = I_i v_i`, `İ_i = v_i ×* I_i − I_i v_i×` (the inertia's rate, symmetric), and for each
//! subtree `k` the sums `Ic_k = Σ I_i`, `Hc_k = Σ h_i`, `Bc_k = Σ İ_i` and its force `F_k = Σ f_i`.
//! Moving coordinate `c` of joint `j` along `integrate(q, ε e)` turns `j`'s subtree rigidly by the
//! world twist `ξ = J_jc`, which gives, with `λ` the parent of `j`'s body,
//!
//! - `∂J_k = ξ × J_k`, `∂v_i = ξ × (v_i − v_λ)`, `∂a_i = ξ × (a_i − a_λ) − (ξ × v_λ) × (v_i − v_λ)` for
//!   `k`, `i` in the subtree; hence, with `η = ξ × v_λ` and `α = ξ × a_λ − η × v_λ`,
//!   `∂F_k = ξ ×* F_k − Ic_k α − Bc_k η − η ×* Hc_k` (every covariant part turning with the subtree);
//! - for a velocity coordinate, `∂v_i = ξ`, `∂a_i = ξ × v_i + β` with `β = v_j × ξ − ξ × v_λ`, hence
//!   `∂F_k = Ic_k β + Bc_k ξ + ξ ×* Hc_k`.
//!
//! `τ_k = J_kᵀ F_k` then gives the two blocks of each related pair: for `j` an ancestor of `k` (or `k`
//! itself), the `ξ ×* F_k` term cancels against `∂J_k` and
//! `∂τ_k/∂q_j = −(a_k · α + b_k · η)`, `∂τ_k/∂v_j = a_k · β + b_k · ξ` with the per-coordinate vectors
//! `a_k = Ic_k J_k` and `b_k = Bc_k J_k − J_k ×* Hc_k`; and for `j` below `k`,
//! `∂τ_k/∂q_j = J_k · ∂F_j`, `∂τ_k/∂v_j = J_k · ∂F_j` (its velocity form). The mass matrix comes along:
//! `M_kj = a_k · J_j` (plus armature). Wrenches on links are fixed in their links, so they turn with the
//! subtree and sit in `F` without further terms.

use super::{DynamicsError, LinkWrench, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::{Force, Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::{DMatrix, Matrix6, Vector3};

/// The world-frame quantities of the recursion: per body (placements, velocities, accelerations and
/// the subtree sums) and per velocity coordinate (the subspace column and the three motions of its
/// derivative terms). Made once per model; the calls do not allocate.
#[derive(Clone, Debug)]
pub(crate) struct AnalyticalScratch<T: Real> {
    placement: Vec<Transform<T>>,
    velocity: Vec<Motion<T>>,
    acceleration: Vec<Motion<T>>,
    inertia: Vec<SpatialInertia<T>>,
    momentum: Vec<Force<T>>,
    inertia_rate: Vec<Matrix6<T>>,
    force: Vec<Force<T>>,
    column: Vec<Motion<T>>,
    eta: Vec<Motion<T>>,
    alpha: Vec<Motion<T>>,
    beta: Vec<Motion<T>>,
}

impl<T: Real> AnalyticalScratch<T> {
    pub(crate) fn new(model: &Model<T>) -> Self {
        let (n, nv) = (model.nbodies(), model.nv());
        AnalyticalScratch {
            placement: vec![Transform::identity(); n],
            velocity: vec![Motion::zero(); n],
            acceleration: vec![Motion::zero(); n],
            inertia: vec![SpatialInertia::zero(); n],
            momentum: vec![Force::zero(); n],
            inertia_rate: vec![Matrix6::zeros(); n],
            force: vec![Force::zero(); n],
            column: vec![Motion::zero(); nv],
            eta: vec![Motion::zero(); nv],
            alpha: vec![Motion::zero(); nv],
            beta: vec![Motion::zero(); nv],
        }
    }
}

/// Where the recursion writes: `∂τ/∂q`, `∂τ/∂v` and, where wanted, the mass matrix.
pub(crate) struct InverseDynamicsPartials<'a, T: Real> {
    pub(crate) dtau_dq: &'a mut DMatrix<T>,
    pub(crate) dtau_dv: &'a mut DMatrix<T>,
    pub(crate) mass_matrix: Option<&'a mut DMatrix<T>>,
}

/// `τ = rnea(q, v, q̈)` with the wrenches `f_ext` into `plain.tau`, and its derivatives into `out` by the
/// world-frame recursion (module docs). Inputs are checked by [`super::rnea_ext`]'s value pass.
pub(crate) fn rnea_partials<T: Real>(
    model: &Model<T>,
    plain: &mut Workspace<T>,
    scratch: &mut AnalyticalScratch<T>,
    (q, v, qdd): (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    out: InverseDynamicsPartials<'_, T>,
) -> Result<(), DynamicsError> {
    debug_assert!(!model.has_constraints());
    // The value pass leaves each body's velocity, acceleration (with −g at the root) and subtree force
    // in its own frame.
    super::rnea_ext(model, plain, q, v, qdd, f_ext)?;
    let s = scratch;
    let gravity_acceleration = Motion::new(Vector3::zeros(), -model.gravity);
    // Outward: world placements and the per-body, per-coordinate terms.
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = match joint.parent {
            Some(p) => s.placement[p].compose(&plain.parent_placement[i]),
            // A root body's frame of reference: the world's axes at the body's origin (module docs).
            None => Transform::new(plain.parent_placement[i].rotation, Vector3::zeros()),
        };
        let vel = x.act_motion(&plain.velocity[i]);
        let acc = x.act_motion(&plain.acceleration[i]);
        let inertia = body.inertia.act(&x);
        s.momentum[i] = inertia.mul_motion(&vel);
        s.inertia_rate[i] = inertia_rate(&inertia, &vel);
        s.force[i] = x.act_force(&plain.force[i]);
        let (parent_vel, parent_acc) = match joint.parent {
            Some(p) => (s.velocity[p], s.acceleration[p]),
            None => (Motion::zero(), gravity_acceleration),
        };
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            let xi = x.act_motion(&joint.subspace_column(c));
            let eta = xi.cross_motion(&parent_vel);
            s.alpha[r] = xi.cross_motion(&parent_acc) - eta.cross_motion(&parent_vel);
            s.beta[r] = vel.cross_motion(&xi) - xi.cross_motion(&parent_vel);
            s.eta[r] = eta;
            s.column[r] = xi;
        }
        s.placement[i] = x;
        s.velocity[i] = vel;
        s.acceleration[i] = acc;
        s.inertia[i] = inertia;
    }
    let InverseDynamicsPartials {
        dtau_dq,
        dtau_dv,
        mut mass_matrix,
    } = out;
    dtau_dq.fill(T::zero());
    dtau_dv.fill(T::zero());
    if let Some(m) = mass_matrix.as_deref_mut() {
        m.fill(T::zero());
    }
    // Inward: each body's subtree sums are complete when it is reached (children come after parents).
    for k in (0..model.nbodies()).rev() {
        let joint = &model.joints[k];
        let (ic, hc, bc, fk) = (
            &s.inertia[k],
            &s.momentum[k],
            &s.inertia_rate[k],
            &s.force[k],
        );
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            let xi = s.column[r];
            let a = ic.mul_motion(&xi);
            let bxi = mul6(bc, &xi);
            let b = bxi - xi.cross_force(hc);
            // Rows r, columns of this joint and its ancestors.
            for j in core::iter::once(k).chain(model.ancestors(k)) {
                for col in model.joints[j].v_range() {
                    dtau_dq[(r, col)] = -(s.alpha[col].dot(&a) + s.eta[col].dot(&b));
                    dtau_dv[(r, col)] = s.beta[col].dot(&a) + s.column[col].dot(&b);
                    if let Some(m) = mass_matrix.as_deref_mut() {
                        let mrc = s.column[col].dot(&a);
                        m[(r, col)] = mrc;
                        m[(col, r)] = mrc;
                    }
                }
            }
            // Rows of the strict ancestors, column r: J_j · ∂F_k.
            let (eta, alpha, beta) = (s.eta[r], s.alpha[r], s.beta[r]);
            let force_q =
                xi.cross_force(fk) - ic.mul_motion(&alpha) - mul6(bc, &eta) - eta.cross_force(hc);
            let force_v = ic.mul_motion(&beta) + bxi + xi.cross_force(hc);
            for j in model.ancestors(k) {
                for row in model.joints[j].v_range() {
                    dtau_dq[(row, r)] = s.column[row].dot(&force_q);
                    dtau_dv[(row, r)] = s.column[row].dot(&force_v);
                }
            }
        }
        if joint.has_armature() {
            if let Some(m) = mass_matrix.as_deref_mut() {
                for r in joint.v_range() {
                    m[(r, r)] += joint.armature;
                }
            }
        }
        if let Some(p) = joint.parent {
            let (inertia, momentum, rate) = (s.inertia[k], s.momentum[k], s.inertia_rate[k]);
            s.inertia[p] = s.inertia[p] + inertia;
            s.momentum[p] += momentum;
            s.inertia_rate[p] += rate;
        }
    }
    Ok(())
}

/// `∂q̈/∂q = −M⁻¹ ∂τ/∂q` and `∂q̈/∂v = −M⁻¹ ∂τ/∂v` at `q̈ = aba(q, v, τ)`, given `M⁻¹`: column `c` of
/// `∂τ` is zero but in the rows of its joint's ancestors and subtree, and only those rows are summed.
pub(crate) fn forward_partials<T: Real>(
    model: &Model<T>,
    minv: &DMatrix<T>,
    dtau: &DMatrix<T>,
    out: &mut DMatrix<T>,
) {
    let nv = model.nv();
    for (k, joint) in model.joints.iter().enumerate() {
        let subtree = model.subtree_v_range(k);
        for col in joint.v_range() {
            for row in 0..nv {
                let mut sum = T::zero();
                for j in model.ancestors(k) {
                    for r in model.joints[j].v_range() {
                        sum += minv[(row, r)] * dtau[(r, col)];
                    }
                }
                for r in subtree.clone() {
                    sum += minv[(row, r)] * dtau[(r, col)];
                }
                out[(row, col)] = -sum;
            }
        }
    }
}

/// `İ = v ×* I − I v×` as a 6 × 6 matrix (columns `İ eₘ`), `[angular; linear]` on both sides. It is
/// symmetric (`v ×* = −(v×)ᵀ`): the lower triangle is computed and mirrored, so that the matrix is
/// exactly symmetric and its upper half costs nothing.
fn inertia_rate<T: Real>(inertia: &SpatialInertia<T>, v: &Motion<T>) -> Matrix6<T> {
    let mut m = Matrix6::zeros();
    for c in 0..6 {
        let mut e = [T::zero(); 6];
        e[c] = T::one();
        let e = Motion::from_array(e);
        let col = v.cross_force(&inertia.mul_motion(&e)) - inertia.mul_motion(&v.cross_motion(&e));
        let col = col.to_array();
        for r in c..6 {
            m[(r, c)] = col[r];
            m[(c, r)] = col[r];
        }
    }
    m
}

/// `B x` for a 6 × 6 matrix from motions to forces.
fn mul6<T: Real>(b: &Matrix6<T>, x: &Motion<T>) -> Force<T> {
    let x = x.to_array();
    let mut y = [T::zero(); 6];
    for (r, yr) in y.iter_mut().enumerate() {
        for (c, &xc) in x.iter().enumerate() {
            *yr += b[(r, c)] * xc;
        }
    }
    Force::from_array(y)
}
