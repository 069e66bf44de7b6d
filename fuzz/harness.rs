//! The properties the fuzz targets check, in one place: the libFuzzer targets (`fuzz_targets/`, nightly)
//! and the corpus replay test (`tests/fuzz_corpus.rs`, stable `cargo test`) include this file, so every
//! committed input is checked the same way by both.
//!
//! A violated property panics (libFuzzer reports it as a crash; the replay test as a failure naming the
//! input). The properties (docs/model-format.md and §3: never a panic, never an abort, never a hang, never a silent
//! NaN):
//!
//! - **No panic, abort or hang** on any input: every failure is an `Err`, and the line it names (if
//!   any) is a line of the file.
//! - **Constants fit the scalar**: a model that builds in `T` holds only finite numbers (a constant that
//!   does not fit `T` is a load error, not a different model).
//! - **Non-finite inputs are refused**: an algorithm given a NaN or infinite `q`, `v`, `tau` or `qdd`
//!   returns an error, never `Ok`.
//! - **No silent NaN** — precisely: when the model's numbers and the state are *moderate* for the scalar
//!   (every non-zero mass, inertia, length, axis, ratio, multiplier and offset of the file within
//!   [`comfortable_range`], and the state within |q| ≤ 4, |v| ≤ 10, |τ|, |q̈| ≤ 100), the exact result is
//!   far inside the scalar's range, so every entry of an `Ok` result must be finite; a NaN or infinity
//!   there is a wrong answer that did not say so. Outside that regime the true answer may itself overflow
//!   (a mass of 1e300 under gravity), and only the other properties are checked.
//! - **Answers agree where they must** (f64, moderate, trees): `M q̈ + h = τ` for ABA's `q̈` and
//!   `M⁻¹ M = I`, to a backward error of 1e-6 relative to the magnitudes involved; `complete`'s residual
//!   says when its `q` is not finite.
//! - **Generated code is well-formed** (models of at most [`MAX_CODEGEN_BODIES`] bodies, one algorithm
//!   per input, picked by the state bytes): what
//!   `generate_tokens` accepts, `format_tokens` formats, and no float literal of the `f32` module
//!   overflows `f32` (rustc would refuse the crate).
//! - **The command line's answers are complete** (`eval_input`): an `Ok` document has one finite output
//!   per sample (serde_json writes NaN as `null`, which is checked for), and a state `complete` prints is
//!   accepted by `eval` (no constraint-violation error).

#![allow(dead_code)]

use embedyn_cli::{complete_text, eval_interpreted, Algo, Scalar};
use embedyn_codegen::ir::Robot;
use embedyn_codegen::{
    format_tokens, generate_tokens, parse_urdf, Algorithm, GenerateOptions, Loaded, Location,
    LockedJoint, ModelOptions, Rotors,
};
use embedyn_runtime::constraints::{complete_configuration, complete_velocity, ConstraintKind};
use embedyn_runtime::nalgebra::DMatrix;
use embedyn_runtime::{
    aba, crba, embedding_map, forward_kinematics, link_poses, mass_matrix_inverse,
    reduced_mass_matrix, rnea, Model, Real, Transform, Workspace,
};
use serde_json::Value;
use std::path::Path;

/// Models with more bodies are only loaded and built (the algorithms' cost is not what is fuzzed).
pub const MAX_DYNAMICS_BODIES: usize = 30;
/// Models with at most this many bodies are also traced and their code generated (not compiled).
pub const MAX_CODEGEN_BODIES: usize = 6;

/// Bounds of the moderate state (see the module documentation).
const Q_BOUND: f64 = 4.0;
const V_BOUND: f64 = 10.0;
const FORCE_BOUND: f64 = 100.0;

/// The magnitudes, `[smallest, largest]`, within which every non-zero number of a model file keeps the
/// dynamics far from `T`'s overflow and underflow: the algorithms multiply at most a handful of them
/// (a mass times two lengths times two velocities), which stays within about 1e±200 in `f64` and
/// 1e±30 in `f32`.
pub fn comfortable_range<T: Real>() -> (f64, f64) {
    if T::epsilon().to_f64() < 1e-10 {
        (1e-30, 1e30)
    } else {
        (1e-4, 1e4)
    }
}

// ---------------------------------------------------------------------------------------------------
// The `urdf` target
// ---------------------------------------------------------------------------------------------------

