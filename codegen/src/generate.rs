//! Code generation: the one entry point the `robot!` macro, `build.rs` and `embedyn generate` share.
//!
//! The interpreted algorithms run on the traced scalar ([`crate::trace::Sym`]) over the model built from
//! the IR, which unrolls them for this model and folds its constants; the tape becomes straight-line Rust,
//! once per scalar type.

use crate::emit::{function, Arg, Code, Emitted, Output};
use crate::names::{code_span, shown};
use crate::size;
use crate::trace::{input, record, snap, Sym};
use crate::value_names::Owners;
use crate::{build_model, LoadError, Loaded, Location, ModelOptions};
use embedyn_runtime::constraints::{
    completion_step, constraint_condition, singularity_threshold, COMPLETION_MAX_STEPS,
};
use embedyn_runtime::nalgebra::DMatrix;
use embedyn_runtime::{
    aba, crba, embedding_map_in, forward_kinematics, link_poses, mass_matrix_inverse,
    reduced_mass_matrix_in, rnea, Model, Real, Workspace,
};

use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// The algorithms code can be generated for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Algorithm {
    /// Forward dynamics `aba(q, v, tau, qdd)`.
    Aba,
    /// Inverse dynamics `rnea(q, v, qdd, tau)`.
    Rnea,
    /// Mass matrix `crba(q, m)`.
    Crba,
    /// Link frames `kinematics(q, frames)`: the world pose of every link on a moving body (`FRAMES`),
    /// as `[r00 r01 r02 r10 r11 r12 r20 r21 r22 x y z]` (rotation row-major, then the origin).
    Kinematics,
    /// Inverse mass matrix `minv(q, m_inv)` by the operator factorization of Eq. 6 (O(N²) output).
    Minv,
    /// Models with loops or couplings: `complete(q, q_out) -> residual`, the dependent coordinates solved
    /// from the independent ones by Newton's method from the given guess (iterated to 64 ε or at most
    /// `COMPLETION_MAX_STEPS` steps; `complete_step` is one step).
    Complete,
    /// Models with loops or couplings: `embedding(q, x)`, the map `X` (nv × independent nv) with
    /// `v = X v_independent`; `Xᵀ τ` is the force on the independent coordinates.
    Embedding,
    /// Models with loops or couplings: `crba_independent(q, m)`, the mass matrix over the independent
    /// coordinates, `Xᵀ M X` (what `embedyn eval --algo crba` reports for such a model).
    CrbaIndependent,
}

impl Algorithm {
    /// Every algorithm, in the order generated code lists them.
    pub const ALL: [Algorithm; 8] = [
        Algorithm::Kinematics,
        Algorithm::Aba,
        Algorithm::Rnea,
        Algorithm::Crba,
        Algorithm::Minv,
        Algorithm::Complete,
        Algorithm::Embedding,
        Algorithm::CrbaIndependent,
    ];

    /// The algorithm with this generated function name (`"aba"`, `"crba_independent"`, …); the error
    /// lists the names there are.
    pub fn from_name(name: &str) -> Result<Algorithm, String> {
        Algorithm::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or_else(|| {
                let known: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
                format!("unknown function `{name}` (expected {})", known.join(", "))
            })
    }

    /// Whether the algorithm exists only for models with loops, couplings or mimic joints.
    pub fn needs_constraints(self) -> bool {
        matches!(
            self,
            Algorithm::Complete | Algorithm::Embedding | Algorithm::CrbaIndependent
        )
    }

    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Aba => "aba",
            Algorithm::Rnea => "rnea",
            Algorithm::Crba => "crba",
            Algorithm::Kinematics => "kinematics",
            Algorithm::Minv => "minv",
            Algorithm::Complete => "complete",
            Algorithm::Embedding => "embedding",
            Algorithm::CrbaIndependent => "crba_independent",
        }
    }
}

