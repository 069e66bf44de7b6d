//! The per-call maps of constraint embedding for each group: `θ̇_G = X_G θ̇_R` and the velocity-product
//! part of `θ̈_G = X_G θ̈_R + κ_G` (the paper's `Ẋ_G θ̇_R`, Eq. 39), from the partitioned constraint
//! Jacobian `Y = [Y1 Y2]` (Eqs. 35–38). Linear constraints (gears) give a constant `X_G` and `κ_G = 0`
//! (Eq. 42) through the same code.

use super::{ConstraintKind, Group};
use crate::algorithms::{DynamicsError, Workspace};
use crate::linalg::{condition_number_1, lu_in_place, solve_pivoted_in_place};
use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Motion, Transform};
use crate::Real;
use nalgebra::DMatrix;

/// cond₁(Y1) at or beyond which a call fails instead of returning an inaccurate answer.
pub const SINGULARITY_THRESHOLD: f64 = 1e10;

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
    /// `[Y1 | Y2 | bias]`, solved in place by [`solve_pivoted_in_place`].
    pub(crate) aug: DMatrix<T>,
    /// `[Y1 | −residual]` of a completion Newton step.
    pub(crate) newton: DMatrix<T>,
    /// The pivot ratio of the last [`embed`] (see [`solve_pivoted_in_place`]; 1 for a group without
    /// rows): near 0 at a singular configuration.
    pub pivot_ratio: T,
    /// `X_G`: members × independent.
    pub x: DMatrix<T>,
    /// `κ_G`: members.
    pub kappa: Vec<T>,
    /// Whether any constraint of the group is a loop (then `X_G` depends on the configuration).
    pub(crate) has_loop: bool,
    // Articulated-body quantities, all in the parent body's frame.
    pub(crate) to_parent: Vec<Transform<T>>,
    /// Per member, `J_b` (independent columns).
    pub(crate) jac: Vec<Motion<T>>,
    pub(crate) c: Vec<Motion<T>>,
    pub(crate) inertia: Vec<ArticulatedInertia<T>>,
    pub(crate) bias_force: Vec<Force<T>>,
    /// Per member × independent, `U_b = P_b J_b`.
    pub(crate) u: Vec<Force<T>>,
    /// Per independent, `Ū = Σ_b U_b`.
    pub(crate) u_sum: Vec<Force<T>>,
    pub(crate) d: DMatrix<T>,
    pub(crate) eps: Vec<T>,
    pub(crate) ydd: Vec<T>,
    pub(crate) unit: Vec<T>,
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
        let has_loop = g
            .constraints
            .iter()
            .any(|&c| model.constraints[c].is_loop());
        GroupWorkspace {
            rows,
            k: DMatrix::zeros(r, m),
            bias: vec![T::zero(); r],
            y1: DMatrix::zeros(r, r),
            y1_lu: DMatrix::zeros(r, r),
            perm: vec![0; r],
            scratch: DMatrix::zeros(r, r),
            col: vec![T::zero(); r],
            aug: DMatrix::zeros(r, r + ni + 1),
            newton: DMatrix::zeros(r, r + 1),
            pivot_ratio: T::one(),
            x: DMatrix::zeros(m, ni),
            kappa: vec![T::zero(); m],
            has_loop,
            to_parent: vec![Transform::identity(); m],
            jac: vec![Motion::zero(); m * ni],
            c: vec![Motion::zero(); m],
            inertia: vec![ArticulatedInertia::zero(); m],
            bias_force: vec![Force::zero(); m],
            u: vec![Force::zero(); m * ni],
            u_sum: vec![Force::zero(); ni],
            d: DMatrix::zeros(ni, ni),
            eps: vec![T::zero(); ni],
            ydd: vec![T::zero(); ni],
            unit: vec![T::zero(); ni],
        }
    }
}

fn member(g: &Group, body: usize) -> Option<usize> {
    g.bodies.binary_search(&body).ok()
}

/// Fills `K` (kept rows × members) and, with `with_bias`, the kept rows of `J̇ v`, from the kinematics
/// in `ws` (world placements; velocities and velocity-product accelerations for the bias).
pub(crate) fn group_rows<T: Real>(
    model: &Model<T>,
    ws: &Workspace<T>,
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
                l.for_each_column(model, ws, |v_index, column| {
                    // Loop columns are the member joints' (1-DoF) velocities.
                    if let Some(col) = model_member_of_v(model, g, v_index) {
                        k[(slot, col)] = column[local];
                    }
                });
                if with_bias {
                    l.bias(ws, &mut buf);
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
    ws: &Workspace<T>,
    gi: usize,
    gw: &mut GroupWorkspace<T>,
    with_bias: bool,
) -> Result<(), DynamicsError> {
    let g = &model.groups[gi];
    group_rows(model, ws, g, gw, with_bias);
    let r = g.rows.len();
    // Y1 = K[:, dependent], factor it; X[dep, :] = −Y1⁻¹ Y2, X[indep, :] = I; κ[dep] = −Y1⁻¹ J̇v.
    fill_y1(g, gw);
    gw.x.fill(T::zero());
    for (k, &b) in g.independent.iter().enumerate() {
        gw.x[(member(g, b).expect("member"), k)] = T::one();
    }
    gw.kappa.fill(T::zero());
    gw.pivot_ratio = T::one();
    if r == 0 {
        return Ok(());
    }
    let singular = |condition: f64| DynamicsError::SingularConstraint {
        group: g
            .constraints
            .iter()
            .map(|&c| model.constraints[c].name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        condition,
    };
    if gw.has_loop {
        // Loops: Y1 depends on the configuration, so its conditioning is checked on every call (a NaN
        // in Y1 fails the factorization and reads as infinite).
        let cond = y1_condition_of(gw);
        if cond >= SINGULARITY_THRESHOLD {
            return Err(singular(cond));
        }
    }
    // [Y1 | Y2 | bias] → [· | Y1⁻¹ Y2 | Y1⁻¹ bias], pivoting by selects so that generated code pivots at
    // run time as this code does.
    let ni = g.independent.len();
    for row in 0..r {
        for col in 0..r {
            gw.aug[(row, col)] = gw.y1[(row, col)];
        }
        for (k, &b) in g.independent.iter().enumerate() {
            gw.aug[(row, r + k)] = gw.k[(row, member(g, b).expect("member"))];
        }
        gw.aug[(row, r + ni)] = if with_bias { gw.bias[row] } else { T::zero() };
    }
    gw.pivot_ratio = solve_pivoted_in_place(&mut gw.aug, r);
    // Couplings (constant Y1, checked at load): an exactly zero pivot is the only failure left, and the
    // elimination reports it (a traced ratio has no value and passes).
    if !gw.pivot_ratio.is_positive_finite() {
        return Err(singular(f64::INFINITY));
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

/// The smallest pivot ratio over the groups after the last call that embedded them (embedded `aba`,
/// `embedding_map`, velocity completion): a cheap singularity measure, near 0 at a toggle, 1 for a
/// model without groups. `cond₁(Y1) ≥ 1 / (rows · ratio)` for every group, so a ratio below
/// `1 / (rows · SINGULARITY_THRESHOLD)` means a configuration the interpreted solver refuses.
/// Generated code returns it from `aba` and `embedding` of models with constraints.
pub fn constraint_pivot_ratio<T: Real>(ws: &Workspace<T>) -> T {
    ws.groups.iter().fold(T::one(), |m, gw| {
        m.select_gt(gw.pivot_ratio, gw.pivot_ratio, m)
    })
}
