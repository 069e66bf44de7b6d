//! Aggregate links: the smallest groups of bodies such that, with each group contracted to one node, the
//! system is a tree again; and, once per model, which equations are redundant and which coordinates are
//! independent.

use super::embedding::{fill_y1, group_rows, y1_condition_of, GroupWorkspace};
use super::{jacobian, residuals, residuals_scaled, ConstraintKind};
use crate::algorithms::{forward_kinematics, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::linalg::{independent_columns, independent_rows, solve_least_squares};
use crate::model::{JointType, Model, ModelError};
use crate::Real;
use nalgebra::DMatrix;

/// A group's position in `model.groups`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GroupId(pub usize);

/// How errors name a group: its id and the names of its constraints (displayed as `loop1, gear`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroupLabel {
    /// The group's index in `Model::groups`.
    pub id: GroupId,
    /// The names of the group's constraints, in the order of `Group::constraints`.
    pub constraints: Vec<String>,
}

impl core::fmt::Display for GroupLabel {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (k, name) in self.constraints.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            f.write_str(name)?;
        }
        Ok(())
    }
}

/// A label equals the text it displays as (`label == "loop1"`).
impl PartialEq<str> for GroupLabel {
    fn eq(&self, text: &str) -> bool {
        let mut rest = text;
        for (k, name) in self.constraints.iter().enumerate() {
            if k > 0 {
                match rest.strip_prefix(", ") {
                    Some(r) => rest = r,
                    None => return false,
                }
            }
            match rest.strip_prefix(name.as_str()) {
                Some(r) => rest = r,
                None => return false,
            }
        }
        rest.is_empty()
    }
}

/// What a constraint error is about: one group, or the whole system of a KKT solve.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConstraintSet {
    /// One group of constraints.
    Group(GroupLabel),
    /// Every constraint at once, in the KKT system of `kkt_forward_dynamics`.
    KktSystem,
}

impl core::fmt::Display for ConstraintSet {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ConstraintSet::Group(label) => label.fmt(f),
            ConstraintSet::KktSystem => f.write_str("KKT system"),
        }
    }
}

/// A set equals the text it displays as (`group == "loop1"`).
impl PartialEq<str> for ConstraintSet {
    fn eq(&self, text: &str) -> bool {
        match self {
            ConstraintSet::Group(label) => label == text,
            ConstraintSet::KktSystem => text == "KKT system",
        }
    }
}

/// An aggregate link: bodies tied together by loops, couplings or mimic joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Its id and its constraints' names, for messages.
    pub label: GroupLabel,
    /// Member bodies (= their joints), ascending (parents before children).
    pub bodies: Vec<usize>,
    /// The one body every member hangs from (`None`: the world).
    pub parent: Option<usize>,
    /// Indices into `model.constraints`.
    pub constraints: Vec<usize>,
    /// Kept (independent) equations, as global raw-row indices; the others are redundant.
    pub rows: Vec<usize>,
    /// Member joints whose coordinates are independent (`θ_R`), ascending.
    pub independent: Vec<usize>,
    /// Member joints whose coordinates are solved from the others, ascending.
    pub dependent: Vec<usize>,
    /// Whether embedyn chose `dependent` (the file declared no `independent="false"` in this group).
    pub chosen: bool,
    /// cond₁(Y1) at the configuration used to make these choices.
    pub condition_at_load: f64,
}

/// Relative tolerance of the rank decisions (on the pivots of a column-pivoted QR).
const RANK_TOLERANCE: f64 = 1e-9;

fn lca<T: Real>(model: &Model<T>, a: Option<usize>, b: Option<usize>) -> Option<usize> {
    crate::tree::common_ancestor(|body| model.joints[body].parent, a, b)
}

/// Bodies from `b` up to (excluding) `top`.
fn path_to<T: Real>(model: &Model<T>, b: Option<usize>, top: Option<usize>, out: &mut Vec<usize>) {
    crate::tree::path_to_ancestor(|body| model.joints[body].parent, b, top, out);
}

