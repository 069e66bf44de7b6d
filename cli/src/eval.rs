//! `embedyn eval`: ABA, RNEA, generalized gravity, nonlinear effects, CRBA, `integrate` or `difference` on
//! every sample.

use super::runner::RowShape;
use super::samples::Samples;
use super::{Algo, CliError, Engine, Scalar, StateProblem};
use embedyn_codegen::{Loaded, ModelOptions};
use embedyn_runtime::constraints::{constraint_violation, singularity_threshold};
use embedyn_runtime::nalgebra;
use embedyn_runtime::{
    aba, crba, difference, embedding_map, gravity, integrate, nle, reduced_mass_matrix, rnea,
    DynamicsError, JointType, Model, Real, Workspace,
};
use serde::Serialize;

/// What `eval` prints: `{"joints": [names], "samples": [...]}`, one output per input sample.
#[derive(Serialize)]
pub struct Evaluated {
    joints: Vec<String>,
    samples: Vec<Output>,
}

/// One sample's output (the algorithm's fields, without a tag).
#[derive(Serialize)]
#[serde(untagged)]
enum Output {
    Aba {
        qdd: Vec<f64>,
        qdd_independent: Vec<f64>,
    },
    /// `rnea`, `gravity`, `nle`: joint forces on the spanning tree and their projection `Xᵀ τ`.
    Torques {
        tau: Vec<f64>,
        tau_independent: Vec<f64>,
    },
    Crba {
        #[serde(rename = "M")]
        m: Vec<Vec<f64>>,
    },
    /// `integrate`: `q ⊕ v`.
    Integrated { q: Vec<f64> },
    /// `difference`: `q1 ⊖ q`.
    Difference { v: Vec<f64> },
}

/// Whether the algorithm works on the configuration space (`integrate`, `difference`): on the spanning
/// tree's coordinates as given, which need not satisfy the constraints.
fn on_configuration_space(algo: Algo) -> bool {
    matches!(algo, Algo::Integrate | Algo::Difference)
}

/// Whether the algorithm's output is a generalized force (`rnea`, `gravity`, `nle`), reported as `tau` on
/// the spanning tree's joints and `tau_independent` = `Xᵀ τ`.
fn gives_torques(algo: Algo) -> bool {
    matches!(algo, Algo::Rnea | Algo::Gravity | Algo::Nle)
}

/// Whether the algorithm reads a velocity (`v` of the sample; else the state is at rest).
fn reads_velocity(algo: Algo) -> bool {
    algo.spec().inputs.iter().any(|input| input.name == "v")
}

impl Evaluated {
    fn new<T: Real>(model: &Model<T>, samples: Vec<Output>) -> Self {
        let joints = model.joints.iter().map(|j| j.name.clone()).collect();
        Evaluated { joints, samples }
    }
}

