//! `eval` with external wrenches (`f_ext` on `aba`, `rnea`, `nle`), `--algo jacobian`, `com` and
//! `centroidal` (CONTRACT §2, §3) through the command line, against Pinocchio 4.1
//! (tests/data/pinocchio/contact.py: a fixed UR5 and a floating ANYmal B) to 1e-9 relative; their errors;
//! and the `_independent` fields of a loop model.

use crate::cli::{json_of, repo};
use serde_json::{json, Value};

const TOL: f64 = 1e-9;

/// CONTRACT §2: max|a − b| / max(1, max|b|).
pub fn relative_error(a: &[f64], b: &[f64]) -> f64 {
    embedyn_runtime::relative_error(a, b)
}

pub fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn rows(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().unwrap().iter().map(vecf).collect()
}

/// A reference robot: its `eval` arguments, Pinocchio's JSON and the coordinate maps (our index →
/// Pinocchio's), by joint name from `embedyn info` and the JSON's `joints`.
pub struct Robot {
    pub name: &'static str,
    args: Vec<String>,
    pub json: Value,
    q_map: Vec<usize>,
    v_map: Vec<usize>,
}

impl Robot {
    fn load(name: &'static str, urdf: &str, floating: bool) -> Robot {
        Robot::with_reference(name, urdf, floating, "contact")
    }

