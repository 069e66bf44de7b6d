//! How much memory rustc will need for generated code, and the refusal, with the numbers and the ways
//! to shrink it, when that is more than the user allows — instead of an out-of-memory abort in rustc
//! minutes later.
//!
//! The model of the estimate: rustc holds the whole crate's HIR and MIR at once, so its peak memory
//! is a base plus a cost per operation of the generated code, once per scalar module (`f64` and `f32`
//! hold the same code). The operations come from the traced tape; its size is known exactly once an
//! algorithm is traced, and before that it is predicted from the model's structure. Two checks:
//!
//! 1. before tracing, from the model: the O(N) algorithms trace to at most ~440 (`aba`), ~215 (`rnea`)
//!    and ~40 (`kinematics`) operations per degree of freedom, the O(N²) ones to ~24 per pair of
//!    degrees of freedom on one branch (`crba`) and ~38 per pair of any two (`minv`) — the counts of a
//!    chain whose joints have general offsets and whose links have full inertias, which folds least
//!    (robots with axis-aligned joints trace to 60–70 % of these; the derivatives of branched robots to
//!    a quarter to a third: TALOS's `aba_derivatives` 866,400 predicted, 253,310 traced). A request
//!    predicted at more than [`PREDICTION_SLACK`] times the limit is refused here, before the tracer
//!    spends time and memory on it;
//! 2. after tracing each function, from the emitted code itself: its operations, `let` bindings,
//!    indexings and scratch fields, weighted by what rustc builds for each
//!    ([`crate::emit::Emitted::compile_bytes`]). The total is checked against the limit before any
//!    formatting, writing or compiling.
//!
//! Calibrated on measured peak memory (BENCHMARKS.md, "Scale of generation"): within 11 % of 14
//! measured compiles of generated chains of 50–1000 bodies.

use crate::algorithm::{Algorithm, Growth, SizeCounts};
use crate::{LoadError, LoadErrorKind, Loaded, Location};
use embedyn_runtime::Model;

/// The default limit on rustc's estimated memory, MB: a 1000-body chain's `aba` (f64 and f32) fits, a
/// 200-body chain's `crba` does not.
pub const DEFAULT_COMPILE_MEMORY_MB: u64 = 2048;

/// What rustc needs for any generated crate, MB (the intercept of the fit; a crate with a one-body
/// `kinematics` measured 101 MB).
const COMPILER_BASE_MB: f64 = 130.0;

/// rustc's memory per operation of a long function and scalar module, bytes, for predictions before
/// tracing (measured beyond the base: 1.8 KB for `aba`, 2.2–2.5 KB for `crba` and `minv`; the upper
/// end keeps the prediction an upper bound).
const PREDICTED_BYTES_PER_OPERATION: f64 = 2600.0;

/// Bytes of Rust per operation of a long function, for the message (measured: 21 on chains).
const SOURCE_BYTES_PER_OPERATION: f64 = 21.0;

/// How far beyond the limit a prediction may go and still be traced, to be decided on the traced code.
/// The predictions are upper bounds that overshoot branched robots' derivatives by 3–4× (a floating
/// TALOS's `aba_derivatives` and `rnea_derivatives` in f64 and f32: 7.1 GB predicted, which refused at the
/// former slack of 2 a crate whose f64 half compiles in 0.9 GB), and tracing is cheap beside compiling:
/// 0.8 s and 110 MB for those two functions' 358,000 operations, where rustc needs 2.6 KB per operation.
pub const PREDICTION_SLACK: f64 = 4.0;

/// One function's size: exact once traced, else predicted from the model.
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionSize {
    /// The function.
    pub algorithm: Algorithm,
    /// Its operations.
    pub operations: usize,
    /// rustc's estimated memory for the function in one scalar module, bytes.
    pub compile_bytes: f64,
    /// Whether it was traced (else predicted).
    pub traced: bool,
    /// Whether tracing stopped at the tape's budget (`tape_budget`): `operations` is then a lower
    /// bound, the nodes recorded when it stopped.
    pub tracing_stopped: bool,
    /// Whether `compile_bytes` counts an AVX twin of the function (src/dispatch.rs), which
    /// `avx_twins = none` leaves out.
    pub twinned: bool,
    /// The generated function's name where it is not the algorithm's (`frame_foot`): a refusal lists
    /// each frame function by it.
    pub name: Option<String>,
}

