//! The command line at its edges (issue 8, docs/model-format.md, "Names are data" and docs/command-line.md): hostile names, the
//! cache of compiled runners, closed pipes, models without coordinates or that assemble on a narrow
//! range, non-finite results, zero quaternions and exact JSON numbers.

use serde_json::{json, Value};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn repo(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// What one run of `embedyn` gave.
struct Run {
    code: Option<i32>,
    out: String,
    err: String,
}

impl Run {
    fn ok(&self) -> bool {
        self.code == Some(0)
    }

    /// A failure as docs/command-line.md wants it: exit status 1..127, nothing on stdout, a message on stderr.
    fn clean_failure(&self) -> &str {
        let code = self.code.expect("ended by a signal");
        assert!(
            (1..128).contains(&code) && code != 101,
            "exit status {code}: {}",
            self.err
        );
        assert!(self.out.is_empty(), "stdout on error: {}", self.out);
        assert!(!self.err.contains("panicked"), "{}", self.err);
        &self.err
    }

    fn json(&self) -> Value {
        assert!(self.ok(), "failed ({:?}): {}", self.code, self.err);
        serde_json::from_str(&self.out).unwrap()
    }
}

/// Runs `embedyn args` with `stdin` and the environment changes (`None` removes the variable).
fn embedyn_env(args: &[&str], stdin: &str, env: &[(&str, Option<&Path>)]) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_embedyn"));
    cmd.args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in env {
        match v {
            Some(v) => cmd.env(k, v),
            None => cmd.env_remove(k),
        };
    }
    let mut child = cmd.spawn().unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    Run {
        code: out.status.code(),
        out: String::from_utf8(out.stdout).unwrap(),
        err: String::from_utf8(out.stderr).unwrap(),
    }
}

/// `embedyn` with the cache shared by the tests of this file that build runners.
fn embedyn(args: &[&str], stdin: &str) -> Run {
    let cache = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("embedyn-cache-edges");
    embedyn_env(args, stdin, &[("EMBEDYN_CACHE_DIR", Some(&cache))])
}

const HOSTILE: &str = "tests/data/hostile_names.urdf";

#[path = "../../tests/data/hostile_names.rs"]
mod hostile_names;
use hostile_names::{FRAMES as HOSTILE_FRAMES, JOINTS as HOSTILE_JOINTS};