    /// The robot with Pinocchio's reference `tests/data/pinocchio/{name}_{kind}.json`.
    pub fn with_reference(name: &'static str, urdf: &str, floating: bool, kind: &str) -> Robot {
        let mut args = vec![repo(urdf)];
        if floating {
            args.push("--floating".into());
        }
        let text =
            std::fs::read_to_string(repo(&format!("tests/data/pinocchio/{name}_{kind}.json")))
                .unwrap();
        let json: Value = serde_json::from_str(&text).unwrap();
        let mut info_args = vec!["info"];
        info_args.extend(args.iter().map(String::as_str));
        let info = json_of(&info_args, "");
        let (mut q_map, mut v_map) = (Vec::new(), Vec::new());
        for j in info["joints"].as_array().unwrap() {
            let theirs = json["joints"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"] == j["name"])
                .unwrap_or_else(|| panic!("{name}: joint {} not in the reference", j["name"]));
            let index = |v: &Value| v.as_u64().unwrap() as usize;
            for k in 0..index(&j["nq"]) {
                assert_eq!(q_map.len(), index(&j["q_index"]) + k);
                q_map.push(index(&theirs["idx_q"]) + k);
            }
            for k in 0..index(&j["nv"]) {
                assert_eq!(v_map.len(), index(&j["v_index"]) + k);
                v_map.push(index(&theirs["idx_v"]) + k);
            }
        }
        Robot {
            name,
            args,
            json,
            q_map,
            v_map,
        }
    }

    pub fn samples(&self) -> &[Value] {
        self.json["samples"].as_array().unwrap()
    }

    pub fn q(&self, s: &Value) -> Vec<f64> {
        let x = vecf(&s["q"]);
        self.q_map.iter().map(|&i| x[i]).collect()
    }

    pub fn v(&self, x: &Value) -> Vec<f64> {
        let x = vecf(x);
        self.v_map.iter().map(|&i| x[i]).collect()
    }

    /// A Pinocchio matrix with nv columns, in our column order, row-major.
    fn columns(&self, m: &Value) -> Vec<f64> {
        rows(m)
            .iter()
            .flat_map(|r| self.v_map.iter().map(move |&i| r[i]))
            .collect()
    }

    /// A Pinocchio nv × nv matrix in our row and column order, row-major.
    pub fn square(&self, m: &Value) -> Vec<f64> {
        let rows = rows(m);
        self.v_map
            .iter()
            .flat_map(|&r| self.v_map.iter().map(move |&c| (r, c)))
            .map(|(r, c)| rows[r][c])
            .collect()
    }

    /// `embedyn eval` on this robot with `extra` arguments.
    pub fn eval(&self, extra: &[&str], samples: Vec<Value>) -> Vec<Value> {
        let mut args = vec!["eval"];
        args.extend(self.args.iter().map(String::as_str));
        args.extend(extra);
        let out = json_of(&args, &json!({ "samples": samples }).to_string());
        out["samples"].as_array().unwrap().clone()
    }
}

fn robots() -> [Robot; 2] {
    [
        Robot::load("ur5", "tests/data/pinocchio/ur5.urdf", false),
        Robot::load(
            "anymal_b_floating",
            "tests/data/pinocchio/anymal_b.urdf",
            true,
        ),
    ]
}

/// Rows of a JSON matrix, flattened.
pub fn flat_rows(v: &Value) -> Vec<f64> {
    rows(v).concat()
}

/// `aba`, `rnea` and `nle` with wrenches on feet, tool flanges (merged links), bodies and a link fixed to
/// the world (UR5's `base_link`: no effect), in the samples as Pinocchio's reference gives them.
#[test]
fn external_wrenches_match_pinocchio() {
    for r in robots() {
        let mut worst = [0.0f64; 3];
        let state =
            |s: &Value| json!({"q": r.q(s), "v": r.v(&s["v"]), "f_ext": s["f_ext"].clone()});
        let with = |s: &Value, key: &str, value: Vec<f64>| {
            let mut x = state(s);
            x[key] = json!(value);
            x
        };
        let samples = r.samples();
        assert!(samples
            .iter()
            .all(|s| !s["f_ext"].as_object().unwrap().is_empty()));
        let aba = r.eval(
            &["--algo", "aba"],
            samples
                .iter()
                .map(|s| with(s, "tau", r.v(&s["tau"])))
                .collect(),
        );
        let rnea = r.eval(
            &["--algo", "rnea"],
            samples
                .iter()
                .map(|s| with(s, "qdd", r.v(&s["qdd_for_rnea"])))
                .collect(),
        );
        let nle = r.eval(&["--algo", "nle"], samples.iter().map(state).collect());
        for (k, s) in samples.iter().enumerate() {
            worst[0] = worst[0].max(relative_error(&vecf(&aba[k]["qdd"]), &r.v(&s["qdd_ext"])));
            worst[1] = worst[1].max(relative_error(
                &vecf(&rnea[k]["tau"]),
                &r.v(&s["tau_rnea_ext"]),
            ));
            worst[2] = worst[2].max(relative_error(&vecf(&nle[k]["tau"]), &r.v(&s["nle_ext"])));
            // Without the wrenches the answer differs (they do act).
            assert_ne!(aba[k]["qdd"], json!(r.v(&s["qdd"])));
        }
        println!(
            "{}: aba f_ext {:.1e}, rnea f_ext {:.1e}, nle f_ext {:.1e}",
            r.name, worst[0], worst[1], worst[2]
        );
        assert!(worst.iter().all(|&e| e < TOL), "{}: {worst:?}", r.name);
    }
}

/// A wrench on a link fixed to the world changes nothing; the same wrench on a merged link (UR5's `tool0`,
/// fixed to `wrist_3_link`) equals the wrench moved to the body's link.
#[test]
fn wrenches_on_world_fixed_and_merged_links() {
    let model = repo("tests/data/pinocchio/ur5.urdf");
    let q = [0.3, -0.7, 1.1, 0.2, -0.4, 0.9];
    let zero = vec![0.0; 6];
    let tau = |f_ext: Value| -> Vec<f64> {
        let input = json!({"samples": [{"q": q, "v": zero, "qdd": zero, "f_ext": f_ext}]});
        vecf(&json_of(&["eval", &model, "--algo", "rnea"], &input.to_string())["samples"][0]["tau"])
    };
    let plain = tau(json!({}));
    let world = tau(json!({"base_link": {"force": [10.0, 20.0, 30.0], "torque": [1.0, 2.0, 3.0]}}));
    assert_eq!(plain, world);
    let pushed = tau(json!({"tool0": {"force": [0.0, 0.0, 5.0], "torque": [0.0, 0.0, 0.0]}}));
    assert!(
        relative_error(&pushed, &plain) > 1e-3,
        "{pushed:?} {plain:?}"
    );
}

/// The Jacobians and biases (classical accelerations at qdd = 0) of feet, flanges and bodies in the three
/// references; without `v`, no bias.
#[test]
fn jacobians_match_pinocchio() {
    for r in robots() {
        let links: Vec<String> = r.json["frame_links"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l.as_str().unwrap().to_string())
            .collect();
        let mut worst = [0.0f64; 2];
        let samples = r.samples();
        for link in &links {
            for reference in ["local", "local_world_aligned", "world"] {
                let mut input: Vec<Value> = samples
                    .iter()
                    .map(|s| json!({"q": r.q(s), "v": r.v(&s["v"])}))
                    .collect();
                input.push(json!({"q": r.q(&samples[0])}));
                let out = r.eval(
                    &[
                        "--algo",
                        "jacobian",
                        "--frame",
                        link,
                        "--reference",
                        reference,
                    ],
                    input,
                );
                for (k, s) in samples.iter().enumerate() {
                    let want = &s["frames"][link][reference];
                    let o = &out[k];
                    let j = [flat_rows(&o["J_linear"]), flat_rows(&o["J_angular"])].concat();
                    let e = relative_error(&j, &r.columns(&want["J"]));
                    worst[0] = worst[0].max(e);
                    let bias = [vecf(&o["bias_linear"]), vecf(&o["bias_angular"])].concat();
                    let e = relative_error(&bias, &vecf(&want["classical_acceleration"]));
                    worst[1] = worst[1].max(e);
                    assert!(o.get("J_linear_independent").is_none());
                }
                let last = &out[samples.len()];
                assert!(last.get("bias_linear").is_none() && last.get("bias_angular").is_none());
                assert_eq!(last["J_linear"], out[0]["J_linear"]);
            }
        }
        // The default reference is local_world_aligned.
        let s = &samples[0];
        let default = r.eval(
            &["--algo", "jacobian", "--frame", &links[0]],
            vec![json!({"q": r.q(s), "v": r.v(&s["v"])})],
        );
        let aligned = r.eval(
            &[
                "--algo",
                "jacobian",
                "--frame",
                &links[0],
                "--reference",
                "local_world_aligned",
            ],
            vec![json!({"q": r.q(s), "v": r.v(&s["v"])})],
        );
        assert_eq!(default, aligned);
        println!(
            "{}: J {:.1e}, bias {:.1e} ({} frames × 3 references)",
            r.name,
            worst[0],
            worst[1],
            links.len()
        );
        assert!(worst.iter().all(|&e| e < TOL), "{}: {worst:?}", r.name);
    }
}

/// com, vcom, J_com; A_g and h_g.
#[test]
fn com_and_centroidal_match_pinocchio() {
    for r in robots() {
        let samples = r.samples();
        let states: Vec<Value> = samples
            .iter()
            .map(|s| json!({"q": r.q(s), "v": r.v(&s["v"])}))
            .collect();
        let com = r.eval(&["--algo", "com"], states.clone());
        let centroidal = r.eval(&["--algo", "centroidal"], states);
        let mut worst = [0.0f64; 5];
        for (k, s) in samples.iter().enumerate() {
            let c = &com[k];
            worst[0] = worst[0].max(relative_error(&vecf(&c["com"]), &vecf(&s["com"])));
            worst[1] = worst[1].max(relative_error(&vecf(&c["vcom"]), &vecf(&s["vcom"])));
            worst[2] = worst[2].max(relative_error(
                &flat_rows(&c["J_com"]),
                &r.columns(&s["J_com"]),
            ));
            let g = &centroidal[k];
            worst[3] = worst[3].max(relative_error(&flat_rows(&g["A_g"]), &r.columns(&s["A_g"])));
            worst[4] = worst[4].max(relative_error(&vecf(&g["h_g"]), &vecf(&s["h_g"])));
            assert!(g.get("dh_g").is_none(), "centroidal reports A_g and h_g");
            assert!(g.get("A_g_independent").is_none() && c.get("J_com_independent").is_none());
        }
        // Without v: no vcom.
        let at_rest = r.eval(&["--algo", "com"], vec![json!({"q": r.q(&samples[0])})]);
        assert!(at_rest[0].get("vcom").is_none());
        assert_eq!(at_rest[0]["com"], com[0]["com"]);
        println!(
            "{}: com {:.1e}, vcom {:.1e}, J_com {:.1e}, A_g {:.1e}, h_g {:.1e}",
            r.name, worst[0], worst[1], worst[2], worst[3], worst[4]
        );
        assert!(worst.iter().all(|&e| e < TOL), "{}: {worst:?}", r.name);
    }
}

/// f32 evaluates the new algorithms and the wrenches too, close to f64.
#[test]
fn new_algorithms_in_f32_are_close_to_f64() {
    let r = Robot::load(
        "anymal_b_floating",
        "tests/data/pinocchio/anymal_b.urdf",
        true,
    );
    let s = &r.samples()[0];
    let state = json!({"q": r.q(s), "v": r.v(&s["v"]), "tau": r.v(&s["tau"]), "f_ext": s["f_ext"]});
    for (algo, fields) in [
        (&["--algo", "aba"][..], &["qdd"][..]),
        (
            &["--algo", "jacobian", "--frame", "LF_FOOT"],
            &["J_linear", "J_angular", "bias_linear", "bias_angular"],
        ),
        (&["--algo", "com"], &["com", "J_com", "vcom"]),
        (&["--algo", "centroidal"], &["A_g", "h_g"]),
    ] {
        let f64_out = &r.eval(algo, vec![state.clone()])[0];
        let f32_out = &r.eval(&[algo, &["--scalar", "f32"]].concat(), vec![state.clone()])[0];
        for field in fields {
            let flat = |v: &Value| match v[field][0].is_array() {
                true => flat_rows(&v[field]),
                false => vecf(&v[field]),
            };
            let e = relative_error(&flat(f32_out), &flat(f64_out));
            assert!(e < 1e-4, "{algo:?} {field}: {e:e}");
        }
    }
}

/// Runs `embedyn args` expecting failure with exit status `code`: the message on stderr, no panic, nothing
/// on stdout.
pub fn refused(args: &[&str], stdin: &str, code: i32) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_embedyn"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .and_then(|mut child| {
            use std::io::Write;
            // A usage error ends before the input is read: the pipe may be closed.
            let _ = child.stdin.take().unwrap().write_all(stdin.as_bytes());
            child.wait_with_output()
        })
        .unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}: stdout on error");
    assert!(
        err.contains("error: ") && !err.contains("panicked") && !err.contains("internal error"),
        "{err}"
    );
    err
}

