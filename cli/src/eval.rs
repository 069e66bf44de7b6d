//! `embedyn eval`: ABA, RNEA, generalized gravity, nonlinear effects (the three with external wrenches),
//! CRBA, `integrate`, `difference`, a frame's Jacobian, the centre of mass or the centroidal momentum on
//! every sample.

use super::runner::RowShape;
use super::samples::{Extras, Samples, Wrench, F_EXT};
use super::{
    Algo, CliError, Engine, EvalAlgo, InternalError, Reference, SampleProblem, Scalar,
    StateProblem, WrenchPartProblem,
};
use embedyn_codegen::{Loaded, ModelOptions};
use embedyn_runtime::constraints::{constraint_violation, singularity_threshold};
use embedyn_runtime::nalgebra::{DMatrix, Matrix3xX, Matrix6xX, Vector3};
use embedyn_runtime::{
    aba_derivatives, aba_derivatives_independent, aba_ext, center_of_mass, centroidal_momentum,
    centroidal_momentum_matrix, com_jacobian, crba, difference, embedding_map, forward_kinematics,
    forward_kinematics_acceleration, frame_classical_acceleration, frame_jacobian, gravity,
    integrate, nle_ext, reduced_mass_matrix, rnea_derivatives, rnea_ext, AbaDerivatives,
    DerivativeWorkspace, DynamicsError, FrameId, JointType, LinkWrench, ManifoldDerivatives, Model,
    Real, RneaDerivatives, Workspace,
};
use serde::Serialize;
use std::ops::Range;

/// What `eval` is asked: the algorithm and, for `jacobian`, the frame and the reference.
pub struct Query {
    algo: EvalAlgo,
    frame: Option<String>,
    reference: Reference,
}

impl Query {
    /// The query, if the options fit the algorithm: `--frame` for `jacobian` and for nothing else,
    /// `--reference` only with it (usage errors).
    pub fn new(
        algo: EvalAlgo,
        frame: Option<String>,
        reference: Option<Reference>,
    ) -> Result<Query, CliError> {
        let bad = |option, message: String| CliError::BadOption { option, message };
        match (algo, &frame, reference) {
            (EvalAlgo::Jacobian, None, _) => Err(bad(
                "--frame",
                "`--algo jacobian` needs the frame: --frame LINK (a link of the model file; `embedyn info` lists them under `frames`)".into(),
            )),
            (EvalAlgo::Jacobian, Some(_), _) => Ok(()),
            (other, Some(_), _) => Err(bad(
                "--frame",
                format!("only `--algo jacobian` takes a frame, not `--algo {}`", other.name()),
            )),
            (other, None, Some(_)) => Err(bad(
                "--reference",
                format!("only `--algo jacobian` takes a reference, not `--algo {}`", other.name()),
            )),
            (_, None, None) => Ok(()),
        }?;
        Ok(Query {
            algo,
            frame,
            reference: reference.unwrap_or_default(),
        })
    }

    /// The frame of `--frame` in `model` (a usage error if the model has no such link).
    fn frame<T: Real>(&self, model: &Model<T>) -> Result<Option<FrameId>, CliError> {
        let Some(name) = &self.frame else {
            return Ok(None);
        };
        match model.frame(name) {
            Some(frame) => Ok(Some(frame)),
            None => {
                let names = model.frames().filter_map(|f| model.frame_name(f));
                let suggestions = super::suggest::close_names(name, names);
                Err(CliError::BadOption {
                    option: "--frame",
                    message: format!(
                        "the model has no link {}{}",
                        embedyn_codegen::names::fenced(&embedyn_codegen::shortened(name)),
                        match suggestions.is_empty() {
                            true => " (`embedyn info` lists the links under `frames`)".to_string(),
                            false => super::suggest::did_you_mean(&suggestions),
                        }
                    ),
                })
            }
        }
    }
}

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
    /// `jacobian`: rows linear then angular, columns in `v` order; the bias with `v`; `J X` for a model
    /// with constraints.
    Jacobian {
        #[serde(rename = "J_linear")]
        j_linear: Vec<Vec<f64>>,
        #[serde(rename = "J_angular")]
        j_angular: Vec<Vec<f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        bias_linear: Option<Vec<f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        bias_angular: Option<Vec<f64>>,
        #[serde(
            rename = "J_linear_independent",
            skip_serializing_if = "Option::is_none"
        )]
        j_linear_independent: Option<Vec<Vec<f64>>>,
        #[serde(
            rename = "J_angular_independent",
            skip_serializing_if = "Option::is_none"
        )]
        j_angular_independent: Option<Vec<Vec<f64>>>,
    },
    /// `com`: the centre of mass, its Jacobian, its velocity with `v`, `J_com X` for a model with
    /// constraints.
    Com {
        com: Vec<f64>,
        #[serde(rename = "J_com")]
        j_com: Vec<Vec<f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        vcom: Option<Vec<f64>>,
        #[serde(rename = "J_com_independent", skip_serializing_if = "Option::is_none")]
        j_com_independent: Option<Vec<Vec<f64>>>,
    },
    /// `centroidal`: `A_g` (rows linear then angular), `h_g = A_g v` (linear then angular), `A_g X` for a
    /// model with constraints. (Ȧ_g v is the library's `centroidal_momentum_rate` and the generated
    /// `centroidal_bias`; CONTRACT §3's `centroidal` reports `A_g` and `h_g`.)
    Centroidal {
        #[serde(rename = "A_g")]
        a_g: Vec<Vec<f64>>,
        h_g: Vec<f64>,
        #[serde(rename = "A_g_independent", skip_serializing_if = "Option::is_none")]
        a_g_independent: Option<Vec<Vec<f64>>>,
    },
    /// `aba_derivatives`: `q̈` and its derivatives over the spanning tree (rows `q̈ᵢ`, columns directions in
    /// `v` order; `∂/∂q` in the tangent space); for a model with constraints also those of the independent
    /// accelerations along the constraint manifold.
    AbaDerivatives {
        qdd: Vec<f64>,
        dqdd_dq: Vec<Vec<f64>>,
        dqdd_dv: Vec<Vec<f64>>,
        dqdd_dtau: Vec<Vec<f64>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        dqdd_independent_dq_independent: Option<Vec<Vec<f64>>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        dqdd_independent_dv_independent: Option<Vec<Vec<f64>>>,
        #[serde(skip_serializing_if = "Option::is_none")]
        dqdd_independent_dtau: Option<Vec<Vec<f64>>>,
    },
    /// `rnea_derivatives`: `τ` and its derivatives (`∂τ/∂q̈ = M`).
    RneaDerivatives {
        tau: Vec<f64>,
        dtau_dq: Vec<Vec<f64>>,
        dtau_dv: Vec<Vec<f64>>,
        dtau_dqdd: Vec<Vec<f64>>,
    },
}

