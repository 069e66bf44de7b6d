//! Dynamics of models with aggregate links (constraint embedding), and the Lagrange-multiplier oracle.
//!
//! The O(N) forward dynamics is Eq. 9 with the aggregate-link steps of Eqs. 19–24, in the arrangement of
//! the alternative form (Eqs. 26–34): every member of a group is referred to the one body the group hangs
//! from, so the group's `E_G` is the identity per member, its `φ_G H*_G X_G` is one 6-vector per member and
//! independent coordinate (`J_b`), and what the group passes to its parent is `Σ_b P_b − Ū D⁻¹ Ūᵀ` with
//! `Ū = Σ_b P_b J_b` — no 6k×6k matrix is ever formed. The products of a member's `P_b` (`D_G`, `ε_G`,
//! `P_b J_b`) are taken in the member's own frame and only their sums moved to the parent's: see
//! [`group_backward`] for why.
//!
//! Errata of the paper, checked against this implementation (and its KKT oracle) rather than copied:
//! - Eqs. 21 and 24: the step from the aggregate link to its outboard body uses the articulated
//!   quantities of body `j−1` (the body after the group), so some `(i−1)` there read `(j−1)`; and `𝒯(i)` in
//!   Eq. 21 stands for the aggregate's generalized force `X_Gᵀ 𝒯_G` (here `ε_G = X_Gᵀ τ_G − …`).
//! - The prose under Eq. 43 is copied from Eq. 44: Eq. 43's matrices cut c's hinge to link `i+1`, a loop
//!   closed back onto the tree (URDF+ writes it as a `<loop>` whose successor is an ancestor); both cuts
//!   are tested to give the same motion (tests/constraint_embedding.rs).

use super::aba::{backward_step, forward_step, init_articulated};
use super::kinematics::world_placements;
use super::{
    check_configuration, check_input, crba, forward_kinematics, parent_placement, rnea,
    DynamicsError, Sweep, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::constraints::{embed, ConstraintSet};
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place, lu_in_place, lu_solve_in_place};
use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Motion};
use crate::Real;
use nalgebra::{DMatrix, Vector3};

/// Kinematics the constraint equations need: parent and world placements, body velocities, and the
/// velocity-product accelerations (q̈ = 0, no gravity) in `ws.acceleration`.
pub fn constraint_kinematics<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
) -> Result<(), DynamicsError> {
    forward_kinematics(model, ws, q, v)?;
    for (i, joint) in model.joints.iter().enumerate() {
        ws.acceleration[i] = match joint.parent {
            Some(p) => ws.parent_placement[i].inv_act_motion(&ws.acceleration[p]) + ws.coriolis[i],
            None => ws.coriolis[i],
        };
    }
    // forward_kinematics_acceleration(q, v, 0): the same sums, without the zero joint terms.
    ws.sweep = Sweep::Accelerations;
    Ok(())
}

/// [`constraint_kinematics`] at rest (what position-level constraint work needs: placements and the
/// constraint Jacobian): placements from `q`, every velocity and acceleration zero.
pub(crate) fn position_kinematics<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q)?;
    ws.sweep = Sweep::None;
    for (i, joint) in model.joints.iter().enumerate() {
        ws.parent_placement[i] = parent_placement(joint, q);
        ws.velocity[i] = Motion::zero();
        ws.coriolis[i] = Motion::zero();
        ws.acceleration[i] = Motion::zero();
    }
    world_placements(model, ws);
    // Velocities zero, not the caller's.
    ws.sweep = Sweep::Placements;
    Ok(())
}

/// Forward dynamics with aggregate links: `qdd` over all spanning joints (consistent with the constraints
/// at acceleration level); only `Xᵀ τ` of `tau` acts.
pub(crate) fn aba<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[super::LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    constraint_kinematics(model, ws, q, v)?;
    // The accelerations become those of the motion with gravity; placements and velocities stay valid,
    // but `aba` promises as little as the tree's `aba` does (whose sweep leaves no world placements).
    ws.sweep = Sweep::None;
    let (kin, scratch) = ws.split_constraints();
    for (g, gw) in scratch.groups.iter_mut().enumerate() {
        embed(model, kin, g, gw, true)?;
    }
    init_articulated(model, ws);
    super::wrenches::subtract_wrenches(model, ws, f_ext);
    for i in (0..model.nbodies()).rev() {
        match model.group_of(i) {
            None => backward_step(model, ws, i, tau),
            Some(g) if model.groups[g].bodies[0] == i => group_backward(model, ws, g, tau)?,
            Some(_) => {}
        }
    }
    for i in 0..model.nbodies() {
        match model.group_of(i) {
            None => forward_step(model, ws, i)?,
            Some(g) if model.groups[g].bodies[0] == i => group_forward(model, ws, g),
            Some(_) => {}
        }
    }
    Ok(&ws.qdd)
}