#[test]
fn frame_options_are_checked() {
    let model = repo("tests/data/pinocchio/ur5.urdf");
    let input = json!({"samples": [{"q": vec![0.0; 6]}]}).to_string();
    let e = refused(
        &["eval", &model, "--algo", "jacobian", "--frame", "tool"],
        &input,
        2,
    );
    assert!(
        e.contains("--frame")
            && e.contains("no link `tool`")
            && e.contains("did you mean `tool0`?"),
        "{e}"
    );
    let e = refused(&["eval", &model, "--algo", "jacobian"], &input, 2);
    assert!(e.contains("--frame LINK"), "{e}");
    for algo in ["aba", "com", "centroidal", "crba"] {
        let e = refused(
            &["eval", &model, "--algo", algo, "--frame", "tool0"],
            &input,
            2,
        );
        assert!(e.contains("only `--algo jacobian` takes a frame"), "{e}");
    }
    let e = refused(
        &["eval", &model, "--algo", "com", "--reference", "world"],
        &input,
        2,
    );
    assert!(e.contains("--reference"), "{e}");
    let e = refused(
        &[
            "eval",
            &model,
            "--algo",
            "jacobian",
            "--frame",
            "tool0",
            "--reference",
            "global",
        ],
        &input,
        2,
    );
    assert!(e.contains("local, local_world_aligned or world"), "{e}");
    // A link fixed to the world is a frame: its Jacobian is zero.
    let out = json_of(
        &["eval", &model, "--algo", "jacobian", "--frame", "base_link"],
        &json!({"samples": [{"q": vec![0.3; 6], "v": vec![1.0; 6]}]}).to_string(),
    );
    let s = &out["samples"][0];
    assert!(flat_rows(&s["J_linear"]).iter().all(|&x| x == 0.0), "{s}");
    assert_eq!(s["bias_linear"], json!([0.0, 0.0, 0.0]));
    // centroidal needs v; jacobian's and com's v has the model's length when given.
    let e = refused(&["eval", &model, "--algo", "centroidal"], &input, 1);
    assert!(e.contains("sample 0: missing field `v`"), "{e}");
    let e = refused(
        &["eval", &model, "--algo", "com"],
        &json!({"samples": [{"q": vec![0.0; 6], "v": vec![0.0; 5]}]}).to_string(),
        1,
    );
    assert!(
        e.contains("sample 0: field `v` has 5 entries, the model needs 6"),
        "{e}"
    );
}