/// Whether the algorithm's samples may carry external wrenches (`f_ext`).
fn takes_wrenches(algo: EvalAlgo) -> bool {
    matches!(
        algo,
        EvalAlgo::Dynamics(Algo::Aba | Algo::Rnea | Algo::Nle)
            | EvalAlgo::AbaDerivatives
            | EvalAlgo::RneaDerivatives
    )
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
    query: &Query,
    engine: Engine,
    scalar: Scalar,
    input: &str,
    max_compile_memory_mb: u64,
) -> Result<Evaluated, CliError> {
    // Consistency with the constraints is judged in f64 whatever the scalar (1e-9 is below f32's
    // resolution of typical angles).
    let model64 = loaded.model::<f64>(options)?;
    let frame = query.frame(&model64)?;
    let samples = read_samples(&model64, options, query, input)?;
    if engine == Engine::Generated {
        // Before anything is compiled.
        samples.check_all()?;
        let plan = Plan::new(&model64, query, &samples)?;
        let wrench_count = plan.wrench_rows.len();
        let rows = generated_rows(&model64, &plan, scalar, &samples, wrench_count)?;
        // (Built once every sample is known to be evaluable.)
        let gen_options = generated_options(options, &plan, scalar, max_compile_memory_mb);
        let binary = super::runner::build_runner(loaded, &gen_options)?;
        return generated_outputs(
            loaded, options, &model64, &plan, scalar, &samples, &rows, &binary,
        );
    }
    match scalar {
        Scalar::F64 => eval_in::<f64>(&model64, query, frame, &samples),
        Scalar::F32 => eval_in::<f32>(&loaded.model(options)?, query, frame, &samples),
    }
}

/// The samples of `input` for `query` on `model`, each state checked against the constraints.
fn read_samples(
    model64: &Model<f64>,
    options: &ModelOptions,
    query: &Query,
    input: &str,
) -> Result<Samples, CliError> {
    // Only the fields the algorithm uses are read, at the lengths the model needs.
    // The sample's fields are the function's inputs (its descriptor's).
    let (nq, nv) = (model64.nq(), model64.nv());
    let dims = embedyn_codegen::algorithm::Dims::of(model64);
    let (request, optional): (Vec<(&'static str, usize)>, &[&'static str]) = match query.algo {
        EvalAlgo::Dynamics(algo) => (
            algo.spec()
                .inputs
                .iter()
                .map(|input| (input.name, input.len.len(&dims)))
                .collect(),
            &[],
        ),
        EvalAlgo::Jacobian | EvalAlgo::Com => (vec![("q", nq), ("v", nv)], &["v"]),
        EvalAlgo::Centroidal => (vec![("q", nq), ("v", nv)], &[]),
        EvalAlgo::AbaDerivatives => (vec![("q", nq), ("v", nv), ("tau", nv)], &[]),
        EvalAlgo::RneaDerivatives => (vec![("q", nq), ("v", nv), ("qdd", nv)], &[]),
    };
    let links: Vec<&str> = model64
        .frames()
        .filter_map(|f| model64.frame_name(f))
        .collect();
    let extras = Extras {
        optional,
        links: takes_wrenches(query.algo).then_some(&links[..]),
    };
    let samples = Samples::parse_with(input, &request, &extras)
        .map_err(|e| e.with_state_hint(model64, options))?;
    let on_configurations = matches!(
        query.algo,
        EvalAlgo::Dynamics(a) if on_configuration_space(a)
    );
    if model64.has_constraints() && !on_configurations {
        let mut ws = Workspace::new(model64);
        let zero = vec![0.0; nv];
        for i in 0..samples.len() {
            let q = samples.vector(i, "q")?;
            // `v` must satisfy the velocity constraints where the algorithm reads one (`nle` too).
            let v = match query.algo {
                EvalAlgo::Dynamics(a) if reads_velocity(a) => samples.vector(i, "v")?,
                EvalAlgo::Dynamics(_) => &zero[..],
                _ => samples.optional_vector(i, "v")?.unwrap_or(&zero[..]),
            };
            check_consistent(model64, &mut ws, q, v, i)?;
        }
    }
    Ok(samples)
}

