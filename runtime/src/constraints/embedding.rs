//! The per-call maps of constraint embedding for each group: `θ̇_G = X_G θ̇_R` and the velocity-product
//! part of `θ̈_G = X_G θ̈_R + κ_G` (the paper's `Ẋ_G θ̇_R`, Eq. 39), from the partitioned constraint
//! Jacobian `Y = [Y1 Y2]` (Eqs. 35–38). Linear constraints (gears) give a constant `X_G` and `κ_G = 0`
//! (Eq. 42) through the same code.

use super::{ConstraintKind, ConstraintSet, Group};
use crate::algorithms::{DynamicsError, Kinematics, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::linalg::{condition_number_1, lu_in_place, solve_pivoted_in_place};
use crate::model::Model;
use crate::spatial::{Force, Motion, Transform};
use crate::Real;
use nalgebra::DMatrix;

/// cond₁(Y1) at or beyond which a call in scalar `T` fails instead of returning an inaccurate answer:
/// `min(1e10, 10⁻³ / ε)` with ε the scalar's unit roundoff — 1e10 in `f64` (and wider types), about 8.4e3 in
/// `f32`. Below it the dependent accelerations keep about three correct digits or more (the solve loses up
/// to cond · ε of relative accuracy); at or above it the dependent joints are not determined by the
/// independent ones to any useful accuracy (docs/conventions.md, "Singular loops"). One rule for every engine.
pub fn singularity_threshold<T: Real>() -> f64 {
    (1e-3 / T::epsilon().to_f64()).min(1e10)
}

/// The condition number reported for a configuration where it is not a finite number (a NaN from an
/// exactly singular or non-finite `Y1`): large enough to exceed every threshold, finite so that generated
/// code can carry it as a literal in any scalar type.
const SINGULAR_CONDITION: f64 = 1e30;

/// Scratch memory of one group, sized at workspace creation.
#[derive(Clone, Debug)]
pub struct GroupWorkspace<T: Real> {
    /// Kept rows as (constraint, row within the constraint).
    pub(crate) rows: Vec<(usize, usize)>,
    /// Member index of each v index of the group's joints is found by binary search in `group.bodies`.
    /// `K`: kept rows × members.
    pub(crate) k: DMatrix<T>,
    pub(crate) bias: Vec<T>,
    pub(crate) y1: DMatrix<T>,
    pub(crate) y1_lu: DMatrix<T>,
    pub(crate) perm: Vec<usize>,
    pub(crate) scratch: DMatrix<T>,
    pub(crate) col: Vec<T>,
    /// `[Y1 | Y2 | bias | I]`, solved in place by [`solve_pivoted_in_place`] (the last block becomes
    /// `Y1⁻¹`, whose norm gives the condition number).
    pub(crate) aug: DMatrix<T>,
    /// `[Y1 | −residual]` of a completion Newton step.
    pub(crate) newton: DMatrix<T>,
    /// cond₁(Y1) at the last [`embed`] (1 for a group without rows; [`SINGULAR_CONDITION`] where it is
    /// not a number): the group's singularity measure.
    pub condition: T,
    /// `X_G`: members × independent.
    pub x: DMatrix<T>,
    /// `κ_G`: members.
    pub kappa: Vec<T>,
    /// Per dependent coordinate (in `Group::dependent` order): whether a loop of the group moves it
    /// (completion limits the Newton steps of those, not of coordinates only gears and mimics drive).
    pub(crate) loop_dependent: Vec<bool>,
    // Articulated-body quantities: each member's in its own frame, their sums in the parent body's.
    /// Per member, the pose of its frame in the parent body's frame.
    pub(crate) to_parent: Vec<Transform<T>>,
    /// Per member × independent, `J_b` in the member's frame.
    pub(crate) jac: Vec<Motion<T>>,
    /// Per member, its acceleration at `θ̈_R = 0` and rest parent (velocity products and `κ`), in its
    /// frame.
    pub(crate) c: Vec<Motion<T>>,
    /// Per independent, `Ū = Σ_b P_b J_b` in the parent body's frame.
    pub(crate) u_sum: Vec<Force<T>>,
    pub(crate) d: DMatrix<T>,
    pub(crate) eps: Vec<T>,
    pub(crate) ydd: Vec<T>,
    pub(crate) unit: Vec<T>,
}

/// An empty workspace (what a group's slot holds while completion borrows it).
impl<T: Real> Default for GroupWorkspace<T> {
    fn default() -> Self {
        let m = || DMatrix::zeros(0, 0);
        GroupWorkspace {
            rows: Vec::new(),
            k: m(),
            bias: Vec::new(),
            y1: m(),
            y1_lu: m(),
            perm: Vec::new(),
            scratch: m(),
            col: Vec::new(),
            aug: m(),
            newton: m(),
            condition: T::one(),
            x: m(),
            kappa: Vec::new(),
            loop_dependent: Vec::new(),
            to_parent: Vec::new(),
            jac: Vec::new(),
            c: Vec::new(),
            u_sum: Vec::new(),
            d: m(),
            eps: Vec::new(),
            ydd: Vec::new(),
            unit: Vec::new(),
        }
    }
}

impl<T: Real> GroupWorkspace<T> {
    /// `unit = e_k` (for applying `D⁻¹` column by column).
    pub(crate) fn col_unit(&mut self, k: usize) {
        self.unit.fill(T::zero());
        self.unit[k] = T::one();
    }
}

impl<T: Real> GroupWorkspace<T> {
    pub fn new(model: &Model<T>, g: &Group) -> Self {
        let offsets = model.constraint_row_offsets();
        let mut rows = Vec::with_capacity(g.rows.len());
        for &r in &g.rows {
            let c = offsets
                .iter()
                .rposition(|&o| o <= r)
                .expect("row belongs to a constraint");
            rows.push((c, r - offsets[c]));
        }
        let (m, r, ni) = (g.bodies.len(), g.rows.len(), g.independent.len());
        // Bodies on a loop's two paths up to their common ancestor.
        let mut in_loop = vec![false; model.nbodies()];
        for &c in &g.constraints {
            if let super::ConstraintKind::Loop(l) = &model.constraints[c].kind {
                for b in super::grouping::loop_path(model, l) {
                    in_loop[b] = true;
                }
            }
        }
        let loop_dependent = g.dependent.iter().map(|&b| in_loop[b]).collect();
        GroupWorkspace {
            rows,
            k: DMatrix::zeros(r, m),
            bias: vec![T::zero(); r],
            y1: DMatrix::zeros(r, r),
            y1_lu: DMatrix::zeros(r, r),
            perm: vec![0; r],
            scratch: DMatrix::zeros(r, r),
            col: vec![T::zero(); r],
            aug: DMatrix::zeros(r, r + ni + 1 + r),
            newton: DMatrix::zeros(r, r + 1),
            condition: T::one(),
            x: DMatrix::zeros(m, ni),
            kappa: vec![T::zero(); m],
            loop_dependent,
            to_parent: vec![Transform::identity(); m],
            jac: vec![Motion::zero(); m * ni],
            c: vec![Motion::zero(); m],
            u_sum: vec![Force::zero(); ni],
            d: DMatrix::zeros(ni, ni),
            eps: vec![T::zero(); ni],
            ydd: vec![T::zero(); ni],
            unit: vec![T::zero(); ni],
        }
    }
}

pub(crate) fn member(g: &Group, body: usize) -> Option<usize> {
    g.bodies.binary_search(&body).ok()
}

/// Fills `K` (kept rows × members) and, with `with_bias`, the kept rows of `J̇ v`, from the kinematics
/// in `kin` (world placements; velocities and velocity-product accelerations for the bias).
pub(crate) fn group_rows<T: Real>(
    model: &Model<T>,
    kin: Kinematics<'_, T>,
    g: &Group,
    gw: &mut GroupWorkspace<T>,
    with_bias: bool,
) {
    gw.k.fill(T::zero());
    let mut buf = [T::zero(); 6];
    for (slot, &(c, local)) in gw.rows.iter().enumerate() {
        match &model.constraints[c].kind {
            ConstraintKind::Linear { terms, .. } => {
                for &(j, coef) in terms {
                    if let Some(col) = member(g, j) {
                        gw.k[(slot, col)] += coef;
                    }
                }
                if with_bias {
                    gw.bias[slot] = T::zero();
                }
            }
            ConstraintKind::Loop(l) => {
                let k = &mut gw.k;
                l.for_each_column(model, kin, |v_index, column| {
                    // Loop columns are the member joints' (1-DoF) velocities.
                    if let Some(col) = model_member_of_v(model, g, v_index) {
                        k[(slot, col)] = column[local];
                    }
                });
                if with_bias {
                    l.bias(kin, &mut buf);
                    gw.bias[slot] = buf[local];
                }
            }
        }
    }
}

fn model_member_of_v<T: Real>(model: &Model<T>, g: &Group, v_index: usize) -> Option<usize> {
    g.bodies
        .iter()
        .position(|&b| model.joints[b].v_index == v_index)
}

/// `Y1 = K[:, dependent]` into `gw.y1`, from the `K` of [`group_rows`].
pub(crate) fn fill_y1<T: Real>(g: &Group, gw: &mut GroupWorkspace<T>) {
    for (col, &b) in g.dependent.iter().enumerate() {
        let m = member(g, b).expect("dependent joints are members");
        for row in 0..g.rows.len() {
            gw.y1[(row, col)] = gw.k[(row, m)];
        }
    }
}

/// cond₁ of `gw.y1`, factoring it into `gw.y1_lu` (∞ when singular).
pub(crate) fn y1_condition_of<T: Real>(gw: &mut GroupWorkspace<T>) -> f64 {
    gw.y1_lu.copy_from(&gw.y1);
    if lu_in_place(&mut gw.y1_lu, &mut gw.perm).is_err() {
        return f64::INFINITY;
    }
    condition_number_1(&gw.y1, &gw.y1_lu, &gw.perm, &mut gw.scratch).to_f64()
}

/// `X_G` and `κ_G` of group `gi` at the current kinematics. Fails past the singularity threshold.
pub(crate) fn embed<T: Real>(
    model: &Model<T>,
    kin: Kinematics<'_, T>,
    gi: usize,
    gw: &mut GroupWorkspace<T>,
    with_bias: bool,
) -> Result<(), DynamicsError> {
    let g = &model.groups[gi];
    group_rows(model, kin, g, gw, with_bias);
    let r = g.rows.len();
    // Y1 = K[:, dependent], factor it; X[dep, :] = −Y1⁻¹ Y2, X[indep, :] = I; κ[dep] = −Y1⁻¹ J̇v.
    fill_y1(g, gw);
    gw.x.fill(T::zero());
    for (k, &b) in g.independent.iter().enumerate() {
        gw.x[(member(g, b).expect("member"), k)] = T::one();
    }
    gw.kappa.fill(T::zero());
    gw.condition = T::one();
    if r == 0 {
        return Ok(());
    }
    // [Y1 | Y2 | bias | I] → [· | Y1⁻¹ Y2 | Y1⁻¹ bias | Y1⁻¹], pivoting by selects so that generated code
    // pivots at run time as this code does, and computes the same condition number.
    let ni = g.independent.len();
    for row in 0..r {
        for col in 0..r {
            gw.aug[(row, col)] = gw.y1[(row, col)];
            gw.aug[(row, r + ni + 1 + col)] = if row == col { T::one() } else { T::zero() };
        }
        for (k, &b) in g.independent.iter().enumerate() {
            gw.aug[(row, r + k)] = gw.k[(row, member(g, b).expect("member"))];
        }
        gw.aug[(row, r + ni)] = if with_bias { gw.bias[row] } else { T::zero() };
    }
    solve_pivoted_in_place(&mut gw.aug, r);
    // cond₁(Y1) = ‖Y1‖₁ ‖Y1⁻¹‖₁: one singularity measure for every engine and scalar (traced, it is the
    // generated code's own; for couplings, whose Y1 is constant, it folds to a constant).
    let inverse_norm = max_column_sum(r, |i, j| gw.aug[(i, r + ni + 1 + j)]);
    let cond = max_column_sum(r, |i, j| gw.y1[(i, j)]) * inverse_norm;
    // NaN (an exactly zero pivot, a non-finite Y1) and ∞ read as singular.
    let huge = T::from_f64(SINGULAR_CONDITION);
    let cond = huge.select_gt(cond, cond, huge);
    gw.condition = cond;
    if let Some(c) = cond.value() {
        if c.is_nan() || c >= singularity_threshold::<T>() {
            return Err(DynamicsError::SingularConstraint {
                group: ConstraintSet::Group(g.label.clone()),
                condition: c,
                threshold: singularity_threshold::<T>(),
            });
        }
    }
    for (d, &bd) in g.dependent.iter().enumerate() {
        let m = member(g, bd).expect("member");
        for k in 0..ni {
            gw.x[(m, k)] = -gw.aug[(d, r + k)];
        }
        if with_bias {
            gw.kappa[m] = -gw.aug[(d, r + ni)];
        }
    }
    Ok(())
}

/// The largest cond₁(Y1) over the groups after the last call that embedded them (embedded `aba`,
/// `embedding_map`, the reduced mass matrix, velocity completion): 1 for a model without groups, and at or
/// above [`singularity_threshold`] where the interpreted solver refuses. Generated code returns it from
/// `aba`, `embedding` and `crba_independent` of models with constraints, for its caller to compare.
pub fn constraint_condition<T: Real>(ws: &Workspace<T>) -> T {
    ws.constraints
        .groups
        .iter()
        .fold(T::one(), |m, gw| gw.condition.select_gt(m, gw.condition, m))
}

/// `max_j Σ_i |a(i, j)|` over an `n × n` matrix (branch-free, for tracing).
fn max_column_sum<T: Real>(n: usize, a: impl Fn(usize, usize) -> T) -> T {
    let mut norm = T::zero();
    for j in 0..n {
        let mut s = T::zero();
        for i in 0..n {
            s += a(i, j).abs();
        }
        // A column sum that is not a number (the inverse of an exactly singular Y1) makes the norm NaN,
        // which reads as singular; skipping it could report a finite condition number for a singular Y1
        // and a silent NaN in X (found by fuzzing).
        norm = super::max_keeping_nan(norm, s);
    }
    norm
}