/// The string values of `pub const NAME: [&str; N] = [...]` in a generated source file.
fn string_constant(file: &syn::File, name: &str) -> Vec<String> {
    for item in &file.items {
        if let syn::Item::Const(c) = item {
            if c.ident == name {
                let syn::Expr::Array(a) = &*c.expr else {
                    panic!("{name} is not an array")
                };
                return a
                    .elems
                    .iter()
                    .map(|e| match e {
                        syn::Expr::Lit(syn::ExprLit {
                            lit: syn::Lit::Str(s),
                            ..
                        }) => s.value(),
                        other => panic!("{name}: not a string literal: {}", quote::quote!(#other)),
                    })
                    .collect();
            }
        }
    }
    panic!("no constant {name}")
}

/// Keys of a TOML table, sorted.
fn keys(t: &toml::Table) -> Vec<&str> {
    let mut k: Vec<&str> = t.keys().map(String::as_str).collect();
    k.sort();
    k
}

/// Names with quotes, backslashes, newlines, a carriage return, `*/`, `compile_error!`, keywords, unicode
/// and names that collide after sanitizing, in the robot, its links and joints and its file name: the
/// generated crate has exactly the manifest keys it should, builds without a warning, and its `JOINTS`
/// and `FRAMES` are the model's names exactly.
#[test]
fn hostile_names_generate_a_crate_that_builds_and_means_what_the_model_says() {
    let dir = tmp("hostile_models");
    std::fs::create_dir_all(&dir).unwrap();
    // The file name reaches the docs too: a quote, a backtick, a backslash and a newline in it.
    let model = dir.join("we\"ird `*\\\nname.urdf");
    std::fs::copy(repo(HOSTILE), &model).unwrap();
    let out = tmp("hostile_crate");
    let run = embedyn(
        &[
            "generate",
            model.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let reply = run.json();

    let manifest: toml::Table = std::fs::read_to_string(out.join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(keys(&manifest), ["dependencies", "package", "workspace"]);
    let package = manifest["package"].as_table().unwrap();
    assert_eq!(
        keys(package),
        [
            "description",
            "edition",
            "license",
            "name",
            "publish",
            "rust-version",
            "version"
        ]
    );
    let name = package["name"].as_str().unwrap();
    assert_eq!(reply["crate"], name);
    assert!(
        name.starts_with("x_build_evil_rs_compile_error_boom_fn_") && name.ends_with("_dynamics"),
        "{name}"
    );
    assert_eq!(keys(manifest["dependencies"].as_table().unwrap()), ["libm"]);
    assert!(manifest["workspace"].as_table().unwrap().is_empty());

    let source = std::fs::read_to_string(out.join("src/lib.rs")).unwrap();
    let file = syn::parse_file(&source).unwrap();
    assert_eq!(string_constant(&file, "JOINTS"), HOSTILE_JOINTS);
    assert_eq!(string_constant(&file, "FRAMES"), HOSTILE_FRAMES);
    // No item other than the generated ones (no macro call smuggled in by a name).
    for item in &file.items {
        assert!(
            matches!(item, syn::Item::Const(_) | syn::Item::Mod(_)),
            "unexpected item: {}",
            quote::quote!(#item)
        );
    }
    // The README's joint table: one row of ten cells per joint (name, constant, type, indices, four
    // limits, independent), names shown escaped.
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    let rows: Vec<&str> = readme.lines().filter(|l| l.starts_with("| `")).collect();
    assert_eq!(rows.len(), HOSTILE_JOINTS.len(), "{readme}");
    for r in &rows {
        let cells = r.replace("\\|", "").matches('|').count();
        assert_eq!(cells, 11, "{r}");
    }
    assert!(
        readme.contains("| `fn` | `FN_0F1E18BB` | revolute | 4 | 4 | -3 | 3 | 10 | 10 | yes |"),
        "{readme}"
    );
    assert!(
        readme.contains("| `new\\nline\\rbuild = \\\"evil.rs\\\"` |"),
        "{readme}"
    );

    let target = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("generated-target");
    // A debug build: the warnings are the same, and it compiles faster than an optimized one.
    let build = Command::new(env!("CARGO"))
        .args(["build", "--offline"])
        .current_dir(&out)
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&build.stderr);
    assert!(
        build.status.success(),
        "the generated crate does not build:\n{stderr}"
    );
    assert!(!stderr.contains("warning"), "warnings:\n{stderr}");
}

/// `--engine generated` on a model with a hostile name: the runner (its own Cargo.toml with a `[[bin]]` and a
/// generated main.rs) builds and answers as the interpreted solver does; the cache entry is private,
/// checked before each use, and rebuilt when its binary is truncated, its manifest corrupt or stale;
/// cargo reads no configuration planted above the cache. Two runs on an empty cache at once both succeed.
#[test]
fn the_runner_cache_is_private_checked_and_rebuilt() {
    // A cargo configuration planted above the cache (as another user could in a shared folder) names a
    // compiler wrapper that does not exist: the build fails if cargo reads it.
    let parent = tmp("private-cache-parent");
    std::fs::create_dir_all(parent.join(".cargo")).unwrap();
    std::fs::write(
        parent.join(".cargo/config.toml"),
        "[build]\nrustc-wrapper = \"/nonexistent/planted-wrapper\"\n",
    )
    .unwrap();
    let cache = parent.join("cache");
    // Issue 8's reproducer: its robot name would add `build = "evil.rs"` to an unescaped Cargo.toml.
    let model = repo("tests/data/evil_robot_name.urdf");
    let input = json!({"samples": [{"q": [0.3], "v": [0.2], "tau": [0.5]}]}).to_string();
    let args = ["eval", &model, "--algo", "aba", "--engine", "generated"];
    let env = [("EMBEDYN_CACHE_DIR", Some(cache.as_path()))];
    let interpreted = embedyn(&["eval", &model, "--algo", "aba"], &input).json();
    let agrees = |run: &Run| {
        let got = run.json();
        let (a, b) = (&got["samples"][0]["qdd"], &interpreted["samples"][0]["qdd"]);
        let (a, b) = (a.as_array().unwrap(), b.as_array().unwrap());
        assert_eq!(a.len(), 1);
        for (x, y) in a.iter().zip(b) {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-9 * (1.0 + y.abs()), "{x} vs {y}");
        }
    };
    // Two runs at once on an empty cache.
    std::thread::scope(|s| {
        let runs: Vec<_> = (0..2)
            .map(|_| s.spawn(|| embedyn_env(&args, &input, &env)))
            .collect();
        for r in runs {
            agrees(&r.join().unwrap());
        }
    });
    let entries: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("entry.json").exists())
        .collect();
    assert_eq!(entries.len(), 1, "{entries:?}");
    let entry = &entries[0];
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        for d in [cache.as_path(), entry.as_path()] {
            let mode = std::fs::metadata(d).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o700, "{}", d.display());
        }
    }
    // The runner's manifest: the package, its [lib] (the crate's name under a package named with the
    // entry's key), one [[bin]], libm, an empty workspace; nothing else.
    let manifest: toml::Table = std::fs::read_to_string(entry.join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        keys(&manifest),
        ["bin", "dependencies", "lib", "package", "workspace"]
    );
    assert_eq!(keys(manifest["lib"].as_table().unwrap()), ["name", "path"]);
    let package = manifest["package"]["name"].as_str().unwrap();
    let lib = manifest["lib"]["name"].as_str().unwrap();
    assert!(
        package.starts_with(&format!("{lib}_")) && package.len() == lib.len() + 17,
        "{package}"
    );
    let bins = manifest["bin"].as_array().unwrap();
    assert_eq!(bins.len(), 1);
    assert_eq!(keys(bins[0].as_table().unwrap()), ["name", "path"]);
    assert_eq!(bins[0]["path"].as_str(), Some("src/main.rs"));
    assert!(syn::parse_file(&std::fs::read_to_string(entry.join("src/main.rs")).unwrap()).is_ok());

    // A valid entry is used as it is.
    let run = embedyn_env(&args, &input, &env);
    agrees(&run);
    assert!(!run.err.contains("compiling"), "{}", run.err);

    let runner = std::fs::read_dir(entry)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.file_stem().is_some_and(|s| s == "runner"))
        .unwrap();
    let manifest_path = entry.join("entry.json");
    let spoil = |why: &str| match why {
        "binary does not match" => {
            let bytes = std::fs::read(&runner).unwrap();
            std::fs::write(&runner, &bytes[..bytes.len() / 2]).unwrap();
        }
        "manifest is corrupt" => {
            let text = std::fs::read(&manifest_path).unwrap();
            std::fs::write(&manifest_path, &text[..text.len() / 2]).unwrap();
        }
        "stale" => {
            let mut m: Value =
                serde_json::from_slice(&std::fs::read(&manifest_path).unwrap()).unwrap();
            m["source_sha256"] = json!("0".repeat(64));
            std::fs::write(&manifest_path, m.to_string()).unwrap();
        }
        _ => std::fs::remove_file(&runner).unwrap(),
    };
    let damage = [
        "binary does not match",
        "manifest is corrupt",
        "stale",
        "binary cannot be read",
    ];
    for why in damage {
        spoil(why);
        let run = embedyn_env(&args, &input, &env);
        agrees(&run);
        assert!(
            run.err.contains("not usable")
                && run.err.contains(why)
                && run.err.contains("rebuilding"),
            "{why}: {}",
            run.err
        );
        // And the rebuilt entry is trusted again.
        let again = embedyn_env(&args, &input, &env);
        agrees(&again);
        assert!(!again.err.contains("rebuilding"), "{}", again.err);
    }
}

