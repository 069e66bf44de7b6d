//! The extremes, measured: f32 and f64 against the double-double reference on (a) chains of N = 10 … 1000
//! bodies (ABA against CRBA + Cholesky, and cond(M)), (b) adjacent mass ratios 1 … 1e10, (c) a four-bar
//! approaching its toggle 1e-1 … 1e-12 rad, (d) geared motors of ratio 1 … 1000 with rotor inertia
//! 1e-2 … 1e-8 kg·m², (e) the energy drift of 10 s of simulation of a tree and a loop model with
//! semi-implicit Euler and RK4. Writes CSV data and SVG figures (docs/accuracy.md explains them):
//!
//! ```sh
//! cargo run --release -p embedyn-cli --example accuracy -- --out docs/accuracy
//! ```
//!
//! `--quick` runs smaller sizes (for trying changes; the published figures are from the full run).
//! Everything is deterministic (fixed seeds of `SplitMix64`): the same build gives the same files. Progress
//! goes to stderr, with the table of observed bounds at the end.
//!
//! "Relative error" is the project's: max|a − b| / max(1, max|b|) over the vector (CONTRACT §2). The
//! interpreted solver stands for the generated code too (the generated code is the interpreted solver
//! traced: same arithmetic in the same order). Every model is built in f64 and converted to each scalar
//! (its constants rounded once, `Model::try_cast`), and f32 rounds its inputs, as firmware would; the
//! reference is the same f64 model and inputs evaluated in double-double (≈ 32 digits).

use embedyn_cli::plot::{Marker, Plot, Series};
use embedyn_codegen::{parse_urdf, ModelOptions};
use embedyn_runtime::constraints::{
    complete_configuration, complete_velocity, singularity_threshold, y1_condition,
};
use embedyn_runtime::linalg::{condition_number_1_of, solve_spd};
use embedyn_runtime::nalgebra::{DMatrix, Matrix3, Vector3};
use embedyn_runtime::random::SplitMix64;
use embedyn_runtime::{
    aba, crba, forward_kinematics, kinetic_energy, mass_matrix_inverse, potential_energy,
    reduced_mass_matrix_in, relative_error, rnea, DoubleDouble, DynamicsError, JointType, Model,
    Real, SpatialInertia, Transform, Workspace,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

type Dd = DoubleDouble;

/// Below this relative error an answer keeps at least one correct digit; above it, it must not be given
/// quietly (the check this program makes of every f32 and f64 answer).
const NO_CORRECT_DIGIT: f64 = 0.1;

fn main() {
    let mut out = PathBuf::from("docs/accuracy");
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = PathBuf::from(args.next().expect("--out needs a directory")),
            "--quick" => quick = true,
            other => {
                eprintln!("usage: accuracy [--out DIR] [--quick]   (unknown argument `{other}`)");
                std::process::exit(2);
            }
        }
    }
    std::fs::create_dir_all(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    let start = Instant::now();
    let mut summary = Summary::default();
    chains(&out, quick, &mut summary);
    eprintln!("[{:.0} s] chains done", start.elapsed().as_secs_f64());
    mass_ratio(&out, &mut summary);
    eprintln!("[{:.0} s] mass ratios done", start.elapsed().as_secs_f64());
    four_bar_toggle(&out, &mut summary);
    eprintln!(
        "[{:.0} s] four-bar toggle done",
        start.elapsed().as_secs_f64()
    );
    gears(&out, &mut summary);
    eprintln!("[{:.0} s] gears done", start.elapsed().as_secs_f64());
    energy(&out, quick, &mut summary);
    eprintln!("[{:.0} s] energy done", start.elapsed().as_secs_f64());
    summary.write(&out);
    eprintln!("\n{}", summary.table());
    if summary.quiet_losses > 0 {
        eprintln!(
            "WARNING: {} answer(s) with no correct digit were returned without an error",
            summary.quiet_losses
        );
    }
    eprintln!(
        "wrote {} in {:.0} s",
        out.display(),
        start.elapsed().as_secs_f64()
    );
}

// ---------------------------------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------------------------------

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

fn cast<T: Real>(x: &[f64]) -> Vec<T> {
    x.iter().map(|&v| T::from_f64(v)).collect()
}

fn back<T: Real>(x: &[T]) -> Vec<f64> {
    x.iter().map(|v| v.to_f64()).collect()
}

/// ABA in `T` from f64 inputs (rounded to `T`), as f64.
fn run_aba<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<Vec<f64>, DynamicsError> {
    aba(model, ws, &cast::<T>(q), &cast::<T>(v), &cast::<T>(tau)).map(back)
}

/// CRBA + Cholesky in `T`: M qdd = τ − RNEA(q, v, 0). `Err` if M is not positive definite in `T`.
fn run_crba_cholesky<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<Vec<f64>, String> {
    let (q, v, tau) = (cast::<T>(q), cast::<T>(v), cast::<T>(tau));
    let zero = vec![T::from_f64(0.0); model.nv()];
    let bias = rnea(model, ws, &q, &v, &zero)
        .map_err(|e| e.to_string())?
        .to_vec();
    let m = crba(model, ws, &q).map_err(|e| e.to_string())?.clone();
    let rhs: Vec<T> = tau.iter().zip(&bias).map(|(t, b)| *t - *b).collect();
    solve_spd(&m, &rhs)
        .map(|x| back(&x))
        .ok_or_else(|| format!("M is not positive definite in {}", T::NAME))
}

/// The operator inverse of the mass matrix (the paper's Eq. 6, `mass_matrix_inverse`) in `T`, applied to
/// τ − RNEA(q, v, 0).
fn run_minv<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<Vec<f64>, String> {
    let (q, v, tau) = (cast::<T>(q), cast::<T>(v), cast::<T>(tau));
    let zero = vec![T::from_f64(0.0); model.nv()];
    let bias = rnea(model, ws, &q, &v, &zero)
        .map_err(|e| e.to_string())?
        .to_vec();
    let inv = mass_matrix_inverse(model, ws, &q).map_err(|e| e.to_string())?;
    let n = model.nv();
    Ok((0..n)
        .map(|i| {
            let mut s = T::from_f64(0.0);
            for j in 0..n {
                s += inv[(i, j)] * (tau[j] - bias[j]);
            }
            s.to_f64()
        })
        .collect())
}

