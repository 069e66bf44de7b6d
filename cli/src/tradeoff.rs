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
    /// Median ns per call of the generated `aba` (`None` where the variant was refused).
    pub aba_ns: Option<f64>,
    /// The largest relative error of the accelerations over the states, against the exact model in
    /// double-double (max|a − b| / max(1, max|b|)): the independent accelerations with exact rotors,
    /// the model's own coordinates with reflected rotors. `None` where the variant was refused or an
    /// answer was not a number.
    pub rel_error: Option<f64>,
    /// Why the variant could not be built (a constant that does not fit f32, …).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
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

/// A state of the exact model: q, v and τ over its spanning coordinates.
type State = (Vec<f64>, Vec<f64>, Vec<f64>);

/// Measures every meaningful variant of `loaded` under `options` (its `--lock`s and gravity are kept;
/// its `--rotors` choice is replaced by each choice in turn).
pub fn tradeoff(
    loaded: &Loaded,
    options: &ModelOptions,
    max_compile_memory_mb: u64,
    progress: &mut dyn FnMut(&str),
) -> Result<Tradeoff, CliError> {
    let mut rotor_choices = vec![Rotors::Exact];
    if !geared_rotors(&loaded.robot).is_empty() {
        rotor_choices.push(Rotors::Reflected);
    }
    let options_with = |rotors| ModelOptions {
        rotors,
        ..options.clone()
    };
    let exact = loaded.model::<f64>(&options_with(Rotors::Exact))?;
    let exact_dd = loaded.model::<DoubleDouble>(&options_with(Rotors::Exact))?;
    let models: Vec<Model<f64>> = rotor_choices
        .iter()
        .map(|&r| loaded.model::<f64>(&options_with(r)))
        .collect::<Result<_, _>>()?;
    // States of the exact model, with torques on the coordinates every variant keeps, so that the same
    // torques act in each (a reflected model lacks the rotors' joints; in the exact model only Xᵀτ acts).
    let found = consistent_states(&exact, STATES, 0x7ade).map_err(BenchError::NoStates)?;
    let restrictions: Vec<(Vec<usize>, Vec<usize>)> =
        models.iter().map(|m| restriction(&exact, m)).collect();
    let shared: Vec<usize> = (0..exact.nv())
        .filter(|i| restrictions.iter().all(|(_, v_of)| v_of.contains(i)))
        .collect();
    let mut rng = SplitMix64::new(0x7ade);
    let states: Vec<State> = found
        .into_iter()
        .map(|s| {
            let mut tau = vec![0.0; exact.nv()];
            for &i in &shared {
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
    // The exact accelerations over all spanning coordinates (they satisfy the constraints).
    let reference: Vec<Vec<f64>> = states
        .iter()
        .enumerate()
        .map(|(sample, (q, v, tau))| {
            let qdd = aba(&exact_dd, &mut ws_dd, &dd(q), &dd(v), &dd(tau))
                .map_err(|error| CliError::Dynamics { sample, error })?;
            Ok(qdd.iter().map(|x| x.to_f64()).collect())
        })
        .collect::<Result<_, CliError>>()?;

    let independent: Vec<usize> = exact.independent_coordinates().collect();
    let mut variants = Vec::new();
    for ((rotors, model), (q_of, v_of)) in rotor_choices.into_iter().zip(&models).zip(&restrictions)
    {
        // What is compared, as (index in the variant's qdd, index in the exact model's): the
        // independent accelerations with exact rotors; every coordinate of the reflected model.
        let compared: Vec<(usize, usize)> = if rotors == Rotors::Exact {
            independent.iter().map(|&i| (i, i)).collect()
        } else {
            v_of.iter().copied().enumerate().collect()
        };
        variants.extend(measure_variant(
            loaded,
            &options_with(rotors),
            model,
            (q_of, v_of),
            &compared,
            &states,
            &reference,
            max_compile_memory_mb,
            progress,
        )?);
    }
    Ok(Tradeoff {
        model: exact.name.clone(),
        variants,
        states: states.len(),
        reference: "the exact model (rotors exact, the same --lock and gravity), interpreted aba in double-double",
    })
}

/// Generates, times and checks one rotor choice's `aba` in f64 and f32 (f32 reported as refused when the
/// model's constants do not fit it).
#[allow(clippy::too_many_arguments)]
fn measure_variant(
    loaded: &Loaded,
    options: &ModelOptions,
    model: &Model<f64>,
    (q_of, v_of): (&[usize], &[usize]),
    compared: &[(usize, usize)],
    states: &[State],
    reference: &[Vec<f64>],
    max_compile_memory_mb: u64,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Variant>, CliError> {
    let rotors = options.rotors.as_str();
    // Each state of the exact model restricted to the variant's joints (matched by name).
    let rows: Vec<Vec<f64>> = states
        .iter()
        .map(|(q, v, tau)| {
            q_of.iter()
                .map(|&i| q[i])
                .chain(v_of.iter().map(|&i| v[i]))
                .chain(v_of.iter().map(|&i| tau[i]))
                // The runner's second configuration (no function of `tradeoff` reads it).
                .chain(q_of.iter().map(|&i| q[i]))
                .collect()
        })
        .collect();
    let f32_refusal = loaded.model::<f32>(options).err().map(|e| e.to_string());
    progress(&format!(
        "generating and compiling aba with {rotors} rotors ({} coordinates)",
        model.nv()
    ));
    let constrained = model.has_constraints();
    let binary = build_runner(
        loaded,
        &GenerateOptions {
            model: options.clone(),
            algorithms: runner_algorithms(&[Algorithm::Aba], constrained),
            exact: true,
            max_compile_memory_mb: Some(max_compile_memory_mb),
            f32: f32_refusal.is_none(),
            ..Default::default()
        },
    )?;
    let len = model.nv() + usize::from(constrained);
    let mut variants = Vec::new();
    for scalar in ["f64", "f32"] {
        if let (Some(why), "f32") = (&f32_refusal, scalar) {
            progress(&format!("f32 with {rotors} rotors refused: {why}"));
            variants.push(Variant {
                engine: "generated",
                scalar,
                rotors,
                aba_ns: None,
                rel_error: None,
                refused: Some(why.clone()),
            });
            continue;
        }
        progress(&format!("timing {scalar} aba with {rotors} rotors"));
        let outputs = run(&binary, "aba", scalar, RowShape::Eval { len }, &rows)?;
        let rel_error = outputs
            .iter()
            .zip(reference)
            .map(|(out, reference)| {
                let (got, want): (Vec<f64>, Vec<f64>) = compared
                    .iter()
                    .map(|&(k, i)| (out[k], reference[i]))
                    .unzip();
                relative_error(&got, &want)
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
            rotors,
            aba_ns: Some(aba_ns),
            rel_error: (!rel_error.is_nan()).then_some(rel_error),
            refused: None,
        });
    }
    Ok(variants)
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
    let base = t
        .variants
        .first()
        .and_then(|v| v.aba_ns)
        .unwrap_or(f64::NAN);
    let mut s = format!(
        "{}: generated aba, {} random consistent states; error of the accelerations against {}\n\
         scalar  rotors      ns/call   × exact f64   relative error   correct digits\n",
        t.model, t.states, t.reference
    );
    for v in &t.variants {
        let (Some(ns), rel_error) = (v.aba_ns, v.rel_error) else {
            s.push_str(&format!(
                "{:<7} {:<9} refused: {}\n",
                v.scalar,
                v.rotors,
                v.refused.as_deref().unwrap_or("")
            ));
            continue;
        };
        let (error, digits) = match rel_error {
            None => ("NaN".to_string(), "none".to_string()),
            Some(e) if e <= 0.0 => ("0".to_string(), "all".to_string()),
            Some(e) => (format!("{e:.2e}"), format!("{:.1}", (-e.log10()).max(0.0))),
        };
        s.push_str(&format!(
            "{:<7} {:<9} {:>9.0} {:>13.2} {:>16}   {}\n",
            v.scalar,
            v.rotors,
            ns,
            ns / base,
            error,
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
                // A refused or NaN variant is left out (the plot counts it under the figure).
                vec![(
                    v.aba_ns.unwrap_or(f64::NAN),
                    v.rel_error.unwrap_or(f64::NAN),
                )],
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