/// Without HOME (and no cache variable), the generated engine refuses to build anywhere shared (such as
/// the temporary folder) and says what to set; a cache folder others can write, or could replace, is
/// refused too.
#[test]
fn no_shared_cache_folder() {
    let model = repo("models/arm7.urdf");
    let input = json!({"samples": [{"q": vec![0.0; 7], "v": vec![0.0; 7], "tau": vec![0.0; 7]}]})
        .to_string();
    let args = ["eval", &model, "--algo", "aba", "--engine", "generated"];
    let run = embedyn_env(
        &args,
        &input,
        &[
            ("HOME", None),
            ("EMBEDYN_CACHE_DIR", None),
            ("XDG_CACHE_HOME", None),
        ],
    );
    let e = run.clean_failure();
    assert!(
        e.contains("HOME is not set")
            && e.contains("EMBEDYN_CACHE_DIR")
            && e.contains("XDG_CACHE_HOME"),
        "{e}"
    );
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let shared = tmp("shared-cache");
        std::fs::create_dir_all(&shared).unwrap();
        std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o777)).unwrap();
        let run = embedyn_env(&args, &input, &[("EMBEDYN_CACHE_DIR", Some(&shared))]);
        let e = run.clean_failure();
        assert!(e.contains("writable by other users"), "{e}");
        assert_eq!(
            std::fs::read_dir(&shared).unwrap().count(),
            0,
            "nothing written"
        );
        // A private cache folder inside a folder that others can write (not sticky): another user could
        // rename it away and put their own in its place between the check and the use. Refused, whether
        // named directly or through a symlink (which is resolved once, and only the resolved path used).
        let private = shared.join("cache");
        std::fs::create_dir_all(&private).unwrap();
        std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o700)).unwrap();
        let link = tmp("cache-link");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&private, &link).unwrap();
        for dir in [&private, &link] {
            let run = embedyn_env(&args, &input, &[("EMBEDYN_CACHE_DIR", Some(dir))]);
            let e = run.clean_failure();
            assert!(
                e.contains("a folder above the cache") && e.contains("shared-cache"),
                "{e}"
            );
            assert_eq!(std::fs::read_dir(&private).unwrap().count(), 0);
        }
    }
}