/// Fuzz input of the `urdf` target: URDF text, optionally followed by a NUL byte and state bytes (XML
/// cannot contain NUL, so the split is unambiguous). Invalid UTF-8 is replaced, so that byte-level
/// mutations still reach the parser.
pub fn urdf(data: &[u8]) {
    let (text, state) = match data.iter().position(|&b| b == 0) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[][..]),
    };
    let text = String::from_utf8_lossy(text);
    let lines = text.matches('\n').count() + 1;
    let loaded = match parse_urdf(&text, Path::new("fuzz.urdf")) {
        Ok(loaded) => loaded,
        Err(e) => return assert_line_in_file(&e.location, lines),
    };
    for w in &loaded.warnings {
        assert_line_in_file(&w.location, lines);
    }
    let mut generated = false;
    for floating in [false, true] {
        let options = ModelOptions {
            floating,
            ..Default::default()
        };
        let (model64, model32) = load_checked(&loaded, &options, lines);
        let Some(model64) = model64 else { continue };
        if model64.nbodies() > MAX_DYNAMICS_BODIES {
            continue;
        }
        dynamics(&model64, &loaded.robot, state, "f64");
        if let Some(model32) = &model32 {
            dynamics(model32, &loaded.robot, state, "f32");
        }
        // One algorithm per input (picked by the state bytes), on the first variant that builds: tracing
        // every algorithm would make each execution slow for little more coverage.
        if model64.nbodies() <= MAX_CODEGEN_BODIES && !generated {
            generated = true;
            let pick = usize::from(StateBytes::new(state).nth(1));
            generation(&loaded, &options, &model64, pick);
        }
    }
    scene_options(&loaded, state, lines);
}

/// The scene options on top of the file (docs/model-format.md): one joint locked, picked by the state
/// bytes, at a moderate value (a `<mimic>`'s driver fixes its followers; a mimic joint, a joint of a
/// loop or coupling, or one of several coordinates is refused at a line of the file), each with exact and
/// reflected rotors. The model that builds holds only finite numbers, and its dynamics keep the
/// properties above.
fn scene_options(loaded: &Loaded, state: &[u8], lines: usize) {
    let joints = &loaded.robot.joints;
    if joints.is_empty() {
        return;
    }
    let joint = &joints[usize::from(StateBytes::new(state).nth(2)) % joints.len()];
    let value = f64::from(StateBytes::new(state).nth(3)) / 32.0 - 4.0;
    for rotors in [Rotors::Exact, Rotors::Reflected] {
        let options = ModelOptions {
            locks: vec![LockedJoint {
                joint: joint.name.clone(),
                value,
            }],
            rotors,
            ..Default::default()
        };
        let (Some(model64), _) = load_checked(loaded, &options, lines) else {
            continue;
        };
        if model64.nbodies() <= MAX_DYNAMICS_BODIES {
            dynamics(&model64, &loaded.robot, state, "f64");
        }
    }
}

/// The model of `options` in f64 and f32, where each builds: an error names a line of the file (`lines`
/// lines), a model holds only finite numbers.
fn load_checked(
    loaded: &Loaded,
    options: &ModelOptions,
    lines: usize,
) -> (Option<Model<f64>>, Option<Model<f32>>) {
    let model64 = loaded.model::<f64>(options);
    let model32 = loaded.model::<f32>(options);
    for e in [model64.as_ref().err(), model32.as_ref().err()]
        .into_iter()
        .flatten()
    {
        assert_line_in_file(&e.location, lines);
    }
    if let Ok(m) = &model64 {
        assert_model_finite(m, "f64");
    }
    if let Ok(m) = &model32 {
        assert_model_finite(m, "f32");
    }
    (model64.ok(), model32.ok())
}

/// A message's line, where it gives one, is a line of the file (`lines` lines).
fn assert_line_in_file(location: &Location, lines: usize) {
    if let Some(line) = location.line {
        assert!(
            (1..=lines).contains(&(line as usize)),
            "{location}: line {line} of a file of {lines} lines"
        );
    }
}

