//! Random consistent states of a model, for benchmarks and comparisons: configurations where the model
//! assembles and velocities that satisfy its velocity constraints.
//!
//! A tree takes any configuration. A model with loops, couplings or mimic joints may assemble only on
//! part of its coordinate space (a four-bar whose crank reaches the coupler only between 0.7 and 1.4
//! rad), so states are looked for in two ways: drawn anywhere in the joints' ranges and completed
//! (which finds the regions where it assembles), and perturbed around states already found and completed
//! (which fills those regions, however narrow). Both are bounded in attempts; a model that assembles
//! nowhere gets a clear error, never a hang.

use embedyn_runtime::constraints::{
    complete_configuration, complete_velocity, constraint_violation,
};
use embedyn_runtime::random::SplitMix64;
use embedyn_runtime::{JointType, Model, Workspace};
use std::f64::consts::PI;

/// A state satisfies the constraints when `constraint_violation` is at most this, at position and at
/// velocity level (docs/conventions.md).
pub const CONSISTENT: f64 = 1e-9;

/// Attempts allowed per state asked for (a draw or a perturbation, each followed by a completion).
const ATTEMPTS_PER_STATE: usize = 100;

/// At least this many attempts, so that a few states of a hard-to-assemble model can still be found.
const MIN_ATTEMPTS: usize = 2000;

/// Largest change of an independent coordinate when perturbing around a state found (rad or m).
const STEP: f64 = 0.3;

/// A consistent state: configuration `q` (unit quaternions) and velocity `v`.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    pub q: Vec<f64>,
    pub v: Vec<f64>,
}

/// Too few consistent states found: the model assembles rarely, or not at all, among the
/// configurations drawn.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("found {found} of the {count} consistent states asked for in {attempts} attempts: `{}` assembles \
         (loop and coupling constraints met to {CONSISTENT:e}) at {} of the configurations tried \
         (independent angles drawn in ±π, displacements in ±1 m, and around the states found)",
    .model.escape_debug(),
    if *.found == 0 { "none" } else { "too few" })]
pub struct NoConsistentStates {
    /// The states found.
    pub found: usize,
    /// The states asked for.
    pub count: usize,
    /// The configurations tried.
    pub attempts: usize,
    /// The model's name.
    pub model: String,
}

/// Draws `count` consistent states of `model` (deterministic for a given `seed`).
pub fn consistent_states(
    model: &Model<f64>,
    count: usize,
    seed: u64,
) -> Result<Vec<State>, NoConsistentStates> {
    let mut rng = SplitMix64::new(seed);
    let mut ws = Workspace::new(model);
    let mut found: Vec<State> = Vec::with_capacity(count);
    if !model.has_constraints() {
        while found.len() < count {
            let q = draw_configuration(model, &mut rng);
            let v = (0..model.nv()).map(|_| rng.uniform(-1.0, 1.0)).collect();
            found.push(State { q, v });
        }
        return Ok(found);
    }
    let attempts = (ATTEMPTS_PER_STATE * count).max(MIN_ATTEMPTS);
    for attempt in 0..attempts {
        if found.len() == count {
            break;
        }
        // Until a first state is found only draws; then half of the attempts explore further (other
        // assembly regions), half perturb a state found (a random walk through the regions found).
        let mut q = if found.is_empty() || attempt % 2 == 0 {
            draw_configuration(model, &mut rng)
        } else {
            let base = &found[rng.below(found.len())].q;
            perturb(model, base, &mut rng)
        };
        if let Some(state) = complete(model, &mut ws, &mut q, &mut rng) {
            found.push(state);
        }
    }
    if found.len() < count {
        return Err(NoConsistentStates {
            found: found.len(),
            count,
            attempts,
            model: model.name.clone(),
        });
    }
    Ok(found)
}

/// Any configuration: angles in ±π, displacements in ±1 m, a free body anywhere in the unit cube with
/// a uniformly random orientation.
fn draw_configuration(model: &Model<f64>, rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = model.neutral_configuration();
    for j in &model.joints {
        let i = j.q_index;
        match j.joint_type {
            JointType::Floating => {
                for k in 0..3 {
                    q[i + k] = rng.uniform(-1.0, 1.0);
                }
                let quaternion = random_unit_quaternion(rng);
                q[i + 3..i + 7].copy_from_slice(&quaternion);
            }
            JointType::Prismatic => q[i] = rng.uniform(-1.0, 1.0),
            _ => {
                for k in 0..j.nq() {
                    q[i + k] = rng.uniform(-PI, PI);
                }
            }
        }
    }
    q
}