#[test]
fn bad_external_wrenches_name_the_sample_the_link_and_the_field() {
    let model = repo("tests/data/pinocchio/ur5.urdf");
    let ok = json!({"force": [0.0, 0.0, 1.0], "torque": [0.0, 0.0, 0.0]});
    let cases: Vec<(Value, &str)> = vec![
        (
            json!({"tool": ok}),
            "sample 1: field `f_ext`: the model has no link `tool`; did you mean `tool0`?",
        ),
        (
            json!({"gripper": ok}),
            "the model has no link `gripper` (`embedyn info` lists the links under `frames`)",
        ),
        (
            json!({"tool0": {"force": [0.0, 1.0], "torque": [0.0, 0.0, 0.0]}}),
            "sample 1: field `f_ext`: link `tool0`: `force` has 2 entries, it needs 3",
        ),
        (
            json!({"tool0": {"force": [0.0, 1.0, 2.0, 3.0], "torque": [0.0, 0.0, 0.0]}}),
            "`force` has 4 entries, it needs 3",
        ),
        (
            json!({"tool0": {"force": [0.0, 1.0, 2.0], "torque": [0.0, null, 0.0]}}),
            "link `tool0`: `torque`[1] is not a finite number: null",
        ),
        (
            json!({"tool0": {"force": [0.0, 1.0, 2.0]}}),
            "link `tool0`: missing `torque`",
        ),
        (
            json!({"tool0": {"force": "up", "torque": [0.0, 0.0, 0.0]}}),
            "link `tool0`: `force` must be an array of 3 numbers",
        ),
        (
            json!({"tool0": [1.0, 2.0]}),
            "link `tool0`: the wrench must be an object",
        ),
        (json!([ok]), "sample 1: field `f_ext` must be an object"),
    ];
    let state =
        json!({"q": vec![0.1; 6], "v": vec![0.0; 6], "tau": vec![0.0; 6], "qdd": vec![0.0; 6]});
    for (f_ext, message) in cases {
        let mut bad = state.clone();
        bad["f_ext"] = f_ext;
        let input = json!({"samples": [state, bad]}).to_string();
        for algo in ["aba", "rnea", "nle"] {
            let e = refused(&["eval", &model, "--algo", algo], &input, 1);
            assert!(e.contains(message), "{algo}: {e}");
        }
    }
    // A link given twice in one object is refused (text: serde_json would keep the last).
    let twice = r#"{"samples": [{"q": [0,0,0,0,0,0], "v": [0,0,0,0,0,0], "tau": [0,0,0,0,0,0],
        "f_ext": {"tool0": {"force": [1,0,0], "torque": [0,0,0]}, "tool0": {"force": [1,0,0], "torque": [0,0,0]}}}]}"#;
    let e = refused(&["eval", &model, "--algo", "aba"], twice, 1);
    assert!(
        e.contains("sample 0: field `f_ext`: link `tool0` is given twice"),
        "{e}"
    );
    // Finite in f64, not in f32.
    let mut big = state.clone();
    big["f_ext"] = json!({"tool0": {"force": [0.0, 1e39, 0.0], "torque": [0.0, 0.0, 0.0]}});
    let input = json!({"samples": [big]}).to_string();
    let e = refused(
        &["eval", &model, "--algo", "aba", "--scalar", "f32"],
        &input,
        1,
    );
    assert!(
        e.contains("link `tool0`: `force`[1] is not a finite number"),
        "{e}"
    );
    json_of(&["eval", &model, "--algo", "aba"], &input);
    // Algorithms without wrenches ignore the field, as any field they do not use.
    json_of(&["eval", &model, "--algo", "gravity"], &input);
}

