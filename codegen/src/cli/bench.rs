//! `embedyn bench`: median ns per call of `aba`, `rnea`, `crba` for the interpreted solver (in this
//! process) and the generated code (f64 and f32, in the compiled runner), on the same pre-generated
//! random states, no I/O inside the timed loops.

use super::runner::{build_runner, run};
use super::CliError;
use crate::{GenerateOptions, Loaded, ModelOptions};
use embedyn_runtime::constraints::{complete_configuration, complete_velocity};
use embedyn_runtime::{aba, crba, reduced_mass_matrix_in, rnea, JointType, Model, Workspace};
use serde_json::{json, Value};
use std::hint::black_box;

/// Median over 101 batches, each sized to last ~0.2 ms.
fn time(f: &mut dyn FnMut()) -> f64 {
    let mut calls = 1usize;
    loop {
        let t = std::time::Instant::now();
        for _ in 0..calls {
            f();
        }
        if t.elapsed().as_micros() >= 200 {
            break;
        }
        calls *= 2;
    }
    let mut runs: Vec<f64> = (0..101)
        .map(|_| {
            let t = std::time::Instant::now();
            for _ in 0..calls {
                f();
            }
            t.elapsed().as_nanos() as f64 / calls as f64
        })
        .collect();
    runs.sort_by(|a, b| a.partial_cmp(b).unwrap());
    runs[50]
}

/// 64 random consistent states: angles in ±π (±0.3 for models with constraints, then completed).
fn states(model: &Model<f64>) -> Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let mut seed: u64 = 0x5eed;
    let mut uniform = move |lo: f64, hi: f64| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut ws = Workspace::new(model);
    let spread = if model.has_constraints() {
        0.3
    } else {
        std::f64::consts::PI
    };
    let mut out = Vec::new();
    while out.len() < 64 {
        let mut q = model.neutral_configuration();
        for j in &model.joints {
            match j.joint_type {
                JointType::Floating => {
                    let quat: Vec<f64> = (0..4).map(|_| uniform(-1.0, 1.0)).collect();
                    let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                    for k in 0..3 {
                        q[j.q_index + k] = uniform(-1.0, 1.0);
                    }
                    for k in 0..4 {
                        q[j.q_index + 3 + k] = quat[k] / n;
                    }
                }
                _ => q[j.q_index] = uniform(-spread, spread),
            }
        }
        let mut v: Vec<f64> = (0..model.nv()).map(|_| uniform(-1.0, 1.0)).collect();
        if model.has_constraints()
            && (complete_configuration(model, &mut ws, &mut q).map_or(true, |r| r > 1e-12)
                || complete_velocity(model, &mut ws, &q, &mut v).is_err())
        {
            continue;
        }
        let x: Vec<f64> = (0..model.nv()).map(|_| uniform(-1.0, 1.0)).collect();
        out.push((q, v, x));
    }
    out
}

pub fn bench(loaded: &Loaded, options: &ModelOptions) -> Result<Value, CliError> {
    let model = loaded.model::<f64>(options)?;
    let st = states(&model);
    let mut ws = Workspace::new(&model);
    let mut k = 0usize;
    let mut interpreted = |algo: &str| -> f64 {
        let ws = &mut ws;
        let model = &model;
        let st = &st;
        match algo {
            "aba" => time(&mut || {
                k = (k + 1) % st.len();
                black_box(
                    aba(model, ws, black_box(&st[k].0), &st[k].1, &st[k].2)
                        .map(|x| x[0])
                        .ok(),
                );
            }),
            "rnea" => time(&mut || {
                k = (k + 1) % st.len();
                black_box(
                    rnea(model, ws, black_box(&st[k].0), &st[k].1, &st[k].2)
                        .map(|x| x[0])
                        .ok(),
                );
            }),
            // What `eval --algo crba` reports: XᵀMX for a model with constraints (as the generated
            // engine's `crba_independent`), M otherwise.
            _ if model.has_constraints() => time(&mut || {
                k = (k + 1) % st.len();
                black_box(
                    reduced_mass_matrix_in(model, ws, black_box(&st[k].0))
                        .map(|m| m[(0, 0)])
                        .ok(),
                );
            }),
            _ => time(&mut || {
                k = (k + 1) % st.len();
                black_box(crba(model, ws, black_box(&st[k].0)).map(|m| m[(0, 0)]).ok());
            }),
        }
    };
    let binary = build_runner(
        loaded,
        &GenerateOptions {
            model: options.clone(),
            ..Default::default()
        },
    )?;
    let rows: Vec<Vec<f64>> = st
        .iter()
        .map(|(q, v, x)| q.iter().chain(v).chain(x).copied().collect())
        .collect();
    let mut result = serde_json::Map::new();
    for algo in ["aba", "rnea", "crba"] {
        let i = interpreted(algo);
        let g64 = run(&binary, algo, "f64", "bench", &rows)?
            .first()
            .and_then(|r| r.first().copied())
            .unwrap_or(f64::NAN);
        let g32 = run(&binary, algo, "f32", "bench", &rows)?
            .first()
            .and_then(|r| r.first().copied())
            .unwrap_or(f64::NAN);
        result.insert(
            algo.into(),
            json!({ "interpreted_f64": i, "generated_f64": g64, "generated_f32": g32 }),
        );
    }
    Ok(Value::Object(result))
}

/// A human-readable table of [`bench`]'s result.
pub fn table(v: &Value) -> String {
    let mut s =
        String::from("median ns per call   interpreted_f64  generated_f64  generated_f32\n");
    for algo in ["aba", "rnea", "crba"] {
        let r = &v[algo];
        let f = |k: &str| r[k].as_f64().map_or("—".to_string(), |x| format!("{x:.0}"));
        s.push_str(&format!(
            "{algo:<20} {:>16} {:>14} {:>14}\n",
            f("interpreted_f64"),
            f("generated_f64"),
            f("generated_f32")
        ));
    }
    s
}