impl FunctionSize {
    /// The name a refusal gives the function: its own, else its algorithm's.
    fn shown_name(&self) -> &str {
        self.name.as_deref().unwrap_or(self.algorithm.name())
    }

    /// A function whose tracing stopped at the tape's budget (`tape_budget`): the nodes recorded, and
    /// the memory that many emitted operations would take at the budget's own rate (at least the limit).
    pub(crate) fn stopped(algorithm: Algorithm, full: crate::trace::TapeFull) -> FunctionSize {
        FunctionSize {
            algorithm,
            operations: full.nodes,
            compile_bytes: full.nodes as f64 * crate::emit_large::PER_OPERATION / TAPE_SLACK,
            traced: true,
            tracing_stopped: true,
            twinned: false,
            name: None,
        }
    }
}

/// A lane module's copy of a function takes about this many times the scalar copy's compile memory
/// (measured 2026-12-02, release, rustc peak: arm7's `aba_derivatives` + `rnea_derivatives` 196 MB without
/// lanes, 956 MB with `lanes = 4`; the quadruped's `aba_derivatives` 1.31 GB with lanes): SIMD values and
/// the inlined lane operations. The size guard counts each lane module's copy at this weight. Raised from
/// 4 on 2026-12-03: the floating TALOS's `aba_derivatives` in f64 with `--lanes 4` peaked at 1,726 MiB
/// where a weight of 4 estimated 1,054 MB (attacker's trial; 330 MiB without lanes, as estimated).
pub const LANE_MEMORY_FACTOR: f64 = 8.0;

/// The share of a lane copy's compile memory that the copy's AVX twin adds (the TALOS trial above: its
/// lane and scalar twins together added 400 MiB to the 1,726).
pub const LANE_TWIN_MEMORY_SHARE: f64 = 0.3;

/// The predicted size of `algorithm` on `model` (an upper bound for the joints embedyn supports).
pub fn predicted(model: &Model<f64>, algorithm: Algorithm) -> FunctionSize {
    let nv = model.nv() as f64;
    let ni = model.independent_nv() as f64;
    // Pairs of degrees of freedom on one branch (the nonzero lower triangle of M on a tree).
    let mut depth = vec![0usize; model.joints.len()];
    let mut branch_pairs = 0usize;
    for (j, joint) in model.joints.iter().enumerate() {
        depth[j] = joint.nv() + joint.parent.map_or(0, |p| depth[p]);
        branch_pairs += joint.nv() * depth[j];
    }
    let counts = SizeCounts {
        nv,
        ni,
        links: model.bodies.iter().map(|b| b.links.len()).sum::<usize>() as f64,
        crba: 24.0 * branch_pairs as f64 + 30.0 * nv,
    };
    let operations = (algorithm.spec().predicted_operations)(&counts);
    FunctionSize {
        algorithm,
        operations: operations.ceil() as usize,
        compile_bytes: operations * PREDICTED_BYTES_PER_OPERATION,
        traced: false,
        tracing_stopped: false,
        twinned: false,
        name: None,
    }
}

/// Nodes a tape may hold for each operation the memory limit allows one function (`tape_budget`): a
/// tape also holds what folding leaves dead (and common subexpressions are merged as they are added),
/// so it runs longer than the emitted function.
const TAPE_SLACK: f64 = 3.0;

/// The nodes a function's tape may reach before tracing stops ([`crate::trace::record_within`]): with
/// at least 1,300 bytes of rustc's memory per emitted operation (`emit_large`'s cheapest form), a
/// function with more operations than `limit_mb` allows in `modules` scalar modules is refused whatever
/// else it holds; the tape may run [`TAPE_SLACK`] times that. `None` without a limit. The predictions
/// before tracing are upper bounds for trees, not for loop groups, whose embedding traces to a cube of
/// the group's size (a 120-link closed chain's `aba`: 52,800 operations predicted, 4.6 million traced in
/// 16 s and 1.6 GB before the budget; a 200-link chain exhausted 5 GB and aborted).
pub fn tape_budget(limit_mb: Option<u64>, modules: usize) -> Option<usize> {
    let limit = limit_mb? as f64;
    let per_module = (limit - COMPILER_BASE_MB).max(0.0) * 1024.0 * 1024.0
        / (CARGO_OVERHEAD * modules.max(1) as f64);
    Some(
        ((TAPE_SLACK * per_module / crate::emit_large::PER_OPERATION) as usize)
            .max(MIN_TAPE_BUDGET),
    )
}

