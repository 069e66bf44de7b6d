//! `embedyn generate`: the standalone crate is deterministic, has no loops over bodies, and builds on its
//! own as `#![no_std]` with no allocator (its only dependency is `libm` from crates.io).

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// Runs `embedyn generate` and returns what it printed (its JSON).
fn generate(model: &str, out: &Path, extra: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args([
            "generate",
            &repo(model).to_string_lossy(),
            "--out",
            &out.to_string_lossy(),
        ])
        .args(extra)
        .stderr(std::process::Stdio::null())
        .output()
        .unwrap();
    assert!(output.status.success(), "embedyn generate {model} failed");
    String::from_utf8(output.stdout).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn generation_is_deterministic() {
    let (a, b) = (tmp("det_a"), tmp("det_b"));
    generate("models/quadruped.urdf", &a, &["--minv"]);
    generate("models/quadruped.urdf", &b, &["--minv"]);
    for f in ["Cargo.toml", "README.md", "src/lib.rs"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs between two runs");
    }
}

#[test]
fn generated_source_has_no_loops_and_no_std_or_alloc() {
    let dir = tmp("noloops");
    generate("models/humanoid34.urdf", &dir, &["--minv"]);
    let src = std::fs::read_to_string(dir.join("src/lib.rs")).unwrap();
    assert!(src.contains("#![no_std]"));
    // The generated functions (the `f64` and `f32` modules); the helper module before them is
    // library code (its sine/cosine batch iterates over a fixed-size array of angles).
    let generated = &src[src.find("pub mod f64").expect("an f64 module")..];
    assert!(src.find("pub mod helpers").unwrap() < src.find("pub mod f64").unwrap());
    let code: Vec<&str> = generated
        .lines()
        .map(|l| l.trim())
        .filter(|l| !l.starts_with("//"))
        .collect();
    for l in &code {
        let words: Vec<&str> = l
            .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
            .collect();
        // `for … in`, `while`, `loop`: (`impl Trait for Type` is not a loop).
        let for_loop = words.contains(&"for") && words.contains(&"in");
        assert!(
            !for_loop && !words.contains(&"while") && !words.contains(&"loop"),
            "a loop in generated code: {l}"
        );
        assert!(
            !l.contains("std::") && !l.contains("alloc") && !l.contains("Vec<"),
            "std or alloc in generated code: {l}"
        );
        assert!(
            !l.contains("panic!") && !l.contains("unwrap") && !l.contains("expect("),
            "a panicking path: {l}"
        );
    }
    // Every joint is unrolled: the functions are split into small parts, each a plain sequence of lets.
    assert!(src.contains("pub fn aba(") && src.contains("pub fn minv("));
}

#[test]
fn standalone_crate_builds_as_no_std() {
    let dir = tmp("nostd_crate");
    generate("models/arm7.urdf", &dir, &[]);
    // One shared target folder for generated crates keeps the suite fast.
    let target = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("generated-target");
    let out = Command::new(env!("CARGO"))
        .args(["build", "--release", "--offline", "--quiet"])
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the generated crate does not build:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(target.join("release/libarm7_dynamics.rlib").exists());
    let cargo = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
    let deps: Vec<&str> = cargo
        .split("[dependencies]")
        .nth(1)
        .unwrap()
        .lines()
        .filter(|l| l.contains('='))
        .take_while(|l| !l.starts_with('['))
        .collect();
    assert_eq!(deps, ["libm = \"0.2\""], "dependencies: {deps:?}");
}

/// With `--lanes 4` the crate has the lane module `f64x4`, carries the lane types in its helpers and
/// depends on `wide` without its `std` feature; it still builds (type-checks) as `no_std`.
#[test]
fn standalone_crate_with_lanes_checks_as_no_std() {
    let dir = tmp("lanes_crate");
    let printed = generate(
        "models/arm7.urdf",
        &dir,
        &[
            "--lanes",
            "4",
            "--scalar",
            "f64",
            "--only",
            "aba",
            "--name",
            "arm7-lanes",
        ],
    );
    let src = std::fs::read_to_string(dir.join("src/lib.rs")).unwrap();
    assert!(src.contains("pub mod f64x4") && src.contains("pub type S = crate::helpers::F64x4;"));
    // The lane functions' AVX twin, over the AVX lane type (checked below with the rest).
    assert!(src.contains("pub type S = crate::helpers::AvxF64x4;"));
    // Twins only where the target has SSE2: a soft-float target (`x86_64-unknown-none`) must not
    // touch vector registers, and LLVM could not compile the lane twins there (attacker's trial).
    assert!(!src.contains("target_arch = \"x86_64\", not(target_feature = \"avx\")"));
    assert!(src.contains(
        "#[cfg(all(target_arch = \"x86_64\", target_feature = \"sse2\", not(target_feature = \"avx\")))]"
    ));
    let cargo = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
    assert!(cargo.contains("name = \"arm7-lanes\""), "{cargo}");
    // The JSON names the crate written (it gave the default name).
    let printed: serde_json::Value = serde_json::from_str(&printed).unwrap();
    assert_eq!(printed["crate"], "arm7-lanes", "{printed}");
    assert!(
        cargo.contains("[dependencies.wide]") && cargo.contains("default-features = false"),
        "{cargo}"
    );
    let target = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("generated-target");
    let out = Command::new(env!("CARGO"))
        .args(["check", "--offline", "--quiet"])
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the generated crate does not check:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `--name` must be a crate name the user's code can refer to: refused otherwise, as a usage error
/// naming the problem, before anything is written.
#[test]
fn crate_names_that_code_cannot_name_are_refused() {
    for (name, problem) in [
        ("9lives", "must start with an ASCII letter"),
        ("arm seven", "is not a letter, digit"),
        ("bras_à_sept", "is not a letter, digit"),
        ("self", "keyword"),
        ("std", "built-in crate"),
        ("-x", "must start with an ASCII letter"),
        ("", "must start with an ASCII letter"),
    ] {
        let dir = tmp("bad_name");
        let out = Command::new(env!("CARGO_BIN_EXE_embedyn"))
            .args([
                "generate",
                &repo("models/arm7.urdf").to_string_lossy(),
                "--out",
            ])
            .arg(&dir)
            .arg(format!("--name={name}"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name:?}: {stderr}");
        assert!(
            stderr.contains("--name") && stderr.contains(problem),
            "{name:?}: {stderr}"
        );
        assert!(!dir.exists(), "{name:?}: nothing is written");
    }
}

/// `--only` writes exactly the functions named (and lists exactly those in the README); unknown names and
/// loop-only functions on a tree are refused with a message naming them.
#[test]
fn only_writes_exactly_the_functions_named() {
    let dir = tmp("only");
    generate(
        "models/loops/slider_crank.urdf",
        &dir,
        // Without AVX twins, whose modules repeat the functions' signatures.
        &["--only", "aba,kinematics", "--avx-twins", "none"],
    );
    let src = std::fs::read_to_string(dir.join("src/lib.rs")).unwrap();
    let readme = std::fs::read_to_string(dir.join("README.md")).unwrap();
    for f in ["aba", "kinematics"] {
        assert_eq!(
            src.matches(&format!("pub fn {f}(")).count(),
            2,
            "{f}: f64 and f32"
        );
        assert!(readme.contains(&format!("`{f}(")), "README lists {f}");
    }
    for f in [
        "rnea",
        "crba",
        "minv",
        "complete",
        "embedding",
        "crba_independent",
    ] {
        assert!(
            !src.contains(&format!("pub fn {f}(")),
            "{f} was not asked for"
        );
        assert!(!readme.contains(&format!("`{f}(")), "README lists {f}");
    }
    // Smaller than the default set by the functions left out (the helper module, the same in both, aside).
    let all = tmp("only_all");
    generate("models/loops/slider_crank.urdf", &all, &[]);
    let full = std::fs::read_to_string(all.join("src/lib.rs")).unwrap();
    let after_helpers = |s: &str| s.len() - s.find("pub mod joints").expect("a joints module");
    assert!(
        after_helpers(&src) * 2 < after_helpers(&full),
        "{} vs {}",
        after_helpers(&src),
        after_helpers(&full)
    );

    for (model, only, message) in [
        (
            "models/arm7.urdf",
            "aba,forward",
            "unknown function `forward`",
        ),
        (
            "models/arm7.urdf",
            "complete",
            "`complete` exists only for a model with loops",
        ),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_embedyn"))
            .args(["generate", &repo(model).to_string_lossy(), "--out"])
            .arg(tmp("only_bad"))
            .args(["--only", only])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(message),
            "{only}: {err}"
        );
    }
}

/// `embedyn generate … --out .` inside a user's crate replaced its Cargo.toml and src/lib.rs without a
/// word (a new user's trial). It now replaces only the files it wrote itself, refuses before writing
/// anything otherwise (a link too: it could point anywhere), and says so when `--out` is a file.
#[test]
fn generate_never_replaces_files_it_did_not_write() {
    let run = |out: &Path| {
        let output = Command::new(env!("CARGO_BIN_EXE_embedyn"))
            .arg("generate")
            .arg(repo("models/arm7.urdf"))
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        (
            output.status.code(),
            String::from_utf8_lossy(&output.stderr).into_owned(),
        )
    };
    // A user's crate, which may well mention embedyn (the attacker's): nothing of it is touched, and
    // the message names the file.
    let mine = tmp("users_crate");
    std::fs::create_dir_all(mine.join("src")).unwrap();
    let manifest =
        "[package]\nname = \"mine\"\ndescription = \"MPC on dynamics generated by embedyn\"\n";
    std::fs::write(mine.join("Cargo.toml"), manifest).unwrap();
    std::fs::write(
        mine.join("src/lib.rs"),
        "//! Uses dynamics generated by embedyn.\npub fn mine() {}\n",
    )
    .unwrap();
    let (code, stderr) = run(&mine);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains("Cargo.toml: exists and was not written by embedyn"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(mine.join("Cargo.toml")).unwrap(),
        manifest
    );
    assert_eq!(
        std::fs::read_to_string(mine.join("src/lib.rs")).unwrap(),
        "//! Uses dynamics generated by embedyn.\npub fn mine() {}\n"
    );
    assert!(!mine.join("README.md").exists(), "nothing is written");
    // Its own files it replaces: generating twice into one folder works.
    let ours = tmp("regenerated");
    assert_eq!(run(&ours).0, Some(0));
    let (code, stderr) = run(&ours);
    assert_eq!(code, Some(0), "{stderr}");
    // A link in place of a generated file is refused, whatever it points to.
    #[cfg(unix)]
    {
        let target = tmp("link_target.toml");
        std::fs::write(&target, "# Generated by embedyn, or so it says\n").unwrap();
        std::fs::remove_file(ours.join("Cargo.toml")).unwrap();
        std::os::unix::fs::symlink(&target, ours.join("Cargo.toml")).unwrap();
        let (code, stderr) = run(&ours);
        assert_eq!(code, Some(1), "{stderr}");
        assert!(
            stderr.contains("exists and was not written by embedyn"),
            "{stderr}"
        );
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "# Generated by embedyn, or so it says\n"
        );
    }
    // A `src` that is a link: nothing is written through it (the attacker's wrote lib.rs outside).
    #[cfg(unix)]
    {
        let elsewhere = tmp("src_elsewhere");
        std::fs::create_dir_all(&elsewhere).unwrap();
        let linked = tmp("src_linked");
        std::fs::create_dir_all(&linked).unwrap();
        std::os::unix::fs::symlink(&elsewhere, linked.join("src")).unwrap();
        let (code, stderr) = run(&linked);
        assert_eq!(code, Some(1), "{stderr}");
        assert!(
            stderr.contains("src: exists and was not written by embedyn"),
            "{stderr}"
        );
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
        assert!(!linked.join("Cargo.toml").exists());
    }
    // A crate generated before the README and lib.rs had their markers (known by its Cargo.toml's).
    let older = tmp("older_crate");
    assert_eq!(run(&older).0, Some(0));
    for file in ["README.md", "src/lib.rs"] {
        let text = std::fs::read_to_string(older.join(file)).unwrap();
        let without_marker = &text[text.find('\n').unwrap() + 1..];
        std::fs::write(older.join(file), without_marker).unwrap();
    }
    let (code, stderr) = run(&older);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(std::fs::read_to_string(older.join("src/lib.rs"))
        .unwrap()
        .starts_with("// Generated by embedyn "));
    assert!(
        std::fs::read_dir(&older).unwrap().all(|e| !e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".embedyn-new")),
        "no staged file is left"
    );
    // A file as --out.
    let file = tmp("out_is_a_file");
    std::fs::write(&file, "").unwrap();
    let (code, stderr) = run(&file);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("is not a folder"), "{stderr}");
}

