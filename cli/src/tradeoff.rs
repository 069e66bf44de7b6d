//! `embedyn tradeoff`: what each modelling choice costs and buys on the user's own model. For every
//! variant — scalar f64 | f32 × rotors exact | reflected (the latter where the model has geared rotors) —
//! the generated `aba`'s median time per call and the relative error of its independent accelerations
//! against the exact model evaluated in double-double, over the same random consistent states.

use super::runner::{build_runner, run, runner_algorithms, RowShape};
use super::CliError;
use crate::bench::BenchError;
use crate::sampling::consistent_states;
use embedyn_codegen::{geared_rotors, Algorithm, GenerateOptions, Loaded, ModelOptions, Rotors};
use embedyn_runtime::random::SplitMix64;
use embedyn_runtime::{aba, relative_error, DoubleDouble, Model, Workspace};
use serde::Serialize;
use serde_json::Value;

/// States each variant is evaluated on.
pub const STATES: usize = 64;

/// One measured variant.
#[derive(Clone, Debug, Serialize)]
pub struct Variant {
    /// Always `generated`: the code a user would ship.
    pub engine: &'static str,
    /// `f64` or `f32`.
    pub scalar: &'static str,
    /// `exact` or `reflected`.
    pub rotors: &'static str,
    /// Median ns per call of the generated `aba`.
    pub aba_ns: f64,
    /// The largest relative error of the independent accelerations over the states, against the exact
    /// model in double-double (max|a − b| / max(1, max|b|)).
    pub rel_error: f64,
}

/// [`tradeoff`]'s result.
#[derive(Clone, Debug, Serialize)]
pub struct Tradeoff {
    /// The model's name.
    pub model: String,
    /// The variants measured, exact f64 first.
    pub variants: Vec<Variant>,
    /// How many states each variant was evaluated and timed on.
    pub states: usize,
    /// What the errors are measured against.
    pub reference: &'static str,
}

/// Measures every meaningful variant of `loaded` under `options` (its `--lock`s and gravity are kept;
/// its `--rotors` choice is replaced by each choice in turn).
pub fn tradeoff(
    loaded: &Loaded,
    options: &ModelOptions,
    max_compile_memory_mb: u64,
    progress: &mut dyn FnMut(&str),
) -> Result<Tradeoff, CliError> {
    let exact_options = ModelOptions {
        rotors: Rotors::Exact,
        ..options.clone()
    };
    let exact = loaded.model::<f64>(&exact_options)?;
    let exact_dd = loaded.model::<DoubleDouble>(&exact_options)?;
    // States of the exact model; torques on its independent coordinates only, so that the same torques
    // act in every variant (only Xᵀτ acts, and X is the identity on the independent rows).
    let found = consistent_states(&exact, STATES, 0x7ade).map_err(BenchError::NoStates)?;
    let independent = independent_v(&exact);
    let mut rng = SplitMix64::new(0x7ade);
    let states: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = found
        .into_iter()
        .map(|s| {
            let mut tau = vec![0.0; exact.nv()];
            for &i in &independent {
                tau[i] = rng.uniform(-1.0, 1.0);
            }
            (s.q, s.v, tau)
        })
        .collect();
    progress(&format!(
        "reference: the exact model in double-double on {} states",
        states.len()
    ));
    let mut ws_dd = Workspace::new(&exact_dd);
    let dd =
        |x: &[f64]| -> Vec<DoubleDouble> { x.iter().map(|&a| DoubleDouble::from_f64(a)).collect() };
    let reference: Vec<Vec<f64>> = states
        .iter()
        .enumerate()
        .map(|(sample, (q, v, tau))| {
            let qdd = aba(&exact_dd, &mut ws_dd, &dd(q), &dd(v), &dd(tau))
                .map_err(|error| CliError::Dynamics { sample, error })?;
            Ok(independent.iter().map(|&i| qdd[i].to_f64()).collect())
        })
        .collect::<Result<_, CliError>>()?;

    let mut rotor_choices = vec![Rotors::Exact];
    if !geared_rotors(&loaded.robot).is_empty() {
        rotor_choices.push(Rotors::Reflected);
    }
    let mut variants = Vec::new();
    for rotors in rotor_choices {
        let variant_options = ModelOptions {
            rotors,
            ..options.clone()
        };
        let model = loaded.model::<f64>(&variant_options)?;
        // Each state of the exact model restricted to the variant's joints (matched by name: a reflected
        // model keeps exactly the independent joints).
        let (q_of, v_of) = restriction(&exact, &model);
        let rows: Vec<Vec<f64>> = states
            .iter()
            .map(|(q, v, tau)| {
                q_of.iter()
                    .map(|&i| q[i])
                    .chain(v_of.iter().map(|&i| v[i]))
                    .chain(v_of.iter().map(|&i| tau[i]))
                    .collect()
            })
            .collect();
        // The variant's independent coordinates, in the order of the exact model's.
        let variant_independent: Vec<usize> = independent
            .iter()
            .map(|&i| {
                v_of.iter()
                    .position(|&k| k == i)
                    .expect("independent joints are kept")
            })
            .collect();
        progress(&format!(
            "generating and compiling aba with {} rotors ({} coordinates)",
            rotors.as_str(),
            model.nv()
        ));
        let constrained = model.has_constraints();
        let binary = build_runner(
            loaded,
            &GenerateOptions {
                model: variant_options.clone(),
                algorithms: runner_algorithms(&[Algorithm::Aba], constrained),
                exact: true,
                max_compile_memory_mb: Some(max_compile_memory_mb),
                ..Default::default()
            },
        )?;
        let len = model.nv() + usize::from(constrained);
        for scalar in ["f64", "f32"] {
            progress(&format!(
                "timing {scalar} aba with {} rotors",
                rotors.as_str()
            ));
            let outputs = run(&binary, "aba", scalar, RowShape::Eval { len }, &rows)?;
            let rel_error = outputs
                .iter()
                .zip(&reference)
                .map(|(out, want)| {
                    let got: Vec<f64> = variant_independent.iter().map(|&i| out[i]).collect();
                    relative_error(&got, want)
                })
                // NaN (no correct digit, or a refusal the generated code signals by its measure) wins.
                .fold(0.0f64, |m, e| {
                    if e.is_nan() || m.is_nan() {
                        f64::NAN
                    } else {
                        m.max(e)
                    }
                });
            let aba_ns = run(&binary, "aba", scalar, RowShape::Bench, &rows)?
                .first()
                .and_then(|r| r.first().copied())
                .ok_or_else(|| BenchError::NoTime {
                    algorithm: "aba".into(),
                    scalar: scalar.into(),
                })?;
            variants.push(Variant {
                engine: "generated",
                scalar,
                rotors: rotors.as_str(),
                aba_ns,
                rel_error,
            });
        }
    }
    Ok(Tradeoff {
        model: exact.name.clone(),
        variants,
        states: states.len(),
        reference: "the exact model (rotors exact, the same --lock and gravity), interpreted aba in double-double",
    })
}