/// Eqs. 19–22 for one aggregate link: `J_b`, `D_G`, `ε_G`, and the articulated inertia and bias force it
/// passes on.
///
/// Each member's own quantities stay in its own frame: `j_b` and `c_b` (its `J_b` and velocity-product
/// acceleration) are carried down the group from member to member, `u_b = P_b j_b` and the entries of
/// `D_G` and `ε_G` are formed there, and only `Ū = Σ_b U_b`, `Σ_b P_b` and the bias force are moved
/// to the parent body's frame. In that frame a member's inertia about the joint axis would be the
/// difference of much larger terms (a geared rotor's `m|p|²` is 1e5 times its axial inertia, and the
/// gear ratio squares the error: docs/accuracy.md, "(d) gears"); in its own frame nothing large cancels.
fn group_backward<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    gi: usize,
    tau: &[T],
) -> Result<(), DynamicsError> {
    let g = &model.groups[gi];
    let gw = &mut ws.constraints.groups[gi];
    let ni = g.independent.len();
    // ε_G = X_Gᵀ τ_G − Σ_b j_bᵀ (𝔷_b + P_b c_b),  D_G = Σ_b j_bᵀ P_b j_b,  and what the parent sees,
    // Σ_b P_b − Ū D⁻¹ Ūᵀ and Σ_b (𝔷_b + P_b c_b) + Ū D⁻¹ ε (the parts before D⁻¹ summed here).
    gw.eps.fill(T::zero());
    gw.d.fill(T::zero());
    gw.u_sum.fill(Force::zero());
    let mut p_plus = ArticulatedInertia::zero();
    let mut z = Force::zero();
    for (m, &b) in g.bodies.iter().enumerate() {
        let joint = &model.joints[b];
        let parent_member = joint.parent.filter(|&p| Some(p) != g.parent).map(|p| {
            g.bodies
                .binary_search(&p)
                .expect("members hang from the group's parent or another member")
        });
        let s = joint.subspace_column(0);
        let x = &ws.parent_placement[b];
        let mut c = ws.coriolis[b] + s * gw.kappa[m];
        if let Some(pm) = parent_member {
            c += x.inv_act_motion(&gw.c[pm]);
        }
        gw.c[m] = c;
        for k in 0..ni {
            let mut j = s * gw.x[(m, k)];
            if let Some(pm) = parent_member {
                j += x.inv_act_motion(&gw.jac[pm * ni + k]);
            }
            gw.jac[m * ni + k] = j;
        }
        let to_parent = match parent_member {
            None => *x,
            Some(pm) => gw.to_parent[pm].compose(x),
        };
        gw.to_parent[m] = to_parent;
        let p = &ws.inertia[b];
        // 𝔷_b + P_b c_b: its projection on j_b is the member's part of ε (P_b is symmetric).
        let zb = ws.force[b] + p.mul_motion(&c);
        for k in 0..ni {
            let j = gw.jac[m * ni + k];
            let mut eps = gw.x[(m, k)] * tau[joint.v_index] - j.dot(&zb);
            if joint.has_armature() {
                // The members' rotors: θ̈_G = X_G θ̈_R + κ_G, so Xᵀ armature κ is known force.
                eps -= gw.x[(m, k)] * joint.armature * gw.kappa[m];
            }
            gw.eps[k] += eps;
            let u = p.mul_motion(&j);
            for l in 0..=k {
                let mut d = gw.jac[m * ni + l].dot(&u);
                if joint.has_armature() {
                    // D_G += X_Gᵀ armature X_G.
                    d += gw.x[(m, l)] * joint.armature * gw.x[(m, k)];
                }
                gw.d[(l, k)] += d;
            }
            gw.u_sum[k] += to_parent.act_force(&u);
        }
        if g.parent.is_some() {
            p_plus += p.act(&to_parent);
            z += to_parent.act_force(&zb);
        }
    }
    for k in 0..ni {
        for l in 0..k {
            gw.d[(k, l)] = gw.d[(l, k)];
        }
    }
    let pivot = cholesky_in_place(&mut gw.d);
    if pivot.value().is_some_and(|p| !(p > 0.0 && p.is_finite())) {
        return Err(DynamicsError::SingularGroup {
            group: g.label.clone(),
        });
    }
    if let Some(p) = g.parent {
        // ν = D⁻¹ ε; W_k = Σ_l (D⁻¹)_kl Ū_l, one unit vector at a time through the factor.
        gw.ydd.copy_from_slice(&gw.eps);
        cholesky_solve_in_place(&gw.d, &mut gw.ydd);
        for k in 0..ni {
            z += gw.u_sum[k] * gw.ydd[k];
        }
        for k in 0..ni {
            gw.col_unit(k);
            cholesky_solve_in_place(&gw.d, &mut gw.unit);
            let mut w = Force::zero();
            for l in 0..ni {
                w += gw.u_sum[l] * gw.unit[l];
            }
            let uk = gw.u_sum[k];
            p_plus.sub_outer(&uk, &w);
        }
        ws.inertia[p] += p_plus;
        ws.force[p] += z;
    }
    Ok(())
}

