//! # embedyn-cli
//!
//! The `embedyn` command line: `info`, `eval`, `complete`, `generate` and `bench` on a model file, JSON on
//! stdout, errors on stderr with a non-zero exit code (docs/command-line.md). The library part exists for
//! the binary, the tests and the fuzzer; it is not an API to build on (use `embedyn` and
//! `embedyn-codegen`).

#![warn(missing_docs)]

mod bench;
mod complete;
mod eval;
mod info;
mod output;
pub mod plot;
mod runner;
mod samples;
mod sampling;
mod suggest;
pub mod tradeoff;

use clap::{Parser, Subcommand, ValueEnum};
use embedyn_codegen::bounded_read::{read_file_limited, read_to_string_limited, MAX_INPUT_BYTES};
use embedyn_codegen::{
    load, LoadError, Loaded, LockedJoint, ModelOptions, ReadError, Rotors, UnknownAlgorithm,
};

pub use bench::BenchError;
pub use runner::{RunnerError, RunnerOutputProblem, RunnerSourceError};
pub use sampling::NoConsistentStates;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The program: parses the command line, runs the command and writes its result or error through the
/// one output module. Every way out is an exit status (docs/command-line.md): 0, 1 for an error, 2 for a bad
/// command line, never a panic's 101 or a signal.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout, usage errors to stderr; a closed pipe is ignored.
            let _ = e.print();
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(output::FAILURE));
        }
    };
    // The last line of defence: a panic (a bug) still ends with a clear status, not 101.
    match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(Printed::Text(text))) => output::document(&text),
        Ok(Ok(Printed::Json(json))) => output::json_document(&json),
        Ok(Ok(Printed::Evaluated(document))) => output::json_document(&document),
        Ok(Ok(Printed::Completed(document))) => output::json_document(&document),
        Ok(Err(e)) => {
            output::note(&format!("error: {e}"));
            ExitCode::from(e.exit_status())
        }
        Err(_) => {
            output::note("error: internal error in embedyn (a bug; please report it with the command and the model)");
            ExitCode::from(output::INTERNAL_ERROR)
        }
    }
}

/// The parsed command line.
#[derive(Parser, Debug)]
#[command(
    name = "embedyn",
    version,
    about = "Exact, fast rigid-body dynamics from URDF and URDF+",
    long_about = None
)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// Model options every command takes (CONTRACT §1 "Scene options").
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// Make the URDF root free with a floating joint named `root_joint`.
    #[arg(long)]
    pub floating: bool,
    /// Gravity in the world frame, m/s² (default 0,0,-9.81).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_gravity, allow_hyphen_values = true)]
    pub gravity: Option<[f64; 3]>,
    /// Fix a 1-DoF joint at VALUE (rad or m): its coordinate leaves q and v, and the joints that mimic it
    /// are fixed with it (repeatable).
    #[arg(long = "lock", value_name = "JOINT=VALUE", value_parser = parse_lock, allow_hyphen_values = true)]
    pub locks: Vec<LockedJoint>,
    /// How geared rotors are modelled: `exact` (aggregate links) or `reflected` (armature on the driving
    /// joints; the rotors leave the model).
    #[arg(long, value_name = "exact|reflected", value_parser = parse_rotors)]
    pub rotors: Option<Rotors>,
}

impl SceneArgs {
    /// The loader's options for this scene.
    pub fn options(&self) -> ModelOptions {
        let mut options = ModelOptions {
            floating: self.floating,
            locks: self.locks.clone(),
            rotors: self.rotors.unwrap_or_default(),
            ..Default::default()
        };
        if let Some(g) = self.gravity {
            options.gravity = g;
        }
        options
    }
}

impl SceneArgs {
    /// [`SceneArgs::options`] for `loaded`, saying on stderr where an option changes nothing (a
    /// `--rotors reflected` on a model without geared rotors), so that a user does not believe it did.
    pub fn options_for(&self, loaded: &Loaded) -> ModelOptions {
        if self.rotors == Some(Rotors::Reflected)
            && embedyn_codegen::geared_rotors(&loaded.robot).is_empty()
        {
            output::note(&format!(
                "embedyn: {} has no geared rotor (a <coupling> whose faster side is a leaf body): --rotors reflected changes nothing",
                embedyn_codegen::names::code_span(&loaded.robot.name)
            ));
        }
        self.options()
    }
}

/// `JOINT=VALUE`: a joint's name and a finite number (the name may hold `=`; the value follows the last).
fn parse_lock(text: &str) -> Result<LockedJoint, String> {
    let bad = || {
        format!("expected JOINT=VALUE with VALUE a finite number in rad or m (e.g. knee=0.3), got \"{text}\"")
    };
    let (joint, value) = text.rsplit_once('=').ok_or_else(bad)?;
    let value: f64 = value.trim().parse().map_err(|_| bad())?;
    if joint.is_empty() || !value.is_finite() {
        return Err(bad());
    }
    Ok(LockedJoint {
        joint: joint.to_string(),
        value,
    })
}

/// `exact` or `reflected`.
fn parse_rotors(text: &str) -> Result<Rotors, String> {
    Rotors::parse(text).ok_or_else(|| format!("expected exact or reflected, got \"{text}\""))
}