/// The generated crate built the way its users build it (`--release`: opt-level 3) computes what the
/// interpreted solver computes, on random states of the arm7. The suite's own generated code runs at the
/// test profile's opt-level 1, which did not show the miscompilation this pins: rustc 1.95 (LLVM 22.1.2)
/// at opt-level 3 gave one angle of the sine/cosine batch another's quadrant, and the arm7's release
/// `kinematics` had every link below joint 2 wrong by up to 2 (`reduce` in runtime/src/codegen_support.rs).
/// The lane module's batch forms (`--lanes 4`), whose sine/cosine takes each lane's quadrant from the bits
/// of its shifted float as the scalar batch did, give the scalar functions' bits in that build too.
#[test]
fn standalone_crate_in_release_matches_the_interpreted_solver() {
    use embedyn_runtime::{
        aba, crba, forward_kinematics, link_poses, mass_matrix_inverse, rnea, Model, SplitMix64,
        Workspace,
    };
    let dir = tmp("release_check");
    generate(
        "models/arm7.urdf",
        &dir,
        &[
            "--only",
            "kinematics,aba,rnea,crba,minv",
            "--scalar",
            "f64",
            "--lanes",
            "4",
            "--name",
            "arm7-release-check",
        ],
    );
    let loaded = embedyn_codegen::load(&repo("models/arm7.urdf")).unwrap();
    let model: Model<f64> = loaded.model(&Default::default()).unwrap();
    let nv = model.nv();
    let mut ws = Workspace::new(&model);
    let mut rng = SplitMix64::new(20_261_204);
    let list = |x: &[f64]| {
        let items: Vec<String> = x.iter().map(|a| format!("{a:?}")).collect();
        format!("&[{}]", items.join(", "))
    };
    let mut cases = String::new();
    for case in 0..18 {
        // Angles over every quadrant (past the limits: the functions take any angle), and two states at
        // multiples of π/2 and just beside them, where the quadrant changes.
        let q: Vec<f64> = match case {
            16 => (0..nv)
                .map(|k| (k as f64 - 3.0) * core::f64::consts::FRAC_PI_2)
                .collect(),
            17 => (0..nv)
                .map(|k| (k as f64 - 3.0) * core::f64::consts::FRAC_PI_2 + (k as f64 - 3.0) * 1e-12)
                .collect(),
            _ => (0..nv).map(|_| rng.uniform(-6.0, 6.0)).collect(),
        };
        let v: Vec<f64> = (0..nv).map(|_| rng.uniform(-2.0, 2.0)).collect();
        let tau: Vec<f64> = (0..nv).map(|_| rng.uniform(-20.0, 20.0)).collect();
        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let frames: Vec<f64> = link_poses(&model, &ws)
            .flat_map(|(_, x)| {
                let mut f: Vec<f64> = x.rotation.transpose().iter().copied().collect();
                f.extend(x.translation.iter());
                f
            })
            .collect();
        let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let inverse = rnea(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let m = crba(&model, &mut ws, &q)
            .unwrap()
            .transpose()
            .as_slice()
            .to_vec();
        let minv = mass_matrix_inverse(&model, &mut ws, &q)
            .unwrap()
            .transpose()
            .as_slice()
            .to_vec();
        cases += &format!(
            "    states.push(check({}, {}, {}, {}, {}, {}, {}, {}));\n",
            list(&q),
            list(&v),
            list(&tau),
            list(&frames),
            list(&qdd),
            list(&inverse),
            list(&m),
            list(&minv)
        );
    }
    let example = format!(
        r#"use arm7_release_check::f64 as g;
use arm7_release_check::{{FRAMES, NV}};

fn close(what: &str, got: &[f64], want: &[f64]) {{
    let scale = want.iter().fold(1.0f64, |m, w| m.max(w.abs()));
    for (k, (g, w)) in got.iter().zip(want).enumerate() {{
        assert!((g - w).abs() <= 1e-12 * scale, "{{what}}[{{k}}]: {{g}} against {{w}}");
    }}
}}

type State = ([f64; NV], [f64; NV], [f64; NV]);

#[allow(clippy::too_many_arguments)]
fn check(q: &[f64], v: &[f64], tau: &[f64], frames: &[f64], qdd: &[f64], inverse: &[f64], m: &[f64], minv: &[f64]) -> State {{
    let (q, v, tau): ([f64; NV], [f64; NV], [f64; NV]) =
        (q.try_into().unwrap(), v.try_into().unwrap(), tau.try_into().unwrap());
    let mut f = [[0.0; 12]; FRAMES.len()];
    g::kinematics(&q, &mut f);
    close("kinematics", f.as_flattened(), frames);
    let mut out = [0.0; NV];
    let _ = g::aba(&q, &v, &tau, &mut out);
    close("aba", &out, qdd);
    g::rnea(&q, &v, &tau, &mut out);
    close("rnea", &out, inverse);
    let mut mat = [[0.0; NV]; NV];
    g::crba(&q, &mut mat);
    close("crba", mat.as_flattened(), m);
    g::minv(&q, &mut mat);
    close("minv", mat.as_flattened(), minv);
    (q, v, tau)
}}

/// The batch forms against the scalar functions, bit for bit.
fn lanes(states: &[State]) {{
    use arm7_release_check::f64x4 as l;
    let same = |what: &str, k: usize, got: &[f64], want: &[f64]| {{
        for (i, (a, b)) in got.iter().zip(want).enumerate() {{
            assert!(a.to_bits() == b.to_bits(), "{{what}} state {{k}} [{{i}}]: lanes {{a:e}} against scalar {{b:e}}");
        }}
    }};
    let q: Vec<[f64; NV]> = states.iter().map(|s| s.0).collect();
    let v: Vec<[f64; NV]> = states.iter().map(|s| s.1).collect();
    let tau: Vec<[f64; NV]> = states.iter().map(|s| s.2).collect();
    let n = states.len();
    let mut frames = vec![[[0.0; 12]; FRAMES.len()]; n];
    assert!(l::kinematics_batch(&q, &mut frames));
    let mut qdd = vec![[0.0; NV]; n];
    assert!(l::aba_batch(&q, &v, &tau, &mut qdd));
    let mut inverse = vec![[0.0; NV]; n];
    assert!(l::rnea_batch(&q, &v, &tau, &mut inverse));
    let mut m = vec![[[0.0; NV]; NV]; n];
    assert!(l::crba_batch(&q, &mut m));
    for k in 0..n {{
        let mut f = [[0.0; 12]; FRAMES.len()];
        g::kinematics(&q[k], &mut f);
        same("kinematics", k, frames[k].as_flattened(), f.as_flattened());
        let mut out = [0.0; NV];
        let _ = g::aba(&q[k], &v[k], &tau[k], &mut out);
        same("aba", k, &qdd[k], &out);
        g::rnea(&q[k], &v[k], &tau[k], &mut out);
        same("rnea", k, &inverse[k], &out);
        let mut mat = [[0.0; NV]; NV];
        g::crba(&q[k], &mut mat);
        same("crba", k, m[k].as_flattened(), mat.as_flattened());
    }}
}}

fn main() {{
    let mut states = Vec::new();
{cases}    lanes(&states);
    println!("all cases agree");
}}
"#
    );
    std::fs::create_dir_all(dir.join("examples")).unwrap();
    std::fs::write(dir.join("examples/check.rs"), example).unwrap();
    let target = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("generated-target");
    let out = Command::new(env!("CARGO"))
        .args([
            "run",
            "--release",
            "--offline",
            "--quiet",
            "--example",
            "check",
        ])
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("all cases agree"),
        "the release build of the generated crate disagrees with the interpreted solver:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