/// Uniform on the unit sphere of quaternions (a draw in the unit ball, accepted away from the centre,
/// normalized).
fn random_unit_quaternion(rng: &mut SplitMix64) -> [f64; 4] {
    loop {
        let x: [f64; 4] = core::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        let n = x.iter().map(|c| c * c).sum::<f64>().sqrt();
        // Accepted with probability π²/32 ≈ 0.31 per draw; the loop ends almost surely within a few.
        if (0.1..=1.0).contains(&n) {
            return x.map(|c| c / n);
        }
    }
}

/// `base` with each independent coordinate moved by up to [`STEP`] (the dependent ones stay, as the
/// starting guess of the completion: the same assembly branch).
fn perturb(model: &Model<f64>, base: &[f64], rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = base.to_vec();
    for (b, j) in model.joints.iter().enumerate() {
        if !model.is_independent(b) || j.joint_type == JointType::Floating {
            continue;
        }
        for k in 0..j.nq() {
            q[j.q_index + k] += rng.uniform(-STEP, STEP);
        }
    }
    q
}

/// Completes `q` (dependent coordinates solved) and a random velocity (projected); the state if both
/// meet the constraints to [`CONSISTENT`].
fn complete(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    q: &mut [f64],
    rng: &mut SplitMix64,
) -> Option<State> {
    complete_configuration(model, ws, q).ok()?;
    let mut v: Vec<f64> = (0..model.nv()).map(|_| rng.uniform(-1.0, 1.0)).collect();
    complete_velocity(model, ws, q, &mut v).ok()?;
    let (pos, vel) = constraint_violation(model, ws, q, &v).ok()?;
    // NaN fails both comparisons.
    let consistent = pos <= CONSISTENT && vel <= CONSISTENT;
    let finite = q.iter().chain(&v).all(|x| x.is_finite());
    (consistent && finite).then(|| State { q: q.to_vec(), v })
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedyn_codegen::ModelOptions;
    use std::path::PathBuf;

    fn narrow_four_bar_text() -> (String, PathBuf) {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data/loops/narrow_four_bar.urdf");
        (std::fs::read_to_string(&path).unwrap(), path)
    }

    fn model_of(text: &str, path: &std::path::Path) -> Model<f64> {
        embedyn_codegen::parse_urdf(text, path)
            .unwrap()
            .model(&ModelOptions::default())
            .unwrap()
    }

    /// The crank of this four-bar assembles only for |q| in [0.7, 1.4] rad (a draw in ±0.3 rad around
    /// q = 0 never does): the sampler finds states there, consistent, and spread over the range.
    #[test]
    fn narrow_four_bar_states_are_found_where_it_assembles() {
        let (text, path) = narrow_four_bar_text();
        let model = model_of(&text, &path);
        let states = consistent_states(&model, 64, 7).unwrap();
        assert_eq!(states.len(), 64);
        let mut ws = Workspace::new(&model);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for s in &states {
            let crank = s.q[0].abs();
            assert!((0.7 - 1e-9..=1.4 + 1e-9).contains(&crank), "crank {crank}");
            let (pos, vel) = constraint_violation(&model, &mut ws, &s.q, &s.v).unwrap();
            assert!(pos <= CONSISTENT && vel <= CONSISTENT, "{pos:e} {vel:e}");
            // Not the zero velocity: the projection kept a random independent velocity.
            assert!(s.v[0] != 0.0);
            lo = lo.min(crank);
            hi = hi.max(crank);
        }
        assert!(hi - lo > 0.3, "states spread over [{lo}, {hi}] only");
        // Deterministic.
        assert_eq!(consistent_states(&model, 64, 7).unwrap(), states);
    }

    /// A four-bar that assembles at one crank angle only (coupler − rocker = the largest pivot distance,
    /// reached at q_crank = π, a toggle): valid, but no sampled crank angle assembles. A clear error
    /// within the bounded attempts, never a hang.
    #[test]
    fn a_model_that_assembles_almost_nowhere_is_an_error() {
        let (text, path) = narrow_four_bar_text();
        let text = text.replace("0.09871154946931424 0 0", "0.230131987978223966 0 0");
        let model = model_of(&text, &path);
        let error = consistent_states(&model, 8, 1).unwrap_err();
        assert_eq!((error.found, error.count), (0, 8));
        let e = error.to_string();
        assert!(
            e.contains("found 0 of the 8") && e.contains("narrow_four_bar"),
            "{e}"
        );
    }

    #[test]
    fn tree_states_are_unit_quaternion_configurations() {
        let path =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/loops/biped_floating.urdf");
        let model = embedyn_codegen::load(&path)
            .unwrap()
            .model::<f64>(&ModelOptions::default())
            .unwrap();
        let states = consistent_states(&model, 4, 3).unwrap();
        for s in &states {
            let n: f64 = s.q[3..7].iter().map(|x| x * x).sum::<f64>();
            assert!((n - 1.0).abs() < 1e-12, "{n}");
        }
    }
}
