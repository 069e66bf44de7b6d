//! `embedyn bench`: median ns per call of `aba`, `rnea`, `crba` for the interpreted solver (in this
//! process) and the generated code (f64 and f32, in the compiled runner), on the same pre-generated
//! random states, no I/O inside the timed loops.

use super::runner::{build_runner, run, RowShape};
use super::{output, CliError};
use crate::sampling::{consistent_states, NoConsistentStates};
use embedyn_codegen::{Algorithm, GenerateOptions, LoadErrorKind, Loaded, ModelOptions};
use embedyn_runtime::random::SplitMix64;
use embedyn_runtime::{Model, Workspace};
use serde_json::{json, Value};
use std::hint::black_box;

/// Defines the items given and keeps their source text: the timing loop is compiled here, for the
/// interpreted solver, and written into the cached runner's `main.rs`, for the generated code, so that both
/// engines are timed by the same loop.
macro_rules! with_source {
    ($source:ident, $($item:tt)*) => {
        $($item)*
        /// The source text of the items above.
        pub(crate) const $source: &str = stringify!($($item)*);
    };
}

with_source! {
    TIME_SOURCE,
    /// Median ns per call over 101 batches, each sized to last about 0.2 ms.
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
        runs.sort_by(f64::total_cmp);
        runs[50]
    }
}

/// Why `bench` cannot time the model.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// Too few consistent states to time on.
    #[error("bench: {0}")]
    NoStates(#[source] NoConsistentStates),
    /// The runner printed no time.
    #[error("the runner reported no time for {algorithm} in {scalar}")]
    NoTime {
        /// The algorithm timed.
        algorithm: String,
        /// The scalar type.
        scalar: String,
    },
}

/// States timed per algorithm.
const STATES: usize = 64;

/// States per call of the lane module whose `_batch` forms are timed (`generated_f64_batch`, ns per
/// state over all [`STATES`] in one call).
const LANES: usize = 4;

/// `q`, `v` and the third argument (`tau` or `qdd`) of one timed call.
type TimedState = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The states each timed call cycles through: random consistent states (see [`crate::sampling`]), each
/// with a random third vector (`tau` for `aba`, `qdd` for `rnea`).
fn states(model: &Model<f64>) -> Result<Vec<TimedState>, CliError> {
    let mut rng = SplitMix64::new(0x5eed);
    let found = consistent_states(model, STATES, 0x5eed).map_err(BenchError::NoStates)?;
    Ok(found
        .into_iter()
        .map(|s| {
            let x = (0..model.nv()).map(|_| rng.uniform(-1.0, 1.0)).collect();
            (s.q, s.v, x)
        })
        .collect())
}

pub fn bench(
    loaded: &Loaded,
    options: &ModelOptions,
    max_compile_memory_mb: u64,
) -> Result<Value, CliError> {
    let model = loaded.model::<f64>(options)?;
    if model.nv() == 0 {
        super::output::note(&format!(
            "embedyn: {} has no degree of freedom (every joint is fixed): the times are those of calls that compute nothing",
            embedyn_codegen::names::code_span(&model.name)
        ));
    }
    let st = states(&model)?;
    let mut ws = Workspace::new(&model);
    let mut k = 0usize;
    // What is timed is what `eval --algo` reports: for a model with constraints, `crba` is Xᵀ M X (the
    // generated engine's `crba_independent`, the interpreted `reduced_mass_matrix_in`).
    let constrained = model.has_constraints();
    let mut interpreted = |algo: Algorithm| -> f64 {
        let run = algo.reported_by(constrained).spec().interpreted;
        let ws = &mut ws;
        let model = &model;
        let st = &st;
        time(&mut || {
            k = (k + 1) % st.len();
            let (q, v, x) = &st[k];
            black_box(
                run(
                    model,
                    ws,
                    &[black_box(q), v, x],
                    &embedyn_codegen::algorithm::Links::NONE,
                )
                .is_ok(),
            );
        })
    };
    let timed: Vec<Algorithm> = Algorithm::timed_by_bench().collect();
    let generate = |lanes| GenerateOptions {
        model: options.clone(),
        // What is timed, nothing more.
        algorithms: super::runner::runner_algorithms(&timed, constrained),
        exact: true,
        max_compile_memory_mb: Some(max_compile_memory_mb),
        // The f64 lane module's `_batch` forms are timed too (ns per state).
        lanes,
        ..Default::default()
    };
    // The lane module is what `bench` adds to the functions: where the code fits the compile-memory
    // limit only without it (GRBDA's jvrc1 humanoid at 2 GB, whose `crba_independent` alone is 27k
    // operations), the batch forms are left untimed rather than the whole benchmark refused.
    let (binary, lanes) = match build_runner(loaded, &generate(LANES)) {
        Err(CliError::Load(e)) if matches!(e.kind, LoadErrorKind::TooLargeToCompile(_)) => {
            let binary = build_runner(loaded, &generate(0))?;
            output::note(&format!(
                "embedyn bench: the lane module does not fit the compile-memory limit of {max_compile_memory_mb} MB: \
                 no `generated_f64_batch` (raise the limit with --max-compile-memory to time the batch forms)"
            ));
            (binary, 0)
        }
        built => (built?, LANES),
    };
    let rows: Vec<Vec<f64>> = st
        .iter()
        .map(|(q, v, x)| q.iter().chain(v).chain(x).chain(q).copied().collect())
        .collect();
    let mut result = serde_json::Map::new();
    for &algo in &timed {
        let i = interpreted(algo);
        let algo = algo.name();
        let g64 = time_generated(&binary, algo, "f64", &rows)?;
        let g32 = time_generated(&binary, algo, "f32", &rows)?;
        // The lane module's `_batch` forms of the three dynamics algorithms.
        let batch = if lanes > 0 && super::runner::BATCH_TIMED.contains(&algo) {
            json!(time_generated(
                &binary,
                algo,
                &format!("f64x{LANES}"),
                &rows
            )?)
        } else {
            Value::Null
        };
        let mut entry = json!({
            "interpreted_f64": i,
            "generated_f64": g64,
            "generated_f32": g32,
        });
        // Where lane functions were built (CONTRACT: the keys exist where they do).
        if lanes > 0 {
            entry["generated_f64_batch"] = batch;
            entry["lanes"] = json!(lanes);
        }
        result.insert(algo.into(), entry);
    }
    Ok(Value::Object(result))
}

/// The generated code's median ns per call, as the runner reports it (`run` checked it is one positive
/// number).
fn time_generated(
    binary: &std::path::Path,
    algo: &str,
    scalar: &str,
    rows: &[Vec<f64>],
) -> Result<f64, CliError> {
    run(binary, algo, scalar, RowShape::Bench, rows)?
        .first()
        .and_then(|row| row.first().copied())
        .ok_or_else(|| {
            BenchError::NoTime {
                algorithm: algo.to_string(),
                scalar: scalar.to_string(),
            }
            .into()
        })
}

/// A human-readable table of [`bench`]'s result.
pub fn table(v: &Value) -> String {
    let mut s = String::from(
        "median ns per call   interpreted_f64  generated_f64  generated_f32  generated_f64_batch (per state)\n",
    );
    for algo in Algorithm::timed_by_bench().map(Algorithm::name) {
        let r = &v[algo];
        let f = |k: &str| r[k].as_f64().map_or("—".to_string(), |x| format!("{x:.0}"));
        s.push_str(&format!(
            "{algo:<20} {:>16} {:>14} {:>14} {:>20}\n",
            f("interpreted_f64"),
            f("generated_f64"),
            f("generated_f32"),
            f("generated_f64_batch")
        ));
    }
    s
}
