//! `embedyn complete`: dependent coordinates solved from the independent ones, velocities projected.

use super::samples::Samples;
use super::{CliError, StateProblem};
use embedyn_codegen::{Loaded, ModelOptions};
use embedyn_runtime::constraints::{
    complete_configuration, complete_velocity, constraint_violation,
};
use embedyn_runtime::{JointType, Model, Workspace};
use serde::Serialize;

/// What `complete` prints: `{"samples": [{"q", "v", "residual"}]}`.
#[derive(Serialize)]
pub struct Completed {
    samples: Vec<CompletedSample>,
}

#[derive(Serialize)]
struct CompletedSample {
    q: Vec<f64>,
    v: Vec<f64>,
    residual: f64,
}

pub fn complete(
    loaded: &Loaded,
    options: &ModelOptions,
    input: &str,
) -> Result<Completed, CliError> {
    let model = loaded.model::<f64>(options)?;
    let samples = Samples::parse(input, &[("q", model.nq()), ("v", model.nv())])
        .map_err(|e| e.with_state_hint(&model, options))?;
    let mut ws = Workspace::new(&model);
    let mut out = Vec::with_capacity(samples.len());
    for i in 0..samples.len() {
        let at = |e: embedyn_runtime::DynamicsError| CliError::Dynamics {
            sample: i,
            error: e,
        };
        let mut q = samples.vector(i, "q")?.to_vec();
        let mut v = samples.vector(i, "v")?.to_vec();
        normalize_quaternions(&model, &mut q, i)?;
        complete_configuration(&model, &mut ws, &mut q).map_err(at)?;
        complete_velocity(&model, &mut ws, &q, &mut v).map_err(at)?;
        let (pos, vel) = constraint_violation(&model, &mut ws, &q, &v).map_err(at)?;
        let residual = pos.max(vel);
        if residual.is_nan() || residual > 1e-9 {
            return Err(CliError::State {
                sample: i,
                problem: StateProblem::NotAssembled { residual },
            });
        }
        out.push(CompletedSample { q, v, residual });
    }
    Ok(Completed { samples: out })
}

/// Rescales every free joint's quaternion to unit length (`complete` accepts any non-zero one); a zero
/// quaternion is no orientation at all and is refused, naming the sample and the joint.
fn normalize_quaternions(model: &Model<f64>, q: &mut [f64], sample: usize) -> Result<(), CliError> {
    for j in model
        .joints
        .iter()
        .filter(|j| j.joint_type == JointType::Floating)
    {
        let range = j.q_index + 3..j.q_index + 7;
        let s = &mut q[range.clone()];
        // Scaled by the largest entry first, so that a tiny but non-zero quaternion does not underflow.
        let largest = s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if !(largest > 0.0 && largest.is_finite()) {
            return Err(CliError::State {
                sample,
                problem: StateProblem::ZeroQuaternion {
                    joint: j.name.clone(),
                    start: range.start,
                    end: range.end,
                    values: s.to_vec(),
                },
            });
        }
        s.iter_mut().for_each(|x| *x /= largest);
        let norm = s.iter().map(|x| x * x).sum::<f64>().sqrt();
        s.iter_mut().for_each(|x| *x /= norm);
    }
    Ok(())
}