/// Every number of a built model is finite.
fn assert_model_finite<T: Real>(model: &Model<T>, scalar: &str) {
    let bad = |what: String| -> ! {
        panic!("the {scalar} model built, but {what} is not finite (a constant that does not fit the scalar must be a load error)")
    };
    let transform_ok = |x: &Transform<T>| {
        x.rotation
            .iter()
            .chain(x.translation.iter())
            .all(|v| v.is_finite())
    };
    if !model.gravity.iter().all(|v| v.is_finite()) {
        bad("gravity".into());
    }
    for j in &model.joints {
        if !j.axis.iter().all(|v| v.is_finite()) || !transform_ok(&j.placement) {
            bad(format!("joint `{}`'s axis or placement", j.name));
        }
    }
    for b in &model.bodies {
        let i = &b.inertia;
        let inertia_ok = i.mass.is_finite()
            && i.first_moment.iter().all(|v| v.is_finite())
            && i.rotational.iter().all(|v| v.is_finite());
        if !inertia_ok || !b.link_placements.iter().all(transform_ok) {
            bad(format!("body `{}`'s inertia or link placements", b.name));
        }
    }
    for c in &model.constraints {
        let ok = match &c.kind {
            ConstraintKind::Linear { terms, offset } => {
                offset.is_finite() && terms.iter().all(|(_, k)| k.is_finite())
            }
            ConstraintKind::Loop(l) => {
                transform_ok(&l.predecessor_frame)
                    && transform_ok(&l.successor_frame)
                    && l.axis
                        .iter()
                        .chain(&l.e1)
                        .chain(&l.e2)
                        .all(|v| v.is_finite())
            }
        };
        if !ok {
            bad(format!("constraint `{}`", c.name));
        }
    }
}

/// Whether every non-zero number of the file lies in `T`'s [`comfortable_range`].
fn model_is_moderate<T: Real>(robot: &Robot) -> bool {
    let (lo, hi) = comfortable_range::<T>();
    let mut numbers: Vec<f64> = Vec::new();
    for l in &robot.links {
        if let Some(i) = &l.inertial {
            numbers.push(i.mass);
            numbers.extend(i.inertia);
            numbers.extend(i.origin.xyz);
        }
    }
    for j in &robot.joints {
        numbers.extend(j.origin.xyz);
        numbers.extend(j.axis);
        for m in &j.mimics {
            numbers.push(m.multiplier);
            numbers.push(m.offset);
        }
    }
    for l in &robot.loops {
        numbers.extend(l.predecessor.origin.xyz);
        numbers.extend(l.successor.origin.xyz);
        numbers.extend(l.axis);
    }
    for c in &robot.couplings {
        numbers.push(c.ratio);
    }
    numbers
        .iter()
        .all(|&x| x == 0.0 || (lo..=hi).contains(&x.abs()))
}

/// Reads the state from the bytes after the NUL: the first byte picks the mode (below 0xF0: a moderate
/// state, two bytes per number scaled into the bounds; otherwise: raw `f64` bit patterns, NaN and
/// infinities included). Missing bytes continue with a fixed pseudo-random sequence.
struct StateBytes<'a> {
    bytes: &'a [u8],
    seed: u64,
}

impl<'a> StateBytes<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        StateBytes {
            bytes,
            seed: 0x9e37_79b9_7f4a_7c15,
        }
    }

    /// Byte `k` of the sequence.
    fn nth(mut self, k: usize) -> u8 {
        for _ in 0..k {
            self.byte();
        }
        self.byte()
    }

    fn byte(&mut self) -> u8 {
        match self.bytes.split_first() {
            Some((&b, rest)) => {
                self.bytes = rest;
                b
            }
            None => {
                // xorshift64*
                self.seed ^= self.seed >> 12;
                self.seed ^= self.seed << 25;
                self.seed ^= self.seed >> 27;
                (self.seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 56) as u8
            }
        }
    }

    /// A number in [-1, 1].
    fn unit(&mut self) -> f64 {
        let raw = u16::from_le_bytes([self.byte(), self.byte()]);
        f64::from(raw) / 32767.5 - 1.0
    }

    fn raw(&mut self) -> f64 {
        let mut b = [0u8; 8];
        b.iter_mut().for_each(|x| *x = self.byte());
        f64::from_le_bytes(b)
    }
}

/// One state for every algorithm: `q`, `v`, `tau`, `qdd` (f64; cast to the scalar in use).
struct State {
    q: Vec<f64>,
    v: Vec<f64>,
    tau: Vec<f64>,
    qdd: Vec<f64>,
    moderate: bool,
}

