//! The compiled form of `--engine generated` and `embedyn bench`: the model's standalone crate plus a
//! small binary that evaluates or times its functions, built once with cargo into a per-user cache keyed
//! by the generated source itself (so a stale build can never be used).

use super::CliError;
use crate::generate::GenerateOptions;
use crate::standalone::{crate_files, crate_name};
use crate::{Algorithm, Loaded};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The cache folder: `$EMBEDYN_CACHE_DIR`, else `$XDG_CACHE_HOME/embedyn`, else `~/.cache/embedyn`.
pub fn cache_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("EMBEDYN_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("embedyn");
    }
    let home = std::env::var_os("HOME").map_or_else(std::env::temp_dir, PathBuf::from);
    home.join(".cache").join("embedyn")
}

/// FNV-1a, 64 bits: a stable content hash for cache keys.
fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in *p {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        h ^= 0xff;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Writes (or reuses) the runner crate for `loaded` and returns the path of its built binary.
pub fn build_runner(loaded: &Loaded, options: &GenerateOptions) -> Result<PathBuf, CliError> {
    let files = crate_files(loaded, options)?;
    let krate = crate_name(&loaded.robot.name);
    let constrained = loaded.model::<f64>(&options.model)?.has_constraints();
    let main = runner_main(&krate, &options.algorithms, constrained);
    let parts: Vec<&[u8]> = files
        .iter()
        .map(|(_, t)| t.as_bytes())
        .chain(std::iter::once(main.as_bytes()))
        .collect();
    let hash = format!("{:016x}", fnv1a(&parts));
    let key = format!("{krate}-{hash}");
    let root = cache_dir();
    let dir = root.join(&key);
    // One target folder for every model (libm is built once); the binary's name carries the key, so a
    // binary built from other source is never picked up.
    let target = root.join("target");
    let bin_name = format!("run_{hash}");
    let binary = target
        .join("release")
        .join(format!("{bin_name}{}", std::env::consts::EXE_SUFFIX));
    if binary.exists() {
        return Ok(binary);
    }
    let io = |e: std::io::Error, p: &Path| CliError(format!("{}: {e}", p.display()));
    for (rel, text) in &files {
        let p = dir.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).map_err(|e| io(e, &p))?;
        std::fs::write(&p, text).map_err(|e| io(e, &p))?;
    }
    let cargo_toml = files.iter().find(|(p, _)| p == Path::new("Cargo.toml")).unwrap().1.replace(
        "# Standalone: not part of any enclosing workspace.",
        &format!("[[bin]]\nname = \"{bin_name}\"\npath = \"src/main.rs\"\n\n# Standalone: not part of any enclosing workspace."),
    );
    std::fs::write(dir.join("Cargo.toml"), cargo_toml).map_err(|e| io(e, &dir))?;
    std::fs::write(dir.join("src/main.rs"), &main).map_err(|e| io(e, &dir))?;
    eprintln!(
        "embedyn: compiling the generated code of `{}` (first use; cached in {})",
        loaded.robot.name,
        dir.display()
    );
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let build = |offline: bool| {
        let mut cmd = Command::new(&cargo);
        cmd.args(["build", "--release", "--quiet", "--bin", &bin_name]);
        if offline {
            cmd.arg("--offline");
        }
        cmd.current_dir(&dir)
            .env("CARGO_TARGET_DIR", &target)
            .output()
            .map_err(|e| {
                CliError(format!(
                    "cannot run cargo ({}): {e}",
                    cargo.to_string_lossy()
                ))
            })
    };
    // Offline first (the usual case: libm is in cargo's cache); online once if that fails.
    if !build(true)?.status.success() {
        let retry = build(false)?;
        if !retry.status.success() {
            return Err(CliError(format!(
                "compiling the generated code failed:\n{}",
                String::from_utf8_lossy(&retry.stderr)
            )));
        }
    }
    Ok(binary)
}