/// The bodies whose joints a loop's equations involve: the paths from its two frames' bodies up to their
/// common ancestor.
pub(crate) fn loop_path<T: Real>(model: &Model<T>, l: &super::LoopClosure<T>) -> Vec<usize> {
    let top = lca(model, l.predecessor, l.successor);
    let mut v = Vec::new();
    path_to(model, l.predecessor, top, &mut v);
    path_to(model, l.successor, top, &mut v);
    v
}

/// Closes a set of bodies under "all members hang from one common body": adds every body between each
/// member and the members' common ancestor. Returns that ancestor.
fn close<T: Real>(model: &Model<T>, bodies: &mut Vec<usize>) -> Option<usize> {
    let mut top = model.joints[bodies[0]].parent;
    for &b in bodies.iter() {
        top = lca(model, top, model.joints[b].parent);
    }
    let mut all = Vec::new();
    for &b in bodies.iter() {
        path_to(model, Some(b), top, &mut all);
    }
    all.sort_unstable();
    all.dedup();
    *bodies = all;
    top
}

/// Builds the groups of a model whose constraints are set. `declared_dependent[j]`: joint `j` was declared
/// dependent (`independent="false"`, or a mimic joint).
pub(crate) fn build_groups<T: Real>(
    model: &Model<T>,
    declared_dependent: &[bool],
) -> Result<Vec<Group>, ModelError> {
    let n = model.nbodies();
    // Bodies of each constraint, closed under the common-ancestor rule.
    let mut sets: Vec<(Vec<usize>, Vec<usize>)> = Vec::new(); // (bodies, constraints)
    for (ci, c) in model.constraints.iter().enumerate() {
        let mut bodies = match &c.kind {
            ConstraintKind::Linear { terms, .. } => terms.iter().map(|&(j, _)| j).collect(),
            ConstraintKind::Loop(l) => loop_path(model, l),
        };
        if bodies.is_empty() {
            return Err(ModelError::EmptyConstraint {
                constraint: c.name.clone(),
            });
        }
        close(model, &mut bodies);
        sets.push((bodies, vec![ci]));
    }
    // Merge sets sharing a body until none do (overlapping or touching loops become one group).
    let mut merged = true;
    while merged {
        merged = false;
        'outer: for a in 0..sets.len() {
            for b in a + 1..sets.len() {
                if sets[a].0.iter().any(|x| sets[b].0.contains(x)) {
                    let (bb, cb) = sets.remove(b);
                    sets[a].0.extend(bb);
                    sets[a].1.extend(cb);
                    close(model, &mut sets[a].0);
                    merged = true;
                    break 'outer;
                }
            }
        }
    }
    sets.sort_by_key(|s| s.0[0]);

    let row_offset = model.constraint_row_offsets();
    let mut ws = Workspace::new(model);
    let mut groups = Vec::with_capacity(sets.len());
    for (bodies, mut constraints) in sets {
        constraints.sort_unstable();
        let parent = {
            let mut b = bodies.clone();
            close(model, &mut b)
        };
        for &b in &bodies {
            if model.joints[b].joint_type == JointType::Floating {
                return Err(ModelError::FloatingInGroup {
                    joint: model.joints[b].name.clone(),
                });
            }
        }
        let raw_rows: Vec<usize> = constraints
            .iter()
            .flat_map(|&c| row_offset[c]..row_offset[c] + model.constraints[c].raw_rows())
            .collect();
        let label = GroupLabel {
            id: GroupId(groups.len()),
            constraints: constraints
                .iter()
                .map(|&c| model.constraints[c].name.clone())
                .collect(),
        };
        // An assembled, generic configuration of this group: from the neutral configuration, assemble,
        // then move the group's coordinates away (off any symmetric, possibly singular pose) and assemble
        // again. If assembly fails, the rank is still taken where we are: never reject for that.
        let mut q = model.neutral_configuration();
        let cols: Vec<usize> = bodies.iter().map(|&b| model.joints[b].v_index).collect();
        let mut assembled = assemble(model, &mut ws, &mut q, &bodies, &raw_rows, 60);
        for (k, &b) in bodies.iter().enumerate() {
            q[model.joints[b].q_index] +=
                T::from_f64(0.3 * (1.0 + k as f64 * 0.618_033_988_749).sin());
        }
        assembled |= assemble(model, &mut ws, &mut q, &bodies, &raw_rows, 60);
        // A loop that assembles nowhere is a modelling error (its frames can never meet); one that merely
        // fails to assemble at the zero configuration is not. Try spread-out starts before deciding.
        let mut restart = 0;
        while !assembled && restart < 8 {
            restart += 1;
            let mut trial = model.neutral_configuration();
            for (k, &b) in bodies.iter().enumerate() {
                let x = num_traits::Float::fract((restart * 7 + k * 13) as f64 * 0.754_877_666);
                trial[model.joints[b].q_index] =
                    T::from_f64(core::f64::consts::PI * (2.0 * x - 1.0));
            }
            if assemble(model, &mut ws, &mut trial, &bodies, &raw_rows, 200) {
                q = trial;
                assembled = true;
            }
        }
        if !assembled && constraints.iter().any(|&c| model.constraints[c].is_loop()) {
            let zeros = vec![T::zero(); model.nv()];
            forward_kinematics(model, &mut ws, &q, &zeros).expect("sizes match");
            let mut r = vec![T::zero(); model.constraint_raw_rows()];
            residuals(model, &ws, &q, &mut r);
            let gap = raw_rows
                .iter()
                .fold(0.0f64, |m, &i| m.max(r[i].to_f64().abs()));
            return Err(ModelError::LoopNeverCloses { group: label, gap });
        }
        let k_mat = group_jacobian(model, &mut ws, &q, &raw_rows, &cols);
        let kept_local = independent_rows(&k_mat, RANK_TOLERANCE);
        let rank = kept_local.len();
        let rows: Vec<usize> = kept_local.iter().map(|&r| raw_rows[r]).collect();
        let declared: Vec<usize> = bodies
            .iter()
            .copied()
            .filter(|&b| declared_dependent[b])
            .collect();
        let (dependent, chosen) = if declared.is_empty() {
            let kept = DMatrix::from_fn(rank, cols.len(), |r, c| k_mat[(kept_local[r], c)]);
            let dep_local = independent_columns(&kept, RANK_TOLERANCE);
            (
                dep_local.iter().map(|&c| bodies[c]).collect::<Vec<_>>(),
                true,
            )
        } else {
            if declared.len() != rank {
                return Err(ModelError::DependentMismatch {
                    group: label,
                    declared: declared.len(),
                    needed: rank,
                });
            }
            (declared, false)
        };
        let independent: Vec<usize> = bodies
            .iter()
            .copied()
            .filter(|b| !dependent.contains(b))
            .collect();
        let mut group = Group {
            label,
            bodies,
            parent,
            constraints,
            rows,
            independent,
            dependent,
            chosen,
            condition_at_load: 0.0,
        };
        group.condition_at_load = y1_condition(model, &mut ws, &q, &group);
        if (group.condition_at_load.is_nan()
            || group.condition_at_load >= super::singularity_threshold::<T>())
            && rank > 0
        {
            return Err(ModelError::SingularDependentChoice {
                group: group.label.clone(),
                condition: group.condition_at_load,
            });
        }
        groups.push(group);
    }
    let _ = n;
    Ok(groups)
}