fn state_from<T: Real>(model: &Model<T>, bytes: &[u8]) -> State {
    let mut src = StateBytes::new(bytes);
    let moderate = src.byte() < 0xf0;
    let (nq, nv) = (model.nq(), model.nv());
    let mut number = |bound: f64| {
        if moderate {
            bound * src.unit()
        } else {
            src.raw()
        }
    };
    let q: Vec<f64> = (0..nq).map(|_| number(Q_BOUND)).collect();
    let v = (0..nv).map(|_| number(V_BOUND)).collect();
    let tau = (0..nv).map(|_| number(FORCE_BOUND)).collect();
    let qdd = (0..nv).map(|_| number(FORCE_BOUND)).collect();
    State {
        q,
        v,
        tau,
        qdd,
        moderate,
    }
}

fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

fn all_finite<T: Real>(x: impl IntoIterator<Item = T>) -> bool {
    x.into_iter().all(|v| v.is_finite())
}

fn matrix_finite<T: Real>(m: &DMatrix<T>) -> bool {
    all_finite(m.iter().copied())
}

/// The interpreted algorithms at the neutral configuration and at the state from the input bytes.
fn dynamics<T: Real>(model: &Model<T>, robot: &Robot, state_bytes: &[u8], scalar: &str) {
    let nv = model.nv();
    let moderate_model = model_is_moderate::<T>(robot);
    let neutral = State {
        q: model
            .neutral_configuration()
            .iter()
            .map(|x| x.to_f64())
            .collect(),
        v: vec![0.0; nv],
        tau: vec![0.0; nv],
        qdd: vec![0.0; nv],
        moderate: true,
    };
    let derived = state_from(model, state_bytes);
    let mut ws = Workspace::new(model);
    for (label, state) in [("neutral", neutral), ("derived", derived)] {
        let what = format!("{scalar}, {label} state");
        run_algorithms(
            model,
            &mut ws,
            &state,
            moderate_model && state.moderate,
            &what,
        );
    }
}

fn run_algorithms<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    state: &State,
    strict: bool,
    what: &str,
) {
    let mut q: Vec<T> = cast(&state.q);
    let mut v: Vec<T> = cast(&state.v);
    let tau: Vec<T> = cast(&state.tau);
    let qdd: Vec<T> = cast(&state.qdd);

    if model.has_constraints() {
        // The state's dependent entries are the guess; where completion converges, the algorithms run
        // at the assembled state, else at the guess (they must answer or refuse there too).
        let mut qc = q.clone();
        if let Ok(residual) = complete_configuration(model, ws, &mut qc) {
            let converged = residual <= 64.0 * T::epsilon().to_f64();
            if !all_finite(qc.iter().copied()) {
                assert!(
                    !converged,
                    "{what}: complete_configuration reports residual {residual:e} (converged) with a non-finite q"
                );
            } else if converged {
                let mut vc = v.clone();
                if complete_velocity(model, ws, &qc, &mut vc).is_ok() {
                    if strict {
                        assert!(
                            all_finite(vc.iter().copied()),
                            "{what}: complete_velocity returned Ok with a non-finite v"
                        );
                    }
                    q = qc;
                    v = vc;
                }
            }
        }
    }

    // Whether each call's own inputs are finite in `T` (after the cast and the completion).
    let q_finite = all_finite(q.iter().copied());
    let v_finite = all_finite(v.iter().copied());
    let aba_inputs_finite = q_finite && v_finite && all_finite(tau.iter().copied());
    let rnea_inputs_finite = q_finite && v_finite && all_finite(qdd.iter().copied());
    // An Ok answer with a non-finite entry: refused on non-finite inputs, a failure in the moderate regime.
    let check = |name: &str, ok: bool, finite: bool, inputs_ok: bool| {
        if !inputs_ok {
            assert!(!ok, "{what}: {name} returned Ok for a non-finite input");
        } else if strict && ok {
            assert!(
                finite,
                "{what}: {name} returned Ok with a non-finite entry (a silent NaN)"
            );
        }
    };
    let aba_out = aba(model, ws, &q, &v, &tau).map(|x| x.to_vec());
    check(
        "aba",
        aba_out.is_ok(),
        aba_out
            .as_ref()
            .is_ok_and(|x| all_finite(x.iter().copied())),
        aba_inputs_finite,
    );
    let rnea_out = rnea(model, ws, &q, &v, &qdd).map(|x| x.to_vec());
    check(
        "rnea",
        rnea_out.is_ok(),
        rnea_out
            .as_ref()
            .is_ok_and(|x| all_finite(x.iter().copied())),
        rnea_inputs_finite,
    );
    let m = crba(model, ws, &q).cloned();
    check(
        "crba",
        m.is_ok(),
        m.as_ref().is_ok_and(matrix_finite),
        q_finite,
    );
    let minv = mass_matrix_inverse(model, ws, &q).cloned();
    check(
        "mass_matrix_inverse",
        minv.is_ok(),
        minv.as_ref().is_ok_and(matrix_finite),
        q_finite,
    );
    let fk = forward_kinematics(model, ws, &q, &v);
    let fk_finite = fk.is_ok()
        && link_poses(model, ws).all(|(_, x)| {
            all_finite(x.rotation.iter().copied()) && all_finite(x.translation.iter().copied())
        })
        && ws
            .velocity
            .iter()
            .all(|m| all_finite(m.angular.iter().copied()) && all_finite(m.linear.iter().copied()));
    check(
        "forward_kinematics",
        fk.is_ok(),
        fk_finite,
        q_finite && v_finite,
    );
    if model.has_constraints() {
        let x = embedding_map(model, ws, &q);
        check(
            "embedding_map",
            x.is_ok(),
            x.as_ref().is_ok_and(matrix_finite),
            q_finite,
        );
        let r = reduced_mass_matrix(model, ws, &q);
        check(
            "reduced_mass_matrix",
            r.is_ok(),
            r.as_ref().is_ok_and(matrix_finite),
            q_finite,
        );
    } else if strict && T::epsilon().to_f64() < 1e-10 {
        if let (Ok(qdd_aba), Ok(m), Ok(minv)) = (&aba_out, &m, &minv) {
            agreement(model, ws, &q, &v, &tau, qdd_aba, m, minv, what);
        }
    }
}

