//! Completing a state: the dependent coordinates from the independent ones, at position level (Newton's
//! method from the given guess, so it stays on that assembly branch) and at velocity level (`X_G`).

use super::embedding::{fill_y1, group_rows, y1_condition_of};
use super::{embed, residuals};
use crate::algorithms::{constraint_kinematics, position_kinematics, DynamicsError, Workspace};
use crate::linalg::{lu_in_place, solve_least_squares, solve_pivoted_in_place};
use crate::model::Model;
use crate::Real;

/// Largest absolute constraint residual at position level (all equations, redundant ones included) and
/// at velocity level (`|J v|∞`), for checking that a state is consistent (CONTRACT §2: 1e-9).
pub fn constraint_violation<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
) -> Result<(f64, f64), DynamicsError> {
    if !model.has_constraints() {
        return Ok((0.0, 0.0));
    }
    constraint_kinematics(model, ws, q, v)?;
    let mut r = vec![T::zero(); model.constraint_raw_rows()];
    residuals(model, ws, q, &mut r);
    let pos = r.iter().fold(0.0f64, |m, x| m.max(x.to_f64().abs()));
    let mut jac = nalgebra::DMatrix::zeros(model.constraint_raw_rows(), model.nv());
    super::jacobian(model, ws, &mut jac);
    let mut vel = 0.0f64;
    for row in 0..jac.nrows() {
        let s = (0..model.nv()).fold(T::zero(), |s, c| s + jac[(row, c)] * v[c]);
        vel = vel.max(s.to_f64().abs());
    }
    Ok((pos, vel))
}

/// Solves the dependent entries of `q` from its independent entries (the dependent entries are the
/// starting guess: Newton's method converges to the assembly branch nearest it). Returns the largest
/// remaining residual of the kept equations.
pub fn complete_configuration<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
) -> Result<f64, DynamicsError> {
    complete_configuration_with(model, ws, q, 50)
}

/// [`complete_configuration`] with at most `iterations` Newton steps per group (stopping earlier once the
/// residual is below 1e-14). Generated code uses a fixed count: Newton converges quadratically from a
/// guess near the assembly, so a few steps reach machine precision.
pub fn complete_configuration_with<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
    iterations: usize,
) -> Result<f64, DynamicsError> {
    let mut groups = core::mem::take(&mut ws.groups);
    let mut r = core::mem::take(&mut ws.constraint_residual);
    let mut result = Ok(0.0f64);
    'groups: for (gi, gw) in groups.iter_mut().enumerate() {
        let g = &model.groups[gi];
        let mut worst = 0.0;
        for _ in 0..iterations {
            if let Err(e) = position_kinematics(model, ws, q) {
                result = Err(e);
                break 'groups;
            }
            residuals(model, ws, q, &mut r);
            // NaN propagates (f64::max would drop it): an unknown residual never reads as converged, so
            // a traced completion (whose residuals have no value yet) runs every step.
            worst = g.rows.iter().fold(0.0f64, |m, &i| {
                let x = r[i].to_f64().abs();
                if m.is_nan() || x.is_nan() {
                    f64::NAN
                } else {
                    m.max(x)
                }
            });
            if worst <= 1e-14 {
                break;
            }
            // Newton step on the dependent coordinates, Y1 Δ = −r; where Y1 is singular (a guess at a
            // toggle), the minimum-norm least-squares step instead.
            group_rows(model, ws, g, gw, false);
            fill_y1(g, gw);
            for (k, &row) in g.rows.iter().enumerate() {
                gw.col[k] = -r[row];
            }
            gw.y1_lu.copy_from(&gw.y1);
            let mut solved = false;
            if lu_in_place(&mut gw.y1_lu, &mut gw.perm).is_ok() {
                // Solved with select pivoting, so that generated completion pivots at run time too.
                let n = g.rows.len();
                for row in 0..n {
                    for col in 0..n {
                        gw.newton[(row, col)] = gw.y1[(row, col)];
                    }
                    gw.newton[(row, n)] = gw.col[row];
                }
                // An exactly zero pivot in this elimination (where the LU's rounding left a tiny one)
                // is as singular: least squares then. (A traced ratio has no value: always solved.)
                if solve_pivoted_in_place(&mut gw.newton, n).is_positive_finite()
                    && (0..n).all(|row| gw.newton[(row, n)].is_finite())
                {
                    for row in 0..n {
                        gw.col[row] = gw.newton[(row, n)];
                    }
                    solved = true;
                }
            }
            if !solved {
                let step = solve_least_squares(&gw.y1, &gw.col);
                gw.col.copy_from_slice(&step);
            }
            // Limit loop steps so that Newton stays near the branch it starts on (linear equations are
            // solved in one full step).
            // (Selects rather than branches: generated completion limits its steps the same way.)
            let big = gw.col.iter().fold(T::zero(), |m, x| {
                let a = x.abs();
                a.select_gt(m, a, m)
            });
            let half = T::from_f64(0.5);
            let scale = if gw.has_loop {
                big.select_gt(half, half / big, T::one())
            } else {
                T::one()
            };
            for (d, &b) in g.dependent.iter().enumerate() {
                q[model.joints[b].q_index] += gw.col[d] * scale;
            }
        }
        if let Ok(w) = &mut result {
            // NaN (a configuration that left the representable range) is reported, not dropped.
            *w = if w.is_nan() || worst.is_nan() {
                f64::NAN
            } else {
                w.max(worst)
            };
        }
    }
    ws.groups = groups;
    ws.constraint_residual = r;
    result
}

/// Replaces the dependent entries of `v` by `X_G` times the independent ones (the velocity projection).
pub fn complete_velocity<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &mut [T],
) -> Result<(), DynamicsError> {
    position_kinematics(model, ws, q)?;
    let mut groups = core::mem::take(&mut ws.groups);
    let mut result = Ok(());
    for (gi, gw) in groups.iter_mut().enumerate() {
        if let Err(e) = embed(model, ws, gi, gw, false) {
            result = Err(e);
            break;
        }
        let g = &model.groups[gi];
        for (m, &b) in g.bodies.iter().enumerate() {
            if g.dependent.contains(&b) {
                let mut s = T::zero();
                for (k, &ib) in g.independent.iter().enumerate() {
                    s += gw.x[(m, k)] * v[model.joints[ib].v_index];
                }
                v[model.joints[b].v_index] = s;
            }
        }
    }
    ws.groups = groups;
    result
}

/// cond₁(Y1) of group `group` at `q` (the number the singularity threshold is compared with).
pub fn y1_condition<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    group: usize,
) -> Result<f64, DynamicsError> {
    position_kinematics(model, ws, q)?;
    let mut groups = core::mem::take(&mut ws.groups);
    let gw = &mut groups[group];
    group_rows(model, ws, &model.groups[group], gw, false);
    fill_y1(&model.groups[group], gw);
    let cond = y1_condition_of(gw);
    ws.groups = groups;
    Ok(cond)
}