/// `embedyn eval` on the samples of `input`; `max_compile_memory_mb` is the generated engine's limit
/// (`--max-compile-memory`).
pub fn eval(
    loaded: &Loaded,
    options: &ModelOptions,
    algo: Algo,
    engine: Engine,
    scalar: Scalar,
    input: &str,
    max_compile_memory_mb: u64,
) -> Result<Evaluated, CliError> {
    // Consistency with the constraints is judged in f64 whatever the scalar (1e-9 is below f32's
    // resolution of typical angles).
    let model64 = loaded.model::<f64>(options)?;
    // Only the fields the algorithm uses are read, at the lengths the model needs.
    // The sample's fields are the function's inputs (its descriptor's).
    let nv = model64.nv();
    let dims = embedyn_codegen::algorithm::Dims::of(&model64);
    let request: Vec<(&'static str, usize)> = algo
        .spec()
        .inputs
        .iter()
        .map(|input| (input.name, input.len.len(&dims)))
        .collect();
    let samples = Samples::parse(input, &request)?;
    if model64.has_constraints() && !on_configuration_space(algo) {
        let mut ws = Workspace::new(&model64);
        let zero = vec![0.0; nv];
        for i in 0..samples.len() {
            let q = samples.vector(i, "q")?;
            // `v` must satisfy the velocity constraints where the algorithm reads one (`nle` too).
            let v = if reads_velocity(algo) {
                samples.vector(i, "v")?
            } else {
                &zero[..]
            };
            check_consistent(&model64, &mut ws, q, v, i)?;
        }
    }
    if engine == Engine::Generated {
        // Before anything is compiled.
        samples.check_all()?;
        return eval_generated(
            loaded,
            options,
            &model64,
            algo,
            scalar,
            &samples,
            max_compile_memory_mb,
        );
    }
    match scalar {
        Scalar::F64 => eval_in::<f64>(&model64, algo, &samples),
        Scalar::F32 => eval_in::<f32>(&loaded.model(options)?, algo, &samples),
    }
}

/// `--engine generated`: the same samples through the compiled generated code; the independent-coordinate
/// projections (for couplings) use the model's embedding map, as the interpreted engine does.
fn eval_generated(
    loaded: &Loaded,
    options: &ModelOptions,
    model: &Model<f64>,
    algo: Algo,
    scalar: Scalar,
    samples: &Samples,
    max_compile_memory_mb: u64,
) -> Result<Evaluated, CliError> {
    // The function and scalar asked for only: a fraction of the compile time and memory, and a model
    // whose constants do not fit f32 can still be evaluated in f64.
    // What the command reports for a model with constraints may be another function's (`crba`: Xᵀ M X).
    let algorithms = super::runner::runner_algorithms(&[algo], model.has_constraints());
    let gen_options = embedyn_codegen::GenerateOptions {
        model: options.clone(),
        algorithms,
        exact: true,
        f64: scalar == Scalar::F64,
        f32: scalar == Scalar::F32,
        max_compile_memory_mb: Some(max_compile_memory_mb),
        ..Default::default()
    };
    let (nq, nv) = (model.nq(), model.nv());
    let mut rows = Vec::with_capacity(samples.len());
    // The runner reads `q`, two `NV`-vectors and a second configuration per sample: the function's
    // inputs after `q` (its descriptor's) in their slots, zeros for those it does not have.
    use embedyn_codegen::algorithm::Dim;
    let inputs = &algo.spec().inputs[1..];
    let vectors = inputs.iter().filter(|i| i.len == Dim::Nv).count();
    let configurations = inputs.iter().filter(|i| i.len == Dim::Nq).count();
    if vectors > 2 || configurations > 1 || vectors + configurations != inputs.len() {
        return Err(not_evaluated(algo));
    }
    for i in 0..samples.len() {
        let mut row = samples.vector(i, "q")?.to_vec();
        check_quaternions(model, &row, i)?;
        // Finite in f64 but not in the scalar (1e308 as f32): refused as the interpreted engine refuses
        // it, naming the entry, rather than reported later as whatever the generated code makes of inf.
        if scalar == Scalar::F32 {
            fits::<f32>("q", &row, i)?;
        }
        let mut second = vec![0.0; nq];
        for input in inputs {
            let x = samples.vector(i, input.name)?;
            if scalar == Scalar::F32 {
                fits::<f32>(input.name, x, i)?;
            }
            if input.len == Dim::Nq {
                check_quaternions(model, x, i)?;
                second.copy_from_slice(x);
            } else {
                row.extend_from_slice(x);
            }
        }
        row.resize(nq + 2 * nv, 0.0);
        row.extend_from_slice(&second);
        rows.push(row);
    }
    // (Built once every sample is known to be evaluable.)
    let binary = super::runner::build_runner(loaded, &gen_options)?;
    let name = algo.name();
    let scalar_name = match scalar {
        Scalar::F64 => "f64",
        Scalar::F32 => "f32",
    };
    // What one output row holds; the runner's output is checked against it (count and length).
    let len = match algo {
        Algo::Aba if model.has_constraints() => nv + 1,
        Algo::Aba => nv,
        a if gives_torques(a) => nv,
        Algo::Crba if model.has_constraints() => model.independent_nv().pow(2) + 1,
        Algo::Crba => nv * nv,
        Algo::Integrate => nq,
        Algo::Difference => nv,
        other => return Err(not_evaluated(other)),
    };
    let outputs = super::runner::run(&binary, name, scalar_name, RowShape::Eval { len }, &rows)?;
    let mut ws = Workspace::new(model);
    let mut model32 = match scalar {
        Scalar::F32 if gives_torques(algo) && model.has_constraints() => {
            let m32 = loaded.model::<f32>(options)?;
            let ws32 = Workspace::new(&m32);
            Some((m32, ws32))
        }
        _ => None,
    };
    let independent = independent_indices(model);
    let mut out = Vec::with_capacity(outputs.len());
    for (i, (o, row)) in outputs.iter().zip(&rows).enumerate() {
        let mut o = o.clone();
        if algo
            .reported_by(model.has_constraints())
            .spec()
            .returns_value(model.has_constraints())
        {
            // The generated `aba` and `crba_independent` also return the singularity measure cond₁(Y1);
            // refuse where the interpreted engine does, by the same threshold for the scalar (NaN counts
            // as singular).
            let condition = o.pop().unwrap_or(f64::NAN);
            let threshold = match scalar {
                Scalar::F64 => singularity_threshold::<f64>(),
                Scalar::F32 => singularity_threshold::<f32>(),
            };
            if condition.is_nan() || condition >= threshold {
                return Err(CliError::State {
                    sample: i,
                    problem: StateProblem::Singular {
                        condition,
                        threshold,
                        scalar: scalar_name,
                    },
                });
            }
        }
        // Named as the output is in the JSON, as the interpreted engine names it.
        let output = match algo {
            Algo::Aba => "qdd",
            a if gives_torques(a) => "tau",
            Algo::Crba => "M",
            Algo::Integrate => "q",
            Algo::Difference => "v",
            _ => name,
        };
        let o = finite(&o, i, output)?;
        let q = &row[..nq];
        out.push(match algo {
            Algo::Aba => Output::Aba {
                qdd_independent: independent.iter().map(|&k| o[k]).collect(),
                qdd: o,
            },
            a if gives_torques(a) => {
                // Xᵀ τ with X in the scalar asked for, so that the singularity verdict is that scalar's.
                let tau_independent: Vec<f64> = match model32.as_mut() {
                    Some((m32, ws32)) if model.has_constraints() => project(m32, ws32, q, &o, i)?,
                    _ if model.has_constraints() => project(model, &mut ws, q, &o, i)?,
                    _ => o.clone(),
                };
                let tau_independent = finite(&tau_independent, i, "tau_independent")?;
                Output::Torques {
                    tau: o,
                    tau_independent,
                }
            }
            Algo::Crba => {
                // Xᵀ M X for a model with constraints (the generated `crba_independent`).
                let n = if model.has_constraints() {
                    model.independent_nv()
                } else {
                    nv
                };
                let m = nalgebra::DMatrix::from_row_slice(n, n, &o);
                Output::Crba {
                    m: (0..n)
                        .map(|r| (0..n).map(|c| m[(r, c)]).collect())
                        .collect(),
                }
            }
            Algo::Integrate => Output::Integrated { q: o },
            Algo::Difference => Output::Difference { v: o },
            other => return Err(not_evaluated(other)),
        });
    }
    Ok(Evaluated::new(model, out))
}

/// `Xᵀ τ` (the generalized force on the independent coordinates) with `X` of `model` at `q`.
fn project<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    tau: &[f64],
    sample: usize,
) -> Result<Vec<f64>, CliError> {
    let q = cast::<T>(q);
    let x = embedding_map(model, ws, &q).map_err(|e| CliError::Dynamics { sample, error: e })?;
    Ok((0..x.ncols())
        .map(|c| (0..tau.len()).map(|r| x[(r, c)].to_f64() * tau[r]).sum())
        .collect())
}