/// Runs the runner: `rows` are the samples (q ‖ a ‖ b). Returns one output row per sample, or in bench
/// mode one line with the median ns per call.
pub fn run(
    binary: &Path,
    algo: &str,
    scalar: &str,
    mode: &str,
    rows: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, CliError> {
    let mut child = Command::new(binary)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| CliError(format!("cannot run {}: {e}", binary.display())))?;
    {
        let mut stdin = child.stdin.take().unwrap();
        let mut text = format!("{algo} {scalar} {mode}\n");
        for r in rows {
            let line: Vec<String> = r.iter().map(|x| format!("{x:?}")).collect();
            text.push_str(&line.join(" "));
            text.push('\n');
        }
        stdin
            .write_all(text.as_bytes())
            .map_err(|e| CliError(format!("runner input: {e}")))?;
    }
    let out = child
        .wait_with_output()
        .map_err(|e| CliError(format!("runner: {e}")))?;
    if !out.status.success() {
        return Err(CliError(format!(
            "the generated code's runner failed: {}",
            String::from_utf8_lossy(&out.stderr)
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split_whitespace()
                .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect())
}

/// The runner's `main.rs`.
///
/// For a model with constraints, `aba` prints the pivot ratio after `qdd` and `crba` is
/// `crba_independent` (`Xᵀ M X`, what the CLI reports).
fn runner_main(krate: &str, algorithms: &[Algorithm], constrained: bool) -> String {
    let mut eval_arms = String::new();
    let mut bench_arms = String::new();
    for a in algorithms {
        let name = a.name();
        let (call, bench_call, emit) = match a {
            Algorithm::Aba if constrained => (
                "let ratio = m::aba(&q, &a, &b, &mut out)",
                "black_box(m::aba(black_box(&s.0), &s.1, &s.2, &mut out))",
                "let mut o = out.to_vec(); o.push(ratio); emit(&o)",
            ),
            Algorithm::Aba => (
                "m::aba(&q, &a, &b, &mut out)",
                "m::aba(black_box(&s.0), &s.1, &s.2, &mut out)",
                "emit(&out)",
            ),
            Algorithm::Crba if constrained => (
                "m::crba_independent(&q, &mut mat_i)",
                "m::crba_independent(black_box(&s.0), &mut mat_i)",
                "emit(mat_i.as_flattened())",
            ),
            Algorithm::Rnea => (
                "m::rnea(&q, &a, &b, &mut out)",
                "m::rnea(black_box(&s.0), &s.1, &s.2, &mut out)",
                "emit(&out)",
            ),
            Algorithm::Crba => (
                "m::crba(&q, &mut mat)",
                "m::crba(black_box(&s.0), &mut mat)",
                "emit(mat.as_flattened())",
            ),
            Algorithm::Minv => (
                "m::minv(&q, &mut mat)",
                "m::minv(black_box(&s.0), &mut mat)",
                "emit(mat.as_flattened())",
            ),
            // Not evaluated through the runner (the CLI completes states with the interpreted solver).
            Algorithm::Complete
            | Algorithm::Embedding
            | Algorithm::CrbaIndependent
            | Algorithm::Kinematics => continue,
        };
        eval_arms.push_str(&format!(
            "                \"{name}\" => {{ {call}; {emit}; }}\n"
        ));
        bench_arms.push_str(&format!("                \"{name}\" => time(&mut || {{ k = (k + 1) % n; let s = &states[k]; {bench_call}; black_box((&out, &mat, &mat_i)); }}),\n"));
    }
    format!(
        r#"// Evaluates or times the generated functions of `{krate}` for `embedyn eval --engine generated` and
// `embedyn bench`. Protocol on stdin: a line `ALGO SCALAR eval|bench`, then one sample per line (q, then
// two vectors of length NV), numbers separated by spaces. Output: one line per sample (eval) or the
// median ns per call (bench).
use std::hint::black_box;
use std::io::BufRead;
use {krate}::{{NI, NQ, NV}};

fn emit<T: std::fmt::Debug>(x: &[T]) {{
    let s: Vec<String> = x.iter().map(|v| format!("{{v:?}}")).collect();
    println!("{{}}", s.join(" "));
}}

fn time(f: &mut dyn FnMut()) -> f64 {{
    let mut calls = 1usize;
    loop {{
        let t = std::time::Instant::now();
        for _ in 0..calls {{ f(); }}
        if t.elapsed().as_micros() >= 200 {{ break; }}
        calls *= 2;
    }}
    let mut runs: Vec<f64> = (0..101).map(|_| {{
        let t = std::time::Instant::now();
        for _ in 0..calls {{ f(); }}
        t.elapsed().as_nanos() as f64 / calls as f64
    }}).collect();
    runs.sort_by(|a, b| a.partial_cmp(b).unwrap());
    runs[50]
}}

macro_rules! run {{
    ($m:ident, $S:ty, $algo:expr, $bench:expr, $rows:expr) => {{{{
        use {krate}::$m as m;
        let states: Vec<([$S; NQ], [$S; NV], [$S; NV])> = $rows
            .iter()
            .map(|r: &Vec<f64>| {{
                let c = |k: usize| r[k] as $S;
                (core::array::from_fn(|i| c(i)), core::array::from_fn(|i| c(NQ + i)), core::array::from_fn(|i| c(NQ + NV + i)))
            }})
            .collect();
        let mut out = [0.0 as $S; NV];
        let mut mat = [[0.0 as $S; NV]; NV];
        let mut mat_i = [[0.0 as $S; NI]; NI];
        let n = states.len().max(1);
        let mut k = 0usize;
        if $bench {{
            let ns = match $algo {{
{bench_arms}                other => panic!("unknown algorithm {{other}}"),
            }};
            println!("{{ns}}");
        }} else {{
            for (q, a, b) in &states {{
                let _ = (a, b, &mut mat, &mut mat_i);
                match $algo {{
{eval_arms}                    other => panic!("unknown algorithm {{other}}"),
                }}
            }}
        }}
        let _ = (&mut k, n);
    }}}};
}}

fn main() {{
    let mut lines = std::io::stdin().lock().lines();
    let header = lines.next().expect("a header line").expect("stdin");
    let h: Vec<String> = header.split_whitespace().map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.expect("stdin").split_whitespace().map(|x| x.parse::<f64>().expect("a number")).collect())
        .collect();
    let bench = h[2] == "bench";
    match h[1].as_str() {{
        "f64" => run!(f64, f64, h[0].as_str(), bench, rows),
        _ => run!(f32, f32, h[0].as_str(), bench, rows),
    }}
}}
"#
    )
}