/// What the generated engine compiles and runs for a query: one generated function, the links it is
/// generated for, and the wrenches' rows.
#[derive(Debug, PartialEq)]
struct Plan {
    /// What the command reports (its outputs' fields).
    algo: EvalAlgo,
    /// The generated function that computes it (`aba_ext` for `aba` with wrenches, `frame` for
    /// `jacobian`, …).
    function: Algo,
    /// The links it is generated for: the wrenches' links, the frame and its reference. Part of the
    /// generated source, hence of the runner's cache key.
    links: embedyn_codegen::LinkOptions,
    /// The runner's name for the function (`frame_<link>` for a frame function).
    arm: String,
    /// For each row of `f_ext`, the link's index among the model's frames (the samples' numbering).
    wrench_rows: Vec<usize>,
    /// Whether the model has constraints.
    constrained: bool,
}

impl Plan {
    /// The plan for `query` on `samples`: the plain function where no sample carries a wrench; else the
    /// one with wrenches, for the union of the links the samples name, in the model's frame order
    /// (links fixed to the world left out: a wrench there moves nothing, as in the interpreted engine).
    fn new(model: &Model<f64>, query: &Query, samples: &Samples) -> Result<Plan, CliError> {
        let frames: Vec<FrameId> = model.frames().collect();
        let name_of = |f: FrameId| model.frame_name(f).unwrap_or_default().to_string();
        let mut plan = Plan {
            algo: query.algo,
            function: Algo::Aba,
            links: embedyn_codegen::LinkOptions::default(),
            arm: String::new(),
            wrench_rows: Vec::new(),
            constrained: model.has_constraints(),
        };
        if takes_wrenches(query.algo) && samples.has_wrenches() {
            let mut rows = Vec::new();
            for i in 0..samples.len() {
                for w in samples.wrenches(i)? {
                    let frame = *frames
                        .get(w.frame)
                        .ok_or(InternalError::SampleNotInInput { sample: i })?;
                    if frame.body.is_some() && !rows.contains(&w.frame) {
                        rows.push(w.frame);
                    }
                }
            }
            rows.sort_unstable();
            plan.links.wrenches = rows.iter().map(|&k| name_of(frames[k])).collect();
            plan.wrench_rows = rows;
        }
        let with_wrenches = !plan.wrench_rows.is_empty();
        plan.function = match query.algo {
            EvalAlgo::Dynamics(algo) if with_wrenches => match algo {
                Algo::Aba => Algo::AbaExt,
                Algo::Rnea => Algo::RneaExt,
                Algo::Nle => Algo::NleExt,
                other => return Err(not_evaluated(other)),
            },
            EvalAlgo::Dynamics(algo) => algo,
            EvalAlgo::Jacobian => {
                let link = query.frame.clone().ok_or(InternalError::FieldNotRead {
                    field: "--frame".into(),
                })?;
                plan.links.reference = query.reference;
                plan.links.frames = vec![link];
                Algo::Frame
            }
            EvalAlgo::Com => Algo::Com,
            EvalAlgo::Centroidal => Algo::Centroidal,
            EvalAlgo::AbaDerivatives | EvalAlgo::RneaDerivatives => {
                // The command's output on a model with constraints adds the manifold derivatives, a
                // second function; the runner runs one function per query.
                if plan.constrained {
                    return Err(CliError::BadOption {
                        option: "--engine",
                        message: format!(
                            "`--algo {}` on a model with loops, couplings or mimic joints is not run through generated code: use `--engine interpreted` (the library's generated `aba_derivatives_independent` gives the manifold derivatives)",
                            query.algo.name()
                        ),
                    });
                }
                match (query.algo, with_wrenches) {
                    (EvalAlgo::AbaDerivatives, false) => Algo::AbaDerivatives,
                    (EvalAlgo::AbaDerivatives, true) => Algo::AbaDerivativesExt,
                    (_, false) => Algo::RneaDerivatives,
                    (_, true) => Algo::RneaDerivativesExt,
                }
            }
        };
        plan.arm = match plan.function {
            Algo::Frame => {
                let links: Vec<&str> = plan.links.frames.iter().map(String::as_str).collect();
                embedyn_codegen::frame_function_names(model, &links)
                    .pop()
                    .unwrap_or_default()
            }
            other => other.name().to_string(),
        };
        Ok(plan)
    }
}