/// Eqs. 23–24: `θ̈_R = D⁻¹(ε − Ūᵀ α_parent)`, the members' accelerations (each in its own frame,
/// `α_b = X α_parent + c_b + j_b θ̈_R`), and `θ̈_G = X_G θ̈_R + κ_G`.
fn group_forward<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, gi: usize) {
    let g = &model.groups[gi];
    let gw = &mut ws.constraints.groups[gi];
    let ni = g.independent.len();
    // Accelerations with gravity.
    ws.sweep = Sweep::None;
    let a_parent = match g.parent {
        Some(p) => ws.acceleration[p],
        None => Motion::new(Vector3::zeros(), -model.gravity),
    };
    for k in 0..ni {
        gw.ydd[k] = gw.eps[k] - gw.u_sum[k].dot_motion(&a_parent);
    }
    cholesky_solve_in_place(&gw.d, &mut gw.ydd);
    for (m, &b) in g.bodies.iter().enumerate() {
        let mut a = gw.to_parent[m].inv_act_motion(&a_parent) + gw.c[m];
        let mut qdd = gw.kappa[m];
        for k in 0..ni {
            a += gw.jac[m * ni + k] * gw.ydd[k];
            qdd += gw.x[(m, k)] * gw.ydd[k];
        }
        ws.acceleration[b] = a;
        ws.qdd[model.joints[b].v_index] = qdd;
    }
}

/// The embedding map of the whole model, `θ̇ = X θ̇_R` (nv × independent nv) at `q`: `Xᵀ τ` is the
/// generalized force on the independent coordinates. Allocates its result (see [`embedding_map_in`]).
pub fn embedding_map<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
) -> Result<DMatrix<T>, DynamicsError> {
    embedding_map_in(model, ws, q).cloned()
}

/// [`embedding_map`] into `ws.embedding`, without allocating (once the workspace has it: see
/// [`Workspace::reserve_embedding`]).
pub fn embedding_map_in<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    check_configuration(model, q)?;
    ws.reserve_embedding(model);
    position_kinematics(model, ws, q)?;
    let (kin, scratch) = ws.split_constraints();
    for (g, gw) in scratch.groups.iter_mut().enumerate() {
        embed(model, kin, g, gw, false)?;
    }
    let (out, groups) = (&mut ws.embedding, &ws.constraints.groups);
    out.fill(T::zero());
    let mut col = 0;
    for j in (0..model.joints.len()).filter(|&j| model.is_independent(j)) {
        let joint = &model.joints[j];
        match model.group_of(j) {
            None => {
                for k in 0..joint.nv() {
                    out[(joint.v_index + k, col + k)] = T::one();
                }
            }
            Some(g) => {
                let group = &model.groups[g];
                let k = group
                    .independent
                    .iter()
                    .position(|&b| b == j)
                    .expect("independent member");
                for (m, &b) in group.bodies.iter().enumerate() {
                    out[(model.joints[b].v_index, col)] = groups[g].x[(m, k)];
                }
            }
        }
        col += joint.nv();
    }
    Ok(&ws.embedding)
}