/// `embedyn info M | head -c 10`: the reader closes the pipe early; the program ends quietly (status 0,
/// no panic), for stdout and for stderr, and with a real write error (a full disk) it fails cleanly.
#[test]
fn closed_pipes_end_quietly() {
    // A large document (a 400-joint model), so that it cannot fit the pipe before the reader closes it.
    let big = repo("models/loops/rotor_chain_200.urdf");
    let mut child = Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args(["info", &big])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 10];
    child
        .stdout
        .as_mut()
        .unwrap()
        .read_exact(&mut first)
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(&first, b"{\"name\":\"r");

    // Warnings into a closed stderr: the command still does its work.
    let warns = repo("tests/data/bad/triangle_violation.urdf");
    let mut child = Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args(["info", &warns])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    assert!(serde_json::from_slice::<Value>(&out.stdout).is_ok());

    #[cfg(target_os = "linux")]
    {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_embedyn"))
            .args(["info", &big])
            .stdout(full)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(
            err.contains("cannot write the output") && !err.contains("panicked"),
            "{err}"
        );
    }
}

/// `bench` on a model without degrees of freedom gives times (of empty calls) instead of indexing an
/// empty vector, and on a four-bar that assembles only for a crank in [0.7, 1.4] rad it finds its states
/// there instead of looping forever.
#[test]
fn bench_handles_no_coordinates_and_narrow_assembly() {
    for model in [
        "tests/data/no_dof.urdf",
        "tests/data/loops/narrow_four_bar.urdf",
    ] {
        let v = embedyn(&["bench", &repo(model), "--json"], "").json();
        for algo in ["aba", "rnea", "crba"] {
            for engine in ["interpreted_f64", "generated_f64", "generated_f32"] {
                let ns = v[algo][engine].as_f64().unwrap_or(f64::NAN);
                assert!(ns.is_finite() && ns > 0.0, "{model} {algo} {engine}: {ns}");
            }
        }
    }
}