/// Several `eval --engine generated` queries on one model through one runner, built in the cache folder
/// `folder` (else the usual one): the union of the queries' functions, links and scalars (where two
/// queries name wrench links, or two name a reference, they must agree). Each answer is what `eval`
/// prints for its query alone. For tests, which otherwise pay a compile per query.
pub fn eval_generated_together(
    loaded: &Loaded,
    options: &ModelOptions,
    queries: &[(Query, Scalar, &str)],
    folder: Option<&std::path::Path>,
) -> Result<Vec<Evaluated>, CliError> {
    let model64 = loaded.model::<f64>(options)?;
    let constrained = model64.has_constraints();
    let mut gen_options = embedyn_codegen::GenerateOptions {
        model: options.clone(),
        algorithms: Vec::new(),
        exact: true,
        f64: false,
        f32: false,
        max_compile_memory_mb: None,
        ..Default::default()
    };
    let disagree = |what: &str| CliError::BadOption {
        option: "--engine generated",
        message: format!("queries run together must name the same {what}"),
    };
    let mut prepared = Vec::with_capacity(queries.len());
    let mut reference = None;
    for (query, scalar, input) in queries {
        query.frame(&model64)?;
        let samples = read_samples(&model64, options, query, input)?;
        samples.check_all()?;
        let plan = Plan::new(&model64, query, &samples)?;
        for a in super::runner::runner_algorithms(&[plan.function], constrained) {
            if !gen_options.algorithms.contains(&a) {
                gen_options.algorithms.push(a);
            }
        }
        let links = &mut gen_options.links;
        if !plan.links.wrenches.is_empty() {
            if !links.wrenches.is_empty() && links.wrenches != plan.links.wrenches {
                return Err(disagree("wrench links"));
            }
            links.wrenches.clone_from(&plan.links.wrenches);
        }
        for f in &plan.links.frames {
            if !links.frames.contains(f) {
                links.frames.push(f.clone());
            }
            if reference.is_some_and(|r| r != plan.links.reference) {
                return Err(disagree("reference"));
            }
            reference = Some(plan.links.reference);
            links.reference = plan.links.reference;
        }
        gen_options.f64 |= *scalar == Scalar::F64;
        gen_options.f32 |= *scalar == Scalar::F32;
        prepared.push((plan, *scalar, samples));
    }
    let wrench_count = gen_options.links.wrenches.len();
    let mut rows = Vec::with_capacity(prepared.len());
    for (plan, scalar, samples) in &prepared {
        rows.push(generated_rows(
            &model64,
            plan,
            *scalar,
            samples,
            wrench_count,
        )?);
    }
    let binary = super::runner::build_runner_in(loaded, &gen_options, folder)?;
    prepared
        .iter()
        .zip(&rows)
        .map(|((plan, scalar, samples), rows)| {
            generated_outputs(
                loaded, options, &model64, plan, *scalar, samples, rows, &binary,
            )
        })
        .collect()
}

/// What `--engine generated` compiles for `plan`: the function and scalar asked for only (a fraction of
/// the compile time and memory, and a model whose constants do not fit f32 can still be evaluated in
/// f64), with the plan's links; what the command reports for a model with constraints may be another
/// function's (`crba`: Xᵀ M X).
fn generated_options(
    options: &ModelOptions,
    plan: &Plan,
    scalar: Scalar,
    max_compile_memory_mb: u64,
) -> embedyn_codegen::GenerateOptions {
    embedyn_codegen::GenerateOptions {
        model: options.clone(),
        algorithms: super::runner::runner_algorithms(&[plan.function], plan.constrained),
        exact: true,
        f64: scalar == Scalar::F64,
        f32: scalar == Scalar::F32,
        max_compile_memory_mb: Some(max_compile_memory_mb),
        links: plan.links.clone(),
        ..Default::default()
    }
}

