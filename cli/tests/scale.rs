//! Generation at scale (issue 8, "Scale of generation"): the source of the O(N) functions grows
//! linearly and compactly with the number of bodies, long functions are cut into parts of bounded
//! size (rustc's optimizer is superlinear in function size), and code too large to compile within the
//! memory limit is refused up front with the estimate and the ways to shrink it — never an
//! out-of-memory abort of rustc.

#[path = "../../codegen/tests/support/chain_urdf.rs"]
mod chain_urdf;

use chain_urdf::chain_urdf;
use embedyn_codegen::{generate_source, parse_urdf, Algorithm, GenerateOptions, Loaded};
use std::path::{Path, PathBuf};
use std::process::Command;

fn chain(n: usize) -> Loaded {
    parse_urdf(&chain_urdf(n), Path::new(&format!("chain{n}.urdf"))).unwrap()
}

fn only(algorithms: &[Algorithm]) -> GenerateOptions {
    GenerateOptions {
        algorithms: algorithms.to_vec(),
        exact: true,
        ..Default::default()
    }
}

/// The statements of each part of function `name` of generated source (the private functions
/// `name_…`, named after the bodies they cover), in order.
fn part_lengths(source: &str, name: &str) -> Vec<usize> {
    let mut lengths = Vec::new();
    let mut current: Option<usize> = None;
    // A part's header (`pub(super) fn aba_…(`, in its module) and its closing brace at the same indent.
    let head = format!("pub(super) fn {name}_");
    let mut end = String::new();
    for line in source.lines() {
        let body = line.trim_start();
        if body.starts_with(&head) {
            current = Some(0);
            end = format!("{}}}", &line[..line.len() - body.len()]);
        } else if current.is_some() && line == end {
            lengths.extend(current.take());
        } else if let Some(n) = current.as_mut() {
            *n += 1;
        }
    }
    lengths
}

#[test]
fn the_committed_chain_is_the_generators() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/scale/chain24.urdf");
    assert_eq!(std::fs::read_to_string(path).unwrap(), chain_urdf(24));
}

#[test]
fn aba_source_grows_linearly_in_parts_of_bounded_size() {
    let options = only(&[Algorithm::Aba]);
    let small = generate_source(&chain(100), &options).unwrap();
    let large = generate_source(&chain(1000), &options).unwrap();
    // The constants, the joint names and the two modules' headers are shared overhead: compare the
    // growth from 100 to 1000 bodies with the size at 100.
    let per_body_small = small.len() as f64 / 100.0;
    let per_body_growth = (large.len() - small.len()) as f64 / 900.0;
    eprintln!(
        "aba source (f64 and f32): {} bytes at 100 bodies, {} at 1000; {per_body_small:.0} and \
         {per_body_growth:.0} bytes per body",
        small.len(),
        large.len()
    );
    assert!(
        per_body_growth < 1.15 * per_body_small && per_body_growth > 0.85 * per_body_small,
        "aba source is not linear in the number of bodies: {per_body_small:.0} bytes per body at \
         100, {per_body_growth:.0} per added body up to 1000"
    );
    // One `let` per operation, as before the long-function form, took 44 KB per body; the parts' modules
    // (one indentation level more) brought 22.7 KB to 24.3 KB.
    assert!(
        per_body_growth < 25_500.0,
        "{per_body_growth:.0} bytes per body"
    );
    // Every part stays near 2,000 operations (nesting makes a statement one or more operations), so
    // rustc's work per part is bounded and the total linear.
    let parts = part_lengths(&large, "aba");
    // (390 parts for both scalars since the bodies' origins sit on their joint axes, 400 before.)
    assert!(parts.len() >= 2 * 150, "{} parts", parts.len());
    let longest = parts.iter().max().unwrap();
    assert!(*longest <= 2_600, "a part of {longest} statements");
}

#[test]
fn split_functions_pass_values_through_a_reused_scratch_tuple() {
    let source = generate_source(&chain(24), &only(&[Algorithm::Aba])).unwrap();
    // (The parts are named after their bodies; each is documented as "Part k of n".)
    assert!(source.contains("Part 2 of "), "not split");
    let declaration = source
        .lines()
        .find(|l| l.trim_start().starts_with("type aba_scratch = ("))
        .expect("a scratch tuple");
    let slots = declaration.matches('S').count();
    // Each part's results are read by later parts; slots whose last reader has run are reused, so
    // there are fewer slots than values written into the scratch.
    let f64_module = &source[..source.find("pub mod f32").unwrap()];
    let writes = f64_module
        .lines()
        .filter(|l| l.trim_start().starts_with("s.") && l.contains(" = "))
        .count();
    assert!(slots < writes, "{slots} slots for {writes} values");
}