/// Every entry of `x` is finite once converted to `T` (what the interpreted engine's input check finds
/// after [`cast`]), else the same error.
fn fits<T: Real>(name: &'static str, x: &[f64], sample: usize) -> Result<(), CliError> {
    for (index, &value) in x.iter().enumerate() {
        let converted = T::from_f64(value).to_f64();
        if !converted.is_finite() {
            return Err(CliError::Dynamics {
                sample,
                error: DynamicsError::NonFiniteInput {
                    name,
                    index,
                    value: converted,
                },
            });
        }
    }
    Ok(())
}

/// v indices of the independent joints, in joint order.
pub(super) fn independent_indices<T: Real>(model: &Model<T>) -> Vec<usize> {
    model
        .independent_joints()
        .iter()
        .flat_map(|&j| {
            let joint = &model.joints[j];
            joint.v_index..joint.v_index + joint.nv()
        })
        .collect()
}

fn eval_in<T: Real>(
    model: &Model<T>,
    algo: Algo,
    samples: &Samples,
) -> Result<Evaluated, CliError> {
    let mut ws = Workspace::new(model);
    let independent = independent_indices(model);
    let pick = |x: &[f64]| -> Vec<f64> { independent.iter().map(|&i| x[i]).collect() };
    let mut out = Vec::with_capacity(samples.len());
    for i in 0..samples.len() {
        let at = |e: DynamicsError| CliError::Dynamics {
            sample: i,
            error: e,
        };
        let q = samples.vector(i, "q")?;
        check_quaternions(model, q, i)?;
        let q = cast::<T>(q);
        let v = || samples.vector(i, "v").map(cast::<T>);
        let value = match algo {
            Algo::Aba => {
                let v = v()?;
                let tau = cast::<T>(samples.vector(i, "tau")?);
                let qdd = finite(aba(model, &mut ws, &q, &v, &tau).map_err(at)?, i, "qdd")?;
                Output::Aba {
                    qdd_independent: pick(&qdd),
                    qdd,
                }
            }
            a if gives_torques(a) => {
                let tau = match a {
                    Algo::Rnea => {
                        let qdd = cast::<T>(samples.vector(i, "qdd")?);
                        rnea(model, &mut ws, &q, &v()?, &qdd)
                    }
                    Algo::Nle => nle(model, &mut ws, &q, &v()?),
                    Algo::Gravity => gravity(model, &mut ws, &q),
                    other => return Err(not_evaluated(other)),
                };
                let tau = finite(tau.map_err(at)?, i, "tau")?;
                let tau_independent: Vec<f64> = if model.has_constraints() {
                    // Only Xᵀ τ acts on the independent coordinates.
                    let x = embedding_map(model, &mut ws, &q).map_err(at)?;
                    (0..x.ncols())
                        .map(|c| (0..tau.len()).map(|r| x[(r, c)].to_f64() * tau[r]).sum())
                        .collect()
                } else {
                    tau.clone()
                };
                let tau_independent = finite(&tau_independent, i, "tau_independent")?;
                Output::Torques {
                    tau,
                    tau_independent,
                }
            }
            Algo::Crba => {
                let m = if model.has_constraints() {
                    reduced_mass_matrix(model, &mut ws, &q).map_err(at)?
                } else {
                    crba(model, &mut ws, &q).map_err(at)?.clone()
                };
                let n = m.nrows();
                let flat: Vec<T> = m.iter().copied().collect();
                finite(&flat, i, "M")?;
                let rows: Vec<Vec<f64>> = (0..n)
                    .map(|r| (0..n).map(|c| m[(r, c)].to_f64()).collect())
                    .collect();
                Output::Crba { m: rows }
            }
            Algo::Integrate => {
                let mut q_out = vec![T::zero(); model.nq()];
                integrate(model, &q, &v()?, &mut q_out).map_err(at)?;
                Output::Integrated {
                    q: finite(&q_out, i, "q")?,
                }
            }
            Algo::Difference => {
                let q1 = samples.vector(i, "q1")?;
                check_quaternions(model, q1, i)?;
                let mut v_out = vec![T::zero(); model.nv()];
                difference(model, &q, &cast::<T>(q1), &mut v_out).map_err(at)?;
                Output::Difference {
                    v: finite(&v_out, i, "v")?,
                }
            }
            other => return Err(not_evaluated(other)),
        };
        out.push(value);
    }
    Ok(Evaluated::new(model, out))
}