/// `M q̈ + h = τ` and `M⁻¹ M = I` to a backward error of 1e-6 relative to the magnitudes involved. Those of
/// `h` include the velocity products' terms, about ‖M‖ ‖v‖², not only their sum: the gyroscopic torque of
/// a body whose inertia is isotropic cancels exactly, but each algorithm rounds the cancelling terms its own
/// way (finding 5, fuzz/README.md: an isotropic 1e28 kg·m² inertia at 2 rad/s left a bias of 2e12 N·m in
/// f64 where the exact one is 0, which the recursion of ABA and the RNEA round differently).
#[allow(clippy::too_many_arguments)]
fn agreement<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    qdd: &[T],
    m: &DMatrix<T>,
    minv: &DMatrix<T>,
    what: &str,
) {
    let nv = model.nv();
    let f = |x: T| x.to_f64();
    let zeros = vec![T::zero(); nv];
    let Ok(h) = rnea(model, ws, q, v, &zeros).map(|x| x.to_vec()) else {
        return;
    };
    let norm_inf = |x: &DMatrix<T>| {
        (0..x.nrows())
            .map(|r| (0..x.ncols()).map(|c| f(x[(r, c)]).abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let vec_inf = |x: &[T]| x.iter().map(|&y| f(y).abs()).fold(0.0, f64::max);
    let (m_norm, minv_norm) = (norm_inf(m), norm_inf(minv));
    let v_inf = vec_inf(v);
    let scale = m_norm * (vec_inf(qdd) + v_inf * v_inf) + vec_inf(&h) + vec_inf(tau);
    for r in 0..nv {
        let mq: f64 = (0..nv).map(|c| f(m[(r, c)]) * f(qdd[c])).sum();
        let residual = (mq + f(h[r]) - f(tau[r])).abs();
        assert!(
            residual <= 1e-6 * scale,
            "{what}: aba's q̈ does not satisfy M q̈ + h = τ: row {r} off by {residual:e} (scale {scale:e})"
        );
    }
    for r in 0..nv {
        for c in 0..nv {
            let p: f64 = (0..nv).map(|k| f(minv[(r, k)]) * f(m[(k, c)])).sum();
            let expected = if r == c { 1.0 } else { 0.0 };
            let err = (p - expected).abs();
            assert!(
                err <= 1e-6 * minv_norm * m_norm,
                "{what}: M⁻¹ M differs from I at ({r}, {c}) by {err:e} (‖M⁻¹‖‖M‖ = {:e})",
                minv_norm * m_norm
            );
        }
    }
}

/// Traces and emits algorithm number `pick` (modulo those the model has) in the f64 and f32 modules,
/// without compiling.
fn generation(loaded: &Loaded, options: &ModelOptions, model: &Model<f64>, pick: usize) {
    let algorithms: Vec<Algorithm> = Algorithm::ALL
        .into_iter()
        .filter(|a| model.has_constraints() || !a.needs_constraints())
        .collect();
    let generate = GenerateOptions {
        model: options.clone(),
        algorithms: vec![algorithms[pick % algorithms.len()]],
        exact: true,
        ..Default::default()
    };
    let Ok(tokens) = generate_tokens(loaded, &generate) else {
        return;
    };
    if let Err(e) = format_tokens(&tokens) {
        panic!("generate_tokens succeeded but its output does not format: {e}");
    }
    assert_f32_literals_fit(&tokens);
}

/// Every float literal inside `mod f32 { … }` is finite as an `f32` (rustc refuses `1e300` there).
fn assert_f32_literals_fit(tokens: &proc_macro2::TokenStream) {
    use proc_macro2::TokenTree;
    fn literals(stream: proc_macro2::TokenStream, out: &mut Vec<String>) {
        for t in stream {
            match t {
                TokenTree::Group(g) => literals(g.stream(), out),
                TokenTree::Literal(l) => out.push(l.to_string()),
                _ => {}
            }
        }
    }
    let trees: Vec<TokenTree> = tokens.clone().into_iter().collect();
    for w in trees.windows(3) {
        let is_f32_module = matches!(&w[0], TokenTree::Ident(i) if i == "mod")
            && matches!(&w[1], TokenTree::Ident(i) if i == "f32");
        if let (true, TokenTree::Group(body)) = (is_f32_module, &w[2]) {
            let mut found = Vec::new();
            literals(body.stream(), &mut found);
            for l in found {
                if let Ok(x) = l.parse::<f32>() {
                    assert!(
                        x.is_finite(),
                        "the generated f32 module has the literal {l}, which overflows f32"
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// The `eval_input` target
// ---------------------------------------------------------------------------------------------------

/// The bundled models `eval_input` drives: a tree, a floating tree, a loop, a coupling, mimic joints and
/// a scene with two free bodies.
pub const EVAL_MODELS: [(&str, &str); 6] = [
    ("models/arm7.urdf", include_str!("../models/arm7.urdf")),
    (
        "models/quadruped.urdf",
        include_str!("../models/quadruped.urdf"),
    ),
    (
        "models/loops/four_bar_internal.urdf",
        include_str!("../models/loops/four_bar_internal.urdf"),
    ),
    (
        "models/loops/geared_motor.urdf",
        include_str!("../models/loops/geared_motor.urdf"),
    ),
    (
        "models/loops/differential_wrist.urdf",
        include_str!("../models/loops/differential_wrist.urdf"),
    ),
    (
        "tests/data/scenes/two_free_bodies.urdf",
        include_str!("../tests/data/scenes/two_free_bodies.urdf"),
    ),
];

/// The commands `eval_input` drives, picked by the selector byte.
pub const EVAL_COMMANDS: [Command; 7] = [
    Command::Eval(Algo::Aba, Scalar::F64),
    Command::Eval(Algo::Aba, Scalar::F32),
    Command::Eval(Algo::Rnea, Scalar::F64),
    Command::Eval(Algo::Rnea, Scalar::F32),
    Command::Eval(Algo::Crba, Scalar::F64),
    Command::Eval(Algo::Crba, Scalar::F32),
    Command::Complete,
];

#[derive(Clone, Copy, Debug)]
pub enum Command {
    Eval(Algo, Scalar),
    Complete,
}

fn eval_models() -> &'static [Loaded] {
    static MODELS: std::sync::OnceLock<Vec<Loaded>> = std::sync::OnceLock::new();
    MODELS.get_or_init(|| {
        EVAL_MODELS
            .iter()
            .map(|(path, text)| {
                parse_urdf(text, Path::new(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
            })
            .collect()
    })
}

/// What the selector byte picks: model, command, `--floating`.
pub fn eval_selection(selector: u8) -> (usize, Command, bool) {
    let s = usize::from(selector);
    let nm = EVAL_MODELS.len();
    let nc = EVAL_COMMANDS.len();
    (
        s % nm,
        EVAL_COMMANDS[(s / nm) % nc],
        (s / (nm * nc)) % 2 == 1,
    )
}

/// The selector byte for a model, command and `--floating` (the inverse of [`eval_selection`]).
pub fn eval_selector(model: usize, command: usize, floating: bool) -> u8 {
    let nm = EVAL_MODELS.len();
    let nc = EVAL_COMMANDS.len();
    (model + nm * command + nm * nc * usize::from(floating)) as u8
}

/// Fuzz input of the `eval_input` target: a selector byte (see [`eval_selection`]), then the JSON input
/// text of `embedyn eval` or `embedyn complete`.
pub fn eval_input(data: &[u8]) {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let text = String::from_utf8_lossy(rest);
    let (m, command, floating) = eval_selection(selector);
    let loaded = &eval_models()[m];
    let options = ModelOptions {
        floating,
        ..Default::default()
    };
    let what = format!("{} {command:?} floating={floating}", EVAL_MODELS[m].0);
    let result = match command {
        Command::Eval(algo, scalar) => eval_interpreted(loaded, &options, algo, scalar, &text),
        Command::Complete => complete_text(loaded, &options, &text),
    };
    let Ok(document) = result else { return };
    let samples_in = serde_json::from_str::<Value>(&text)
        .ok()
        .and_then(|v| v.get("samples").and_then(Value::as_array).map(Vec::len))
        .expect("an accepted input has an array `samples`");
    let samples = document["samples"]
        .as_array()
        .unwrap_or_else(|| panic!("{what}: the output has no array `samples`: {document}"));
    assert_eq!(
        samples.len(),
        samples_in,
        "{what}: one output per input sample"
    );
    assert_no_null(&document, &what);
    let Ok(model) = loaded.model::<f64>(&options) else {
        panic!("{what}: the command succeeded on a model that does not build")
    };
    let (nq, nv, ni) = (model.nq(), model.nv(), model.independent_nv());
    for s in samples {
        let len = |field: &str| s[field].as_array().map(Vec::len);
        match command {
            Command::Eval(Algo::Aba, _) => {
                assert_eq!(len("qdd"), Some(nv), "{what}: qdd");
                assert_eq!(len("qdd_independent"), Some(ni), "{what}: qdd_independent");
                if !model.has_constraints() {
                    assert_eq!(s["qdd_independent"], s["qdd"], "{what}: a tree's qdd");
                }
            }
            Command::Eval(Algo::Rnea, _) => {
                assert_eq!(len("tau"), Some(nv), "{what}: tau");
                assert_eq!(len("tau_independent"), Some(ni), "{what}: tau_independent");
                if !model.has_constraints() {
                    // docs/command-line.md: for a model without constraints tau_independent equals tau.
                    assert_eq!(s["tau_independent"], s["tau"], "{what}: a tree's tau");
                }
            }
            Command::Eval(Algo::Crba, _) => {
                let n = if model.has_constraints() { ni } else { nv };
                let rows = s["M"].as_array().expect("M is an array of rows");
                assert_eq!(rows.len(), n, "{what}: rows of M");
                assert!(rows.iter().all(|r| r.as_array().map(Vec::len) == Some(n)));
            }
            Command::Eval(other, _) => {
                panic!(
                    "{what}: `eval` evaluated `{}`, which it does not offer",
                    other.name()
                )
            }
            Command::Complete => {
                assert_eq!(len("q"), Some(nq), "{what}: q");
                assert_eq!(len("v"), Some(nv), "{what}: v");
                let residual = s["residual"].as_f64().expect("a numeric residual");
                assert!(
                    residual <= 1e-9,
                    "{what}: residual {residual:e} in an Ok answer"
                );
                // What `complete` prints, `eval` accepts (docs/command-line.md: numbers are read exactly).
                let input = serde_json::json!({"samples": [{"q": s["q"], "v": s["v"], "tau": vec![0.0; nv]}]})
                    .to_string();
                if let Err(e) = eval_interpreted(loaded, &options, Algo::Aba, Scalar::F64, &input) {
                    assert!(
                        !e.to_string().contains("violates"),
                        "{what}: eval refuses the state complete printed: {}",
                        e
                    );
                }
            }
        }
    }
}

/// No `null` anywhere (serde_json writes a NaN or an infinity as `null`).
fn assert_no_null(v: &Value, what: &str) {
    match v {
        Value::Null => panic!("{what}: the output holds null (a non-finite number)"),
        Value::Array(a) => a.iter().for_each(|x| assert_no_null(x, what)),
        Value::Object(o) => o.values().for_each(|x| assert_no_null(x, what)),
        _ => {}
    }
}
