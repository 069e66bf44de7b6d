//! Derivatives of inverse dynamics by a recursion over the tree in one frame per root body, and of forward
//! dynamics from them (`∂q̈ = −M⁻¹ ∂τ`): the analytical alternative to the dual numbers of
//! [`super::derivatives`], for models without loops, couplings or mimic joints.
//!
//! Why: forward mode costs every input direction a pass through the whole algorithm, `O(nv²)` tangent
//! work with a large constant; here each pair of related coordinates (one an ancestor of the other)
//! costs a few dot products, and each coordinate a few spatial products, `O(nv · depth)`.
//!
//! # The recursion
//!
//! Everything is in one inertial frame per root body: that body's own frame at `q`, held fixed while
//! the coordinates move. Any inertial frame serves; this one
//! - keeps the numbers of the robot's size: about the world origin a body `d` away has inertia entries
//!   of `m d²` that the dot products cancel back, losing digits as `ε d²` (a robot 100 m out had 1e-11
//!   in f64 and 4 % in f32 when the world's origin was used);
//! - leaves the root's own quantities constant and its children's transforms as sparse as the model's:
//!   only gravity turns with the root (with the world's axes, the free flyer's dense rotation entered
//!   every body's placement; with this frame, the inertia rate's 9 numbers, `β = −2η` and the value
//!   pass below, the floating ANYmal B's `rnea_derivatives` went from 10.2k operations to 5.2k);
//! - subtrees of different roots never meet, so each keeps its own.
//!
//! In it: `Jₖ` the columns of joint `k`'s motion subspace, `v_i` and `a_i` the bodies' spatial velocities
//! and accelerations (the root's parent accelerating at `−g`), `I_i` their inertias, `h_i = I_i v_i`,
//! `İ_i = v_i ×* I_i − I_i v_i×` (the inertia's rate, [`InertiaRate`]: symmetric, with no mass), and for
//! each subtree `k` the sums `Ic_k = Σ I_i`, `Hc_k = Σ h_i`, `Bc_k = Σ İ_i` and its force `F_k = Σ f_i`.
//! Moving coordinate `c` of joint `j` along `integrate(q, ε e)` turns `j`'s subtree rigidly by the
//! twist `ξ = J_jc`, which gives, with `λ` the parent of `j`'s body,
//!
//! - `∂J_k = ξ × J_k`, `∂v_i = ξ × (v_i − v_λ)`, `∂a_i = ξ × (a_i − a_λ) − (ξ × v_λ) × (v_i − v_λ)` for
//!   `k`, `i` in the subtree; hence, with `η = ξ × v_λ` and `α = ξ × a_λ − η × v_λ`,
//!   `∂F_k = ξ ×* F_k − Ic_k α − Bc_k η − η ×* Hc_k` (every covariant part turning with the subtree);
//! - for a velocity coordinate, `∂v_i = ξ`, `∂a_i = ξ × v_i + β` with `β = v_j × ξ − ξ × v_λ` (`−2η` for
//!   a joint of one coordinate, whose `v_j = v_λ + ξ q̇`), hence `∂F_k = Ic_k β + Bc_k ξ + ξ ×* Hc_k`.
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
use nalgebra::{DMatrix, Matrix3, Vector3};

/// The root-frame quantities of the recursion: per body (placements, velocities, accelerations and
/// the subtree sums) and per velocity coordinate (the subspace column and the three motions of its
/// derivative terms). Made once per model; the calls do not allocate.
#[derive(Clone, Debug)]
pub(crate) struct AnalyticalScratch<T: Real> {
    placement: Vec<Transform<T>>,
    velocity: Vec<Motion<T>>,
    acceleration: Vec<Motion<T>>,
    inertia: Vec<SpatialInertia<T>>,
    momentum: Vec<Force<T>>,
    inertia_rate: Vec<InertiaRate<T>>,
    force: Vec<Force<T>>,
    /// `v_i × Σ ξ q̇` (the joint's velocity-product acceleration) and, for a root, the world's acceleration
    /// `−g` seen from it (zero elsewhere).
    bias: Vec<Motion<T>>,
    root_acceleration: Vec<Motion<T>>,
    /// The subtree sums `Ic`, `Hc`, `Bc` and `F` of the module docs.
    composite_inertia: Vec<SpatialInertia<T>>,
    composite_momentum: Vec<Force<T>>,
    composite_rate: Vec<InertiaRate<T>>,
    subtree_force: Vec<Force<T>>,
    column: Vec<Motion<T>>,
    eta: Vec<Motion<T>>,
    alpha: Vec<Motion<T>>,
    beta: Vec<Motion<T>>,
    /// [`forward_factors_by_mass_matrix`]'s `LᵀDL` factors, `L⁻¹` and `D⁻¹`, and each coordinate's joint
    /// and parent coordinate.
    factor: DMatrix<T>,
    factor_inverse: DMatrix<T>,
    pivot_inverse: Vec<T>,
    coordinate_joint: Vec<usize>,
    coordinate_parent: Vec<Option<usize>>,
}