/// Every number of an answer, fields in name order (rows after rows).
fn numbers(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(numbers).collect(),
        Value::Object(o) => {
            let mut keys: Vec<&String> = o.keys().collect();
            keys.sort();
            keys.into_iter().flat_map(|k| numbers(&o[k])).collect()
        }
        x => vec![x.as_f64().unwrap()],
    }
}

/// The generated answer agrees with the interpreted one: the same fields in every sample, to `tol`
/// (CONTRACT §2's relative error, per sample).
fn agrees(what: &str, generated: &Value, interpreted: &Value, tol: f64) -> f64 {
    let (g, i) = (
        generated["samples"].as_array().unwrap(),
        interpreted["samples"].as_array().unwrap(),
    );
    assert_eq!(g.len(), i.len(), "{what}");
    let mut worst = 0.0f64;
    for (k, (g, i)) in g.iter().zip(i).enumerate() {
        let keys = |v: &Value| {
            let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
            k.sort();
            k
        };
        assert_eq!(keys(g), keys(i), "{what}, sample {k}");
        let e = relative_error(&numbers(g), &numbers(i));
        assert!(
            e <= tol,
            "{what}, sample {k}: generated vs interpreted {e:e}"
        );
        worst = worst.max(e);
    }
    worst
}

/// A random state of floating ANYmal B (nq 19, nv 18), reproducible.
fn anymal_state(seed: u64) -> Value {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut q: Vec<f64> = (0..19).map(|_| next()).collect();
    let n = q[3..7].iter().map(|a| a * a).sum::<f64>().sqrt();
    for a in &mut q[3..7] {
        *a /= n;
    }
    let v: Vec<f64> = (0..18).map(|_| 2.0 * next()).collect();
    let tau: Vec<f64> = (0..18).map(|_| 10.0 * next()).collect();
    let qdd: Vec<f64> = (0..18).map(|_| 3.0 * next()).collect();
    json!({"q": q, "v": v, "tau": tau, "qdd": qdd})
}