/// docs/conventions.md: `q` and `v` must satisfy the constraints to 1e-9 (`embedyn complete` makes them so).
fn check_consistent(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    q: &[f64],
    v: &[f64],
    i: usize,
) -> Result<(), CliError> {
    let (pos, vel) = constraint_violation(model, ws, q, v).map_err(|e| CliError::Dynamics {
        sample: i,
        error: e,
    })?;
    if pos > 1e-9 {
        return Err(CliError::State {
            sample: i,
            problem: StateProblem::PositionViolation { violation: pos },
        });
    }
    if vel > 1e-9 {
        return Err(CliError::State {
            sample: i,
            problem: StateProblem::VelocityViolation { violation: vel },
        });
    }
    Ok(())
}

fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

/// The result as f64, or an error if any entry is not finite (never a silent NaN).
fn finite<T: Real>(x: &[T], sample: usize, name: &'static str) -> Result<Vec<f64>, CliError> {
    let y: Vec<f64> = x.iter().map(|v| v.to_f64()).collect();
    match y.iter().position(|v| !v.is_finite()) {
        None => Ok(y),
        Some(k) => Err(CliError::State {
            sample,
            problem: StateProblem::NotFinite {
                output: name,
                index: k,
                value: y[k],
            },
        }),
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
            return Err(CliError::State {
                sample,
                problem: StateProblem::NotUnitQuaternion {
                    joint: j.name.clone(),
                    start: j.q_index + 3,
                    end: j.q_index + 7,
                    norm: n,
                },
            });
        }
    }
    Ok(())
}

/// An algorithm the command line does not evaluate (`--algo` offers only those with a command-line entry
/// in their descriptor).
fn not_evaluated(algo: Algo) -> CliError {
    CliError::NotEvaluated { algorithm: algo }
}