/// What to generate.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    pub model: ModelOptions,
    /// Default: `kinematics`, `aba`, `rnea`, `crba` (the O(N²) inverse only when asked for).
    pub algorithms: Vec<Algorithm>,
    /// Emit the `f64` module.
    pub f64: bool,
    /// Emit the `f32` module.
    pub f32: bool,
    /// Path of the helper module the code calls (`sincos`, `sqrt`); `::embedyn::codegen_support` for
    /// the macro, `crate::helpers` for a standalone crate.
    pub helpers: TokenStream,
    /// Generate exactly `algorithms` (the user chose them: firmware that needs only `aba` pays only for
    /// `aba`). When false, a model with constraints also gets `complete`, `embedding` and
    /// `crba_independent`.
    pub exact: bool,
    /// Refuse to generate code that rustc is estimated to need more than this many MB of memory to
    /// compile (checked before tracing from the model and after tracing from the code, always before
    /// anything is formatted or written; see `size.rs`). `None`: no limit.
    pub max_compile_memory_mb: Option<u64>,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            model: ModelOptions::default(),
            algorithms: vec![
                Algorithm::Kinematics,
                Algorithm::Aba,
                Algorithm::Rnea,
                Algorithm::Crba,
            ],
            f64: true,
            f32: true,
            helpers: quote!(::embedyn::codegen_support),
            exact: false,
            max_compile_memory_mb: Some(crate::size::DEFAULT_COMPILE_MEMORY_MB),
        }
    }
}

/// Version of the generator, part of every cache key: generated code from another version is never reused.
pub const GENERATOR_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "-g4");

/// The model the generator traces: rotations and axes within 1e-14 of 0 or ±1 made exact, so that the
/// zero structure of axis-aligned joints and right-angle frames folds away.
fn snapped(model: &Model<f64>) -> Model<f64> {
    let mut m = model.clone();
    for j in &mut m.joints {
        j.axis = j.axis.map(snap);
        j.placement.rotation = j.placement.rotation.map(snap);
    }
    m
}

fn gen_error(loaded: &Loaded, msg: impl Into<String>) -> LoadError {
    LoadError::new(
        Location::new(
            &loaded.robot.source,
            None,
            format!("robot \"{}\"", shown(&loaded.robot.name)),
        ),
        msg,
    )
}

/// The generated items before they are joined into a file or a token stream: the constants at the top
/// and the functions of the scalar modules (the same code for `f64` and `f32`: only `S` differs, so
/// each algorithm is traced and emitted once).
struct Generated {
    header: TokenStream,
    scalars: Vec<&'static str>,
    functions: Vec<Emitted>,
    /// Whether the model has loops, couplings or mimic joints (then each scalar module has its
    /// `SINGULARITY_THRESHOLD`).
    constrained: bool,
}