/// `X,Y,Z`: three finite numbers.
fn parse_gravity(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let numbers: Vec<f64> = parts
        .iter()
        .filter_map(|p| p.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    match numbers[..] {
        [x, y, z] if parts.len() == 3 => Ok([x, y, z]),
        _ => Err(format!(
            "expected three finite numbers X,Y,Z in m/s² (e.g. 0,0,-9.81), got \"{text}\""
        )),
    }
}

/// The commands of `embedyn`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Print the model's structure: joints in coordinate order, bodies, loops and couplings.
    Info {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// The scene: `--floating`, `--gravity`, `--lock`, `--rotors`.
        #[command(flatten)]
        scene: SceneArgs,
    },
    /// Make states consistent with the loops and couplings: solve the dependent coordinates of `q` from the
    /// independent ones (the given dependent entries are the starting guess) and project `v`.
    Complete {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// The scene: `--floating`, `--gravity`, `--lock`, `--rotors`.
        #[command(flatten)]
        scene: SceneArgs,
        /// JSON input: `{"samples": [{"q": [...], "v": [...]}]}`; stdin when absent.
        #[arg(long)]
        input: Option<PathBuf>,
    },
    /// Write a standalone, formatted, `no_std` Rust crate with the model's generated dynamics.
    Generate {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// Output folder (created if needed).
        #[arg(long)]
        out: PathBuf,
        /// The scene: `--floating`, `--gravity`, `--lock`, `--rotors`.
        #[command(flatten)]
        scene: SceneArgs,
        /// Also generate `minv` (the O(N²) inverse mass matrix of Eq. 6).
        #[arg(long)]
        minv: bool,
        /// Generate exactly these functions (the help text, from the descriptors, lists them).
        #[arg(long, value_delimiter = ',', help = only_help())]
        only: Option<Vec<String>>,
        /// Generate only this scalar type's module (default: both `f64` and `f32`).
        #[arg(long, value_enum)]
        scalar: Option<Scalar>,
        /// Refuse code that rustc is estimated to need more than this many MB of memory to compile.
        #[arg(long, value_name = "MB", default_value_t = embedyn_codegen::DEFAULT_COMPILE_MEMORY_MB)]
        max_compile_memory: u64,
        /// Links that take external wrenches, comma-separated: `aba_ext` and `rnea_ext` (and `nle_ext`
        /// with `--only`) take one row `[fx, fy, fz, tx, ty, tz]` of `f_ext` per link, in this order, in
        /// the link's frame about its origin.
        #[arg(long, value_delimiter = ',', value_name = "LINK,...")]
        wrenches: Vec<String>,
        /// Links that get a function `frame_<link>` each, comma-separated: world pose, 6 × nv Jacobian and
        /// bias (classical acceleration at qdd = 0).
        #[arg(long, value_delimiter = ',', value_name = "LINK,...")]
        frames: Vec<String>,
        /// Where the frame functions express their Jacobian and bias (Pinocchio's references).
        #[arg(long, value_parser = ["local", "local_world_aligned", "world"], default_value = "local_world_aligned")]
        reference: String,
        /// Also write lane modules of this many states per call (`f64x4`, `f32x4` for 4; 2 or 4 for
        /// f64, 4 or 8 for f32): every function evaluating that many states at once, one per SIMD lane.
        #[arg(long, value_name = "N")]
        lanes: Option<usize>,
        /// Which f64 functions also get an AVX copy that runs where the CPU has it (x86-64; same results,
        /// up to half the time): `large` (4,000 to 25,000 statements, smaller ones smallest first while
        /// the twins total at most 17,000, and every lane function of `f64x4` or `f32x8` up to 25,000;
        /// with 24 or more degrees of freedom the smallest twinned ones, up to 4,000 statements, also get
        /// an AVX-512 copy), `all`, or `none` (less compile time).
        #[arg(long, value_parser = ["none", "large", "all"], default_value = "large")]
        avx_twins: String,
        /// The crate's package name (default: the robot's name as an identifier, then `_dynamics`), e.g.
        /// to keep crates generated with different options apart.
        #[arg(long, value_name = "NAME")]
        name: Option<String>,
    },
    /// Time every algorithm for each engine and scalar (median ns per call, in-process, pre-generated
    /// random states).
    Bench {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// The scene: `--floating`, `--gravity`, `--lock`, `--rotors`.
        #[command(flatten)]
        scene: SceneArgs,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Refuse generated code whose compilation is estimated to need more memory than this (MB).
        #[arg(long, value_name = "MB", default_value_t = embedyn_codegen::DEFAULT_COMPILE_MEMORY_MB)]
        max_compile_memory: u64,
    },
    /// What each modelling choice costs and buys on this model: generated `aba` time per call and the
    /// error of the independent accelerations against the exact model in double-double, for f64 and f32
    /// and, where the model has geared rotors, exact and reflected rotors.
    Tradeoff {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// The scene: `--floating`, `--gravity`, `--lock` (`--rotors` is varied).
        #[command(flatten)]
        scene: SceneArgs,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Also draw error against time (log axes) as an SVG file.
        #[arg(long, value_name = "FILE")]
        svg: Option<PathBuf>,
        /// Refuse generated code whose compilation is estimated to need more memory than this (MB).
        #[arg(long, value_name = "MB", default_value_t = embedyn_codegen::DEFAULT_COMPILE_MEMORY_MB)]
        max_compile_memory: u64,
    },
    /// Evaluate an algorithm on the samples of a JSON file (or stdin).
    Eval {
        /// The model file (URDF or URDF+).
        model: PathBuf,
        /// The algorithm to evaluate.
        #[arg(long, value_parser = algo_parser())]
        algo: EvalAlgo,
        /// Which engine evaluates it.
        #[arg(long, value_enum, default_value = "interpreted")]
        engine: Engine,
        /// The scalar type it computes in.
        #[arg(long, value_enum, default_value = "f64")]
        scalar: Scalar,
        /// The scene: `--floating`, `--gravity`, `--lock`, `--rotors`.
        #[command(flatten)]
        scene: SceneArgs,
        /// JSON input: `{"samples": [...]}`; stdin when absent.
        #[arg(long)]
        input: Option<PathBuf>,
        /// `--algo jacobian`: the frame, a link of the model file (`info` lists them under `frames`).
        #[arg(long, value_name = "LINK")]
        frame: Option<String>,
        /// `--algo jacobian`: where the Jacobian and its bias are expressed (default
        /// local_world_aligned: world axes at the frame's origin).
        #[arg(long, value_name = "local|local_world_aligned|world", value_parser = parse_reference)]
        reference: Option<Reference>,
        /// `--engine generated`: refuse generated code whose compilation is estimated to need more memory
        /// than this (MB).
        #[arg(long, value_name = "MB", default_value_t = embedyn_codegen::DEFAULT_COMPILE_MEMORY_MB)]
        max_compile_memory: u64,
    },
}