impl<T: Real> AnalyticalScratch<T> {
    pub(crate) fn new(model: &Model<T>) -> Self {
        let (n, nv) = (model.nbodies(), model.nv());
        let (coordinate_joint, coordinate_parent) = coordinate_tree(model);
        AnalyticalScratch {
            placement: vec![Transform::identity(); n],
            velocity: vec![Motion::zero(); n],
            acceleration: vec![Motion::zero(); n],
            inertia: vec![SpatialInertia::zero(); n],
            momentum: vec![Force::zero(); n],
            inertia_rate: vec![InertiaRate::zero(); n],
            force: vec![Force::zero(); n],
            bias: vec![Motion::zero(); n],
            root_acceleration: vec![Motion::zero(); n],
            composite_inertia: vec![SpatialInertia::zero(); n],
            composite_momentum: vec![Force::zero(); n],
            composite_rate: vec![InertiaRate::zero(); n],
            subtree_force: vec![Force::zero(); n],
            column: vec![Motion::zero(); nv],
            eta: vec![Motion::zero(); nv],
            alpha: vec![Motion::zero(); nv],
            beta: vec![Motion::zero(); nv],
            factor: DMatrix::zeros(nv, nv),
            factor_inverse: DMatrix::zeros(nv, nv),
            pivot_inverse: vec![T::zero(); nv],
            coordinate_joint,
            coordinate_parent,
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
/// recursion of the module docs. The value pass runs in the root's frame too: there a body's velocity is
/// its parent's plus `Σ ξ q̇` and its force needs no transform, where a pass in the bodies' own frames
/// followed by a move of every result into the root's frame cost the Z1 arm 1,000 more operations.
pub(crate) fn rnea_partials<T: Real>(
    model: &Model<T>,
    plain: &mut Workspace<T>,
    scratch: &mut AnalyticalScratch<T>,
    (q, v, qdd): (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    out: InverseDynamicsPartials<'_, T>,
) -> Result<(), DynamicsError> {
    check_inputs(model, q, v, ("qdd", qdd), f_ext)?;
    let s = scratch;
    outward_velocities(model, s, q, v);
    outward_accelerations(model, s, qdd, f_ext);
    subtree_sums(model, s);
    pair_terms(model, s, qdd, out, &mut plain.tau);
    Ok(())
}

/// The inputs of either entry point: `q`, `v`, the third input (`q̈` or `τ`, by name) and the wrenches.
fn check_inputs<T: Real>(
    model: &Model<T>,
    q: &[T],
    v: &[T],
    (name, u): (&'static str, &[T]),
    f_ext: &[LinkWrench<T>],
) -> Result<(), DynamicsError> {
    debug_assert!(!model.has_constraints());
    super::check_configuration(model, q)?;
    super::check_input("v", v, model.nv())?;
    super::check_input(name, u, model.nv())?;
    super::wrenches::check_wrenches(model, f_ext)
}

/// Outward, from `q` and `v`: placements in the root's frame, velocities, the subspace columns `ξ`, the
/// bodies' inertias, momenta and inertia rates, and the per-coordinate `η`, `β`.
fn outward_velocities<T: Real>(model: &Model<T>, s: &mut AnalyticalScratch<T>, q: &[T], v: &[T]) {
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let parent_x = super::parent_placement(joint, q);
        let (x, parent_vel) = match joint.parent {
            Some(p) => (s.placement[p].compose(&parent_x), s.velocity[p]),
            // A root body's frame of reference is its own frame at `q` (module docs), in which the
            // fixed world accelerates at −g.
            None => {
                s.root_acceleration[i] = super::gravity_in(&model.gravity, &parent_x);
                (Transform::identity(), Motion::zero())
            }
        };
        let mut joint_vel = Motion::zero();
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            let xi = x.act_motion(&joint.subspace_column(c));
            joint_vel += xi * v[r];
            s.column[r] = xi;
        }
        let vel = parent_vel + joint_vel;
        s.bias[i] = vel.cross_motion(&joint_vel);
        let inertia = body.inertia.act(&x);
        s.momentum[i] = inertia.mul_motion(&vel);
        s.inertia_rate[i] = InertiaRate::of(&inertia, &vel);
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            let xi = s.column[r];
            let eta = xi.cross_motion(&parent_vel);
            s.beta[r] = if joint.nv() == 1 {
                // One column: v_i = v_λ + ξ q̇ and ξ × ξ = 0, so v_i × ξ = v_λ × ξ = −η and β = −2η,
                // without the two cross products.
                -(eta + eta)
            } else {
                vel.cross_motion(&xi) - xi.cross_motion(&parent_vel)
            };
            s.eta[r] = eta;
        }
        s.placement[i] = x;
        s.velocity[i] = vel;
        s.inertia[i] = inertia;
    }
}

/// Outward, from `q̈` (after [`outward_velocities`]): accelerations, the bodies' forces (less the
/// wrenches `f_ext`, fixed in their links' frames) and the per-coordinate `α`.
fn outward_accelerations<T: Real>(
    model: &Model<T>,
    s: &mut AnalyticalScratch<T>,
    qdd: &[T],
    f_ext: &[LinkWrench<T>],
) {
    for (i, joint) in model.joints.iter().enumerate() {
        let (parent_vel, parent_acc) = match joint.parent {
            Some(p) => (s.velocity[p], s.acceleration[p]),
            None => (Motion::zero(), s.root_acceleration[i]),
        };
        let mut acc = parent_acc + s.bias[i];
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            acc += s.column[r] * qdd[r];
            let eta = s.eta[r];
            s.alpha[r] = s.column[r].cross_motion(&parent_acc) - eta.cross_motion(&parent_vel);
        }
        s.force[i] = s.inertia[i].mul_motion(&acc) + s.velocity[i].cross_force(&s.momentum[i]);
        s.acceleration[i] = acc;
    }
    for w in f_ext {
        if let Some((b, in_body)) = super::wrenches::wrench_in_body(model, w) {
            s.force[b] -= s.placement[b].act_force(&in_body);
        }
    }
}

/// Inward: the subtree sums `Ic`, `Hc`, `Bc` and `F` (children come after their parents).
fn subtree_sums<T: Real>(model: &Model<T>, s: &mut AnalyticalScratch<T>) {
    s.composite_inertia.copy_from_slice(&s.inertia);
    s.composite_momentum.copy_from_slice(&s.momentum);
    s.composite_rate.copy_from_slice(&s.inertia_rate);
    s.subtree_force.copy_from_slice(&s.force);
    for k in (0..model.nbodies()).rev() {
        if let Some(p) = model.joints[k].parent {
            s.composite_inertia[p] = s.composite_inertia[p] + s.composite_inertia[k];
            s.composite_momentum[p] = s.composite_momentum[p] + s.composite_momentum[k];
            s.composite_rate[p] = s.composite_rate[p] + s.composite_rate[k];
            s.subtree_force[p] = s.subtree_force[p] + s.subtree_force[k];
        }
    }
}

/// The two blocks of each related pair of coordinates (module docs) into `out`, and `τ = Jᵀ F` (with
/// armature) into `tau`, from the passes before.
fn pair_terms<T: Real>(
    model: &Model<T>,
    s: &AnalyticalScratch<T>,
    qdd: &[T],
    out: InverseDynamicsPartials<'_, T>,
    tau: &mut [T],
) {
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
    for k in (0..model.nbodies()).rev() {
        let joint = &model.joints[k];
        let (ic, hc, bc, fk) = (
            &s.composite_inertia[k],
            &s.composite_momentum[k],
            &s.composite_rate[k],
            &s.subtree_force[k],
        );
        for c in 0..joint.nv() {
            let r = joint.v_index + c;
            let xi = s.column[r];
            let a = ic.mul_motion(&xi);
            let bxi = bc.mul_motion(&xi);
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
            let force_q = xi.cross_force(fk)
                - ic.mul_motion(&alpha)
                - bc.mul_motion(&eta)
                - eta.cross_force(hc);
            let force_v = ic.mul_motion(&beta) + bxi + xi.cross_force(hc);
            for j in model.ancestors(k) {
                for row in model.joints[j].v_range() {
                    dtau_dq[(row, r)] = s.column[row].dot(&force_q);
                    dtau_dv[(row, r)] = s.column[row].dot(&force_v);
                }
            }
        }
        for r in joint.v_range() {
            let mut value = s.column[r].dot(fk);
            if joint.has_armature() {
                value += joint.armature * qdd[r];
            }
            tau[r] = value;
        }
        if joint.has_armature() {
            if let Some(m) = mass_matrix.as_deref_mut() {
                for r in joint.v_range() {
                    m[(r, r)] += joint.armature;
                }
            }
        }
    }
}

/// Each coordinate's joint, and the coordinate it hangs from in the tree: the one before it in a
/// multi-coordinate joint, else the last one of its joint's nearest ancestor that has any.
fn coordinate_tree<T: Real>(model: &Model<T>) -> (Vec<usize>, Vec<Option<usize>>) {
    let mut joint_of = Vec::with_capacity(model.nv());
    let mut parent = Vec::with_capacity(model.nv());
    for (j, joint) in model.joints.iter().enumerate() {
        for c in joint.v_range() {
            joint_of.push(j);
            parent.push(if c > joint.v_index {
                Some(c - 1)
            } else {
                model
                    .ancestors(j)
                    .find(|&a| model.joints[a].nv() > 0)
                    .map(|a| model.joints[a].v_index + model.joints[a].nv() - 1)
            });
        }
    }
    (joint_of, parent)
}

/// The forward dynamics' factors by the recursion alone: `q̈ = M⁻¹ (τ − C(q, v) v − g(q) + Jᵀ f)`
/// with `M` from the composite inertias and its sparse factorization `M = Lᵀ D L` (Featherstone's,
/// `L` unit lower triangular with nonzeros only where a coordinate's ancestor is), `M⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ`,
/// then `∂τ/∂q`, `∂τ/∂v` at that `q̈`, into `(qdd, dtau_dq, dtau_dv, minv)`.
///
/// Why: the recursion's passes already hold what `M` and the bias need, so this replaces the
/// articulated-body pass of `aba` and the two sweeps of `M⁻¹` (together about as many operations as
/// the recursion on the Z1 arm) by dot products and a factorization of `nv · depth²`. The price is
/// accuracy where `M` is ill-conditioned: `M⁻¹` and `q̈` from `M` lose digits as `cond(M) ε`, which grows
/// as the cube of a chain's length, where the articulated-body factorization does not (docs/accuracy.md).
/// Generated code takes this way only where it runs fewer statements, and the interpreted solver only
/// when asked ([`crate::DerivativeMethod::MassMatrixFactorization`]).
#[allow(clippy::type_complexity)]
pub(crate) fn forward_factors_by_mass_matrix<T: Real>(
    model: &Model<T>,
    plain: &mut Workspace<T>,
    s: &mut AnalyticalScratch<T>,
    (q, v, tau): (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    (qdd, dtau_dq, dtau_dv, minv): (
        &mut nalgebra::DVector<T>,
        &mut DMatrix<T>,
        &mut DMatrix<T>,
        &mut DMatrix<T>,
    ),
) -> Result<(), DynamicsError> {
    check_inputs(model, q, v, ("tau", tau), f_ext)?;
    let nv = model.nv();
    outward_velocities(model, s, q, v);
    // The bias C(q, v) v + g(q) − Jᵀ f: the recursion's forces at q̈ = 0.
    qdd.fill(T::zero());
    outward_accelerations(model, s, qdd.as_slice(), f_ext);
    subtree_sums(model, s);
    // M's lower triangle (rows below their ancestors' columns) into the factor, and τ − bias into q̈.
    let h = &mut s.factor;
    h.fill(T::zero());
    for (k, joint) in model.joints.iter().enumerate() {
        let ic = &s.composite_inertia[k];
        for r in joint.v_range() {
            let a = ic.mul_motion(&s.column[r]);
            let mut c = Some(r);
            while let Some(col) = c {
                h[(r, col)] = s.column[col].dot(&a);
                c = s.coordinate_parent[col];
            }
            if joint.has_armature() {
                h[(r, r)] += joint.armature;
            }
            qdd[r] = tau[r] - s.column[r].dot(&s.subtree_force[k]);
        }
    }
    // Lᵀ D L in place, leaves first: row k's entries left of the diagonal become L, the diagonal D. Each
    // pivot's reciprocal is taken once (a division costs several multiplications' time, and a tree has
    // one per coordinate against one per related pair of coordinates for the quotients).
    for k in (0..nv).rev() {
        // A singular M (a massless subtree) leaves no finite q̈; ABA's pivot check says the same.
        super::aba::check_pivot(&model.joints[s.coordinate_joint[k]], h[(k, k)])?;
        let d_inv = T::one() / h[(k, k)];
        s.pivot_inverse[k] = d_inv;
        let mut i = s.coordinate_parent[k];
        while let Some(ii) = i {
            let a = h[(k, ii)] * d_inv;
            let mut j = Some(ii);
            while let Some(jj) = j {
                let update = h[(ii, jj)] - a * h[(k, jj)];
                h[(ii, jj)] = update;
                j = s.coordinate_parent[jj];
            }
            h[(k, ii)] = a;
            i = s.coordinate_parent[ii];
        }
    }
    // q̈ = L⁻¹ D⁻¹ L⁻ᵀ (τ − bias).
    for i in (0..nv).rev() {
        let mut j = s.coordinate_parent[i];
        while let Some(jj) = j {
            let update = qdd[jj] - h[(i, jj)] * qdd[i];
            qdd[jj] = update;
            j = s.coordinate_parent[jj];
        }
    }
    for i in 0..nv {
        qdd[i] *= s.pivot_inverse[i];
    }
    for i in 0..nv {
        let mut j = s.coordinate_parent[i];
        while let Some(jj) = j {
            let update = qdd[i] - h[(i, jj)] * qdd[jj];
            qdd[i] = update;
            j = s.coordinate_parent[jj];
        }
    }
    // L⁻¹ (unit lower triangular, nonzero only at ancestors): row r from the rows above it,
    // X[r][k] = −Σ L[r][i] X[i][k] over the coordinates i from r's parent up to k.
    let x = &mut s.factor_inverse;
    x.fill(T::zero());
    for r in 0..nv {
        x[(r, r)] = T::one();
        let mut k = s.coordinate_parent[r];
        while let Some(kk) = k {
            let mut sum = T::zero();
            let mut i = s.coordinate_parent[r];
            while let Some(ii) = i {
                sum += h[(r, ii)] * x[(ii, kk)];
                if ii == kk {
                    break;
                }
                i = s.coordinate_parent[ii];
            }
            x[(r, kk)] = -sum;
            k = s.coordinate_parent[kk];
        }
    }
    // M⁻¹[r][c] = Σ_k L⁻¹[r][k] L⁻¹[c][k] / D_k over the common ancestors k of r and c, the lower
    // triangle computed and mirrored (exactly symmetric).
    for r in 0..nv {
        for c in 0..=r {
            let mut sum = T::zero();
            let mut k = Some(c);
            while let Some(kk) = k {
                sum += x[(r, kk)] * (x[(c, kk)] * s.pivot_inverse[kk]);
                k = s.coordinate_parent[kk];
            }
            minv[(r, c)] = sum;
            minv[(c, r)] = sum;
        }
    }
    // The partials at this q̈.
    outward_accelerations(model, s, qdd.as_slice(), f_ext);
    subtree_sums(model, s);
    let partials = InverseDynamicsPartials {
        dtau_dq,
        dtau_dv,
        mass_matrix: None,
    };
    pair_terms(model, s, qdd.as_slice(), partials, &mut plain.tau);
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

/// The rate `İ = v ×* I − I v×` of a spatial inertia moving with `v`: a spatial inertia's shape with
/// zero mass (the mass does not change), so 9 numbers instead of a 6 × 6 matrix's 36, and `İ x` costs
/// about half a dense product. With `v = [ω; u]` about the frame origin:
/// `ḣ = ω × h + m u` and `İ_o = [ω]× I_o − I_o [ω]× + 2 (u·h) 1 − h uᵀ − u hᵀ` (symmetric).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct InertiaRate<T: Real> {
    /// `ḣ`, the rate of the first moment.
    first_moment: Vector3<T>,
    /// `İ_o`, the rate of the rotational inertia about the origin (symmetric).
    rotational: Matrix3<T>,
}

impl<T: Real> InertiaRate<T> {
    fn zero() -> Self {
        InertiaRate {
            first_moment: Vector3::zeros(),
            rotational: Matrix3::zeros(),
        }
    }

    /// `İ` of `inertia` moving with `v`.
    fn of(inertia: &SpatialInertia<T>, v: &Motion<T>) -> Self {
        let (w, u) = (&v.angular, &v.linear);
        let h = &inertia.first_moment;
        let io = &inertia.rotational;
        // P = [ω]× I_o column by column; I_o [ω]× = −Pᵀ (I_o symmetric), so the rotation's part is P + Pᵀ.
        let p = Matrix3::from_columns(&[
            w.cross(&io.column(0).into_owned()),
            w.cross(&io.column(1).into_owned()),
            w.cross(&io.column(2).into_owned()),
        ]);
        let uh = u.dot(h);
        let two_uh = uh + uh;
        let mut rotational = Matrix3::zeros();
        for r in 0..3 {
            for c in r..3 {
                let mut e = p[(r, c)] + p[(c, r)] - (h[r] * u[c] + u[r] * h[c]);
                if r == c {
                    e += two_uh;
                }
                rotational[(r, c)] = e;
                rotational[(c, r)] = e;
            }
        }
        InertiaRate {
            first_moment: w.cross(h) + u * inertia.mass,
            rotational,
        }
    }

    /// `İ x`: `[İ_o ω + ḣ × u; −ḣ × ω]` for `x = [ω; u]` (no mass term).
    #[inline(always)]
    fn mul_motion(&self, x: &Motion<T>) -> Force<T> {
        Force::new(
            self.rotational * x.angular + self.first_moment.cross(&x.linear),
            -self.first_moment.cross(&x.angular),
        )
    }
}

impl<T: Real> core::ops::Add for InertiaRate<T> {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        InertiaRate {
            first_moment: self.first_moment + rhs.first_moment,
            rotational: self.rotational + rhs.rotational,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;

    /// The 9-number rate against the dense `v ×* I − I v×`, column by column.
    #[test]
    fn inertia_rate_is_the_dense_product() {
        let inertia = SpatialInertia::from_com(
            2.5,
            Vector3::new(0.3, -0.7, 0.2),
            Matrix3::new(0.4, 0.01, -0.02, 0.01, 0.5, 0.03, -0.02, 0.03, 0.6),
        );
        let v = Motion::new(Vector3::new(0.9, -1.3, 0.4), Vector3::new(-0.6, 0.8, 1.7));
        let rate = InertiaRate::of(&inertia, &v);
        let mut dense = Matrix6::<f64>::zeros();
        for c in 0..6 {
            let mut e = [0.0; 6];
            e[c] = 1.0;
            let e = Motion::from_array(e);
            let col =
                v.cross_force(&inertia.mul_motion(&e)) - inertia.mul_motion(&v.cross_motion(&e));
            let col = col.to_array();
            let ours = rate.mul_motion(&e).to_array();
            for r in 0..6 {
                dense[(r, c)] = col[r];
                assert!(
                    (ours[r] - col[r]).abs() < 1e-13,
                    "({r}, {c}): {} vs {}",
                    ours[r],
                    col[r]
                );
            }
        }
        assert!((dense - dense.transpose()).amax() < 1e-13);
    }
}
