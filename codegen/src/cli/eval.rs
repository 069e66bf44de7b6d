//! `embedyn eval`: ABA, RNEA or CRBA on every sample.

use super::samples::{vector, Samples};
use super::{Algo, CliError, Scalar};
use crate::{Loaded, ModelOptions};
use embedyn_runtime::{aba, crba, rnea, JointType, Model, Real, Workspace};
use serde_json::{json, Value};

pub fn eval(
    loaded: &Loaded,
    options: &ModelOptions,
    algo: Algo,
    scalar: Scalar,
    input: &str,
) -> Result<Value, CliError> {
    let samples = Samples::parse(input)?;
    match scalar {
        Scalar::F64 => eval_in::<f64>(&loaded.model(options)?, algo, &samples),
        Scalar::F32 => eval_in::<f32>(&loaded.model(options)?, algo, &samples),
    }
}

fn eval_in<T: Real>(model: &Model<T>, algo: Algo, samples: &Samples) -> Result<Value, CliError> {
    let mut ws = Workspace::new(model);
    let (nq, nv) = (model.nq(), model.nv());
    let mut out = Vec::with_capacity(samples.samples.len());
    for (i, s) in samples.samples.iter().enumerate() {
        let q = vector(s, i, "q", nq)?;
        check_quaternions(model, &q, i)?;
        let q = cast::<T>(&q);
        let value = match algo {
            Algo::Aba => {
                let v = cast::<T>(&vector(s, i, "v", nv)?);
                let tau = cast::<T>(&vector(s, i, "tau", nv)?);
                let qdd = finite(
                    aba(model, &mut ws, &q, &v, &tau)
                        .map_err(|e| CliError(format!("sample {i}: {e}")))?,
                    i,
                    "qdd",
                )?;
                json!({ "qdd": qdd, "qdd_independent": qdd })
            }
            Algo::Rnea => {
                let v = cast::<T>(&vector(s, i, "v", nv)?);
                let qdd = cast::<T>(&vector(s, i, "qdd", nv)?);
                let tau = finite(
                    rnea(model, &mut ws, &q, &v, &qdd)
                        .map_err(|e| CliError(format!("sample {i}: {e}")))?,
                    i,
                    "tau",
                )?;
                json!({ "tau": tau, "tau_independent": tau })
            }
            Algo::Crba => {
                let m =
                    crba(model, &mut ws, &q).map_err(|e| CliError(format!("sample {i}: {e}")))?;
                let rows: Vec<Vec<f64>> = (0..nv)
                    .map(|r| (0..nv).map(|c| m[(r, c)].to_f64()).collect())
                    .collect();
                finite(
                    &rows
                        .concat()
                        .iter()
                        .map(|&x| T::from_f64(x))
                        .collect::<Vec<T>>(),
                    i,
                    "M",
                )?;
                json!({ "M": rows })
            }
        };
        out.push(value);
    }
    let joints: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    Ok(json!({ "joints": joints, "samples": out }))
}

fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

/// The result as f64, or an error if any entry is not finite (never a silent NaN).
fn finite<T: Real>(x: &[T], sample: usize, name: &str) -> Result<Vec<f64>, CliError> {
    let y: Vec<f64> = x.iter().map(|v| v.to_f64()).collect();
    match y.iter().position(|v| !v.is_finite()) {
        None => Ok(y),
        Some(k) => Err(CliError(format!("sample {sample}: `{name}`[{k}] is not finite ({}); the state is outside what the scalar type can represent", y[k]))),
    }
}

/// A floating joint's quaternion must have unit norm (to 1e-6; it is normalized before use).
fn check_quaternions<T: Real>(model: &Model<T>, q: &[f64], sample: usize) -> Result<(), CliError> {
    for j in model
        .joints
        .iter()
        .filter(|j| j.joint_type == JointType::Floating)
    {
        let s = &q[j.q_index + 3..j.q_index + 7];
        let n = s.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (n - 1.0).abs() > 1e-6 {
            return Err(CliError(format!(
                "sample {sample}: field `q`[{}..{}]: the quaternion of joint `{}` has norm {n}; it must be a unit quaternion [qx qy qz qw]",
                j.q_index + 3,
                j.q_index + 7,
                j.name
            )));
        }
    }
    Ok(())
}