#[test]
fn quadratic_functions_of_a_200_body_chain_are_refused_before_tracing() {
    let error = generate_source(&chain(200), &only(&[Algorithm::Crba, Algorithm::Minv]))
        .unwrap_err()
        .to_string();
    for expected in [
        "chain200",
        "predicted from the model before tracing",
        "`minv` 1,554,000 predicted",
        "GB of memory (limit 2.0 GB)",
        "MB of Rust",
        "--only crba",
        "--scalar f64",
        "f64_only",
        "--max-compile-memory",
        "max_compile_memory = ",
    ] {
        assert!(error.contains(expected), "missing {expected:?} in: {error}");
    }
}

#[test]
fn the_limit_is_the_users_to_raise() {
    let loaded = chain(60);
    let with_limit = |mb: u64| GenerateOptions {
        max_compile_memory_mb: Some(mb),
        ..only(&[Algorithm::Crba, Algorithm::Aba])
    };
    // ~70,000 operations per module, about 450 MB: predicted within four times 300 MB
    // (`PREDICTION_SLACK`), so traced, then refused on the count of the traced code.
    let error = generate_source(&loaded, &with_limit(300))
        .unwrap_err()
        .to_string();
    assert!(error.contains("counted in the traced code"), "{error}");
    assert!(error.contains("leave out `crba`"), "{error}");
    assert!(error.contains("--only aba"), "{error}");
    assert!(generate_source(&loaded, &with_limit(2048)).is_ok());
    let unlimited = GenerateOptions {
        max_compile_memory_mb: None,
        ..with_limit(0)
    };
    assert!(generate_source(&loaded, &unlimited).is_ok());
}

