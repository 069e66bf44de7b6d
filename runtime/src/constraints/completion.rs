//! Completing a state: the dependent coordinates from the independent ones, at position level (Newton's
//! method from the given guess, so it stays on that assembly branch) and at velocity level (`X_G`).
//!
//! Residuals are judged relative to the magnitudes they are computed from (docs/conventions.md): a loop far from
//! the world origin, or a gear ratio of 1000, has rounding errors in proportion, and an absolute tolerance
//! would either reject its exact states or accept wrong ones.

use super::embedding::{fill_y1, group_rows, member, y1_condition_of};
use super::{embed, jacobian, relative_residual, residuals_scaled};
use crate::algorithms::{
    check_configuration, check_input, constraint_kinematics, position_kinematics, DynamicsError,
    Sweep, Workspace,
};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::linalg::{solve_least_squares, solve_pivoted_in_place};
use crate::model::Model;
use crate::Real;

/// Newton steps per group at most (it converges quadratically near an assembly; the bound keeps a
/// guess that never converges — an independent coordinate outside the mechanism's range — from spinning).
pub const COMPLETION_MAX_STEPS: usize = 50;

/// Largest constraint residual at position level (all equations, redundant ones included) and at velocity
/// level (`J v`), each relative to the magnitudes in its equation: `|r| / max(1, magnitude)` (docs/conventions.md,
/// so 1e-9 means 1e-9 relative, and at least 1e-9 absolute in m, rad, m/s, rad/s). NaN where a residual is
/// not a number.
///
/// # Errors
/// [`DynamicsError::WrongLength`] or [`DynamicsError::NonFiniteInput`] for a `q` or `v` of the wrong
/// length or with a NaN or infinite entry (also for a model without constraints), and
/// [`DynamicsError::InvalidQuaternion`] as [`crate::aba`].
pub fn constraint_violation<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
) -> Result<(f64, f64), DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    if !model.has_constraints() {
        return Ok((0.0, 0.0));
    }
    constraint_kinematics(model, ws, q, v)?;
    let rows = model.constraint_raw_rows();
    let mut r = vec![T::zero(); rows];
    let mut scale = vec![T::zero(); rows];
    residuals_scaled(model, ws.kinematics(), q, &mut r, &mut scale);
    let pos = r.iter().zip(&scale).fold(0.0, |m, (&x, &s)| {
        max_nan(m, relative_residual(x, s).to_f64())
    });
    let mut jac = nalgebra::DMatrix::zeros(rows, model.nv());
    jacobian(model, ws, &mut jac);
    let mut vel = 0.0f64;
    for row in 0..rows {
        let (mut sum, mut magnitude) = (T::zero(), T::zero());
        for c in 0..model.nv() {
            let term = jac[(row, c)] * v[c];
            sum += term;
            magnitude += term.abs();
        }
        vel = max_nan(vel, relative_residual(sum, magnitude).to_f64());
    }
    // Accelerations at qdd = 0, a qdd the caller never gave.
    ws.sweep = Sweep::Velocities;
    Ok((pos, vel))
}

/// `max` that keeps a NaN (f64::max would drop it): an unknown residual never reads as satisfied.
fn max_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// Solves the dependent entries of `q` from its independent entries (the dependent entries are the
/// starting guess: Newton's method converges to the assembly branch nearest it). Returns the largest
/// remaining relative residual of the kept equations (see [`constraint_violation`]): at most 64 ε of the
/// scalar where it converged, larger (or NaN) where it did not — the caller decides.
pub fn complete_configuration<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
) -> Result<f64, DynamicsError> {
    complete_configuration_with(model, ws, q, COMPLETION_MAX_STEPS)
}

/// [`complete_configuration`] with at most `iterations` Newton steps per group, stopping once the relative
/// residual is below 64 ε.
///
/// # Errors
/// As [`crate::crba`] for a `q` of the wrong length, with a NaN or infinite entry (the dependent entries,
/// the starting guess, included) or a zero quaternion, also for a model without loops; and
/// [`DynamicsError::SingularConstraint`] where a loop's Jacobian is singular at an iterate.
pub fn complete_configuration_with<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
    iterations: usize,
) -> Result<f64, DynamicsError> {
    check_configuration(model, q)?;
    let tolerance = 64.0 * T::epsilon().to_f64();
    let mut worst_overall = 0.0f64;
    for gi in 0..model.groups.len() {
        let mut worst = f64::NAN;
        for step in 0..=iterations {
            let take_step = step < iterations;
            let r = newton_step(model, ws, gi, q, take_step)?;
            worst = r.to_f64();
            // NaN never reads as converged (nor does a traced residual, which has no value yet).
            if worst <= tolerance || !take_step {
                break;
            }
        }
        worst_overall = max_nan(worst_overall, worst);
    }
    Ok(worst_overall)
}

/// One Newton step on every group (what generated `complete` iterates): returns the largest relative
/// residual *before* the step, so that the caller stops when it is small enough.
///
/// # Errors
/// As [`complete_configuration_with`].
pub fn completion_step<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &mut [T],
) -> Result<T, DynamicsError> {
    check_configuration(model, q)?;
    let mut worst = T::zero();
    for gi in 0..model.groups.len() {
        let r = newton_step(model, ws, gi, q, true)?;
        worst = super::max_keeping_nan(worst, r);
    }
    Ok(worst)
}