/// An algorithm of the generated code; `embedyn eval --algo` evaluates those whose descriptor has a
/// command-line entry ([`embedyn_codegen::algorithm::ALGORITHMS`]).
pub use embedyn_codegen::Algorithm as Algo;

pub use embedyn_runtime::Reference;

/// What `embedyn eval --algo` evaluates: an algorithm with a generated counterpart (its descriptor's), or
/// one of the frame and centroidal quantities (CONTRACT §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvalAlgo {
    /// An algorithm of the descriptors (`aba`, `rnea`, `crba`, …).
    Dynamics(Algo),
    /// `jacobian`: a frame's Jacobian and, with `v`, its bias.
    Jacobian,
    /// `com`: the centre of mass, its Jacobian and, with `v`, its velocity.
    Com,
    /// `centroidal`: the centroidal momentum matrix, momentum and bias.
    Centroidal,
    /// `aba_derivatives`: forward dynamics and its derivatives.
    AbaDerivatives,
    /// `rnea_derivatives`: inverse dynamics and its derivatives.
    RneaDerivatives,
}

impl From<Algo> for EvalAlgo {
    fn from(algo: Algo) -> Self {
        EvalAlgo::Dynamics(algo)
    }
}

impl EvalAlgo {
    /// The frame, centroidal and derivative algorithms, with their `--algo` help: the command line's names
    /// for them (the generated engine runs the generated `frame_<link>`, `com`, `centroidal`,
    /// `aba_derivatives` and `rnea_derivatives`). (Should the
    /// descriptors offer one of these names, this entry is the one `--algo` means.)
    const KINEMATIC: [(EvalAlgo, &'static str, &'static str); 5] = [
        (
            EvalAlgo::Jacobian,
            "jacobian",
            "A frame's Jacobian (--frame LINK, --reference) and, with v, its bias",
        ),
        (
            EvalAlgo::Com,
            "com",
            "Centre of mass, its Jacobian and, with v, its velocity",
        ),
        (
            EvalAlgo::Centroidal,
            "centroidal",
            "Centroidal momentum matrix A_g and momentum h_g (Pinocchio's ccrba)",
        ),
        (
            EvalAlgo::AbaDerivatives,
            "aba_derivatives",
            "Forward dynamics and its derivatives dqdd/dq, dqdd/dv, dqdd/dtau",
        ),
        (
            EvalAlgo::RneaDerivatives,
            "rnea_derivatives",
            "Inverse dynamics and its derivatives dtau/dq, dtau/dv, dtau/dqdd = M",
        ),
    ];

    /// The `--algo` value.
    pub fn name(self) -> &'static str {
        match self {
            EvalAlgo::Dynamics(a) => a.name(),
            other => Self::KINEMATIC
                .iter()
                .find(|(a, _, _)| *a == other)
                .map_or("", |&(_, name, _)| name),
        }
    }

    /// The algorithm named `name` on the command line.
    pub fn from_name(name: &str) -> Option<EvalAlgo> {
        Self::KINEMATIC
            .iter()
            .find(|(_, n, _)| *n == name)
            .map(|&(a, _, _)| a)
            .or_else(|| {
                Algo::offered_by_cli()
                    .find(|a| a.name() == name)
                    .map(EvalAlgo::Dynamics)
            })
    }
}

/// `--algo`'s values, with their help: the algorithms' descriptors, then the frame and centroidal ones.
fn algo_parser() -> impl clap::builder::TypedValueParser<Value = EvalAlgo> {
    let only = EvalAlgo::KINEMATIC;
    let values = Algo::offered_by_cli()
        .filter(move |a| only.iter().all(|&(_, name, _)| name != a.name()))
        .map(|a| {
            let help = a.spec().cli.map_or("", |c| c.help);
            clap::builder::PossibleValue::new(a.name()).help(help)
        })
        .chain(
            only.iter()
                .map(|&(_, name, help)| clap::builder::PossibleValue::new(name).help(help)),
        );
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(values)
        .try_map(|name: String| EvalAlgo::from_name(&name).ok_or(UnknownAlgorithm { name }))
}