#[test]
fn the_command_line_refuses_with_the_estimate_instead_of_aborting() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scale_refusal");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("chain200.urdf");
    std::fs::write(&model, chain_urdf(200)).unwrap();
    let out = dir.join("crate");
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args(["generate", model.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(["--only", "crba,minv"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("estimated") && stderr.contains("--max-compile-memory"),
        "{stderr}"
    );
    assert!(
        !out.exists(),
        "nothing is written when the request is refused"
    );
    // One scalar module and the linear functions only: accepted.
    let run = Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args(["generate", model.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(["--only", "aba,rnea", "--scalar", "f64"])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let lib = std::fs::read_to_string(out.join("src/lib.rs")).unwrap();
    assert!(lib.contains("pub mod f64") && !lib.contains("pub mod f32"));
}

/// Derivatives by dual numbers (a model with couplings: GRBDA's Mini Cheetah, its rotors geared to the
/// joints) are predicted at several times what they trace to (the prediction, `600 nv²`, is an upper bound
/// for chains, which fold least). Refusing on the prediction was a false rejection: within
/// `PREDICTION_SLACK` times the limit the functions are traced and the traced code decides, both ways: a
/// limit the traced code fits is kept, one it exceeds (the floating ANYmal B's analytical derivatives) is
/// refused on the traced count.
#[test]
fn derivatives_predicted_beyond_the_limit_are_judged_on_the_traced_code() {
    let generate = |file: &str, floating: bool, mb: u64| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let loaded = embedyn_codegen::load(&path).unwrap();
        let options = GenerateOptions {
            model: embedyn_codegen::ModelOptions {
                floating,
                ..Default::default()
            },
            max_compile_memory_mb: Some(mb),
            f32: false,
            // The function alone: the default's AVX twin gives way to a limit the function fits
            // only without it, which would hide the refusal below.
            avx_twins: embedyn_codegen::AvxTwins::None,
            ..only(&[Algorithm::AbaDerivatives])
        };
        generate_source(&loaded, &options)
    };
    let cheetah = "../tests/data/grbda/mini_cheetah.urdf";
    // The prediction, from the refusal of a limit far below it (refused before tracing).
    let refusal = generate(cheetah, false, 1).unwrap_err().to_string();
    assert!(
        refusal.contains("predicted from the model before tracing"),
        "{refusal}"
    );
    let predicted_mb = estimated_mb(&refusal);
    // A limit the prediction exceeds three times: the traced code fits it (2026-12-03: 1.5 GB predicted, the
    // traced code under a third of it).
    let limit = (predicted_mb / 3.0) as u64;
    let source = generate(cheetah, false, limit)
        .unwrap_or_else(|e| panic!("predicted {predicted_mb:.0} MB, limit {limit} MB: {e}"));
    assert!(source.contains("pub fn aba_derivatives"));
    // A limit below the traced code's estimate, though within four times the prediction: refused on the
    // traced count (the floating ANYmal B, 2026-12-05: 283 MB predicted, 182 MB traced; 230 MB on
    // 2026-12-03).
    let anymal = "../tests/data/pinocchio/anymal_b.urdf";
    let predicted_mb = estimated_mb(&generate(anymal, true, 1).unwrap_err().to_string());
    let error = generate(anymal, true, (predicted_mb / 2.0) as u64)
        .unwrap_err()
        .to_string();
    assert!(error.contains("counted in the traced code"), "{error}");
}

/// rustc's estimated memory in a refusal ("… needs an estimated 1.2 GB of memory …"), MB.
fn estimated_mb(refusal: &str) -> f64 {
    let after = refusal
        .split("needs an estimated ")
        .nth(1)
        .expect("an estimate");
    let mut words = after.split_whitespace();
    let number: f64 = words.next().unwrap().replace(',', "").parse().unwrap();
    match words.next().unwrap() {
        "GB" => number * 1024.0,
        "MB" => number,
        unit => panic!("unit {unit} in {refusal}"),
    }
}

/// A planar closed chain of `n` links (one loop back to the base), general inertias: its loop group's
/// embedding traces to about 2.7 n³ operations of `aba`, where the prediction from the model counts 440
/// per degree of freedom.
fn closed_chain_urdf(n: usize) -> String {
    let turn = std::f64::consts::TAU / (n + 1) as f64;
    let inertial = |k: usize| {
        let c = 0.01 * (k % 7) as f64;
        format!(
            "<inertial><origin xyz=\"{c} 0.02 {}\" rpy=\"0.1 0.2 0.3\"/><mass value=\"{}\"/>\
             <inertia ixx=\"0.1\" ixy=\"0.001\" ixz=\"-0.002\" iyy=\"0.11\" iyz=\"0.0005\" izz=\"0.12\"/></inertial>",
            -c,
            0.5 + 0.1 * (k % 5) as f64
        )
    };
    let mut text = format!(
        "<robot name=\"closed{n}\"><link name=\"base\">{}</link>",
        inertial(n)
    );
    for k in 0..n {
        let (parent, xyz, pitch) = if k == 0 {
            ("base".to_string(), "0 0 0", 0.0)
        } else {
            (format!("l{}", k - 1), "0.1 0 0", turn)
        };
        text += &format!(
            "<link name=\"l{k}\">{}</link><joint name=\"j{k}\" type=\"revolute\"><origin xyz=\"{xyz}\" \
             rpy=\"0 {pitch} 0\"/><parent link=\"{parent}\"/><child link=\"l{k}\"/><axis xyz=\"0 1 0\"/></joint>",
            inertial(k)
        );
    }
    text += &format!(
        "<loop name=\"close\" type=\"revolute\"><predecessor link=\"l{}\"><origin xyz=\"0.1 0 0\"/>\
         </predecessor><successor link=\"base\"/><axis xyz=\"0 1 0\"/></loop></robot>",
        n - 1
    );
    text
}

/// The attacker's closed chain: its `aba` was predicted well within the limit, and tracing it in full
/// took tens of seconds and gigabytes (a 200-link chain aborted at 5 GB). Tracing now stops at the
/// tape's budget (`size::tape_budget`, a few times what the limit allows) and refuses with what it
/// counted; a chain that fits is traced and generated as before.
#[test]
fn a_loop_group_beyond_the_limit_stops_tracing_at_the_budget() {
    let loaded = parse_urdf(&closed_chain_urdf(60), Path::new("closed60.urdf")).unwrap();
    let options = GenerateOptions {
        max_compile_memory_mb: Some(300),
        f32: false,
        ..only(&[Algorithm::Aba])
    };
    let started = std::time::Instant::now();
    let error = generate_source(&loaded, &options).unwrap_err().to_string();
    eprintln!(
        "closed 60-link chain, limit 300 MB: refused in {:.2} s",
        started.elapsed().as_secs_f64()
    );
    for expected in [
        "`aba` more than ",
        "(tracing stopped there)",
        "counted while tracing",
        "Raise the limit where the memory is available (at least `--max-compile-memory 1024`",
    ] {
        assert!(error.contains(expected), "missing {expected:?} in: {error}");
    }
    // A short closed chain is far within any budget: generated as before.
    let short = parse_urdf(&closed_chain_urdf(8), Path::new("closed8.urdf")).unwrap();
    assert!(generate_source(&short, &options).is_ok());
}

/// A limit at or below rustc's own base (130 MB) allows no operation: the tape's budget has a floor, so
/// such a request is refused on the traced count, not as "more than 0 operations" (attacker's trial).
#[test]
fn a_limit_below_rustcs_base_is_refused_on_the_traced_count() {
    let options = GenerateOptions {
        max_compile_memory_mb: Some(100),
        ..only(&[Algorithm::Aba])
    };
    let error = generate_source(&chain(10), &options)
        .unwrap_err()
        .to_string();
    assert!(error.contains("counted in the traced code"), "{error}");
    assert!(!error.contains("more than 0"), "{error}");
}
