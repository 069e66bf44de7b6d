//! Closed loops and couplings: their equations, their grouping into aggregate links, and the maps of
//! constraint embedding (the paper's sections 4–6).
//!
//! A [`Constraint`] is either *linear* in the joint coordinates (gears, belts, mimic joints: the paper's
//! Eq. 42, constant `X_G`) or a *loop closure* between two body frames (Eqs. 35–41: `X_G` from the
//! partitioned constraint Jacobian `Y = [Y1 Y2]`). Constraints that share bodies form a [`Group`], the
//! paper's aggregate link.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
mod closure;
mod completion;
mod embedding;
mod grouping;

pub use closure::{LoopClosure, LoopType};
pub use completion::{
    complete_configuration, complete_configuration_with, complete_velocity, completion_step,
    constraint_violation, y1_condition, COMPLETION_MAX_STEPS,
};
pub use embedding::{constraint_condition, singularity_threshold};
pub(crate) use embedding::{embed, GroupWorkspace};
pub(crate) use grouping::build_groups;
pub use grouping::{ConstraintSet, Group, GroupId, GroupLabel};

use crate::Real;

/// One constraint among spanning-tree coordinates.
#[derive(Clone, Debug)]
pub struct Constraint<T: Real> {
    /// The URDF+ element's name (`<loop name>`, `<coupling name>`, or the mimic joint's name).
    pub name: String,
    /// What the constraint says.
    pub kind: ConstraintKind<T>,
}

/// The two forms a constraint takes.
#[derive(Clone, Debug)]
pub enum ConstraintKind<T: Real> {
    /// `Σ coefficient · q[joint] + offset = 0` over 1-DoF joints (index into `model.joints`).
    /// A linear relation of joint coordinates (couplings and mimic joints).
    Linear {
        /// `(joint index, coefficient)` pairs.
        terms: Vec<(usize, T)>,
        /// The constant term.
        offset: T,
    },
    /// A cut joint between two body frames.
    Loop(LoopClosure<T>),
}

impl<T: Real> Constraint<T> {
    /// Number of scalar equations before redundant ones are removed.
    pub fn raw_rows(&self) -> usize {
        match &self.kind {
            ConstraintKind::Linear { .. } => 1,
            ConstraintKind::Loop(l) => l.kind.rows(),
        }
    }

    /// Whether it is a loop closure (else a linear relation: a coupling or a mimic joint).
    pub fn is_loop(&self) -> bool {
        matches!(self.kind, ConstraintKind::Loop(_))
    }

    /// The same constraint in scalar `U` (through f64).
    pub fn cast<U: Real>(&self) -> Constraint<U> {
        let c = |x: T| U::from_f64(x.to_f64());
        Constraint {
            name: self.name.clone(),
            kind: match &self.kind {
                ConstraintKind::Linear { terms, offset } => ConstraintKind::Linear {
                    terms: terms.iter().map(|&(j, k)| (j, c(k))).collect(),
                    offset: c(*offset),
                },
                ConstraintKind::Loop(l) => ConstraintKind::Loop(l.cast()),
            },
        }
    }
}

use crate::algorithms::{Kinematics, Workspace};
use crate::model::Model;
use nalgebra::DMatrix;

/// Position residuals of every constraint (raw rows, in constraint order), from `ws.world_placement`
/// (run [`crate::forward_kinematics`] first) and `q` (for the linear ones).
///
/// A building block that checks nothing (the checked entry points are [`crate::constraint_kinematics`],
/// [`constraint_violation`] and the completion functions).
///
/// # Panics
/// If `q` is shorter than `model.nq()` or `out` than [`Model::constraint_raw_rows`].
pub fn residuals<T: Real>(model: &Model<T>, ws: &Workspace<T>, q: &[T], out: &mut [T]) {
    let kin = ws.kinematics();
    let mut row = 0;
    let mut scale = [T::zero(); 6];
    for c in &model.constraints {
        let n = c.raw_rows();
        residual_of(model, kin, q, c, &mut out[row..row + n], &mut scale[..n]);
        row += n;
    }
}