/// The relative residual of group `gi` at `q` and, with `take_step`, one Newton step on its dependent
/// coordinates: `Y1 Δ = −r`, solved with run-time pivoting (the least-squares step where `Y1` is exactly
/// singular, a guess at a toggle). Loop coordinates move at most 0.5 rad (m) per step so that Newton stays
/// near the branch it starts on; coordinates only linear equations (gears, mimic joints) involve are not
/// limited, so a group of linear equations is solved exactly in one step and a 20:1 rotor on a four-bar's
/// crank does not crawl after it.
fn newton_step<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    gi: usize,
    q: &mut [T],
    take_step: bool,
) -> Result<T, DynamicsError> {
    position_kinematics(model, ws, q)?;
    let g = &model.groups[gi];
    let (kin, scratch) = ws.split_constraints();
    let gw = &mut scratch.groups[gi];
    let (r, scale) = (&mut scratch.residual, &mut scratch.scale);
    residuals_scaled(model, kin, q, r, scale);
    let mut worst = T::zero();
    for &row in &g.rows {
        let e = relative_residual(r[row], scale[row]);
        worst = super::max_keeping_nan(worst, e);
    }
    if take_step && !g.rows.is_empty() {
        group_rows(model, kin, g, gw, false);
        fill_y1(g, gw);
        let n = g.rows.len();
        for (k, &row) in g.rows.iter().enumerate() {
            for col in 0..n {
                gw.newton[(k, col)] = gw.y1[(k, col)];
            }
            gw.newton[(k, n)] = -r[row];
        }
        let ratio = solve_pivoted_in_place(&mut gw.newton, n);
        for k in 0..n {
            gw.col[k] = gw.newton[(k, n)];
        }
        // An exactly singular Y1 (known only for numbers): the minimum-norm least-squares step.
        let singular = ratio.value().is_some_and(|x| !(x > 0.0 && x.is_finite()))
            || gw
                .col
                .iter()
                .any(|x| x.value().is_some_and(|v| !v.is_finite()));
        if singular {
            let rhs: Vec<T> = g.rows.iter().map(|&row| -r[row]).collect();
            let step = solve_least_squares(&gw.y1, &rhs);
            gw.col.copy_from_slice(&step);
        }
        // (Selects rather than branches: generated completion limits its steps the same way.)
        let mut big = T::zero();
        for (d, &is_loop) in gw.loop_dependent.iter().enumerate() {
            if is_loop {
                let a = gw.col[d].abs();
                big = a.select_gt(big, a, big);
            }
        }
        let half = T::from_f64(0.5);
        let limit = big.select_gt(half, half / big, T::one());
        for (d, &b) in g.dependent.iter().enumerate() {
            q[model.joints[b].q_index] += gw.col[d] * limit;
        }
        // The placements are those of `q` before the step.
        ws.sweep = Sweep::None;
    }
    Ok(worst)
}

/// Replaces the dependent entries of `v` by `X_G` times the independent ones (the velocity projection).
///
/// # Errors
/// As the other algorithms: [`DynamicsError::WrongLength`] or [`DynamicsError::NonFiniteInput`] for a
/// `q` or `v` of the wrong length or with a NaN or infinite entry (every entry of `v`, the dependent ones
/// it replaces included, so that a NaN is named rather than silently dropped), and
/// [`DynamicsError::InvalidQuaternion`]; [`DynamicsError::SingularConstraint`] where a loop is at or too
/// near a singular configuration. `v` is unchanged on an error in the input.
pub fn complete_velocity<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &mut [T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    position_kinematics(model, ws, q)?;
    let (kin, scratch) = ws.split_constraints();
    for (gi, gw) in scratch.groups.iter_mut().enumerate() {
        embed(model, kin, gi, gw, false)?;
        let g = &model.groups[gi];
        for &b in &g.dependent {
            let m = member(g, b).expect("dependent joints are members");
            let mut s = T::zero();
            for (k, &ib) in g.independent.iter().enumerate() {
                s += gw.x[(m, k)] * v[model.joints[ib].v_index];
            }
            v[model.joints[b].v_index] = s;
        }
    }
    Ok(())
}

/// cond₁(Y1) of group `group` at `q` (by an LU factorization: an independent check of the condition
/// number the embedding computes and compares with [`super::singularity_threshold`]).
///
/// # Errors
/// As [`crate::crba`] for a `q` of the wrong length, with a NaN or infinite entry or a zero quaternion.
///
/// # Panics
/// If `group` is not less than `model.groups.len()`.
pub fn y1_condition<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    group: usize,
) -> Result<f64, DynamicsError> {
    position_kinematics(model, ws, q)?;
    let (kin, scratch) = ws.split_constraints();
    let gw = &mut scratch.groups[group];
    group_rows(model, kin, &model.groups[group], gw, false);
    fill_y1(&model.groups[group], gw);
    Ok(y1_condition_of(gw))
}