/// A finite state whose result overflows (velocities of 1e200: their products are ∞) is refused by both
/// engines with the same message, naming the output as the JSON does (`qdd`), not the function.
#[test]
fn an_overflowing_result_is_named_alike_by_both_engines() {
    let model = repo("models/arm7.urdf");
    let (q, v, tau) = (vec![0.1; 7], vec![1e200; 7], vec![0.0; 7]);
    let input = json!({"samples": [{"q": q, "v": v, "tau": tau}]}).to_string();
    let mut messages = Vec::new();
    for engine in ["interpreted", "generated"] {
        let run = embedyn(
            &["eval", &model, "--algo", "aba", "--engine", engine],
            &input,
        );
        let e = run.clean_failure().to_string();
        assert!(
            e.contains("sample 0") && e.contains("`qdd`[") && e.contains("is not finite"),
            "{engine}: {e}"
        );
        // The error line (a first run of the generated engine also notes that it compiles).
        messages.push(
            e.lines()
                .filter(|l| l.starts_with("error:"))
                .collect::<Vec<_>>()
                .join("\n"),
        );
    }
    assert_eq!(messages[0], messages[1]);
}

/// Every output field is checked finite: `tau_independent` (Xᵀτ) overflows for a joint that mimics
/// another with multiplier 1e8 and a huge force on it, although `tau` itself is finite.
#[test]
fn non_finite_tau_independent_is_an_error() {
    let model = repo("tests/data/loops/mimic_1e8.urdf");
    let input =
        json!({"samples": [{"q": [0.0, 0.0], "v": [0.0, 0.0], "qdd": [0.0, 1e308]}]}).to_string();
    let run = embedyn(&["eval", &model, "--algo", "rnea"], &input);
    let e = run.clean_failure();
    assert!(
        e.contains("sample 0") && e.contains("tau_independent") && e.contains("not finite"),
        "{e}"
    );
    // A moderate state is fine, and Xᵀτ = τ₀ + 1e8 τ₁.
    let input =
        json!({"samples": [{"q": [0.0, 0.0], "v": [0.0, 0.0], "qdd": [0.0, 1.0]}]}).to_string();
    let v = embedyn(&["eval", &model, "--algo", "rnea"], &input).json();
    let tau: Vec<f64> = serde_json::from_value(v["samples"][0]["tau"].clone()).unwrap();
    let ti = v["samples"][0]["tau_independent"][0].as_f64().unwrap();
    assert!(
        (ti - (tau[0] + 1e8 * tau[1])).abs() <= 1e-12 * ti.abs(),
        "{ti} {tau:?}"
    );
}

/// `complete` refuses an all-zero quaternion, naming the sample and the joint (it used to report
/// cond(Y1) = inf); any other quaternion is normalized.
#[test]
fn complete_refuses_a_zero_quaternion() {
    let model = repo("models/loops/biped_floating.urdf");
    let mut q = vec![0.0; 23];
    let v = vec![0.0; 22];
    let input = json!({"samples": [{"q": q, "v": v}, {"q": q, "v": v}]});
    let mut good = input.clone();
    good["samples"][0]["q"][6] = json!(1.0);
    good["samples"][1]["q"][6] = json!(1.0);
    let mut bad = good.clone();
    bad["samples"][1]["q"][6] = json!(0.0);
    let run = embedyn(&["complete", &model], &bad.to_string());
    let e = run.clean_failure();
    assert!(
        e.contains("sample 1") && e.contains("floating_base") && e.contains("non-zero quaternion"),
        "{e}"
    );
    // A tiny quaternion (whose squared norm underflows) still has a direction.
    q[6] = 1e-200;
    q[3] = 1e-200;
    let tiny = json!({"samples": [{"q": q, "v": v}]});
    let out = embedyn(&["complete", &model], &tiny.to_string()).json();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let qs: Vec<f64> = serde_json::from_value(out["samples"][0]["q"].clone()).unwrap();
    assert!(
        (qs[3] - h).abs() < 1e-15 && (qs[6] - h).abs() < 1e-15,
        "{qs:?}"
    );
}