/// [`residuals`] and the magnitude each row was computed from (see [`LoopClosure::residual_scaled`]; for
/// a linear row the largest of its terms and its offset): a row is satisfied to tolerance `tol` when
/// `|r| ≤ tol · max(1, magnitude)` (docs/conventions.md). From the kinematics `kin`
/// ([`Workspace::kinematics`]) and `q`.
///
/// A building block that checks nothing (the checked entry points are [`crate::constraint_kinematics`],
/// [`constraint_violation`] and the completion functions).
///
/// # Panics
/// If `q` is shorter than `model.nq()` or `out` or `scale` than [`Model::constraint_raw_rows`].
pub fn residuals_scaled<T: Real>(
    model: &Model<T>,
    kin: Kinematics<'_, T>,
    q: &[T],
    out: &mut [T],
    scale: &mut [T],
) {
    let mut row = 0;
    for c in &model.constraints {
        let n = c.raw_rows();
        residual_of(
            model,
            kin,
            q,
            c,
            &mut out[row..row + n],
            &mut scale[row..row + n],
        );
        row += n;
    }
}

fn residual_of<T: Real>(
    model: &Model<T>,
    kin: Kinematics<'_, T>,
    q: &[T],
    c: &Constraint<T>,
    out: &mut [T],
    scale: &mut [T],
) {
    match &c.kind {
        ConstraintKind::Linear { terms, offset } => {
            let mut sum = *offset;
            let mut magnitude = offset.abs();
            for &(j, k) in terms {
                let term = k * q[model.joints[j].q_index];
                sum += term;
                let a = term.abs();
                magnitude = a.select_gt(magnitude, a, magnitude);
            }
            out[0] = sum;
            scale[0] = magnitude;
        }
        ConstraintKind::Loop(l) => l.residual_scaled(kin, out, scale),
    }
}

/// The larger of `acc` and `x` (both non-negative or NaN), NaN if either is: a norm or a worst residual
/// that is not a number stays not a number through every later comparison, so it reads as singular or
/// unconverged (a plain `max` keeps whichever operand compares true and drops a NaN). Selects, not
/// branches, so that generated code keeps the rule.
#[inline(always)]
pub(crate) fn max_keeping_nan<T: Real>(acc: T, x: T) -> T {
    let larger = x.select_gt(acc, x, acc);
    x.select_gt(T::from_f64(-1.0), larger, x)
}

/// `|r| / max(1, magnitude)`: a residual relative to the numbers it came from (NaN stays NaN).
#[inline(always)]
pub(crate) fn relative_residual<T: Real>(r: T, magnitude: T) -> T {
    let one = T::one();
    r.abs() / magnitude.select_gt(one, magnitude, one)
}

/// The constraint Jacobian over all spanning velocities (raw rows × nv), from `ws.world_placement`.
///
/// A building block that checks nothing (the checked entry points are [`crate::constraint_kinematics`],
/// [`constraint_violation`] and the completion functions).
///
/// # Panics
/// If `out` has fewer than [`Model::constraint_raw_rows`] rows or `model.nv()` columns.
pub fn jacobian<T: Real>(model: &Model<T>, ws: &Workspace<T>, out: &mut DMatrix<T>) {
    let kin = ws.kinematics();
    let mut row = 0;
    for c in &model.constraints {
        match &c.kind {
            ConstraintKind::Linear { terms, .. } => {
                for col in 0..out.ncols() {
                    out[(row, col)] = T::zero();
                }
                for &(j, k) in terms {
                    out[(row, model.joints[j].v_index)] += k;
                }
            }
            ConstraintKind::Loop(l) => l.jacobian(model, kin, out, row),
        }
        row += c.raw_rows();
    }
}

/// `J̇ v` for every constraint (raw rows), from the kinematics and the velocity-product accelerations in
/// `ws` (see [`crate::constraint_kinematics`]).
///
/// A building block that checks nothing (the checked entry points are [`crate::constraint_kinematics`],
/// [`constraint_violation`] and the completion functions).
///
/// # Panics
/// If `out` is shorter than [`Model::constraint_raw_rows`].
pub fn bias<T: Real>(model: &Model<T>, ws: &Workspace<T>, out: &mut [T]) {
    let kin = ws.kinematics();
    let mut row = 0;
    for c in &model.constraints {
        let n = c.raw_rows();
        match &c.kind {
            ConstraintKind::Linear { .. } => out[row] = T::zero(),
            ConstraintKind::Loop(l) => l.bias(kin, &mut out[row..row + n]),
        }
        row += n;
    }
}