/// The Jacobian rows `rows` restricted to the columns `cols`, at `q`.
fn group_jacobian<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    rows: &[usize],
    cols: &[usize],
) -> DMatrix<T> {
    let zeros = vec![T::zero(); model.nv()];
    forward_kinematics(model, ws, q, &zeros).expect("sizes match");
    let mut full = DMatrix::zeros(model.constraint_raw_rows(), model.nv());
    jacobian(model, ws, &mut full);
    DMatrix::from_fn(rows.len(), cols.len(), |r, c| full[(rows[r], cols[c])])
}

/// Damped Newton (minimum-norm steps) on the coordinates of `bodies`' joints until the `rows` residuals
/// vanish. Returns whether it converged (|r|∞ ≤ 1e-12).
pub(crate) fn assemble<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
    bodies: &[usize],
    rows: &[usize],
    iterations: usize,
) -> bool {
    let cols: Vec<usize> = bodies.iter().map(|&b| model.joints[b].v_index).collect();
    let mut r = vec![T::zero(); model.constraint_raw_rows()];
    let mut scale = r.clone();
    let zeros = vec![T::zero(); model.nv()];
    // Relative to the magnitudes of each equation (docs/conventions.md), and reachable in the scalar at hand.
    let tolerance = (64.0 * T::epsilon().to_f64()).max(1e-12);
    for _ in 0..iterations {
        // `q` stays finite: a step that would leave it is refused below.
        forward_kinematics(model, ws, q, &zeros).expect("sizes match");
        residuals_scaled(model, ws.kinematics(), q, &mut r, &mut scale);
        let rr: Vec<T> = rows.iter().map(|&i| -r[i]).collect();
        // A NaN residual (a configuration outside the representable range) never converges.
        let converged = rows
            .iter()
            .all(|&i| super::relative_residual(r[i], scale[i]).to_f64() <= tolerance);
        if converged {
            return true;
        }
        let k = group_jacobian(model, ws, q, rows, &cols);
        let step = solve_least_squares(&k, &rr);
        // Limit the step so that Newton stays near the branch it started on.
        let big = step.iter().fold(T::zero(), |m, x| m.max(x.abs()));
        let scale = if big.to_f64() > 0.5 {
            T::from_f64(0.5) / big
        } else {
            T::one()
        };
        let next: Vec<T> = bodies
            .iter()
            .enumerate()
            .map(|(k, &b)| q[model.joints[b].q_index] + step[k] * scale)
            .collect();
        // A step that overflows the coordinates (a constraint with coefficients near the largest f64,
        // a <mimic multiplier="1e308">, crashed the loader in the kinematics after it): that start does
        // not assemble, and `q` stays as it was, finite, for the caller.
        if next.iter().any(|x| !x.to_f64().is_finite()) {
            return false;
        }
        for (&b, x) in bodies.iter().zip(next) {
            q[model.joints[b].q_index] = x;
        }
    }
    false
}

