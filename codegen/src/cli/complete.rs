//! `embedyn complete`: dependent coordinates solved from the independent ones, velocities projected.

use super::samples::{vector, Samples};
use super::CliError;
use crate::{Loaded, ModelOptions};
use embedyn_runtime::constraints::{
    complete_configuration, complete_velocity, constraint_violation,
};
use embedyn_runtime::Workspace;
use serde_json::{json, Value};

pub fn complete(loaded: &Loaded, options: &ModelOptions, input: &str) -> Result<Value, CliError> {
    let samples = Samples::parse(input)?;
    let model = loaded.model::<f64>(options)?;
    let mut ws = Workspace::new(&model);
    let mut out = Vec::with_capacity(samples.samples.len());
    for (i, s) in samples.samples.iter().enumerate() {
        let at = |e: embedyn_runtime::DynamicsError| CliError(format!("sample {i}: {e}"));
        let mut q = vector(s, i, "q", model.nq())?;
        let mut v = vector(s, i, "v", model.nv())?;
        model.normalize_configuration(&mut q);
        complete_configuration(&model, &mut ws, &mut q).map_err(at)?;
        complete_velocity(&model, &mut ws, &q, &mut v).map_err(at)?;
        let (pos, vel) = constraint_violation(&model, &mut ws, &q, &v).map_err(at)?;
        let residual = pos.max(vel);
        if residual.is_nan() || residual > 1e-9 {
            return Err(CliError(format!(
                "sample {i}: the loop constraints could not be solved from this guess (residual {residual:e}); the independent coordinates may be outside the mechanism's range, or the guess too far from an assembly"
            )));
        }
        out.push(json!({ "q": q, "v": v, "residual": residual }));
    }
    Ok(json!({ "samples": out }))
}