/// The mass matrix in f64 (for torque scaling and cond(M)).
fn mass_matrix(model: &Model<f64>, q: &[f64]) -> DMatrix<f64> {
    let mut ws = Workspace::new(model);
    crba(model, &mut ws, q).expect("crba").clone()
}

/// The outcome of one evaluation against the reference.
#[derive(Clone, Debug)]
enum Outcome {
    /// An answer, with its relative error.
    Error(f64),
    /// An error instead of an answer (its short name).
    Refused(String),
}

impl Outcome {
    fn of<E: std::fmt::Display>(got: Result<Vec<f64>, E>, want: &[f64]) -> Outcome {
        match got {
            Ok(x) => Outcome::Error(relative_error(&x, want)),
            Err(e) => Outcome::Refused(short_reason(&e.to_string())),
        }
    }
    fn error(&self) -> Option<f64> {
        match self {
            Outcome::Error(e) => Some(*e),
            Outcome::Refused(_) => None,
        }
    }
    /// The CSV cells: error (empty when refused), refusal (empty when answered).
    fn csv(&self) -> String {
        match self {
            Outcome::Error(e) => format!("{e:.3e},"),
            Outcome::Refused(r) => format!(",{r}"),
        }
    }
}

fn short_reason(message: &str) -> String {
    if message.contains("singular configuration") {
        "singular_constraint".into()
    } else if message.contains("not positive definite") {
        "not_positive_definite".into()
    } else if message.contains("articulated inertia") {
        "singular_joint".into()
    } else {
        message
            .chars()
            .map(|c| if c == ',' { ';' } else { c })
            .take(60)
            .collect()
    }
}

/// Observed bounds per (extreme, case, scalar): the largest error of an answer, how many answers and
/// refusals, and answers that kept no correct digit.
#[derive(Default)]
struct Summary {
    rows: Vec<SummaryRow>,
    quiet_losses: usize,
}

struct SummaryRow {
    extreme: String,
    case: String,
    scalar: &'static str,
    worst: f64,
    answered: usize,
    refused: usize,
    note: String,
}

impl Summary {
    fn add(
        &mut self,
        extreme: &str,
        case: &str,
        scalar: &'static str,
        outcomes: &[Outcome],
        note: &str,
    ) {
        let worst = outcomes
            .iter()
            .filter_map(Outcome::error)
            .fold(0.0f64, |m, e| if e.is_nan() { f64::NAN } else { m.max(e) });
        let answered = outcomes.iter().filter(|o| o.error().is_some()).count();
        let quiet = outcomes
            .iter()
            .filter(|o| {
                o.error()
                    .is_some_and(|e| e.is_nan() || e > NO_CORRECT_DIGIT)
            })
            .count();
        if quiet > 0 {
            eprintln!("  QUIET LOSS: {extreme} {case} {scalar}: {quiet} answer(s) with relative error > {NO_CORRECT_DIGIT} and no error");
        }
        self.quiet_losses += quiet;
        self.rows.push(SummaryRow {
            extreme: extreme.into(),
            case: case.into(),
            scalar,
            worst,
            answered,
            refused: outcomes.len() - answered,
            note: note.into(),
        });
    }

    fn write(&self, out: &Path) {
        let mut csv =
            String::from("extreme,case,scalar,max_relative_error,answered,refused,note\n");
        for r in &self.rows {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{}",
                r.extreme,
                r.case.replace(',', ";"),
                r.scalar,
                if r.answered > 0 {
                    format!("{:.2e}", r.worst)
                } else {
                    String::new()
                },
                r.answered,
                r.refused,
                r.note.replace(',', ";")
            );
        }
        write_file(&out.join("summary.csv"), &csv);
    }

    fn table(&self) -> String {
        let mut t = String::from(
            "| extreme | case | scalar | max relative error | answered | refused | note |\n|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                t,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.extreme,
                r.case,
                r.scalar,
                if r.answered > 0 {
                    format!("{:.1e}", r.worst)
                } else {
                    "—".into()
                },
                r.answered,
                r.refused,
                r.note
            );
        }
        t
    }
}

fn write_file(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    eprintln!("  wrote {}", path.display());
}