/// cond₁ of `Y1` (kept rows × dependent columns) at `q`.
fn y1_condition<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, q: &[T], g: &Group) -> f64 {
    if g.dependent.is_empty() {
        return 1.0;
    }
    // The same rows, Y1 and conditioning as every call will use.
    let zeros = vec![T::zero(); model.nv()];
    forward_kinematics(model, ws, q, &zeros).expect("sizes match");
    let mut gw = GroupWorkspace::new(model, g);
    group_rows(model, ws.kinematics(), g, &mut gw, false);
    fill_y1(g, &mut gw);
    y1_condition_of(&mut gw)
}

#[cfg(test)]
mod label_tests {
    use super::*;

    #[test]
    fn a_group_label_shows_its_constraint_names_in_order_and_keeps_them_apart() {
        let label = GroupLabel {
            id: GroupId(2),
            constraints: vec!["loop, with comma".to_string(), "gear".to_string()],
        };
        assert_eq!(label.to_string(), "loop, with comma, gear");
        // The names stay separate: a name containing ", " is not split.
        assert_eq!(label.constraints[0], "loop, with comma");
        assert!(label == *"loop, with comma, gear");
        assert!(label != *"loop, with comma");
        assert!(label != *"loop, with comma, gear, belt");
        assert_eq!(ConstraintSet::KktSystem.to_string(), "KKT system");
        assert!(ConstraintSet::Group(label) == *"loop, with comma, gear");
    }
}