/// `--engine generated` on floating ANYmal B agrees with the interpreted engine, in f64 to 1e-12 and
/// in f32 to 1e-4: `aba`, `rnea` and `nle` with wrenches (`aba_ext`, `rnea_ext`, `nle_ext` over the
/// links the samples name: a sample with wrenches on two feet, one with a single foot and the base, one
/// without `f_ext`), `jacobian` of a foot with and without `v`, `com` and `centroidal`. One runner
/// compile: the queries run together (`eval_generated_together`, the union of their functions), each
/// answer what `eval` prints for it alone.
#[test]
fn generated_engine_agrees_on_wrenches_frames_and_centroidal() {
    let path = repo("tests/data/pinocchio/anymal_b.urdf");
    let mut states: Vec<Value> = (0..3).map(anymal_state).collect();
    states[0]["f_ext"] = json!({
        "LF_FOOT": {"force": [1.0, 2.0, 30.0], "torque": [0.1, 0.2, 0.3]},
        "RH_FOOT": {"force": [-3.0, 2.0, 25.0], "torque": [0.0, 0.0, 0.5]}});
    states[1]["f_ext"] = json!({
        "RH_FOOT": {"force": [4.0, -1.0, 20.0], "torque": [0.2, 0.0, 0.0]},
        "base": {"force": [1.0, 1.0, 1.0], "torque": [1.0, -1.0, 1.0]}});
    let with_wrenches = json!({ "samples": states }).to_string();
    let without_v: Vec<Value> = states.iter().map(|s| json!({"q": s["q"]})).collect();
    let without_v = json!({ "samples": without_v }).to_string();
    use embedyn_cli::{EvalAlgo, Scalar};
    let dynamics = |name| EvalAlgo::from_name(name).unwrap();
    let mut queries: Vec<(EvalAlgo, Option<&str>, &str)> = Vec::new();
    for algo in ["aba", "rnea", "nle"] {
        queries.push((dynamics(algo), None, &with_wrenches));
    }
    queries.push((EvalAlgo::Jacobian, Some("LF_FOOT"), &with_wrenches));
    queries.push((EvalAlgo::Jacobian, Some("LF_FOOT"), &without_v));
    queries.push((EvalAlgo::Com, None, &with_wrenches));
    queries.push((EvalAlgo::Com, None, &without_v));
    queries.push((EvalAlgo::Centroidal, None, &with_wrenches));
    let mut together = Vec::new();
    for scalar in [Scalar::F64, Scalar::F32] {
        for &(algo, frame, input) in &queries {
            together.push((algo, frame, None, scalar, input));
        }
    }
    let loaded = embedyn_codegen::load(std::path::Path::new(&path)).unwrap();
    let options = embedyn_codegen::ModelOptions {
        floating: true,
        ..Default::default()
    };
    let cache = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("embedyn-cache");
    let started = std::time::Instant::now();
    let generated =
        embedyn_cli::eval_generated_together(&loaded, &options, &together, Some(&cache)).unwrap();
    eprintln!(
        "floating ANYmal B, {} queries through one runner: {:.1} s (compile included unless cached)",
        together.len(),
        started.elapsed().as_secs_f64()
    );
    let mut worst = [0.0f64; 2];
    for ((algo, frame, _, scalar, input), generated) in together.iter().zip(&generated) {
        let mut args = vec!["eval", &path, "--floating", "--algo", algo.name()];
        if let Some(frame) = frame {
            args.extend(["--frame", frame]);
        }
        let interpreted = json_of(&args, input);
        let (tol, k) = match scalar {
            Scalar::F64 => (1e-12, 0),
            Scalar::F32 => (1e-4, 1),
        };
        let what = format!("{} {frame:?} {scalar:?}", algo.name());
        worst[k] = worst[k].max(agrees(&what, generated, &interpreted, tol));
    }
    eprintln!(
        "worst relative error: f64 {:e}, f32 {:e}",
        worst[0], worst[1]
    );
    // The wrenches act: without them the answers differ.
    let plain = json_of(
        &["eval", &path, "--floating", "--algo", "aba"],
        &json!({"samples": [{"q": states[0]["q"], "v": states[0]["v"], "tau": states[0]["tau"]}]})
            .to_string(),
    );
    let e = relative_error(
        &vecf(&generated[0]["samples"][0]["qdd"]),
        &vecf(&plain["samples"][0]["qdd"]),
    );
    assert!(e > 1e-3, "the wrenches change nothing? {e:e}");
}