/// A revolute chain of `masses.len()` bodies, 0.2 m links along z. `planar`: every axis y (the chain
/// folds in one plane: the classic worst case for the mass matrix's conditioning); otherwise axes
/// alternating z (roll along the link) and y (pitch). Body i has mass `masses[i]`, centre of mass
/// mid-link, inertia that of a 0.2 m rod of 0.22 m diameter scaled with its mass.
fn chain(masses: &[f64], planar: bool) -> Model<f64> {
    let mut b = Model::<f64>::builder(format!(
        "{}_chain{}",
        if planar { "planar" } else { "spatial" },
        masses.len()
    ));
    for (i, &m) in masses.iter().enumerate() {
        let axis = if planar || i % 2 == 1 {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let inertia = SpatialInertia::from_com(
            m,
            Vector3::new(0.0, 0.0, 0.1),
            Matrix3::from_diagonal(&Vector3::new(4e-3 * m, 4e-3 * m, 1e-3 * m)),
        );
        let placement = if i == 0 {
            Transform::identity()
        } else {
            Transform::from_xyz_rpy([0.0, 0.0, 0.2], [0.0; 3])
        };
        b.add_body(
            i.checked_sub(1),
            format!("j{i}"),
            JointType::Revolute,
            axis,
            placement,
            format!("b{i}"),
            inertia,
        )
        .expect("chain body");
    }
    b.build().expect("chain model")
}

/// A random state of a revolute tree: q ∈ [−π, π], v ∈ [−1, 1], and τ = diag(M) ∘ u with u ∈ [−1, 1]
/// (each joint's torque of the size that alone would accelerate it by about 1 rad/s², so that no joint's
/// acceleration dwarfs the others' in the max-norm of the relative error).
fn random_state(model: &Model<f64>, rng: &mut SplitMix64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = model.nv();
    let q: Vec<f64> = (0..n)
        .map(|_| rng.uniform(-std::f64::consts::PI, std::f64::consts::PI))
        .collect();
    let v: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
    let m = mass_matrix(model, &q);
    let tau = (0..n).map(|i| m[(i, i)] * rng.uniform(-1.0, 1.0)).collect();
    (q, v, tau)
}

fn fit_power_law(points: &[(f64, f64)]) -> f64 {
    // Least-squares slope of log y against log x.
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    num / den
}

fn max_by_x(points: &[(f64, Option<f64>)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for &(x, y) in points {
        let Some(y) = y else { continue };
        match out.iter_mut().find(|(px, _)| *px == x) {
            Some(p) => p.1 = p.1.max(y),
            None => out.push((x, y)),
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------------
// (a) Chain length
// ---------------------------------------------------------------------------------------------------

fn chains(out: &Path, quick: bool, summary: &mut Summary) {
    let sizes: &[usize] = if quick {
        &[10, 20, 50, 100, 200]
    } else {
        &[10, 20, 50, 100, 200, 500, 1000]
    };
    let mut csv = String::from(
        "chain,n,sample,cond1_m,aba_f64,aba_f64_refused,crba_cholesky_f64,crba_cholesky_f64_refused,minv_f64,minv_f64_refused,aba_f32,aba_f32_refused,crba_cholesky_f32,crba_cholesky_f32_refused,minv_f32,minv_f32_refused\n",
    );
    let mut cond_series = Vec::new();
    for planar in [true, false] {
        let kind = if planar { "planar" } else { "spatial" };
        // (n, error) per route: aba, crba + Cholesky, M⁻¹ (Eq. 6) in f64, then the same in f32.
        let mut errs: [Vec<(f64, Option<f64>)>; 6] = Default::default();
        let mut outcomes: [Vec<Outcome>; 6] = Default::default();
        let mut conds = Vec::new();
        for &n in sizes {
            let t0 = Instant::now();
            let model = chain(&vec![1.0; n], planar);
            let m32 = model.try_cast::<f32>();
            let mdd = model.cast::<Dd>();
            let (mut ws64, mut wsdd) = (Workspace::new(&model), Workspace::new(&mdd));
            let mut ws32 = m32.as_ref().ok().map(Workspace::new);
            let samples = match n {
                0..=200 => 16,
                201..=500 => 4,
                _ => 2,
            };
            let mut rng = SplitMix64::new(1000 + n as u64);
            for s in 0..samples {
                let (q, v, tau) = random_state(&model, &mut rng);
                let want = run_aba(&mdd, &mut wsdd, &q, &v, &tau).expect("double-double ABA");
                // cond₁(M) in f64 (LU and the exact inverse: O(N³), so only the first sample past 200).
                let cond = if s == 0 || n <= 200 {
                    condition_number_1_of(&mass_matrix(&model, &q))
                } else {
                    f64::NAN
                };
                if cond.is_finite() {
                    conds.push((n as f64, cond));
                }
                let o = [
                    Outcome::of(run_aba(&model, &mut ws64, &q, &v, &tau), &want),
                    Outcome::of(run_crba_cholesky(&model, &mut ws64, &q, &v, &tau), &want),
                    Outcome::of(run_minv(&model, &mut ws64, &q, &v, &tau), &want),
                    match (&m32, ws32.as_mut()) {
                        (Ok(m), Some(ws)) => Outcome::of(run_aba(m, ws, &q, &v, &tau), &want),
                        (Err(e), _) => Outcome::Refused(short_reason(&e.to_string())),
                        _ => unreachable!(),
                    },
                    match (&m32, ws32.as_mut()) {
                        (Ok(m), Some(ws)) => {
                            Outcome::of(run_crba_cholesky(m, ws, &q, &v, &tau), &want)
                        }
                        (Err(e), _) => Outcome::Refused(short_reason(&e.to_string())),
                        _ => unreachable!(),
                    },
                    match (&m32, ws32.as_mut()) {
                        (Ok(m), Some(ws)) => Outcome::of(run_minv(m, ws, &q, &v, &tau), &want),
                        (Err(e), _) => Outcome::Refused(short_reason(&e.to_string())),
                        _ => unreachable!(),
                    },
                ];
                let _ = writeln!(
                    csv,
                    "{kind},{n},{s},{},{}",
                    if cond.is_finite() {
                        format!("{cond:.3e}")
                    } else {
                        String::new()
                    },
                    o.iter().map(Outcome::csv).collect::<Vec<_>>().join(",")
                );
                for k in 0..6 {
                    errs[k].push((n as f64, o[k].error()));
                    outcomes[k].push(o[k].clone());
                }
            }
            let worst = |k: usize| {
                max_by_x(&errs[k])
                    .iter()
                    .find(|(x, _)| *x == n as f64)
                    .map_or(f64::NAN, |p| p.1)
            };
            eprintln!(
                "(a) {kind} chain N = {n}: f64 aba {:.1e}, crba+chol {:.1e}, minv {:.1e}; f32 aba {:.1e}, crba+chol {:.1e}, minv {:.1e}; cond(M) {:.1e} ({:.1} s)",
                worst(0),
                worst(1),
                worst(2),
                worst(3),
                worst(4),
                worst(5),
                conds.iter().filter(|c| c.0 == n as f64).map(|c| c.1).fold(0.0, f64::max),
                t0.elapsed().as_secs_f64()
            );
        }
        let names = [
            "ABA f64",
            "CRBA + Cholesky f64",
            "M⁻¹ (Eq. 6) f64",
            "ABA f32",
            "CRBA + Cholesky f32",
            "M⁻¹ (Eq. 6) f32",
        ];
        let mut plot = Plot::new(
            format!("(a) {kind} chain: error against length (worst of the samples)"),
            "bodies N",
            "relative error of qdd",
        )
        .size(820.0, 440.0)
        .log_x()
        .log_y()
        .hline(f64::EPSILON, "f64 ε")
        .hline(f32::EPSILON as f64, "f32 ε");
        for (k, name) in names.iter().enumerate() {
            let s = Series::new(*name, max_by_x(&errs[k])).colour(k % 3 + 1);
            let s = if k < 3 { s.line(true) } else { s.dashed() };
            let s = s.marker([Marker::Circle, Marker::Square, Marker::Triangle][k % 3]);
            plot = plot.series(s);
        }
        write_file(&out.join(format!("chain_{kind}.svg")), &plot.to_svg());
        let slope = fit_power_law(&conds);
        let case = format!("{kind} chain N ≤ {}", sizes.last().unwrap());
        let note = format!("cond₁(M) ∝ N^{slope:.1}");
        for (k, route) in ["ABA", "CRBA+Cholesky", "M⁻¹ (Eq. 6)"].iter().enumerate() {
            for (j, scalar) in [(0, "f64"), (3, "f32")] {
                let note = if k + j == 0 { note.as_str() } else { "" };
                summary.add(
                    "(a) length",
                    &format!("{case}, {route}"),
                    scalar,
                    &outcomes[k + j],
                    note,
                );
            }
        }
        cond_series.push((kind, conds, slope));
    }
    // cond(M) against N, with N and N⁴ for scale.
    let mut plot = Plot::new(
        "(a) condition number of the mass matrix",
        "bodies N",
        "cond₁(M)",
    )
    .log_x()
    .log_y();
    for (k, (kind, conds, slope)) in cond_series.iter().enumerate() {
        plot = plot.series(
            Series::new(format!("{kind} chain (fit: N^{slope:.1})"), conds.clone()).colour(k + 1),
        );
    }
    if let Some((_, conds, _)) = cond_series.first() {
        let c10 = conds
            .iter()
            .filter(|c| c.0 == 10.0)
            .map(|c| c.1)
            .fold(0.0, f64::max);
        let n_max = *sizes.last().unwrap() as f64;
        for (p, name) in [(1.0, "∝ N"), (4.0, "∝ N⁴")] {
            let pts = vec![(10.0, c10), (n_max, c10 * (n_max / 10.0).powf(p))];
            plot = plot.series(
                Series::new(name, pts)
                    .dashed()
                    .marker(Marker::None)
                    .colour(0),
            );
        }
    }
    write_file(&out.join("chain_condition.svg"), &plot.to_svg());
    write_file(&out.join("chain.csv"), &csv);
}

// ---------------------------------------------------------------------------------------------------
// (b) Mass ratio between adjacent links
// ---------------------------------------------------------------------------------------------------

fn mass_ratio(out: &Path, summary: &mut Summary) {
    let mut csv = String::from(
        "ratio,sample,cond1_m,aba_f64,aba_f64_refused,crba_cholesky_f64,crba_cholesky_f64_refused,aba_f32,aba_f32_refused,crba_cholesky_f32,crba_cholesky_f32_refused\n",
    );
    let mut errs: [Vec<(f64, Option<f64>)>; 4] = Default::default();
    let mut outcomes: [Vec<Outcome>; 4] = Default::default();
    let n = 8;
    for k in 0..=20 {
        let ratio = 10f64.powf(k as f64 / 2.0);
        // Heavy and light bodies alternate: 1 kg, 1/ratio kg, 1 kg, …
        let masses: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { 1.0 / ratio })
            .collect();
        let model = chain(&masses, false);
        let m32 = model.try_cast::<f32>();
        let mdd = model.cast::<Dd>();
        let (mut ws64, mut wsdd) = (Workspace::new(&model), Workspace::new(&mdd));
        let mut ws32 = m32.as_ref().ok().map(Workspace::new);
        let mut rng = SplitMix64::new(2000 + k);
        for s in 0..32 {
            let (q, v, tau) = random_state(&model, &mut rng);
            let want = run_aba(&mdd, &mut wsdd, &q, &v, &tau).expect("double-double ABA");
            let cond = condition_number_1_of(&mass_matrix(&model, &q));
            let o = [
                Outcome::of(run_aba(&model, &mut ws64, &q, &v, &tau), &want),
                Outcome::of(run_crba_cholesky(&model, &mut ws64, &q, &v, &tau), &want),
                match (&m32, ws32.as_mut()) {
                    (Ok(m), Some(ws)) => Outcome::of(run_aba(m, ws, &q, &v, &tau), &want),
                    (Err(e), _) => Outcome::Refused(short_reason(&e.to_string())),
                    _ => unreachable!(),
                },
                match (&m32, ws32.as_mut()) {
                    (Ok(m), Some(ws)) => Outcome::of(run_crba_cholesky(m, ws, &q, &v, &tau), &want),
                    (Err(e), _) => Outcome::Refused(short_reason(&e.to_string())),
                    _ => unreachable!(),
                },
            ];
            let _ = writeln!(
                csv,
                "{ratio:.3e},{s},{cond:.3e},{},{},{},{}",
                o[0].csv(),
                o[1].csv(),
                o[2].csv(),
                o[3].csv()
            );
            for j in 0..4 {
                errs[j].push((ratio, o[j].error()));
                outcomes[j].push(o[j].clone());
            }
        }
        if k % 4 == 0 {
            eprintln!("(b) mass ratio {ratio:.0e} measured");
        }
    }
    let names = [
        "ABA f64",
        "CRBA + Cholesky f64",
        "ABA f32",
        "CRBA + Cholesky f32",
    ];
    let mut plot = Plot::new(
        "(b) 8-body chain, masses alternating 1 kg and 1/ratio kg",
        "mass ratio between adjacent links",
        "relative error of qdd (worst of 32 states)",
    )
    .log_x()
    .log_y()
    .hline(f64::EPSILON, "f64 ε")
    .hline(f32::EPSILON as f64, "f32 ε");
    for k in 0..4 {
        let s = Series::new(names[k], max_by_x(&errs[k])).colour(if k % 2 == 0 { 1 } else { 2 });
        let s = if k < 2 { s.line(true) } else { s.dashed() };
        plot = plot.series(s.marker(if k % 2 == 0 {
            Marker::Circle
        } else {
            Marker::Square
        }));
    }
    write_file(&out.join("mass_ratio.svg"), &plot.to_svg());
    write_file(&out.join("mass_ratio.csv"), &csv);
    let case = "ratio ≤ 1e10";
    summary.add(
        "(b) mass ratio",
        &format!("{case}, ABA"),
        "f64",
        &outcomes[0],
        "",
    );
    summary.add(
        "(b) mass ratio",
        &format!("{case}, CRBA+Cholesky"),
        "f64",
        &outcomes[1],
        "",
    );
    summary.add(
        "(b) mass ratio",
        &format!("{case}, ABA"),
        "f32",
        &outcomes[2],
        "",
    );
    summary.add(
        "(b) mass ratio",
        &format!("{case}, CRBA+Cholesky"),
        "f32",
        &outcomes[3],
        "",
    );
}

// ---------------------------------------------------------------------------------------------------
// (c) Distance to a four-bar's toggle
// ---------------------------------------------------------------------------------------------------

/// The parallelogram four-bar's toggle angle: the crank's origin pitch, as the file's f64 (on the
/// parallelogram branch q_coupler = −q_crank, q_rocker = q_crank, all links collinear at q_crank = this).
pub const TOGGLE: f64 = 1.0471975511965976;

/// The configuration of models/loops/singular_four_bar.urdf at `distance` rad before its toggle, on the
/// parallelogram branch (exact relations: no Newton iteration to lose accuracy near the singularity).
fn four_bar_near_toggle(model: &Model<f64>, distance: f64) -> (Vec<f64>, [usize; 3]) {
    let idx = ["crank_joint", "coupler_joint", "rocker_joint"]
        .map(|n| model.joints[model.joint_index(n).expect(n)].q_index);
    let crank = TOGGLE - distance;
    let mut q = model.neutral_configuration();
    q[idx[0]] = crank;
    q[idx[1]] = -crank;
    q[idx[2]] = crank;
    (q, idx)
}

/// The exact accelerations on the parallelogram branch, in double-double, without the embedding: the
/// branch's relations are linear (X = [1, −1, 1]ᵀ, Ẋ = 0), so qdd = X (Xᵀ M X)⁻¹ Xᵀ (τ − b). A check of the
/// reference where the embedded double-double solve refuses (cond₁(Y1) ≥ 1e10).
fn four_bar_branch_reference(
    mdd: &Model<Dd>,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    idx: [usize; 3],
) -> Vec<f64> {
    let mut ws = Workspace::new(mdd);
    let (q, v, tau) = (cast::<Dd>(q), cast::<Dd>(v), cast::<Dd>(tau));
    let zero = vec![Dd::from_f64(0.0); mdd.nv()];
    let b = rnea(mdd, &mut ws, &q, &v, &zero).expect("rnea").to_vec();
    let m = crba(mdd, &mut ws, &q).expect("crba").clone();
    let mut x = vec![Dd::from_f64(0.0); mdd.nv()];
    x[idx[0]] = Dd::from_f64(1.0);
    x[idx[1]] = Dd::from_f64(-1.0);
    x[idx[2]] = Dd::from_f64(1.0);
    let mut xmx = Dd::from_f64(0.0);
    let mut rhs = Dd::from_f64(0.0);
    for i in 0..mdd.nv() {
        rhs += x[i] * (tau[i] - b[i]);
        for j in 0..mdd.nv() {
            xmx += x[i] * m[(i, j)] * x[j];
        }
    }
    let a = rhs / xmx;
    x.iter().map(|xi| (*xi * a).to_f64()).collect()
}

fn four_bar_toggle(out: &Path, summary: &mut Summary) {
    let loaded = embedyn_codegen::load(&repo("models/loops/singular_four_bar.urdf"))
        .unwrap_or_else(|e| panic!("{e}"));
    let opts = ModelOptions::default();
    let model = loaded.model::<f64>(&opts).unwrap_or_else(|e| panic!("{e}"));
    let m32 = loaded.model::<f32>(&opts).unwrap_or_else(|e| panic!("{e}"));
    let mdd = loaded.model::<Dd>(&opts).unwrap_or_else(|e| panic!("{e}"));
    let (mut ws64, mut ws32, mut wsdd) = (
        Workspace::new(&model),
        Workspace::new(&m32),
        Workspace::new(&mdd),
    );
    let mut csv = String::from(
        "distance_rad,sample,cond1_y1_dd,cond1_y1_f64,cond1_y1_f32,reference,f64,f64_refused,f32,f32_refused\n",
    );
    let mut errs: [Vec<(f64, Option<f64>)>; 2] = Default::default();
    let mut refused: [Vec<(f64, f64)>; 2] = Default::default();
    let mut outcomes: [Vec<Outcome>; 2] = Default::default();
    let mut conds: [Vec<(f64, f64)>; 3] = Default::default();
    let mut worst_gap = 0.0f64;
    let mut rng = SplitMix64::new(3000);
    for k in 2..=24 {
        let distance = 10f64.powf(-(k as f64) / 2.0);
        let (q, idx) = four_bar_near_toggle(&model, distance);
        let c = [
            y1_condition(&mdd, &mut wsdd, &cast::<Dd>(&q), 0).unwrap_or(f64::INFINITY),
            y1_condition(&model, &mut ws64, &q, 0).unwrap_or(f64::INFINITY),
            y1_condition(&m32, &mut ws32, &cast::<f32>(&q), 0).unwrap_or(f64::INFINITY),
        ];
        for (j, cj) in c.iter().enumerate() {
            conds[j].push((distance, *cj));
        }
        for s in 0..8 {
            let w = rng.uniform(-1.0, 1.0);
            let mut v = vec![0.0; model.nv()];
            v[idx[0]] = w;
            v[idx[1]] = -w;
            v[idx[2]] = w;
            let tau: Vec<f64> = (0..model.nv()).map(|_| rng.uniform(-1.0, 1.0)).collect();
            let branch = four_bar_branch_reference(&mdd, &q, &v, &tau, idx);
            let (want, reference) = match run_aba(&mdd, &mut wsdd, &q, &v, &tau) {
                Ok(x) => {
                    worst_gap = worst_gap.max(relative_error(&x, &branch));
                    (x, "double-double embedded")
                }
                Err(_) => (branch, "double-double branch (embedded refused)"),
            };
            let o = [
                Outcome::of(run_aba(&model, &mut ws64, &q, &v, &tau), &want),
                Outcome::of(run_aba(&m32, &mut ws32, &q, &v, &tau), &want),
            ];
            let _ = writeln!(
                csv,
                "{distance:.3e},{s},{:.3e},{:.3e},{:.3e},{reference},{},{}",
                c[0],
                c[1],
                c[2],
                o[0].csv(),
                o[1].csv()
            );
            for j in 0..2 {
                errs[j].push((distance, o[j].error()));
                if o[j].error().is_none() {
                    refused[j].push((distance, 1.0));
                }
                outcomes[j].push(o[j].clone());
            }
        }
        let fmt = |o: &Outcome| match o {
            Outcome::Error(e) => format!("{e:.1e}"),
            Outcome::Refused(r) => r.clone(),
        };
        eprintln!(
            "(c) toggle − {distance:.0e} rad: cond₁(Y1) {:.1e}; f64 {}, f32 {}",
            c[0],
            fmt(outcomes[0].last().unwrap()),
            fmt(outcomes[1].last().unwrap())
        );
    }
    eprintln!("(c) embedded double-double against the branch formula: {worst_gap:.1e} at most");
    let mut plot = Plot::new(
        "(c) parallelogram four-bar approaching its toggle",
        "distance to the toggle (rad)",
        "relative error of qdd (refusals drawn at 1)",
    )
    .log_x()
    .log_y()
    .hline(f64::EPSILON, "f64 ε")
    .hline(f32::EPSILON as f64, "f32 ε");
    for (j, name) in ["f64", "f32"].iter().enumerate() {
        let s = Series::new(format!("{name} answer"), max_by_x(&errs[j]))
            .line(true)
            .colour(j + 1);
        plot = plot.series(if j == 1 { s.marker(Marker::Square) } else { s });
        let mut r = refused[j].clone();
        r.dedup();
        plot = plot.series(
            Series::new(format!("{name} refused (singular_constraint)"), r)
                .marker(Marker::Cross)
                .colour(j + 1),
        );
    }
    write_file(&out.join("four_bar_toggle.svg"), &plot.to_svg());
    let mut plot = Plot::new(
        "(c) cond₁(Y1) approaching the toggle, and each scalar's limit",
        "distance to the toggle (rad)",
        "cond₁(Y1)",
    )
    .log_x()
    .log_y()
    .hline(singularity_threshold::<f64>(), "f64 limit 1e10")
    .hline(
        singularity_threshold::<f32>(),
        format!("f32 limit {:.1e}", singularity_threshold::<f32>()),
    );
    for (j, name) in ["double-double", "f64", "f32"].iter().enumerate() {
        plot = plot.series(
            Series::new(format!("computed in {name}"), conds[j].clone())
                .line(true)
                .colour(j),
        );
    }
    write_file(&out.join("four_bar_condition.svg"), &plot.to_svg());
    write_file(&out.join("four_bar_toggle.csv"), &csv);
    let last_answer = |j: usize| {
        errs[j]
            .iter()
            .filter(|(_, e)| e.is_some())
            .map(|(d, _)| *d)
            .fold(f64::INFINITY, f64::min)
    };
    let first_refusal = |j: usize| refused[j].iter().map(|(d, _)| *d).fold(0.0f64, f64::max);
    for (j, scalar) in [(0, "f64"), (1, "f32")] {
        summary.add(
            "(c) toggle",
            "distance 1e-1 … 1e-12 rad",
            scalar,
            &outcomes[j],
            &format!(
                "answers down to {:.0e} rad; refused from {:.0e} rad (cond₁(Y1) ≥ {:.1e})",
                last_answer(j),
                first_refusal(j),
                if j == 0 {
                    singularity_threshold::<f64>()
                } else {
                    singularity_threshold::<f32>()
                }
            ),
        );
    }
}

// ---------------------------------------------------------------------------------------------------
// (d) Gear ratio and rotor inertia
// ---------------------------------------------------------------------------------------------------

/// models/loops/geared_motor.urdf with both gear ratios `ratio` and both rotors of axial inertia
/// `inertia` (transverse 0.6 × that: a disc-like rotor), read by the URDF+ loader.
fn geared_motor(ratio: f64, inertia: f64) -> embedyn_codegen::Loaded {
    let path = repo("models/loops/geared_motor.urdf");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let rotor = r#"<inertia ixx="5.2e-05" ixy="0" ixz="0" iyy="9e-05" iyz="0" izz="5.2e-05"/>"#;
    assert_eq!(text.matches(rotor).count(), 2, "geared_motor.urdf changed");
    let t = 0.6 * inertia;
    let text = text
        .replace(
            rotor,
            &format!(
                r#"<inertia ixx="{t:e}" ixy="0" ixz="0" iyy="{inertia:e}" iyz="0" izz="{t:e}"/>"#
            ),
        )
        .replace(
            r#"<ratio value="9"/>"#,
            &format!(r#"<ratio value="{ratio}"/>"#),
        )
        .replace(
            r#"<ratio value="6"/>"#,
            &format!(r#"<ratio value="{ratio}"/>"#),
        );
    parse_urdf(&text, &path).unwrap_or_else(|e| panic!("{e}"))
}

fn gears(out: &Path, summary: &mut Summary) {
    let ratios = [1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0];
    let inertias = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];
    let mut csv = String::from(
        "ratio,rotor_inertia,sample,f64_independent,f64_refused,f64_all,f32_independent,f32_refused,f32_all\n",
    );
    let opts = ModelOptions::default();
    // Per scalar, per inertia: (ratio, worst error of the independent accelerations).
    let mut series: [Vec<Vec<(f64, f64)>>; 2] = Default::default();
    let mut outcomes: [Vec<Outcome>; 2] = Default::default();
    let mut outcomes_all: [Vec<Outcome>; 2] = Default::default();
    let mut worst_at_1000: [f64; 2] = [0.0; 2];
    for (ii, &inertia) in inertias.iter().enumerate() {
        for s in &mut series {
            s.push(Vec::new());
        }
        for &ratio in &ratios {
            let loaded = geared_motor(ratio, inertia);
            let model = loaded.model::<f64>(&opts).unwrap_or_else(|e| panic!("{e}"));
            let mdd = loaded.model::<Dd>(&opts).unwrap_or_else(|e| panic!("{e}"));
            let m32 = loaded.model::<f32>(&opts);
            let (mut ws64, mut wsdd) = (Workspace::new(&model), Workspace::new(&mdd));
            let mut ws32 = m32.as_ref().ok().map(Workspace::new);
            let independent: Vec<usize> = model
                .independent_joints()
                .iter()
                .map(|&j| model.joints[j].v_index)
                .collect();
            let mut rng = SplitMix64::new(4000 + (ratio as u64) * 10 + ii as u64);
            let mut worst = [0.0f64; 2];
            for s in 0..16 {
                let mut q = model.neutral_configuration();
                let mut v = vec![0.0; model.nv()];
                for &k in &independent {
                    q[k] = rng.uniform(-std::f64::consts::PI, std::f64::consts::PI);
                    v[k] = rng.uniform(-1.0, 1.0);
                }
                let r = complete_configuration(&model, &mut ws64, &mut q).expect("complete");
                assert!(r <= 1e-13, "gear completion residual {r:e}");
                complete_velocity(&model, &mut ws64, &q, &mut v).expect("complete velocity");
                let mr = reduced_mass_matrix_in(&model, &mut ws64, &q)
                    .expect("reduced M")
                    .clone();
                let mut tau = vec![0.0; model.nv()];
                for (c, &k) in independent.iter().enumerate() {
                    tau[k] = mr[(c, c)] * rng.uniform(-1.0, 1.0);
                }
                let want = run_aba(&mdd, &mut wsdd, &q, &v, &tau).expect("double-double ABA");
                let want_ind: Vec<f64> = independent.iter().map(|&k| want[k]).collect();
                let got = [
                    run_aba(&model, &mut ws64, &q, &v, &tau).map_err(|e| e.to_string()),
                    match (&m32, ws32.as_mut()) {
                        (Ok(m), Some(ws)) => {
                            run_aba(m, ws, &q, &v, &tau).map_err(|e| e.to_string())
                        }
                        (Err(e), _) => Err(e.to_string()),
                        _ => unreachable!(),
                    },
                ];
                let mut line = format!("{ratio},{inertia:e},{s}");
                for j in 0..2 {
                    let ind = Outcome::of(
                        got[j]
                            .clone()
                            .map(|x| independent.iter().map(|&k| x[k]).collect::<Vec<_>>()),
                        &want_ind,
                    );
                    let all = Outcome::of(got[j].clone(), &want);
                    let _ = write!(
                        line,
                        ",{},{}",
                        ind.csv(),
                        all.error().map_or(String::new(), |e| format!("{e:.3e}"))
                    );
                    if let Some(e) = ind.error() {
                        worst[j] = worst[j].max(e);
                    }
                    outcomes[j].push(ind);
                    outcomes_all[j].push(all);
                }
                let _ = writeln!(csv, "{line}");
            }
            for j in 0..2 {
                series[j][ii].push((ratio, worst[j]));
                if ratio == 1000.0 {
                    worst_at_1000[j] = worst_at_1000[j].max(worst[j]);
                }
            }
        }
        eprintln!(
            "(d) rotor inertia {inertia:.0e}: worst over ratios f64 {:.1e}, f32 {:.1e}",
            series[0][ii].iter().map(|p| p.1).fold(0.0, f64::max),
            series[1][ii].iter().map(|p| p.1).fold(0.0, f64::max)
        );
    }
    for (j, scalar) in ["f64", "f32"].iter().enumerate() {
        let mut plot = Plot::new(
            format!("(d) geared 2-DoF arm in {scalar}: error against gear ratio"),
            "gear ratio",
            "relative error of the independent qdd",
        )
        .log_x()
        .log_y()
        .hline(
            if j == 0 {
                f64::EPSILON
            } else {
                f32::EPSILON as f64
            },
            format!("{scalar} ε"),
        );
        for (ii, &inertia) in inertias.iter().enumerate() {
            plot = plot.series(
                Series::new(format!("rotor {inertia:.0e} kg·m²"), series[j][ii].clone())
                    .line(true)
                    .colour(ii),
            );
        }
        write_file(&out.join(format!("gear_{scalar}.svg")), &plot.to_svg());
        summary.add(
            "(d) gears",
            "ratio ≤ 1000, rotor 1e-2 … 1e-8 kg·m², independent qdd",
            if j == 0 { "f64" } else { "f32" },
            &outcomes[j],
            &format!("at ratio 1000: {:.1e}", worst_at_1000[j]),
        );
        summary.add(
            "(d) gears",
            "same, all qdd (rotors included)",
            if j == 0 { "f64" } else { "f32" },
            &outcomes_all[j],
            "",
        );
    }
    write_file(&out.join("gear.csv"), &csv);
}

// ---------------------------------------------------------------------------------------------------
// (e) Energy drift
// ---------------------------------------------------------------------------------------------------

#[derive(Clone, Copy, PartialEq)]
enum Integrator {
    SemiImplicitEuler,
    Rk4,
}

impl Integrator {
    fn name(self) -> &'static str {
        match self {
            Integrator::SemiImplicitEuler => "semi-implicit Euler",
            Integrator::Rk4 => "RK4",
        }
    }
}

/// Total energy of an f64 state of the f64 model.
fn total_energy(model: &Model<f64>, ws: &mut Workspace<f64>, q: &[f64], v: &[f64]) -> f64 {
    forward_kinematics(model, ws, q, v).expect("kinematics");
    kinetic_energy(model, ws) + potential_energy(model, ws)
}

/// Simulates `duration` s with step `h` in scalar `T` (τ = 0, gravity on), projecting onto the loop
/// constraints after every step where the model has any; returns |E(t) − E(0)| (energy evaluated in f64
/// from the state, so that the measure adds no error of `T`) every `every` steps.
#[allow(clippy::too_many_arguments)]
fn simulate<T: Real>(
    model: &Model<T>,
    model64: &Model<f64>,
    q0: &[f64],
    v0: &[f64],
    h: f64,
    duration: f64,
    integrator: Integrator,
    every: usize,
) -> Result<Vec<(f64, f64)>, String> {
    let mut ws = Workspace::new(model);
    let mut ws64 = Workspace::new(model64);
    let (nq, nv) = (model.nq(), model.nv());
    let (mut q, mut v) = (cast::<T>(q0), cast::<T>(v0));
    let loops = model.has_constraints();
    if loops {
        complete_configuration(model, &mut ws, &mut q).map_err(|e| e.to_string())?;
        complete_velocity(model, &mut ws, &q, &mut v).map_err(|e| e.to_string())?;
    }
    let e0 = total_energy(model64, &mut ws64, &back(&q), &back(&v));
    let tau = vec![T::from_f64(0.0); nv];
    let ht = T::from_f64(h);
    let half = T::from_f64(h / 2.0);
    let sixth = T::from_f64(h / 6.0);
    let two = T::from_f64(2.0);
    let steps = (duration / h).round() as usize;
    let mut drift = vec![(0.0, 0.0)];
    let axpy =
        |x: &[T], d: &[T], s: T| -> Vec<T> { x.iter().zip(d).map(|(a, b)| *a + s * *b).collect() };
    for step in 1..=steps {
        let t = step as f64 * h;
        let diverged = |e: DynamicsError| format!("diverged at t = {t:.3} s ({e})");
        match integrator {
            Integrator::SemiImplicitEuler => {
                let a = aba(model, &mut ws, &q, &v, &tau).map_err(diverged)?;
                for i in 0..nv {
                    v[i] += ht * a[i];
                }
                let mut qd = vec![T::from_f64(0.0); nq];
                model.configuration_rate(&q, &v, &mut qd);
                for i in 0..nq {
                    q[i] += ht * qd[i];
                }
            }
            Integrator::Rk4 => {
                let mut deriv = |q: &[T], v: &[T]| -> Result<(Vec<T>, Vec<T>), String> {
                    let mut qd = vec![T::from_f64(0.0); nq];
                    model.configuration_rate(q, v, &mut qd);
                    let a = aba(model, &mut ws, q, v, &tau).map_err(diverged)?;
                    Ok((qd, a.to_vec()))
                };
                let (k1q, k1v) = deriv(&q, &v)?;
                let (k2q, k2v) = deriv(&axpy(&q, &k1q, half), &axpy(&v, &k1v, half))?;
                let (k3q, k3v) = deriv(&axpy(&q, &k2q, half), &axpy(&v, &k2v, half))?;
                let (k4q, k4v) = deriv(&axpy(&q, &k3q, ht), &axpy(&v, &k3v, ht))?;
                for i in 0..nq {
                    q[i] += sixth * (k1q[i] + two * k2q[i] + two * k3q[i] + k4q[i]);
                }
                for i in 0..nv {
                    v[i] += sixth * (k1v[i] + two * k2v[i] + two * k3v[i] + k4v[i]);
                }
            }
        }
        model.normalize_configuration(&mut q);
        if loops {
            complete_configuration(model, &mut ws, &mut q).map_err(diverged)?;
            complete_velocity(model, &mut ws, &q, &mut v).map_err(diverged)?;
        }
        if step % every == 0 {
            let e = total_energy(model64, &mut ws64, &back(&q), &back(&v));
            drift.push((t, (e - e0).abs()));
        }
    }
    Ok(drift)
}

fn energy(out: &Path, quick: bool, summary: &mut Summary) {
    let duration = if quick { 2.0 } else { 10.0 };
    let mut csv = String::from("model,integrator,scalar,h,t,energy_change_j\n");
    let opts = ModelOptions::default();
    for (file, label, short) in [
        ("models/arm7.urdf", "7-DoF arm (tree)", "arm7"),
        (
            "models/loops/four_bar_internal.urdf",
            "four-bar (loop, projected every step)",
            "four_bar",
        ),
    ] {
        let loaded = embedyn_codegen::load(&repo(file)).unwrap_or_else(|e| panic!("{e}"));
        let model = loaded.model::<f64>(&opts).unwrap_or_else(|e| panic!("{e}"));
        let m32 = loaded.model::<f32>(&opts).unwrap_or_else(|e| panic!("{e}"));
        let mut rng = SplitMix64::new(5000);
        let mut q = model.neutral_configuration();
        for j in 0..model.joints.len() {
            if model.is_independent(j) {
                q[model.joints[j].q_index] = rng.uniform(-0.5, 0.5);
            }
        }
        let v: Vec<f64> = (0..model.nv()).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let mut ws = Workspace::new(&model);
        let e0 = {
            let mut q = q.clone();
            let mut v = v.clone();
            if model.has_constraints() {
                complete_configuration(&model, &mut ws, &mut q).expect("complete");
                complete_velocity(&model, &mut ws, &q, &mut v).expect("complete velocity");
            }
            forward_kinematics(&model, &mut ws, &q, &v).expect("kinematics");
            (kinetic_energy(&model, &ws), potential_energy(&model, &ws))
        };
        let mut plot = Plot::new(
            format!("(e) {label}: energy change over {duration} s"),
            "time (s)",
            "|E(t) − E(0)| (J)",
        )
        .size(900.0, 440.0)
        .log_y();
        let runs = [
            (Integrator::SemiImplicitEuler, 1e-3),
            (Integrator::SemiImplicitEuler, 1e-4),
            (Integrator::Rk4, 1e-3),
            (Integrator::Rk4, 1e-4),
        ];
        for (k, (integrator, h)) in runs.into_iter().enumerate() {
            // About 200 points per curve.
            let every = ((duration / h) as usize / 200).max(1);
            for (j, scalar) in ["f64", "f32"].iter().enumerate() {
                let t0 = Instant::now();
                let drift = if j == 0 {
                    simulate(&model, &model, &q, &v, h, duration, integrator, every)
                } else {
                    simulate(&m32, &model, &q, &v, h, duration, integrator, every)
                };
                let case = format!("{short}, {}, h = {h:e} s, {duration} s", integrator.name());
                match drift {
                    Ok(d) => {
                        let worst = d.iter().map(|p| p.1).fold(0.0, f64::max);
                        eprintln!(
                            "(e) {label}, {}, h = {h:e}, {scalar}: max |ΔE| {worst:.2e} J (E kinetic {:.2e} J, potential {:.2e} J; {:.1} s)",
                            integrator.name(),
                            e0.0,
                            e0.1,
                            t0.elapsed().as_secs_f64()
                        );
                        for (t, e) in &d {
                            let _ = writeln!(
                                csv,
                                "{short},{},{scalar},{h},{t:.3},{e:.3e}",
                                integrator.name()
                            );
                        }
                        summary.add(
                            "(e) energy",
                            &case,
                            if j == 0 { "f64" } else { "f32" },
                            &[],
                            &format!("max |ΔE| = {worst:.1e} J"),
                        );
                        let s =
                            Series::new(format!("{}, h = {h:e} s, {scalar}", integrator.name()), d)
                                .colour(k + 1)
                                .marker(Marker::None);
                        plot = plot.series(if j == 0 { s.line(true) } else { s.dashed() });
                    }
                    Err(e) => {
                        eprintln!(
                            "(e) {label}, {}, h = {h:e}, {scalar}: {e}",
                            integrator.name()
                        );
                        summary.add(
                            "(e) energy",
                            &case,
                            if j == 0 { "f64" } else { "f32" },
                            &[],
                            &e,
                        );
                    }
                }
            }
        }
        write_file(&out.join(format!("energy_{short}.svg")), &plot.to_svg());
    }
    write_file(&out.join("energy.csv"), &csv);
}