/// The smallest tape budget: below it tracing costs little (about 30 MB), and a limit at or under
/// rustc's base (130 MB), which allows no operation at all, is then refused on the traced count rather
/// than as "more than 0 operations" (attacker's trial).
const MIN_TAPE_BUDGET: usize = 100_000;

/// `cargo build` over a bare `rustc` compile of the same crate (it also writes metadata and
/// dependency information): measured 1.81 GB against 1.65 GB for the 1000-body chain's `aba`.
const CARGO_OVERHEAD: f64 = 1.1;

/// rustc's estimated peak memory under `cargo build --release`, MB, for these functions in `modules`
/// scalar modules.
pub fn compile_memory_mb(functions: &[FunctionSize], modules: usize) -> f64 {
    let per_module: f64 = functions.iter().map(|f| f.compile_bytes).sum();
    COMPILER_BASE_MB + CARGO_OVERHEAD * modules as f64 * per_module / (1024.0 * 1024.0)
}

/// Refuses when the estimate for `decisive` exceeds `limit_mb` times `slack` ([`PREDICTION_SLACK`] for
/// predictions before tracing, 1 for traced code); the message reports `all` the requested functions.
pub fn check(
    loaded: &Loaded,
    decisive: &[FunctionSize],
    all: &[FunctionSize],
    scalars: &[&'static str],
    limit_mb: Option<u64>,
    slack: f64,
) -> Result<(), LoadError> {
    let Some(limit) = limit_mb else {
        return Ok(());
    };
    if compile_memory_mb(decisive, scalars.len()) <= limit as f64 * slack {
        return Ok(());
    }
    Err(refuse(loaded, all, scalars, limit))
}

/// The refusal of `all` the requested functions under `limit_mb`.
pub fn refuse(
    loaded: &Loaded,
    all: &[FunctionSize],
    scalars: &[&'static str],
    limit: u64,
) -> LoadError {
    let memory = compile_memory_mb(all, scalars.len());
    LoadError::at(
        Location::new(
            &loaded.robot.source,
            None,
            format!("robot \"{}\"", loaded.robot.name),
        ),
        LoadErrorKind::TooLargeToCompile(Box::new(TooLargeToCompile {
            functions: all.to_vec(),
            scalars: scalars.to_vec(),
            memory_mb: memory,
            limit_mb: limit,
        })),
    )
}

/// `1,234,567`.
fn grouped(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `270 MB`, `2.8 GB`.
fn memory_text(mb: f64) -> String {
    if mb < 1024.0 {
        format!("{mb:.0} MB")
    } else {
        format!("{:.1} GB", mb / 1024.0)
    }
}

/// Generated code refused as too large to compile within the memory limit: the sizes that decided it
/// and what shrinks it, as the message says.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", refusal(.functions, .scalars, *.memory_mb, *.limit_mb))]
pub struct TooLargeToCompile {
    /// Every function asked for, traced or predicted.
    pub functions: Vec<FunctionSize>,
    /// The scalar modules asked for (`"f64"`, `"f32"`).
    pub scalars: Vec<&'static str>,
    /// rustc's estimated memory for all of it (MB).
    pub memory_mb: f64,
    /// The limit (MB).
    pub limit_mb: u64,
}

fn refusal(functions: &[FunctionSize], scalars: &[&str], memory: f64, limit: u64) -> String {
    let mut sorted: Vec<&FunctionSize> = functions.iter().collect();
    sorted.sort_by_key(|f| std::cmp::Reverse(f.operations));
    let total: usize = functions.iter().map(|f| f.operations).sum::<usize>() * scalars.len();
    let list: Vec<String> = sorted
        .iter()
        .map(|f| {
            if f.tracing_stopped {
                format!(
                    "`{}` more than {} traced operations (tracing stopped there)",
                    f.shown_name(),
                    grouped(f.operations)
                )
            } else {
                format!(
                    "`{}` {}{}",
                    f.shown_name(),
                    grouped(f.operations),
                    if f.traced { "" } else { " predicted" }
                )
            }
        })
        .collect();
    let how = if functions.iter().any(|f| f.tracing_stopped) {
        "counted while tracing, which stopped once the code could no longer fit the limit"
    } else if functions.iter().all(|f| f.traced) {
        "counted in the traced code"
    } else if functions.iter().any(|f| f.traced) {
        "counted in the traced code, and predicted from the model for what is not traced yet"
    } else {
        "predicted from the model before tracing"
    };
    let quadratic: Vec<&str> = sorted
        .iter()
        .map(|f| f.algorithm)
        .filter(|a| a.spec().growth == Growth::Quadratic)
        .map(Algorithm::name)
        .collect();
    let linear: Vec<&str> = sorted
        .iter()
        .map(|f| f.algorithm.name())
        .filter(|n| !quadratic.contains(n))
        .collect();
    let by_name = |names: &[&str], sep: &str| -> String {
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(sep)
    };
    let fewer = match (quadratic.is_empty(), linear.is_empty()) {
        _ if sorted.len() == 1 => String::new(),
        (false, false) => format!(
            "leave out {} — the mass matrix and its inverse grow with the square of the number of \
             degrees of freedom, the other functions linearly (`--only {}` for `embedyn generate`, \
             `only({})` in `robot!`, `GenerateOptions::algorithms` in build.rs); ",
            by_name(&quadratic, " and "),
            linear.join(","),
            linear.join(", ")
        ),
        (false, true) => format!(
            "generate {} one at a time — each grows with the square of the number of degrees of \
             freedom (`--only {}` for `embedyn generate`, `only({})` in `robot!`); ",
            by_name(&quadratic, " and "),
            quadratic[quadratic.len() - 1],
            quadratic[quadratic.len() - 1]
        ),
        (true, _) => "generate fewer functions (`--only …` for `embedyn generate`, `only(…)` in \
                      `robot!`, `GenerateOptions::algorithms` in build.rs); "
            .to_string(),
    };
    let twinned = functions.iter().any(|f| f.twinned);
    // The AVX copies are in the f64 module only: one scalar type halves the rest.
    let one_scalar = match (scalars.len() > 1, twinned) {
        (false, _) => "",
        (true, false) => {
            "generate one scalar type, which halves it (`--scalar f64` for `embedyn generate`, \
             `f64_only` in `robot!`, `GenerateOptions::f32 = false`); "
        }
        (true, true) => {
            "generate one scalar type (`--scalar f64` for `embedyn generate`, `f64_only` in \
             `robot!`, `GenerateOptions::f32 = false`); "
        }
    };
    let twins = if twinned {
        "leave out the AVX copies of the `f64` functions (`--avx-twins none` for `embedyn generate`, \
         `avx_twins = none` in `robot!`, `GenerateOptions::avx_twins`); "
    } else {
        ""
    };
    let stopped = functions.iter().any(|f| f.tracing_stopped);
    // Stopped tracing leaves the size unknown beyond the limit: at least twice it, then.
    let needed = if stopped {
        ((2.0 * limit as f64 / 1024.0).ceil() as u64).max(1) * 1024
    } else {
        ((memory / 1024.0).ceil() as u64) * 1024
    };
    // With one function in one scalar module there is nothing to leave out.
    let remedy = if fewer.is_empty() && one_scalar.is_empty() && twins.is_empty() {
        "Raise the limit".to_string()
    } else {
        format!("To shrink it, {twins}{fewer}{one_scalar}or raise the limit")
    };
    // Stopped tracing counted the tape's values, not the operations that would reach the code: an amount
    // of source is not known then.
    let (operations, rust, estimated, at_least) = if stopped {
        (
            format!("more than {} traced operations", grouped(total)),
            ",".to_string(),
            "more than an estimated",
            "at least ",
        )
    } else {
        (
            format!("{} operations", grouped(total)),
            format!(
                ", about {} MB of Rust,",
                grouped((total as f64 * SOURCE_BYTES_PER_OPERATION / 1e6).ceil() as usize)
            ),
            "an estimated",
            "",
        )
    };
    format!(
        "the generated code is too large to compile within the memory limit: {operations} in {} \
         (each: {}; {}){rust} for which rustc needs {estimated} {} of memory (limit {}). {remedy} \
         where the memory is available ({at_least}`--max-compile-memory {needed}`, \
         `max_compile_memory = {needed}` in `robot!`, `GenerateOptions::max_compile_memory_mb`)",
        if scalars.len() > 1 {
            format!("the {} modules", scalars.join(" and "))
        } else {
            format!("the {} module", scalars.join(""))
        },
        list.join(", "),
        how,
        memory_text(memory),
        memory_text(limit as f64),
    )
}