/// JSON numbers are read and written exactly: doubles that a fast, inexact parser gets wrong by an ulp,
/// subnormals, 0.1 + 0.2 and integers beyond 2^53 go through `eval` bit for bit (on a unit mass sliding
/// freely, where qdd = tau exactly), and a state printed by `complete` is accepted by `eval`.
#[test]
fn json_numbers_round_trip_exactly() {
    let tricky = [
        1e-310,
        5e-324,
        0.1 + 0.2,
        9007199254740993.0,
        9.109e-31,
        4.000887762015429e-14,
        5.559021647124125e-269,
        f64::MAX,
        f64::MIN_POSITIVE,
        -1.0 / 3.0,
    ];
    let model = repo("tests/data/unit_slider.urdf");
    let samples: Vec<Value> = tricky
        .iter()
        .map(|&t| json!({"q": [0.0], "v": [0.0], "tau": [t], "qdd": [t]}))
        .collect();
    let input = json!({ "samples": samples }).to_string();
    for (algo, field) in [("aba", "qdd"), ("rnea", "tau")] {
        let out = embedyn(&["eval", &model, "--algo", algo], &input).json();
        for (k, &t) in tricky.iter().enumerate() {
            let got = out["samples"][k][field][0].as_f64().unwrap();
            assert_eq!(
                got.to_bits(),
                t.to_bits(),
                "{algo}: {t:e} came back as {got:e}"
            );
        }
    }

    // complete → eval, through the JSON text each prints.
    let model = repo("tests/data/loops/narrow_four_bar.urdf");
    let guess = json!({"samples": [{"q": [1.0, -1.7, 0.6], "v": [0.3, 0.0, 0.0]}, {"q": [0.9, -1.5, 0.4], "v": [-0.7, 0.0, 0.0]}]});
    let completed = embedyn(&["complete", &model], &guess.to_string());
    let mut states = completed.json();
    for s in states["samples"].as_array_mut().unwrap() {
        s["tau"] = json!([0.1, 0.0, 0.0]);
    }
    embedyn(&["eval", &model, "--algo", "aba"], &states.to_string()).json();
}

/// Trial 9: the command line's own messages (not the loader's) printed names raw: a joint name with
/// U+202E reversed the rest of the line, and a name of megabytes became megabytes of stderr. Every line
/// on stderr goes through the loader's escaping and is cut at a bounded length.
#[test]
fn the_command_lines_own_messages_escape_and_shorten_names() {
    let dir = tmp("own-messages");
    std::fs::create_dir_all(&dir).unwrap();
    let long = "n".repeat(100_000);
    for (file, name, shown) in [
        (
            "rlo.urdf",
            "f&#x202E;x&#x2028;y",
            "f\\u{202e}x\\u{2028}y".to_string(),
        ),
        (
            "long.urdf",
            long.as_str(),
            format!("{}… (100000 bytes)", &long[..80]),
        ),
    ] {
        let model = dir.join(file);
        std::fs::write(
            &model,
            format!(
                r#"<robot name="r"><link name="world"/><link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="{name}" type="floating"><parent link="world"/><child link="b"/></joint></robot>"#
            ),
        )
        .unwrap();
        let zeros = [0.0; 6];
        let input = json!({"samples": [{"q": [0, 0, 0, 0, 0, 0, 2], "v": zeros, "tau": zeros}]});
        let run = embedyn(
            &["eval", model.to_str().unwrap(), "--algo", "aba"],
            &input.to_string(),
        );
        let e = run.clean_failure();
        assert!(
            e.contains("unit quaternion") && e.contains(&shown),
            "{}",
            &e[..e.len().min(300)]
        );
        assert!(!e.contains('\u{202E}') && !e.contains('\u{2028}'), "{e:?}");
        assert!(e.len() < 5000, "{} bytes of stderr", e.len());
    }
}