/// The v indices of `model`'s independent coordinates, in joint order.
fn independent_v(model: &Model<f64>) -> Vec<usize> {
    model
        .independent_joints()
        .iter()
        .flat_map(|&j| {
            let joint = &model.joints[j];
            joint.v_index..joint.v_index + joint.nv()
        })
        .collect()
}

/// For each q and v entry of `variant`, the index of the same coordinate in `exact` (joints matched by
/// name).
fn restriction(exact: &Model<f64>, variant: &Model<f64>) -> (Vec<usize>, Vec<usize>) {
    let (mut q_of, mut v_of) = (Vec::new(), Vec::new());
    for joint in &variant.joints {
        let e = &exact.joints[exact
            .joint_index(&joint.name)
            .expect("a variant keeps a subset of the exact model's joints")];
        q_of.extend(e.q_index..e.q_index + e.nq());
        v_of.extend(e.v_index..e.v_index + e.nv());
    }
    (q_of, v_of)
}

/// A table of the variants, one per line, with each one's time and error relative to exact f64.
pub fn table(t: &Tradeoff) -> String {
    let base = t.variants.first().map_or(f64::NAN, |v| v.aba_ns);
    let mut s = format!(
        "{}: generated aba, {} random consistent states; error of the independent accelerations against {}\n\
         scalar  rotors      ns/call   × exact f64   relative error   correct digits\n",
        t.model, t.states, t.reference
    );
    for v in &t.variants {
        let digits = if v.rel_error.is_nan() {
            "none (NaN)".to_string()
        } else if v.rel_error <= 0.0 {
            "all".to_string()
        } else {
            format!("{:.1}", (-v.rel_error.log10()).max(0.0))
        };
        s.push_str(&format!(
            "{:<7} {:<9} {:>9.0} {:>13.2} {:>16.2e}   {}\n",
            v.scalar,
            v.rotors,
            v.aba_ns,
            v.aba_ns / base,
            v.rel_error,
            digits
        ));
    }
    s
}

/// [`Tradeoff`] as the JSON of CONTRACT §3.
pub fn to_json(t: &Tradeoff) -> Value {
    serde_json::to_value(t).expect("plain data serializes")
}

/// Error against time, log axes, one point per variant: the picture of the trade.
pub fn svg(t: &Tradeoff) -> String {
    use crate::plot::{Marker, Plot, Series};
    let mut plot = Plot::new(
        format!("{}: generated aba, speed against accuracy", t.model),
        "ns per call",
        "relative error of the independent accelerations",
    )
    .log_x()
    .log_y()
    .hline(1e-3, "three correct digits");
    for (k, v) in t.variants.iter().enumerate() {
        let marker = if v.rotors == "exact" {
            Marker::Circle
        } else {
            Marker::Triangle
        };
        plot = plot.series(
            Series::new(
                format!("{} {} rotors", v.scalar, v.rotors),
                vec![(v.aba_ns, v.rel_error)],
            )
            .marker(marker)
            .colour(k + 1),
        );
    }
    plot.to_svg()
}

/// Writes [`svg`] to `path`.
pub fn write_svg(t: &Tradeoff, path: &std::path::Path) -> Result<(), CliError> {
    std::fs::write(path, svg(t)).map_err(|error| CliError::WriteFile {
        path: path.to_path_buf(),
        error,
    })
}