fn generate_items(loaded: &Loaded, options: &GenerateOptions) -> Result<Generated, LoadError> {
    let model64 = loaded.model::<f64>(&options.model)?;
    if options.f32 {
        // The f32 functions fold the same constants as f32 literals: each must fit f32.
        crate::assemble::convert_model::<f32>(&loaded.robot, &model64).map_err(|mut e| {
            e.message += " (generated f32 code cannot hold it; generate the f64 functions only)";
            e
        })?;
    }
    if let Some(a) = options
        .algorithms
        .iter()
        .find(|a| a.needs_constraints() && !model64.has_constraints())
    {
        return Err(gen_error(
            loaded,
            format!(
                "`{}` exists only for a model with loops, couplings or mimic joints; this one is a tree",
                a.name()
            ),
        ));
    }
    let model: Model<Sym> = snapped(&model64).cast();
    let (nq, nv) = (model.nq(), model.nv());
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let scalars: Vec<&'static str> = [(options.f64, "f64"), (options.f32, "f32")]
        .into_iter()
        .filter_map(|(enabled, scalar)| enabled.then_some(scalar))
        .collect();
    let mut algorithms = options.algorithms.clone();
    // A model with constraints also gets its position completion and embedding map.
    if model.has_constraints() && !options.exact {
        for extra in [
            Algorithm::Complete,
            Algorithm::Embedding,
            Algorithm::CrbaIndependent,
        ] {
            if !algorithms.contains(&extra) {
                algorithms.push(extra);
            }
        }
    }
    let mut functions = Vec::new();
    if !scalars.is_empty() {
        let mut sizes =
            check_size_before_tracing(loaded, &model64, &algorithms, &scalars, options)?;
        for (k, &algo) in algorithms.iter().enumerate() {
            let function = generate_algorithm(loaded, &model, algo, &options.helpers)?;
            // Constants are folded in f64; the f32 module writes them as f32 literals.
            if options.f32 && function.largest_constant > f64::from(f32::MAX) {
                return Err(gen_error(
                    loaded,
                    format!(
                        "`{}`: the constant {:e}, folded from the model's numbers, is beyond the range of the scalar type f32 (largest {:e}); generated f32 code cannot hold it, generate the f64 functions only",
                        algo.name(),
                        function.largest_constant,
                        f32::MAX
                    ),
                ));
            }
            sizes[k] = size::FunctionSize {
                algorithm: algo,
                operations: function.operations,
                compile_bytes: function.compile_bytes,
                traced: true,
            };
            // Exact for what is traced: refused as soon as that alone is too large.
            let limit = options.max_compile_memory_mb;
            size::check(loaded, &sizes[..=k], &sizes, &scalars, limit, 1.0)?;
            functions.push(function);
        }
    }
    let independent: Vec<bool> = (0..model64.joints.len())
        .map(|j| model64.is_independent(j))
        .collect();
    let nj = names.len();
    let frames: Vec<&str> = model64
        .bodies
        .iter()
        .flat_map(|b| b.links.iter().map(String::as_str))
        .collect();
    let nf = frames.len();
    let ni = model64.independent_nv();
    // Names reach the docs as escaped code spans (docs/model-format.md, "Names are data"); `JOINTS` and
    // `FRAMES` below hold them exactly, as string literals that `quote` escapes.
    let shown: Vec<String> = names.iter().map(|n| code_span(n)).collect();
    let doc = format!(
        "Dynamics of {} generated by embedyn {} from {}: nq = {nq}, nv = {nv}; joints in coordinate order: {}.",
        code_span(&model64.name),
        GENERATOR_VERSION,
        code_span(&loaded.robot.source.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned())),
        shown.join(", ")
    );
    let doc = format!(" {doc}");
    let [nq, nv, ni, nj, nf] = [nq, nv, ni, nj, nf].map(proc_macro2::Literal::usize_unsuffixed);
    let header = quote! {
        #[doc = #doc]
        #[allow(dead_code)]
        pub const NQ: usize = #nq;
        /// Length of `v`, `tau` and `qdd`.
        #[allow(dead_code)]
        pub const NV: usize = #nv;
        /// Number of independent velocity coordinates (`NV` for a tree).
        #[allow(dead_code)]
        pub const NI: usize = #ni;
        /// Joint names in coordinate order (embedyn's docs/conventions.md).
        #[allow(dead_code)]
        pub const JOINTS: [&str; #nj] = [#(#names),*];
        /// Whether each joint's coordinate is independent (false for gear- or mimic-driven joints).
        #[allow(dead_code)]
        pub const INDEPENDENT: [bool; #nj] = [#(#independent),*];
        /// The links whose poses `kinematics` returns, in its order (every link on a moving body; links
        /// fixed to the world are constant and not listed).
        #[allow(dead_code)]
        pub const FRAMES: [&str; #nf] = [#(#frames),*];
    };
    Ok(Generated {
        header,
        scalars,
        functions,
        constrained: model64.has_constraints(),
    })
}

/// The size guard's first step: the functions' sizes predicted from the model, refused before any
/// tracing when far beyond the limit (see `size.rs`).
fn check_size_before_tracing(
    loaded: &Loaded,
    model: &Model<f64>,
    algorithms: &[Algorithm],
    scalars: &[&str],
    options: &GenerateOptions,
) -> Result<Vec<size::FunctionSize>, LoadError> {
    let predicted: Vec<size::FunctionSize> = algorithms
        .iter()
        .map(|&a| size::predicted(model, a))
        .collect();
    let limit = options.max_compile_memory_mb;
    size::check(loaded, &predicted, &predicted, scalars, limit, 2.0)?;
    Ok(predicted)
}

/// The scalar module `pub mod f64 { type S = f64; … }` around `functions`; for a model with constraints
/// it also holds the scalar's singularity threshold.
fn scalar_module(scalar: &str, constrained: bool, functions: &[TokenStream]) -> TokenStream {
    let module = format_ident!("{}", scalar);
    let doc = format!(" The generated dynamics in `{scalar}`.");
    let threshold = if constrained {
        let value = proc_macro2::Literal::f64_unsuffixed(match scalar {
            "f32" => singularity_threshold::<f32>(),
            _ => singularity_threshold::<f64>(),
        });
        quote! {
            /// cond₁(Y1) at or above which a configuration counts as singular in this scalar type,
            /// `min(1e10, 10⁻³ / ε)`: where the condition number returned by `aba`, `embedding` or
            /// `crba_independent` is not below it (`cond.is_nan() || cond >= SINGULARITY_THRESHOLD`), the
            /// results are meaningless and the interpreted solver refuses.
            pub const SINGULARITY_THRESHOLD: S = #value;
        }
    } else {
        quote!()
    };
    quote! {
        #[doc = #doc]
        // A program uses some of the functions generated for it; the others are not dead code to fix.
        #[allow(clippy::all, clippy::pedantic, unused_parens, non_snake_case, dead_code)]
        pub mod #module {
            type S = #module;
            #threshold
            #(#functions)*
        }
    }
}

/// Generates the items for a model: `NQ`, `NV`, `JOINTS`, and modules `f64`/`f32` with one function per
/// algorithm.
pub fn generate_tokens(
    loaded: &Loaded,
    options: &GenerateOptions,
) -> Result<TokenStream, LoadError> {
    let generated = generate_items(loaded, options)?;
    let functions = generated
        .functions
        .into_iter()
        .map(|f| match f.code {
            Code::Tokens(t) => Ok(t),
            Code::Text(text) => text
                .parse::<TokenStream>()
                .map_err(|e| gen_error(loaded, format!("generated code does not tokenize: {e}"))),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let modules = generated
        .scalars
        .iter()
        .map(|scalar| scalar_module(scalar, generated.constrained, &functions));
    let header = generated.header;
    Ok(quote! {
        #header
        #(#modules)*
    })
}

/// Generates the model's code as formatted source text: the same items as [`generate_tokens`], with
/// the small functions formatted by `prettyplease` and the long ones written formatted by the emitter
/// (pretty-printing millions of tokens would cost more time and memory than generating them).
pub fn generate_source(loaded: &Loaded, options: &GenerateOptions) -> Result<String, LoadError> {
    let generated = generate_items(loaded, options)?;
    let fail = |e: String| gen_error(loaded, e);
    let mut text = format_tokens(&generated.header).map_err(fail)?;
    // Each function formatted on its own inside a module, so that it is indented (and its lines
    // broken) exactly as inside the scalar module.
    let functions = generated
        .functions
        .iter()
        .map(|f| match &f.code {
            Code::Tokens(t) => {
                let wrapped = format_tokens(&quote!(mod m { #t })).map_err(fail)?;
                Ok(module_body(&wrapped).to_string())
            }
            Code::Text(body) => Ok(body.clone()),
        })
        .collect::<Result<Vec<String>, LoadError>>()?;
    for scalar in &generated.scalars {
        let empty =
            format_tokens(&scalar_module(scalar, generated.constrained, &[])).map_err(fail)?;
        text.push_str(empty.strip_suffix("}\n").unwrap_or(&empty));
        for f in &functions {
            text.push_str(f);
        }
        text.push_str("}\n");
    }
    Ok(text)
}

/// The lines between `mod m {` and the closing `}` of a formatted module.
fn module_body(formatted: &str) -> &str {
    let start = formatted.find('\n').map_or(0, |i| i + 1);
    formatted[start..]
        .strip_suffix("}\n")
        .unwrap_or(&formatted[start..])
}

/// `complete`: `complete_step` iterated until the relative residual is below 64 ε (or NaN) or the step
/// budget is spent. The iteration is over Newton steps, not over bodies: the step itself is unrolled.
fn complete_loop() -> TokenStream {
    let max_steps = proc_macro2::Literal::usize_unsuffixed(COMPLETION_MAX_STEPS);
    let must_use = crate::emit::MUST_USE;
    quote! {
        /// Position completion: `q_out` is `q` with its dependent coordinates solved from the independent
        /// ones by Newton's method from `q`'s dependent entries as the guess (it converges to the assembly
        /// branch nearest the guess), iterated until the largest residual, relative to the magnitudes in
        /// each equation, is below 64 ε or for at most `COMPLETION_MAX_STEPS` steps. Returns that residual:
        /// check it — a guess outside the mechanism's range does not converge (or gives NaN).
        #[must_use = #must_use]
        pub fn complete(q: &[S; super::NQ], q_out: &mut [S; super::NQ]) -> S {
            let tolerance: S = 64.0 * S::EPSILON;
            *q_out = *q;
            let mut next = *q;
            for _ in 0..COMPLETION_MAX_STEPS {
                let residual = complete_step(q_out, &mut next);
                if !(residual > tolerance) {
                    return residual;
                }
                *q_out = next;
            }
            complete_step(q_out, &mut next)
        }
        /// Newton steps `complete` takes at most.
        pub const COMPLETION_MAX_STEPS: usize = #max_steps;
    }
}

/// Components of a joint's coordinates in the names of generated code (a floating joint has 7).
const COORDINATE: [&str; 7] = ["0", "1", "2", "3", "4", "5", "6"];

/// The name of an algorithm's third argument (`aba(q, v, tau)`, `rnea(q, v, qdd)`).
fn third_input(algo: Algorithm) -> &'static str {
    match algo {
        Algorithm::Rnea => "qdd",
        _ => "tau",
    }
}

/// A matrix result as a row-major output.
fn matrix_output(name: &'static str, m: &DMatrix<Sym>) -> Output {
    let (rows, cols) = m.shape();
    Output::Matrix {
        name,
        rows,
        cols,
        values: (0..rows * cols).map(|k| m[(k / cols, k % cols)]).collect(),
    }
}

fn generate_algorithm(
    loaded: &Loaded,
    model: &Model<Sym>,
    algo: Algorithm,
    helpers: &TokenStream,
) -> Result<Emitted, LoadError> {
    let (nq, nv) = (model.nq(), model.nv());
    // Inputs are named after their joints: `knee_q`, `knee_v`, `base_q_3` (a joint with several
    // coordinates), so that generated code reads `let knee_q = q[2];`.
    let inputs = |arg: u8, n: usize| -> Vec<Sym> {
        let quantity = ["q", "v", third_input(algo)][arg as usize];
        (0..n)
            .map(|i| {
                let value = input(arg, i);
                let owner = model.joints.iter().find(|j| {
                    let (start, len) = if arg == 0 {
                        (j.q_index, j.nq())
                    } else {
                        (j.v_index, j.nv())
                    };
                    (start..start + len).contains(&i)
                });
                match owner {
                    Some(j) if (if arg == 0 { j.nq() } else { j.nv() }) == 1 => {
                        value.named(&j.name, quantity, "")
                    }
                    Some(j) => {
                        let start = if arg == 0 { j.q_index } else { j.v_index };
                        value.named(&j.name, quantity, COORDINATE[(i - start).min(6)])
                    }
                    None => value,
                }
            })
            .collect()
    };
    let fail = |e: embedyn_runtime::DynamicsError| {
        gen_error(loaded, format!("tracing {}: {e}", algo.name()))
    };
    let (outputs, tape) = record(|| -> Result<Vec<Output>, LoadError> {
        let mut ws = Workspace::new(model);
        let q = inputs(0, nq);
        Ok(match algo {
            Algorithm::Aba => {
                let (v, tau) = (inputs(1, nv), inputs(2, nv));
                let mut out = vec![Output::Vector {
                    name: "qdd",
                    values: aba(model, &mut ws, &q, &v, &tau).map_err(fail)?.to_vec(),
                }];
                if model.has_constraints() {
                    out.push(Output::Return(constraint_condition(&ws)));
                }
                out
            }
            Algorithm::Rnea => {
                let (v, qdd) = (inputs(1, nv), inputs(2, nv));
                vec![Output::Vector {
                    name: "tau",
                    values: rnea(model, &mut ws, &q, &v, &qdd).map_err(fail)?.to_vec(),
                }]
            }
            Algorithm::Crba => {
                vec![matrix_output("m", crba(model, &mut ws, &q).map_err(fail)?)]
            }
            Algorithm::Kinematics => {
                let zeros = vec![Sym::Const(0.0); nv];
                forward_kinematics(model, &mut ws, &q, &zeros).map_err(fail)?;
                let mut values = Vec::new();
                for (_, x) in link_poses(model, &ws) {
                    for r in 0..3 {
                        for c in 0..3 {
                            values.push(x.rotation[(r, c)]);
                        }
                    }
                    values.extend(x.translation.iter().copied());
                }
                vec![Output::Matrix {
                    name: "frames",
                    rows: values.len() / 12,
                    cols: 12,
                    values,
                }]
            }
            Algorithm::Minv => {
                vec![matrix_output(
                    "m_inv",
                    mass_matrix_inverse(model, &mut ws, &q).map_err(fail)?,
                )]
            }
            Algorithm::Complete => {
                let mut q_out = q.clone();
                let residual = completion_step(model, &mut ws, &mut q_out).map_err(fail)?;
                vec![
                    Output::Vector {
                        name: "q_out",
                        values: q_out,
                    },
                    Output::Return(residual),
                ]
            }
            Algorithm::Embedding => {
                let x = embedding_map_in(model, &mut ws, &q).map_err(fail)?;
                vec![
                    matrix_output("x", x),
                    Output::Return(constraint_condition(&ws)),
                ]
            }
            Algorithm::CrbaIndependent => {
                let m = reduced_mass_matrix_in(model, &mut ws, &q).map_err(fail)?;
                vec![
                    matrix_output("m", m),
                    Output::Return(constraint_condition(&ws)),
                ]
            }
        })
    });
    let outputs = outputs?;
    let owners = Owners::new(
        model.joints.iter().map(|j| j.name.as_str()),
        model.bodies.iter().map(|b| b.name.as_str()),
    );
    let (args, doc): (Vec<Arg>, &str) = match algo {
        Algorithm::Aba => (
            vec![Arg { name: "q", len: nq }, Arg { name: "v", len: nv }, Arg { name: "tau", len: nv }],
            if model.has_constraints() {
                "Forward dynamics with constraint embedding: `qdd` over all spanning coordinates (the O(N) articulated-body algorithm with each aggregate link inline, unrolled); only `Xᵀ τ` acts. Returns the singularity measure, the largest condition number cond₁(Y1) over the loops: where it is not below `SINGULARITY_THRESHOLD` (`!(cond < SINGULARITY_THRESHOLD)`, which also catches NaN) the configuration is at or too near a singular one (a toggle) and `qdd` is meaningless — the interpreted solver refuses there."
            } else {
                "Forward dynamics: `qdd = M(q)⁻¹ (τ − C(q, v) − g(q))` (the O(N) articulated-body algorithm, unrolled)."
            },
        ),
        Algorithm::Rnea => (
            vec![Arg { name: "q", len: nq }, Arg { name: "v", len: nv }, Arg { name: "qdd", len: nv }],
            "Inverse dynamics: `τ = M(q) qdd + C(q, v) + g(q)` (recursive Newton–Euler, unrolled).",
        ),
        Algorithm::Crba => (vec![Arg { name: "q", len: nq }], "The joint-space mass matrix `M(q)` (composite-rigid-body algorithm, unrolled)."),
        Algorithm::Kinematics => (vec![Arg { name: "q", len: nq }], "Forward kinematics: the world pose of every link on a moving body, in the order of `FRAMES`, as `[r00, r01, r02, r10, r11, r12, r20, r21, r22, x, y, z]` (the rotation row-major: its columns are the link's axes in world coordinates; then the link origin in the world)."),
        Algorithm::Minv => (vec![Arg { name: "q", len: nq }], "The inverse mass matrix `M(q)⁻¹` by the operator factorization of Eq. 6, unrolled."),
        Algorithm::Complete => (
            vec![Arg { name: "q", len: nq }],
            "One Newton step of the position completion: `q_out` is `q` with its dependent coordinates moved towards the solution of the loop, gear and mimic equations (loop coordinates by at most 0.5 rad or m). Returns the largest residual at `q`, relative to the magnitudes in each equation (`complete` iterates this).",
        ),
        Algorithm::Embedding => (vec![Arg { name: "q", len: nq }], "The embedding map `X` (rows: all velocity coordinates, columns: independent ones): `v = X v_independent`. Returns the singularity measure cond₁(Y1) (as `aba` does)."),
        Algorithm::CrbaIndependent => (vec![Arg { name: "q", len: nq }], "The mass matrix over the independent coordinates, `Xᵀ M(q) X` (the spanning tree's `M` is `crba`). Returns the singularity measure cond₁(Y1) (as `aba` does)."),
    };
    if algo == Algorithm::Complete {
        let mut step = function(
            "complete_step",
            doc,
            &args,
            &outputs,
            &tape,
            helpers,
            &owners,
        )
        .map_err(|e| gen_error(loaded, e.0))?;
        let wrapper = complete_loop();
        step.code = match step.code {
            Code::Tokens(t) => Code::Tokens(quote! { #t #wrapper }),
            Code::Text(text) => {
                let formatted =
                    format_tokens(&quote!(mod m { #wrapper })).map_err(|e| gen_error(loaded, e))?;
                Code::Text(text + module_body(&formatted))
            }
        };
        return Ok(step);
    }
    function(algo.name(), doc, &args, &outputs, &tape, helpers, &owners)
        .map_err(|e| gen_error(loaded, e.0))
}

/// Formats generated items as a source file with `prettyplease`.
pub fn format_tokens(tokens: &TokenStream) -> Result<String, String> {
    let file: syn::File =
        syn::parse2(tokens.clone()).map_err(|e| format!("generated code does not parse: {e}"))?;
    Ok(prettyplease::unparse(&file))
}

/// For `build.rs`: generates the model's code as a formatted Rust source file (include it with
/// `include!(concat!(env!("OUT_DIR"), "/robot.rs"))` inside a module). Prints the `cargo:rerun-if-changed`
/// line for the model file.
///
/// ```no_run
/// // in build.rs's main():
/// let out = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("arm.rs");
/// embedyn_codegen::generate_file("models/arm7.urdf".as_ref(), &Default::default(), &out).unwrap();
/// ```
pub fn generate_file(
    model_path: &std::path::Path,
    options: &GenerateOptions,
    out: &std::path::Path,
) -> Result<(), LoadError> {
    // The path goes into cargo's line-based build-script protocol: a line break in it would add a
    // directive of its own.
    let shown_path = model_path.display().to_string();
    if shown_path.contains(['\n', '\r']) {
        return Err(LoadError::new(
            Location::new(model_path, None, ""),
            "a model path with a line break cannot be given to cargo (cargo:rerun-if-changed)",
        ));
    }
    println!("cargo:rerun-if-changed={shown_path}");
    let loaded = crate::load(model_path)?;
    let text = generate_source(&loaded, options)?;
    std::fs::write(out, text)
        .map_err(|e| gen_error(&loaded, format!("cannot write {}: {e}", out.display())))
}

/// Builds the f64 model the way generated code sees it (for comparisons in tests).
pub fn generation_model(loaded: &Loaded, options: &ModelOptions) -> Result<Model<f64>, LoadError> {
    Ok(snapped(&build_model::<f64>(&loaded.robot, options)?))
}