/// The runner's input rows for `plan` on `samples`, each checked as the interpreted engine checks its
/// input; `wrench_count` is the runner's number of wrench links (rows end with `f_ext`, zeros on the
/// links a sample puts no wrench on).
fn generated_rows(
    model: &Model<f64>,
    plan: &Plan,
    scalar: Scalar,
    samples: &Samples,
    wrench_count: usize,
) -> Result<Vec<Vec<f64>>, CliError> {
    let function = plan.function;
    let (nq, nv) = (model.nq(), model.nv());
    let frames: Vec<FrameId> = model.frames().collect();
    let mut rows = Vec::with_capacity(samples.len());
    // The runner reads `q`, two `NV`-vectors, a second configuration and, with wrench links, `f_ext` per
    // sample: the function's inputs after `q` (its descriptor's) in their slots, zeros for those it does
    // not have (and for an optional `v` a sample leaves out, and for a link a sample puts no wrench on).
    use embedyn_codegen::algorithm::Dim;
    let inputs = &function.spec().inputs[1..];
    let vectors = inputs.iter().filter(|i| i.len == Dim::Nv).count();
    let configurations = inputs.iter().filter(|i| i.len == Dim::Nq).count();
    let wrench_inputs = inputs.iter().filter(|i| i.len == Dim::WrenchLinks).count();
    if vectors > 2 || configurations > 1 || vectors + configurations + wrench_inputs != inputs.len()
    {
        return Err(not_evaluated(function));
    }
    let zeros = vec![0.0; nv.max(nq)];
    for i in 0..samples.len() {
        let mut row = samples.vector(i, "q")?.to_vec();
        check_quaternions(model, &row, i)?;
        // Finite in f64 but not in the scalar (1e308 as f32): refused as the interpreted engine refuses
        // it, naming the entry, rather than reported later as whatever the generated code makes of inf.
        if scalar == Scalar::F32 {
            fits::<f32>("q", &row, i)?;
        }
        let mut second = vec![0.0; nq];
        let mut f_ext = vec![0.0; 6 * wrench_count];
        for input in inputs {
            if input.len == Dim::WrenchLinks {
                let given = samples.wrenches(i)?;
                if scalar == Scalar::F32 {
                    wrenches::<f64, f32>(model, &frames, given, i)?;
                }
                // Two wrenches on one link add up, as in the interpreted engine.
                for w in given {
                    if let Some(k) = plan.wrench_rows.iter().position(|&r| r == w.frame) {
                        for (j, x) in w.force.iter().chain(&w.torque).enumerate() {
                            f_ext[6 * k + j] += x;
                        }
                    }
                }
                continue;
            }
            let x = match samples.optional_vector(i, input.name)? {
                Some(x) => x,
                None => &zeros[..input.len.len(&embedyn_codegen::algorithm::Dims::of(model))],
            };
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
        row.extend_from_slice(&f_ext);
        rows.push(row);
    }
    Ok(rows)
}

/// The answers of the runner `binary` to `rows` ([`generated_rows`]) for `plan`, as the command prints
/// them; the independent-coordinate projections (for couplings and loops) use the model's embedding map
/// in the scalar asked for, as the interpreted engine does.
#[allow(clippy::too_many_arguments)]
fn generated_outputs(
    loaded: &Loaded,
    options: &ModelOptions,
    model: &Model<f64>,
    plan: &Plan,
    scalar: Scalar,
    samples: &Samples,
    rows: &[Vec<f64>],
    binary: &std::path::Path,
) -> Result<Evaluated, CliError> {
    let constrained = model.has_constraints();
    let function = plan.function;
    let (nq, nv) = (model.nq(), model.nv());
    let scalar_name = match scalar {
        Scalar::F64 => "f64",
        Scalar::F32 => "f32",
    };
    // What one output row holds (the reported function's outputs in order, then the singularity
    // measure it returns); the runner's output is checked against it (count and length).
    let reported = function.reported_by(constrained).spec();
    let dims = embedyn_codegen::algorithm::Dims::of(model);
    let sizes: Vec<usize> = reported
        .outputs
        .iter()
        .map(|o| match o.shape {
            embedyn_codegen::algorithm::Shape::Vector(d) => d.len(&dims),
            embedyn_codegen::algorithm::Shape::Matrix(r, c) => r.len(&dims) * c.len(&dims),
        })
        .collect();
    let returns_value = reported.returns_value(constrained);
    let len = sizes.iter().sum::<usize>() + usize::from(returns_value);
    let outputs = super::runner::run(binary, &plan.arm, scalar_name, RowShape::Eval { len }, rows)?;
    let mut ws = Workspace::new(model);
    // X in the scalar asked for, so that the singularity verdict is that scalar's.
    let mut model32 = match scalar {
        Scalar::F32 if constrained => {
            let m32 = loaded.model::<f32>(options)?;
            let ws32 = Workspace::new(&m32);
            Some((m32, ws32))
        }
        _ => None,
    };
    let mut embedding = |q: &[f64], i: usize| -> Result<DMatrix<f64>, CliError> {
        match model32.as_mut() {
            Some((m32, ws32)) => embedding_f64(m32, ws32, q, i),
            None => embedding_f64(model, &mut ws, q, i),
        }
    };
    let independent: Vec<usize> = model.independent_coordinates().collect();
    let mut out = Vec::with_capacity(outputs.len());
    for (i, (o, row)) in outputs.iter().zip(rows).enumerate() {
        let mut o = o.clone();
        if returns_value {
            // The generated `aba`, `aba_ext` and `crba_independent` also return the singularity measure
            // cond₁(Y1); refuse where the interpreted engine does, by the same threshold for the scalar
            // (NaN counts as singular).
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
        // The outputs, in order.
        let mut parts = Vec::with_capacity(sizes.len());
        let mut start = 0;
        for &n in &sizes {
            parts.push(&o[start..start + n]);
            start += n;
        }
        let q = &row[..nq];
        let x = match (constrained, plan.algo) {
            (true, EvalAlgo::Jacobian | EvalAlgo::Com | EvalAlgo::Centroidal) => {
                Some(embedding(q, i)?)
            }
            _ => None,
        };
        let x = x.as_ref();
        let has_v = samples.optional_vector(i, "v").ok().flatten().is_some();
        let square = |m: &[f64], name| -> Result<Vec<Vec<f64>>, CliError> {
            // `max(1)`: a model without coordinates has 0 × 0 matrices (no rows), not a panic.
            Ok(finite(m, i, name)?
                .chunks(nv.max(1))
                .map(<[f64]>::to_vec)
                .collect())
        };
        out.push(match (plan.algo, &parts[..]) {
            (EvalAlgo::AbaDerivatives, [qdd, dq, dv, dtau]) => Output::AbaDerivatives {
                qdd: finite(qdd, i, "qdd")?,
                dqdd_dq: square(dq, "dqdd_dq")?,
                dqdd_dv: square(dv, "dqdd_dv")?,
                dqdd_dtau: square(dtau, "dqdd_dtau")?,
                dqdd_independent_dq_independent: None,
                dqdd_independent_dv_independent: None,
                dqdd_independent_dtau: None,
            },
            (EvalAlgo::RneaDerivatives, [tau, dq, dv, m]) => Output::RneaDerivatives {
                tau: finite(tau, i, "tau")?,
                dtau_dq: square(dq, "dtau_dq")?,
                dtau_dv: square(dv, "dtau_dv")?,
                dtau_dqdd: square(m, "dtau_dqdd")?,
            },
            (EvalAlgo::Dynamics(Algo::Aba), [qdd]) => {
                let qdd = finite(qdd, i, "qdd")?;
                Output::Aba {
                    qdd_independent: independent.iter().map(|&k| qdd[k]).collect(),
                    qdd,
                }
            }
            (EvalAlgo::Dynamics(a), [tau]) if gives_torques(a) => {
                let tau = finite(tau, i, "tau")?;
                // Xᵀ τ with X in the scalar asked for, so that the singularity verdict is that scalar's.
                let tau_independent: Vec<f64> = match constrained {
                    true => {
                        let x = embedding(q, i)?;
                        (0..x.ncols())
                            .map(|c| (0..tau.len()).map(|r| x[(r, c)] * tau[r]).sum())
                            .collect()
                    }
                    false => tau.clone(),
                };
                let tau_independent = finite(&tau_independent, i, "tau_independent")?;
                Output::Torques {
                    tau,
                    tau_independent,
                }
            }
            (EvalAlgo::Dynamics(Algo::Crba), [m]) => {
                // Xᵀ M X for a model with constraints (the generated `crba_independent`).
                let m = finite(m, i, "M")?;
                let n = if constrained {
                    model.independent_nv()
                } else {
                    nv
                };
                Output::Crba {
                    m: m.chunks(n.max(1)).take(n).map(<[f64]>::to_vec).collect(),
                }
            }
            (EvalAlgo::Dynamics(Algo::Integrate), [q]) => Output::Integrated {
                q: finite(q, i, "q")?,
            },
            (EvalAlgo::Dynamics(Algo::Difference), [v]) => Output::Difference {
                v: finite(v, i, "v")?,
            },
            (EvalAlgo::Jacobian, [_pose, j, bias]) => {
                let get = |r: usize, c: usize| j[r * nv + c];
                let bias = |range: Range<usize>, name| {
                    has_v.then(|| finite(&bias[range], i, name)).transpose()
                };
                Output::Jacobian {
                    j_linear: matrix_rows(get, 0..3, nv, None, i, "J_linear")?,
                    j_angular: matrix_rows(get, 3..6, nv, None, i, "J_angular")?,
                    bias_linear: bias(0..3, "bias_linear")?,
                    bias_angular: bias(3..6, "bias_angular")?,
                    j_linear_independent: x
                        .map(|x| matrix_rows(get, 0..3, nv, Some(x), i, "J_linear_independent"))
                        .transpose()?,
                    j_angular_independent: x
                        .map(|x| matrix_rows(get, 3..6, nv, Some(x), i, "J_angular_independent"))
                        .transpose()?,
                }
            }
            (EvalAlgo::Com, [com, vcom, j]) => {
                let get = |r: usize, c: usize| j[r * nv + c];
                Output::Com {
                    com: finite(com, i, "com")?,
                    j_com: matrix_rows(get, 0..3, nv, None, i, "J_com")?,
                    vcom: has_v.then(|| finite(vcom, i, "vcom")).transpose()?,
                    j_com_independent: x
                        .map(|x| matrix_rows(get, 0..3, nv, Some(x), i, "J_com_independent"))
                        .transpose()?,
                }
            }
            (EvalAlgo::Centroidal, [h_g, a_g]) => {
                let get = |r: usize, c: usize| a_g[r * nv + c];
                Output::Centroidal {
                    a_g: matrix_rows(get, 0..6, nv, None, i, "A_g")?,
                    h_g: finite(h_g, i, "h_g")?,
                    a_g_independent: x
                        .map(|x| matrix_rows(get, 0..6, nv, Some(x), i, "A_g_independent"))
                        .transpose()?,
                }
            }
            _ => return Err(not_evaluated(function)),
        });
    }
    Ok(Evaluated::new(model, out))
}

/// The embedding map `X` of `model` at `q` (in the model's scalar), as f64.
fn embedding_f64<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    sample: usize,
) -> Result<DMatrix<f64>, CliError> {
    let q = cast::<T>(q);
    let x = embedding_map(model, ws, &q).map_err(|e| CliError::Dynamics { sample, error: e })?;
    Ok(x.map(|v| v.to_f64()))
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

fn eval_in<T: Real>(
    model: &Model<T>,
    query: &Query,
    frame: Option<FrameId>,
    samples: &Samples,
) -> Result<Evaluated, CliError> {
    let mut ws = Workspace::new(model);
    let independent: Vec<usize> = model.independent_coordinates().collect();
    let pick = |x: &[f64]| -> Vec<f64> { independent.iter().map(|&i| x[i]).collect() };
    let frames: Vec<FrameId> = model.frames().collect();
    let mut out = Vec::with_capacity(samples.len());
    let algo = match query.algo {
        EvalAlgo::Dynamics(algo) => algo,
        EvalAlgo::AbaDerivatives | EvalAlgo::RneaDerivatives => {
            return derivatives_in(model, query.algo, &frames, samples)
        }
        other => {
            let mut kinematics = Kinematics::new(model, query.reference, frame);
            for i in 0..samples.len() {
                out.push(kinematics.sample(other, samples, i)?);
            }
            return Ok(Evaluated::new(model, out));
        }
    };
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
                let f_ext = wrenches(model, &frames, samples.wrenches(i)?, i)?;
                // (Without wrenches `aba_ext` is `aba`.)
                let qdd = aba_ext(model, &mut ws, &q, &v, &tau, &f_ext);
                let qdd = finite(qdd.map_err(at)?, i, "qdd")?;
                Output::Aba {
                    qdd_independent: pick(&qdd),
                    qdd,
                }
            }
            a if gives_torques(a) => {
                let f_ext = match a {
                    Algo::Rnea | Algo::Nle => wrenches(model, &frames, samples.wrenches(i)?, i)?,
                    _ => Vec::new(),
                };
                let tau = match a {
                    Algo::Rnea => {
                        let qdd = cast::<T>(samples.vector(i, "qdd")?);
                        rnea_ext(model, &mut ws, &q, &v()?, &qdd, &f_ext)
                    }
                    Algo::Nle => nle_ext(model, &mut ws, &q, &v()?, &f_ext),
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

/// `aba_derivatives` or `rnea_derivatives` on every sample (one workspace for all).
fn derivatives_in<T: Real>(
    model: &Model<T>,
    algo: EvalAlgo,
    frames: &[FrameId],
    samples: &Samples,
) -> Result<Evaluated, CliError> {
    let mut dws = DerivativeWorkspace::new(model);
    let mut forward = AbaDerivatives::new(model);
    let mut inverse = RneaDerivatives::new(model);
    let mut manifold = ManifoldDerivatives::new(model);
    let mut out = Vec::with_capacity(samples.len());
    for i in 0..samples.len() {
        let at = |e: DynamicsError| CliError::Dynamics {
            sample: i,
            error: e,
        };
        let q = samples.vector(i, "q")?;
        check_quaternions(model, q, i)?;
        let q = cast::<T>(q);
        let v = cast::<T>(samples.vector(i, "v")?);
        let f_ext = wrenches(model, frames, samples.wrenches(i)?, i)?;
        let rows = |m: &DMatrix<T>, name| {
            matrix_rows(|r, c| m[(r, c)], 0..m.nrows(), m.ncols(), None, i, name)
        };
        out.push(match algo {
            EvalAlgo::AbaDerivatives => {
                let tau = cast::<T>(samples.vector(i, "tau")?);
                aba_derivatives(model, &mut dws, &q, &v, &tau, &f_ext, &mut forward).map_err(at)?;
                let on_manifold = if model.has_constraints() {
                    aba_derivatives_independent(
                        model,
                        &mut dws,
                        &q,
                        &v,
                        &tau,
                        &f_ext,
                        &mut manifold,
                    )
                    .map_err(at)?;
                    Some(&manifold)
                } else {
                    None
                };
                Output::AbaDerivatives {
                    qdd: finite(forward.qdd.as_slice(), i, "qdd")?,
                    dqdd_dq: rows(&forward.dqdd_dq, "dqdd_dq")?,
                    dqdd_dv: rows(&forward.dqdd_dv, "dqdd_dv")?,
                    dqdd_dtau: rows(&forward.dqdd_dtau, "dqdd_dtau")?,
                    dqdd_independent_dq_independent: on_manifold
                        .map(|m| rows(&m.dqdd_dq, "dqdd_independent_dq_independent"))
                        .transpose()?,
                    dqdd_independent_dv_independent: on_manifold
                        .map(|m| rows(&m.dqdd_dv, "dqdd_independent_dv_independent"))
                        .transpose()?,
                    dqdd_independent_dtau: on_manifold
                        .map(|m| rows(&m.dqdd_dtau, "dqdd_independent_dtau"))
                        .transpose()?,
                }
            }
            _ => {
                let qdd = cast::<T>(samples.vector(i, "qdd")?);
                rnea_derivatives(model, &mut dws, &q, &v, &qdd, &f_ext, &mut inverse)
                    .map_err(at)?;
                Output::RneaDerivatives {
                    tau: finite(inverse.tau.as_slice(), i, "tau")?,
                    dtau_dq: rows(&inverse.dtau_dq, "dtau_dq")?,
                    dtau_dv: rows(&inverse.dtau_dv, "dtau_dv")?,
                    dtau_dqdd: rows(&inverse.dtau_dqdd, "dtau_dqdd")?,
                }
            }
        });
    }
    Ok(Evaluated::new(model, out))
}

/// A sample's wrenches in the scalar `T`, on the model's frames (`frames`, the order the samples were
/// read with); a value finite in f64 but not in `T` is refused naming the link and the entry.
fn wrenches<M: Real, T: Real>(
    model: &Model<M>,
    frames: &[FrameId],
    given: &[Wrench],
    sample: usize,
) -> Result<Vec<LinkWrench<T>>, CliError> {
    let mut out = Vec::with_capacity(given.len());
    for w in given {
        let frame = *frames
            .get(w.frame)
            .ok_or(InternalError::SampleNotInInput { sample })?;
        let mut parts = [Vector3::zeros(); 2];
        for ((part, x), v) in ["force", "torque"]
            .into_iter()
            .zip([w.force, w.torque])
            .zip(&mut parts)
        {
            for (k, &value) in x.iter().enumerate() {
                let converted = T::from_f64(value);
                if !converted.to_f64().is_finite() {
                    return Err(CliError::Sample {
                        sample,
                        field: F_EXT.to_string(),
                        problem: SampleProblem::WrenchPart {
                            link: model.frame_name(frame).unwrap_or_default().to_string(),
                            part,
                            problem: WrenchPartProblem::NotFinite {
                                index: k,
                                shown: format!(
                                    "{value:e} ({} in this scalar type)",
                                    converted.to_f64()
                                ),
                            },
                        },
                    });
                }
                v[k] = converted;
            }
        }
        out.push(LinkWrench::new(frame, parts[0], parts[1]));
    }
    Ok(out)
}

/// The frame, centre-of-mass and centroidal algorithms on one model, with their scratch.
struct Kinematics<'m, T: Real> {
    model: &'m Model<T>,
    ws: Workspace<T>,
    reference: Reference,
    frame: Option<FrameId>,
    zeros: Vec<T>,
    j6: Matrix6xX<T>,
    j3: Matrix3xX<T>,
}

impl<'m, T: Real> Kinematics<'m, T> {
    fn new(model: &'m Model<T>, reference: Reference, frame: Option<FrameId>) -> Self {
        let nv = model.nv();
        Kinematics {
            model,
            ws: Workspace::new(model),
            reference,
            frame,
            zeros: vec![T::zero(); nv],
            j6: Matrix6xX::zeros(nv),
            j3: Matrix3xX::zeros(nv),
        }
    }

    /// `algo` (`jacobian`, `com` or `centroidal`) on sample `i`.
    fn sample(&mut self, algo: EvalAlgo, samples: &Samples, i: usize) -> Result<Output, CliError> {
        let model = self.model;
        let at = |e: DynamicsError| CliError::Dynamics {
            sample: i,
            error: e,
        };
        let q = samples.vector(i, "q")?;
        check_quaternions(model, q, i)?;
        let q = cast::<T>(q);
        let v = samples.optional_vector(i, "v")?.map(cast::<T>);
        // X first: it leaves position kinematics of its own in the workspace.
        let x = match model.has_constraints() {
            true => Some(embedding_map(model, &mut self.ws, &q).map_err(at)?),
            false => None,
        };
        let ws = &mut self.ws;
        let v_or_zero = v.as_deref().unwrap_or(&self.zeros);
        match (&v, algo) {
            // The velocity-product accelerations (qdd = 0) for the biases.
            (Some(v), EvalAlgo::Jacobian | EvalAlgo::Centroidal) => {
                forward_kinematics_acceleration(model, ws, &q, v, &self.zeros).map_err(at)?
            }
            _ => forward_kinematics(model, ws, &q, v_or_zero).map_err(at)?,
        }
        let x = x.as_ref();
        Ok(match algo {
            EvalAlgo::Jacobian => {
                let frame = self.frame.ok_or(InternalError::FieldNotRead {
                    field: "--frame".into(),
                })?;
                let j = &mut self.j6;
                frame_jacobian(model, ws, frame, self.reference, j).map_err(at)?;
                let bias = match v {
                    Some(_) => Some(
                        frame_classical_acceleration(model, ws, frame, self.reference)
                            .map_err(at)?,
                    ),
                    None => None,
                };
                let get = |r, c| j[(r, c)];
                let independent = |rows, name| {
                    x.map(|x| matrix_rows(get, rows, j.ncols(), Some(x), i, name))
                        .transpose()
                };
                Output::Jacobian {
                    j_linear: matrix_rows(get, 0..3, j.ncols(), None, i, "J_linear")?,
                    j_angular: matrix_rows(get, 3..6, j.ncols(), None, i, "J_angular")?,
                    bias_linear: bias
                        .map(|b| finite(b.linear.as_slice(), i, "bias_linear"))
                        .transpose()?,
                    bias_angular: bias
                        .map(|b| finite(b.angular.as_slice(), i, "bias_angular"))
                        .transpose()?,
                    j_linear_independent: independent(0..3, "J_linear_independent")?,
                    j_angular_independent: independent(3..6, "J_angular_independent")?,
                }
            }
            EvalAlgo::Com => {
                let c = center_of_mass(model, ws).map_err(at)?;
                let j = &mut self.j3;
                let com = com_jacobian(model, ws, j).map_err(at)?;
                let get = |r, c| j[(r, c)];
                Output::Com {
                    com: finite(com.as_slice(), i, "com")?,
                    j_com: matrix_rows(get, 0..3, j.ncols(), None, i, "J_com")?,
                    vcom: v
                        .map(|_| finite(c.vcom.as_slice(), i, "vcom"))
                        .transpose()?,
                    j_com_independent: x
                        .map(|x| matrix_rows(get, 0..3, j.ncols(), Some(x), i, "J_com_independent"))
                        .transpose()?,
                }
            }
            EvalAlgo::Centroidal => {
                let a = &mut self.j6;
                centroidal_momentum_matrix(model, ws, a).map_err(at)?;
                let h = centroidal_momentum(model, ws).map_err(at)?;
                let linear_angular = |f: &embedyn_runtime::Force<T>| -> Vec<T> {
                    f.linear.iter().chain(f.angular.iter()).copied().collect()
                };
                let get = |r, c| a[(r, c)];
                Output::Centroidal {
                    a_g: matrix_rows(get, 0..6, a.ncols(), None, i, "A_g")?,
                    h_g: finite(&linear_angular(&h), i, "h_g")?,
                    a_g_independent: x
                        .map(|x| matrix_rows(get, 0..6, a.ncols(), Some(x), i, "A_g_independent"))
                        .transpose()?,
                }
            }
            EvalAlgo::Dynamics(other) => return Err(not_evaluated(other)),
            EvalAlgo::AbaDerivatives | EvalAlgo::RneaDerivatives => {
                return Err(InternalError::FieldNotRead {
                    field: algo.name().into(),
                }
                .into())
            }
        })
    }
}

/// Rows `rows` of a matrix with `ncols` columns (entry `(r, c)` is `get(r, c)`), times `x` when given, as
/// f64 rows; an entry that is not finite is an error naming `name` and the entry (row-major index).
fn matrix_rows<T: Real>(
    get: impl Fn(usize, usize) -> T,
    rows: Range<usize>,
    ncols: usize,
    x: Option<&DMatrix<T>>,
    sample: usize,
    name: &'static str,
) -> Result<Vec<Vec<f64>>, CliError> {
    let width = x.map_or(ncols, |x| x.ncols());
    let entry = |r: usize, k: usize| -> T {
        match x {
            None => get(r, k),
            Some(x) => (0..ncols).fold(T::zero(), |sum, c| sum + get(r, c) * x[(c, k)]),
        }
    };
    let mut out = Vec::with_capacity(rows.len());
    for (n, r) in rows.enumerate() {
        let row: Vec<T> = (0..width).map(|k| entry(r, k)).collect();
        out.push(finite(&row, sample, name).map_err(|e| match e {
            CliError::State {
                sample,
                problem:
                    StateProblem::NotFinite {
                        output,
                        index,
                        value,
                    },
            } => CliError::State {
                sample,
                problem: StateProblem::NotFinite {
                    output,
                    index: n * width + index,
                    value,
                },
            },
            other => other,
        })?);
    }
    Ok(out)
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