/// `--engine generated` on the four-bar linkage (a loop), through the command line: `jacobian` in two
/// references, each compiled from its own source (the reference is part of the generated code, hence of
/// the runner's cache key: the second eval does not reuse the first's runner), both agreeing with the
/// interpreted engine to 1e-12, `J_linear_independent` and `J_angular_independent` included; the two
/// references give different Jacobians.
#[test]
fn generated_jacobians_of_a_loop_model_in_two_references() {
    let path = repo("models/loops/four_bar_internal.urdf");
    let done = json_of(
        &["complete", &path],
        &json!({"samples": [{"q": [0.4, 0.0, 0.2, 0.0], "v": [1.3, 0.0, -0.5, 0.0]},
            {"q": [-0.3, 0.0, -0.6, 0.0], "v": [-0.7, 0.0, 0.9, 0.0]}]})
        .to_string(),
    );
    let mut states: Vec<Value> = done["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| json!({"q": s["q"], "v": s["v"]}))
        .collect();
    states.push(json!({"q": states[0]["q"]}));
    let input = json!({ "samples": states }).to_string();
    let mut answers = Vec::new();
    for reference in ["local", "world"] {
        let args = [
            "eval",
            &path,
            "--algo",
            "jacobian",
            "--frame",
            "tip",
            "--reference",
            reference,
        ];
        let interpreted = json_of(&args, &input);
        let mut generated_args = args.to_vec();
        generated_args.extend(["--engine", "generated"]);
        let started = std::time::Instant::now();
        let (ok, out, err) = crate::cli::embedyn_cached(&generated_args, &input);
        assert!(ok, "{reference}: {err}");
        eprintln!(
            "four-bar jacobian {reference}: {:.1} s{}",
            started.elapsed().as_secs_f64(),
            if err.contains("compiling") {
                " (compiled)"
            } else {
                ""
            }
        );
        let generated: Value = serde_json::from_str(&out).unwrap();
        assert!(generated["samples"][0]["J_linear_independent"].is_array());
        assert!(generated["samples"][0]["bias_linear"].is_array());
        assert!(generated["samples"][2]["bias_linear"].is_null());
        agrees(reference, &generated, &interpreted, 1e-12);
        answers.push(generated);
    }
    let e = relative_error(
        &numbers(&answers[0]["samples"][0]["J_linear"]),
        &numbers(&answers[1]["samples"][0]["J_linear"]),
    );
    assert!(e > 1e-3, "local and world Jacobians agree? {e:e}");
}

/// A loop model: `J_linear_independent`, `J_angular_independent` are J · X, with X the model's embedding
/// map; so J_independent · v_independent = J · v on a consistent state from `embedyn complete`; com's
/// `J_com_independent` and centroidal's `A_g_independent` likewise.
#[test]
fn loop_model_independent_jacobians_are_j_times_x() {
    let path = repo("models/loops/four_bar_internal.urdf");
    let info = json_of(&["info", &path], "");
    let independent: Vec<usize> = info["joints"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|j| j["independent"] == json!(true))
        .map(|j| j["v_index"].as_u64().unwrap() as usize)
        .collect();
    assert_eq!(independent.len(), 2);
    let done = json_of(
        &["complete", &path],
        &json!({"samples": [{"q": [0.4, 0.0, 0.2, 0.0], "v": [1.3, 0.0, -0.5, 0.0]},
            {"q": [-0.3, 0.0, -0.6, 0.0], "v": [-0.7, 0.0, 0.9, 0.0]}]})
        .to_string(),
    );
    let states: Vec<Value> = done["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| json!({"q": s["q"], "v": s["v"]}))
        .collect();
    // X from the library, on the same model.
    let loaded = embedyn_codegen::load(std::path::Path::new(&path)).unwrap();
    let model = loaded
        .model::<f64>(&embedyn_codegen::ModelOptions::default())
        .unwrap();
    let mut ws = embedyn_runtime::Workspace::new(&model);
    let product = |m: &[Vec<f64>], x: &embedyn_runtime::nalgebra::DMatrix<f64>| -> Vec<f64> {
        m.iter()
            .flat_map(|row| {
                (0..x.ncols()).map(move |k| (0..row.len()).map(|c| row[c] * x[(c, k)]).sum())
            })
            .collect()
    };
    let times = |m: &[Vec<f64>], v: &[f64]| -> Vec<f64> {
        m.iter()
            .map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum())
            .collect()
    };
    let mut worst = [0.0f64; 2];
    for link in ["crank", "coupler", "tip", "rocker", "base"] {
        for reference in ["local", "local_world_aligned", "world"] {
            let out = json_of(
                &[
                    "eval",
                    &path,
                    "--algo",
                    "jacobian",
                    "--frame",
                    link,
                    "--reference",
                    reference,
                ],
                &json!({ "samples": states }).to_string(),
            );
            for (s, o) in states.iter().zip(out["samples"].as_array().unwrap()) {
                let (q, v) = (vecf(&s["q"]), vecf(&s["v"]));
                let v_ind: Vec<f64> = independent.iter().map(|&k| v[k]).collect();
                let x = embedyn_runtime::embedding_map(&model, &mut ws, &q).unwrap();
                for part in ["linear", "angular"] {
                    let j = rows(&o[format!("J_{part}").as_str()]);
                    let j_ind = rows(&o[format!("J_{part}_independent").as_str()]);
                    assert_eq!((j_ind.len(), j_ind[0].len()), (3, 2), "{o}");
                    worst[0] = worst[0].max(relative_error(&j_ind.concat(), &product(&j, &x)));
                    worst[1] = worst[1].max(relative_error(&times(&j_ind, &v_ind), &times(&j, &v)));
                }
            }
        }
    }
    let input = json!({ "samples": states }).to_string();
    let com = json_of(&["eval", &path, "--algo", "com"], &input);
    let centroidal = json_of(&["eval", &path, "--algo", "centroidal"], &input);
    for (k, s) in states.iter().enumerate() {
        let x = embedyn_runtime::embedding_map(&model, &mut ws, &vecf(&s["q"])).unwrap();
        let c = &com["samples"][k];
        let e = relative_error(
            &flat_rows(&c["J_com_independent"]),
            &product(&rows(&c["J_com"]), &x),
        );
        worst[0] = worst[0].max(e);
        let v_ind: Vec<f64> = independent.iter().map(|&i| vecf(&s["v"])[i]).collect();
        let vcom = times(&rows(&c["J_com_independent"]), &v_ind);
        worst[1] = worst[1].max(relative_error(&vcom, &vecf(&c["vcom"])));
        let g = &centroidal["samples"][k];
        let a_ind = rows(&g["A_g_independent"]);
        assert_eq!((a_ind.len(), a_ind[0].len()), (6, 2));
        worst[0] = worst[0].max(relative_error(
            &a_ind.concat(),
            &product(&rows(&g["A_g"]), &x),
        ));
        worst[1] = worst[1].max(relative_error(&times(&a_ind, &v_ind), &vecf(&g["h_g"])));
    }
    println!(
        "four_bar_internal: J_independent vs J X {:.1e}, J_independent v_independent vs J v {:.1e}",
        worst[0], worst[1]
    );
    assert!(worst.iter().all(|&e| e < 1e-12), "{worst:?}");
    // An inconsistent v is refused, as for every algorithm that reads one.
    let mut bad = states[0].clone();
    bad["v"][1] = json!(5.0);
    let e = refused(
        &["eval", &path, "--algo", "jacobian", "--frame", "tip"],
        &json!({"samples": [bad]}).to_string(),
        1,
    );
    assert!(e.contains("violates the velocity constraints"), "{e}");
}