/// `local`, `local_world_aligned` or `world`.
fn parse_reference(text: &str) -> Result<Reference, String> {
    Reference::from_name(text)
        .ok_or_else(|| format!("expected local, local_world_aligned or world, got \"{text}\""))
}

/// `generate --only`'s help: the function names and the defaults, from the algorithms' descriptors.
fn only_help() -> String {
    use embedyn_codegen::algorithm::WhenGenerated;
    let names = |algorithms: &mut dyn Iterator<Item = Algo>| -> Vec<&'static str> {
        algorithms.map(Algo::name).collect()
    };
    let all = names(&mut Algo::ALL.into_iter());
    let default = names(&mut Algo::generated(WhenGenerated::ByDefault));
    let constrained = names(&mut Algo::generated(WhenGenerated::WithConstraints));
    let (last, rest) = constrained.split_last().unwrap_or((&"", &[]));
    format!(
        "Generate exactly these functions, comma-separated ({}); default: {} and, for a model with constraints, {} and {last}",
        all.join(", "),
        default.join(", "),
        rest.join(", "),
    )
}

/// Which engine `embedyn eval` and `bench` use.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The interpreted solver (the oracle).
    Interpreted,
    /// Generated straight-line code, compiled on demand.
    Generated,
}

/// The scalar type of a computation.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// Double precision (64-bit).
    F64,
    /// Single precision (32-bit), as on a microcontroller FPU.
    F32,
}