/// The reduced mass matrix `Xᵀ M X` over the independent coordinates (docs/command-line.md `crba` for models with
/// loops); allocates its result (see [`reduced_mass_matrix_in`]).
pub fn reduced_mass_matrix<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
) -> Result<DMatrix<T>, DynamicsError> {
    reduced_mass_matrix_in(model, ws, q).cloned()
}

/// [`reduced_mass_matrix`] into `ws.reduced_mass_matrix` (also leaving `M` in `ws.mass_matrix` and `X`
/// in `ws.embedding`), without allocating once the workspace has its buffers.
pub fn reduced_mass_matrix_in<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
) -> Result<&'w DMatrix<T>, DynamicsError> {
    embedding_map_in(model, ws, q)?;
    crba(model, ws, q)?;
    // Plain loops rather than nalgebra's gemm (which allocates packing buffers for larger matrices),
    // skipping the zeros of X — most of its entries: identity columns for the joints outside groups.
    let (nv, ni) = ws.embedding.shape();
    let (x, m) = (&ws.embedding, &ws.mass_matrix);
    let mx = &mut ws.mass_times_x;
    mx.fill(T::zero());
    for c in 0..ni {
        for k in 0..nv {
            let xk = x[(k, c)];
            if xk != T::zero() {
                for r in 0..nv {
                    mx[(r, c)] += m[(r, k)] * xk;
                }
            }
        }
    }
    // Xᵀ (M X), one triangle computed and mirrored so that the result is exactly symmetric.
    let red = &mut ws.reduced_mass_matrix;
    for c in 0..ni {
        for r in 0..=c {
            let mut s = T::zero();
            for k in 0..nv {
                let xk = x[(k, r)];
                if xk != T::zero() {
                    s += xk * mx[(k, c)];
                }
            }
            red[(r, c)] = s;
            red[(c, r)] = s;
        }
    }
    Ok(&ws.reduced_mass_matrix)
}

/// The Lagrange-multiplier oracle: `[M Jᵀ; J 0] [qdd; −λ] = [τ − C − g; −J̇ v]` over the spanning tree,
/// with the kept (non-redundant) constraint rows. A separate, plain implementation: the test oracle and
/// the baseline the benchmarks compare against. Allocates.
pub fn kkt_forward_dynamics<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
) -> Result<Vec<T>, DynamicsError> {
    // In the order of the other algorithms (q, v, then tau), so that the same input gets the same error.
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    check_input("tau", tau, model.nv())?;
    let nv = model.nv();
    let zeros = vec![T::zero(); nv];
    let nle = rnea(model, ws, q, v, &zeros)?.to_vec();
    let m = crba(model, ws, q)?.clone();
    constraint_kinematics(model, ws, q, v)?;
    let raw = model.constraint_raw_rows();
    let mut jac = DMatrix::zeros(raw, nv);
    crate::constraints::jacobian(model, ws, &mut jac);
    let mut bias = vec![T::zero(); raw];
    crate::constraints::bias(model, ws, &mut bias);
    // Accelerations at qdd = 0, not at the qdd returned.
    ws.sweep = Sweep::Velocities;
    let rows: Vec<usize> = model
        .groups
        .iter()
        .flat_map(|g| g.rows.iter().copied())
        .collect();
    let n = nv + rows.len();
    let mut kkt = DMatrix::zeros(n, n);
    let mut rhs = vec![T::zero(); n];
    for r in 0..nv {
        for c in 0..nv {
            kkt[(r, c)] = m[(r, c)];
        }
        rhs[r] = tau[r] - nle[r];
    }
    for (k, &row) in rows.iter().enumerate() {
        for c in 0..nv {
            kkt[(nv + k, c)] = jac[(row, c)];
            kkt[(c, nv + k)] = jac[(row, c)];
        }
        rhs[nv + k] = -bias[row];
    }
    let mut perm = vec![0; n];
    lu_in_place(&mut kkt, &mut perm).map_err(|_| DynamicsError::SingularConstraint {
        group: ConstraintSet::KktSystem,
        condition: f64::INFINITY,
        threshold: crate::constraints::singularity_threshold::<T>(),
    })?;
    lu_solve_in_place(&kkt, &perm, &mut rhs);
    rhs.truncate(nv);
    Ok(rhs)
}