/// An error of the command line, printed to stderr as `error: …`.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// An option's value that the command line parser could not check (`--only`).
    #[error("{option}: {problem}")]
    Usage {
        /// The option.
        option: &'static str,
        /// What is wrong with it.
        #[source]
        problem: UnknownAlgorithm,
    },
    /// The input document as a whole (not JSON, no `samples`).
    #[error("{0}")]
    Input(#[from] InputError),
    /// One field of one sample of the input.
    #[error("sample {sample}: {}", field_problem(.field, .problem))]
    Sample {
        /// The sample, counted from 0.
        sample: usize,
        /// The field (`q`, `v`, …).
        field: String,
        /// What is wrong with it.
        problem: SampleProblem,
    },
    /// A sample the model cannot evaluate (outside the constraints, a zero quaternion, …).
    #[error("sample {sample}: {problem}")]
    State {
        /// The sample, counted from 0.
        sample: usize,
        /// What is wrong with it.
        problem: StateProblem,
    },
    /// An algorithm refused a sample.
    #[error("sample {sample}: {error}")]
    Dynamics {
        /// The sample, counted from 0.
        sample: usize,
        /// The algorithm's error.
        #[source]
        error: embedyn_runtime::DynamicsError,
    },
    /// The model file.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The input could not be read (`path` `None`: stdin).
    #[error("{}", read_failure(.path.as_deref(), .error))]
    ReadInput {
        /// The file (`None`: stdin).
        path: Option<PathBuf>,
        /// Why.
        #[source]
        error: ReadError,
    },
    /// Building, caching or running the generated code's runner.
    #[error("{0}")]
    Runner(#[from] RunnerError),
    /// A file the command was asked to write (`tradeoff --svg`).
    #[error("cannot write {}: {error}", embedyn_codegen::Printable(&.path.to_string_lossy()))]
    WriteFile {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// Timing (`bench`).
    #[error("{0}")]
    Bench(#[from] BenchError),
    /// An algorithm `embedyn eval` does not evaluate (`--algo` offers only those it does).
    #[error("`embedyn eval` does not evaluate `{}`", .algorithm.name())]
    NotEvaluated {
        /// The algorithm asked for.
        algorithm: Algo,
    },
    /// An option that does not fit the others or the model (`--frame` without `--algo jacobian`, a
    /// frame the model does not have): a usage error, exit status 2.
    #[error("{option}: {message}")]
    BadOption {
        /// The option.
        option: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A broken invariant of embedyn itself.
    #[error("internal error: {0} (a bug)")]
    Internal(#[from] InternalError),
}

impl CliError {
    /// The exit status of the error (docs/command-line.md): 2 for a usage error, 1 otherwise.
    pub fn exit_status(&self) -> u8 {
        match self {
            CliError::BadOption { .. } => USAGE_ERROR,
            _ => output::FAILURE,
        }
    }
}

/// The exit status of a usage error (as clap's).
pub const USAGE_ERROR: u8 = 2;

/// What is wrong with the input document as a whole.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The text is not JSON.
    #[error("the input is not valid JSON: {0}")]
    NotJson(#[source] serde_json::Error),
    /// The document has no field `samples`.
    #[error("the input has no field `samples` (expected {{\"samples\": [...]}})")]
    NoSamples,
    /// The field `samples` is not an array.
    #[error("the input's field `samples` must be an array")]
    SamplesNotArray,
    /// A field of a sample has more entries than the model needs (refused within 8 entries past the
    /// model's length, `samples::EXTRA_COUNTED`).
    #[error(
        "sample {sample}: field `{field}` has {} entries, the model needs {len}{hint}",
        entries_given(*.given, *.exact)
    )]
    TooManyEntries {
        /// The sample, counted from 0.
        sample: usize,
        /// The field.
        field: &'static str,
        /// The entries the model needs.
        len: usize,
        /// The entries read: all of them when `exact`, else the reading stopped there.
        given: usize,
        /// Whether `given` is the field's whole length.
        exact: bool,
        /// [`FLOATING_HINT`] or [`LOCK_HINT`] where one applies, else empty.
        hint: &'static str,
    },
}

/// `36`, or `more than 37` where the reading stopped.
fn entries_given(given: usize, exact: bool) -> String {
    if exact {
        given.to_string()
    } else {
        format!("more than {}", given)
    }
}

/// What an overlong `q` (or `q1`) 7 entries too long, or `v` (`tau`, `qdd`) 6 too long, of a model without a
/// free joint adds to its error: the usual cause is a state of the robot with a free-floating base
/// (example-robot-data's G1, whose file has its free joint in a comment), read without `--floating` (a new
/// user's trial with the G1, 2026-12-05).
pub const FLOATING_HINT: &str =
    "; a free-floating base adds 7 entries to `q` and 6 to `v`: for such a state pass `--floating`";

/// What any other overlong state vector of a model with `--lock` adds to its error (an attacker's trial:
/// the full `q` of an arm with one joint locked was told to pass `--floating`).
pub const LOCK_HINT: &str = "; `--lock` removes the locked joints' entries from `q` and `v` (`embedyn info` with the same options lists the joints left)";

/// The fields laid out as `q`, and as `v`.
const Q_FIELDS: [&str; 2] = ["q", "q1"];
const V_FIELDS: [&str; 3] = ["v", "tau", "qdd"];

impl CliError {
    /// [`FLOATING_HINT`] added to a state vector exactly a floating base's entries too long when the
    /// model has no free joint; else [`LOCK_HINT`] to an overlong state vector when joints are locked.
    pub(crate) fn with_state_hint(
        mut self,
        model: &embedyn_runtime::Model<f64>,
        options: &ModelOptions,
    ) -> CliError {
        if let CliError::Input(InputError::TooManyEntries {
            field,
            len,
            given,
            exact,
            hint,
            ..
        }) = &mut self
        {
            let floating_extra = if Q_FIELDS.contains(field) {
                Some(7)
            } else if V_FIELDS.contains(field) {
                Some(6)
            } else {
                None
            };
            *hint = match floating_extra {
                Some(extra)
                    if *exact
                        && *given == *len + extra
                        && !model.joints.iter().any(|j| j.nq() == 7) =>
                {
                    FLOATING_HINT
                }
                Some(_) if !options.locks.is_empty() => LOCK_HINT,
                _ => "",
            };
        }
        self
    }
}

/// Why a sample's state cannot be evaluated or completed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StateProblem {
    /// `complete` found no assembly from the sample's guess.
    #[error("the loop constraints could not be solved from this guess (residual {residual:e}); the independent coordinates may be outside the mechanism's range, or the guess too far from an assembly")]
    NotAssembled {
        /// The largest residual left.
        residual: f64,
    },
    /// A free joint's quaternion is zero (or not finite), so `complete` cannot normalize it.
    #[error("field `q`[{start}..{end}]: the quaternion of joint `{}` is {values:?}; it must be a non-zero quaternion [qx qy qz qw] (it is normalized)", embedyn_codegen::shortened(.joint).escape_debug())]
    ZeroQuaternion {
        /// The joint.
        joint: String,
        /// The quaternion's first index in `q`.
        start: usize,
        /// One past its last index.
        end: usize,
        /// The quaternion as given.
        values: Vec<f64>,
    },
    /// A free joint's quaternion is not of unit norm.
    #[error("field `q`[{start}..{end}]: the quaternion of joint `{}` has norm {norm}; it must be a unit quaternion [qx qy qz qw]", embedyn_codegen::shortened(.joint))]
    NotUnitQuaternion {
        /// The joint.
        joint: String,
        /// The quaternion's first index in `q`.
        start: usize,
        /// One past its last index.
        end: usize,
        /// Its norm.
        norm: f64,
    },
    /// A loop is at or too near a singular configuration (by the generated code's measure).
    #[error("a loop is at or too near a singular configuration: cond(Y1) = {condition:.3e} ≥ {threshold:.1e}, the limit in this scalar type, {scalar} (the dependent joints are not determined by the independent ones here; the generated code gives the worst loop's measure, the interpreted engine names the loop)")]
    Singular {
        /// The condition number cond₁(Y1) the generated code returned.
        condition: f64,
        /// The scalar type's limit.
        threshold: f64,
        /// The scalar type.
        scalar: &'static str,
    },
    /// `q` does not satisfy the constraints.
    #[error("`q` violates the loop and coupling constraints by {violation:e} (more than 1e-9); `embedyn complete` solves the dependent coordinates")]
    PositionViolation {
        /// The largest residual.
        violation: f64,
    },
    /// `v` does not satisfy the velocity constraints.
    #[error("`v` violates the velocity constraints by {violation:e} (more than 1e-9); `embedyn complete` projects it")]
    VelocityViolation {
        /// The largest residual.
        violation: f64,
    },
    /// A result is not finite in the scalar type.
    #[error("`{output}`[{index}] is not finite ({value}); the state is outside what the scalar type can represent")]
    NotFinite {
        /// The output.
        output: &'static str,
        /// The entry.
        index: usize,
        /// Its value.
        value: f64,
    },
}

/// A broken invariant of embedyn itself.
#[derive(Debug, thiserror::Error)]
pub enum InternalError {
    /// A result could not be turned into JSON.
    #[error("the result is not JSON: {0}")]
    NotJson(#[source] serde_json::Error),
    /// A field of the samples was asked for that was not read.
    #[error("field `{field}` of the samples was not read")]
    FieldNotRead {
        /// The field.
        field: String,
    },
    /// A sample was asked for that the input does not hold.
    #[error("sample {sample} is not in the input")]
    SampleNotInInput {
        /// The sample, counted from 0.
        sample: usize,
    },
}

/// What is wrong with one field of a sample.
#[derive(Clone, Debug, PartialEq)]
pub enum SampleProblem {
    /// The field is absent.
    Missing,
    /// The field is not an array of numbers.
    NotArray,
    /// Fewer or more entries than the model needs.
    Length {
        /// The entries given.
        got: usize,
        /// The entries the model needs.
        expected: usize,
    },
    /// Entry `index` is not a finite number (`shown` as written).
    NotFinite {
        /// The entry.
        index: usize,
        /// The entry as written.
        shown: String,
    },
    /// `f_ext` is not an object of links to wrenches.
    NotWrenches,
    /// `f_ext` names a link the model does not have.
    UnknownLink {
        /// The name given.
        link: String,
        /// The model's links with a close name.
        suggestions: Vec<String>,
    },
    /// `f_ext` names a link twice.
    DuplicateLink {
        /// The link.
        link: String,
    },
    /// A link's wrench is not an object `{"force", "torque"}`.
    WrenchNotObject {
        /// The link.
        link: String,
    },
    /// A link's `force` or `torque`.
    WrenchPart {
        /// The link.
        link: String,
        /// `force` or `torque`.
        part: &'static str,
        /// What is wrong with it.
        problem: WrenchPartProblem,
    },
}

/// What is wrong with the `force` or `torque` of a wrench.
#[derive(Clone, Debug, PartialEq)]
pub enum WrenchPartProblem {
    /// Absent.
    Missing,
    /// Not an array.
    NotArray,
    /// Not three entries.
    Length {
        /// The entries given.
        got: usize,
    },
    /// Entry `index` is not a finite number (`shown` as written).
    NotFinite {
        /// The entry.
        index: usize,
        /// The entry as written.
        shown: String,
    },
}

/// `{"LINK": {"force": [fx, fy, fz], "torque": [tx, ty, tz]}, …}`, as messages show it.
const WRENCHES_SHAPE: &str = r#"{"LINK": {"force": [fx, fy, fz], "torque": [tx, ty, tz]}, …}"#;

fn field_problem(field: &str, problem: &SampleProblem) -> String {
    match problem {
        SampleProblem::Missing => format!("missing field `{field}`"),
        SampleProblem::NotArray => format!("field `{field}` must be an array of numbers"),
        SampleProblem::Length { got, expected } => {
            format!("field `{field}` has {got} entries, the model needs {expected}")
        }
        SampleProblem::NotFinite { index, shown } => {
            format!("field `{field}`[{index}] is not a finite number: {shown}")
        }
        SampleProblem::NotWrenches => {
            format!("field `{field}` must be an object {WRENCHES_SHAPE}")
        }
        SampleProblem::UnknownLink { link, suggestions } => format!(
            "field `{field}`: the model has no link {}{}",
            embedyn_codegen::names::fenced(&embedyn_codegen::shortened(link)),
            match suggestions.is_empty() {
                true => " (`embedyn info` lists the links under `frames`)".to_string(),
                false => suggest::did_you_mean(suggestions),
            }
        ),
        SampleProblem::DuplicateLink { link } => format!(
            "field `{field}`: link `{}` is given twice (one wrench per link: add them up)",
            embedyn_codegen::shortened(link)
        ),
        SampleProblem::WrenchNotObject { link } => format!(
            "field `{field}`: link `{}`: the wrench must be an object {{\"force\": [fx, fy, fz], \"torque\": [tx, ty, tz]}}",
            embedyn_codegen::shortened(link)
        ),
        SampleProblem::WrenchPart {
            link,
            part,
            problem,
        } => {
            let what = match problem {
                WrenchPartProblem::Missing => format!("missing `{part}`"),
                WrenchPartProblem::NotArray => format!("`{part}` must be an array of 3 numbers"),
                WrenchPartProblem::Length { got } => {
                    format!("`{part}` has {got} entries, it needs 3")
                }
                WrenchPartProblem::NotFinite { index, shown } => {
                    format!("`{part}`[{index}] is not a finite number: {shown}")
                }
            };
            format!(
                "field `{field}`: link `{}`: {what}",
                embedyn_codegen::shortened(link)
            )
        }
    }
}

fn read_failure(path: Option<&Path>, e: &ReadError) -> String {
    match path {
        Some(p) => format!("{}: cannot read the input: {e}", p.display()),
        None => format!("cannot read the input from stdin: {e}"),
    }
}

/// What a command prints on success.
pub enum Printed {
    /// A JSON document.
    Json(serde_json::Value),
    /// `eval`'s results, typed: one sample's output costs its numbers, not a tree of JSON values.
    Evaluated(eval::Evaluated),
    /// `complete`'s results, typed likewise.
    Completed(complete::Completed),
    /// Text for people (`bench`'s table).
    Text(String),
}

/// Runs a parsed command, returning what to print.
pub fn run(cli: Cli) -> Result<Printed, CliError> {
    match cli.command {
        Command::Info { model, scene } => {
            let loaded = load_reporting(&model, &scene)?;
            info::info(&loaded, &scene.options_for(&loaded)).map(Printed::Json)
        }
        Command::Bench {
            model,
            scene,
            json,
            max_compile_memory,
        } => {
            let loaded = load_reporting(&model, &scene)?;
            let result = bench::bench(&loaded, &scene.options_for(&loaded), max_compile_memory)?;
            Ok(if json {
                Printed::Json(result)
            } else {
                Printed::Text(bench::table(&result))
            })
        }
        Command::Tradeoff {
            model,
            scene,
            json,
            svg,
            max_compile_memory,
        } => {
            let loaded = load_reporting(&model, &scene)?;
            if scene.rotors.is_some() {
                output::note("embedyn tradeoff: measures every rotor choice; --rotors is ignored");
            }
            let result =
                tradeoff::tradeoff(&loaded, &scene.options(), max_compile_memory, &mut |step| {
                    output::note(&format!("embedyn tradeoff: {step}"))
                })?;
            if let Some(path) = svg {
                tradeoff::write_svg(&result, &path)?;
            }
            Ok(if json {
                Printed::Json(tradeoff::to_json(&result))
            } else {
                Printed::Text(tradeoff::table(&result))
            })
        }
        Command::Generate {
            model,
            out,
            scene,
            minv,
            only,
            scalar,
            max_compile_memory,
            wrenches,
            frames,
            reference,
            lanes,
            avx_twins,
            name,
        } => {
            if let Some(Err(message)) = name
                .as_deref()
                .map(embedyn_codegen::names::check_crate_name)
            {
                return Err(CliError::BadOption {
                    option: "--name",
                    message,
                });
            }
            if lanes == Some(0) {
                return Err(CliError::BadOption {
                    option: "--lanes",
                    message: "--lanes N: 2 or 4 for f64, 4 or 8 for f32 (leave it out for no lane modules)"
                        .into(),
                });
            }
            let loaded = load_reporting(&model, &scene)?;
            let options = embedyn_codegen::GenerateOptions {
                lanes: lanes.unwrap_or(0),
                avx_twins: embedyn_codegen::AvxTwins::from_name(&avx_twins)
                    .expect("clap checked the value"),
                crate_name: name,
                model: scene.options_for(&loaded),
                f64: scalar != Some(Scalar::F32),
                f32: scalar != Some(Scalar::F64),
                max_compile_memory_mb: Some(max_compile_memory),
                links: embedyn_codegen::LinkOptions {
                    // Link names are data: taken exactly as given.
                    wrenches,
                    frames,
                    // The parser admits only the three names.
                    reference: embedyn_codegen::Reference::from_name(&reference)
                        .unwrap_or_default(),
                },
                ..Default::default()
            };
            let only = only
                .map(|names| {
                    names
                        .iter()
                        .map(|name| embedyn_codegen::Algorithm::from_name(name.trim()))
                        .collect::<Result<Vec<_>, _>>()
                })
                .transpose()
                .map_err(|problem| CliError::Usage {
                    option: "--only",
                    problem,
                })?;
            let requested = if minv {
                &[embedyn_codegen::Algorithm::Minv][..]
            } else {
                &[]
            };
            let options = options.with_requested(only, requested);
            let files = embedyn_codegen::standalone::write_crate(&loaded, &options, &out)?;
            Ok(Printed::Json(serde_json::json!({
                // The name written (`--name`, else the robot's), checked by `write_crate` above.
                "crate": options.crate_name.clone().unwrap_or_else(|| {
                    embedyn_codegen::standalone::crate_name(&loaded.robot.name)
                }),
                "out": out,
                "files": files,
            })))
        }
        Command::Complete {
            model,
            scene,
            input,
        } => {
            let loaded = load_reporting(&model, &scene)?;
            let text = read_input(input.as_deref())?;
            complete::complete(&loaded, &scene.options_for(&loaded), &text).map(Printed::Completed)
        }
        Command::Eval {
            model,
            algo,
            engine,
            scalar,
            scene,
            input,
            frame,
            reference,
            max_compile_memory,
        } => {
            let query = eval::Query::new(algo, frame, reference)?;
            let loaded = load_reporting(&model, &scene)?;
            let text = read_input(input.as_deref())?;
            eval::eval(
                &loaded,
                &scene.options_for(&loaded),
                &query,
                engine,
                scalar,
                &text,
                max_compile_memory,
            )
            .map(Printed::Evaluated)
        }
    }
}

/// `embedyn eval --engine interpreted` on input text already read: the JSON document the command prints,
/// or its error. (The command line's own path, without file or stdin; the fuzzer drives it.)
pub fn eval_interpreted(
    loaded: &Loaded,
    options: &ModelOptions,
    algo: impl Into<EvalAlgo>,
    scalar: Scalar,
    input: &str,
) -> Result<serde_json::Value, CliError> {
    let query = eval::Query::new(algo.into(), None, None)?;
    let document = eval::eval(
        loaded,
        options,
        &query,
        Engine::Interpreted,
        scalar,
        input,
        0,
    )?;
    as_value(&document)
}

/// One query of [`eval_generated_together`]: `(algorithm, --frame, --reference, --scalar, input)`.
pub type GeneratedQuery<'a> = (
    EvalAlgo,
    Option<&'a str>,
    Option<Reference>,
    Scalar,
    &'a str,
);

/// Several `embedyn eval --engine generated` queries on one model, each `(algorithm, --frame,
/// --reference, --scalar, input)`, through one runner compiled in the cache folder `folder` (else the
/// usual one) with the union of their functions, links and scalars (wrench links and references must
/// agree): for tests, which would otherwise pay a compile per query. Each answer is the JSON document
/// `eval` prints for its query alone.
#[doc(hidden)]
pub fn eval_generated_together(
    loaded: &Loaded,
    options: &ModelOptions,
    queries: &[GeneratedQuery],
    folder: Option<&Path>,
) -> Result<Vec<serde_json::Value>, CliError> {
    let queries = queries
        .iter()
        .map(|&(algo, frame, reference, scalar, input)| {
            eval::Query::new(algo, frame.map(str::to_string), reference).map(|q| (q, scalar, input))
        })
        .collect::<Result<Vec<_>, CliError>>()?;
    eval::eval_generated_together(loaded, options, &queries, folder)?
        .iter()
        .map(as_value)
        .collect()
}

/// `embedyn complete` on input text already read: the JSON document the command prints, or its error.
pub fn complete_text(
    loaded: &Loaded,
    options: &ModelOptions,
    input: &str,
) -> Result<serde_json::Value, CliError> {
    as_value(&complete::complete(loaded, options, input)?)
}

/// The document as a JSON tree (for the fuzzer, which inspects it; inputs there are small).
fn as_value<T: serde::Serialize>(document: &T) -> Result<serde_json::Value, CliError> {
    serde_json::to_value(document).map_err(|e| InternalError::NotJson(e).into())
}

/// The most warnings printed one by one; the rest are counted, as errors are
/// ([`embedyn_codegen::MAX_LISTED_ERRORS`]).
pub const MAX_PRINTED_WARNINGS: usize = 20;

/// Loads the model and prints its warnings to stderr (at most [`MAX_PRINTED_WARNINGS`], then how many
/// more), but not the floating joint left in a comment when `--floating` makes the root free anyway.
fn load_reporting(path: &Path, scene: &SceneArgs) -> Result<Loaded, CliError> {
    let loaded = load(path)?;
    let shown: Vec<&embedyn_codegen::Warning> = loaded
        .warnings
        .iter()
        .filter(|w| {
            !(scene.floating
                && matches!(
                    w.kind,
                    embedyn_codegen::WarningKind::FloatingJointInComment { .. }
                ))
        })
        .collect();
    for w in shown.iter().take(MAX_PRINTED_WARNINGS) {
        output::note(&w.to_string());
    }
    if shown.len() > MAX_PRINTED_WARNINGS {
        output::note(&format!(
            "and {} more warnings",
            shown.len() - MAX_PRINTED_WARNINGS
        ));
    }
    Ok(loaded)
}

fn read_input(path: Option<&Path>) -> Result<String, CliError> {
    match path {
        Some(p) => read_file_limited(p, MAX_INPUT_BYTES).map_err(|error| CliError::ReadInput {
            path: Some(p.to_path_buf()),
            error,
        }),
        None => read_to_string_limited(std::io::stdin(), MAX_INPUT_BYTES)
            .map_err(|error| CliError::ReadInput { path: None, error }),
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;

    fn slider() -> Loaded {
        load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/unit_slider.urdf")).unwrap()
    }

    #[test]
    fn input_errors_carry_their_kind() {
        let loaded = slider();
        let options = ModelOptions::default();
        let nq = loaded.model::<f64>(&options).unwrap().nq();
        let refused = |input: &str| complete_text(&loaded, &options, input).unwrap_err();
        assert!(matches!(
            refused("{"),
            CliError::Input(InputError::NotJson(_))
        ));
        assert!(matches!(
            refused("{}"),
            CliError::Input(InputError::NoSamples)
        ));
        assert!(matches!(
            refused(r#"{"samples": 1}"#),
            CliError::Input(InputError::SamplesNotArray)
        ));
        let q = vec!["0"; nq + 1].join(", ");
        match refused(&format!(r#"{{"samples": [{{"q": [{q}], "v": []}}]}}"#)) {
            CliError::Input(InputError::TooManyEntries {
                sample, field, len, ..
            }) => {
                assert_eq!((sample, field, len), (0, "q", nq));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn state_problems_carry_their_data() {
        let loaded =
            load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/arm7.urdf")).unwrap();
        let options = ModelOptions {
            floating: true,
            ..Default::default()
        };
        let model = loaded.model::<f64>(&options).unwrap();
        let zeros = |n: usize| vec!["0"; n].join(", ");
        let input = format!(
            r#"{{"samples": [{{"q": [{}], "v": [{}]}}]}}"#,
            zeros(model.nq()),
            zeros(model.nv())
        );
        match complete_text(&loaded, &options, &input).unwrap_err() {
            CliError::State {
                sample: 0,
                problem:
                    StateProblem::ZeroQuaternion {
                        joint,
                        start,
                        end,
                        values,
                    },
            } => {
                assert_eq!(joint, embedyn_codegen::ROOT_JOINT);
                assert_eq!((start, end), (3, 7));
                assert_eq!(values, [0.0; 4]);
            }
            other => panic!("{other:?}"),
        }
    }
}
