//! `embedyn eval --algo integrate|difference` (docs/command-line.md): `{"q", "v"}` → `{"q"}` and
//! `{"q", "q1"}` → `{"v"}`, interpreted and generated (two compiles: generated `integrate` in f64 and
//! `difference` in f32), on a floating arm.

use crate::cli::{embedyn, embedyn_cached, json_of, repo};
use serde_json::{json, Value};

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn integrate_and_difference_on_the_command_line() {
    let model = repo("models/arm7.urdf");
    let args = |algo: &'static str| -> Vec<String> {
        ["eval", &model, "--floating", "--algo", algo]
            .iter()
            .map(|s| s.to_string())
            .collect()
    };
    let run = |args: Vec<String>, extra: &[&str], input: &str| -> Value {
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        all.extend_from_slice(extra);
        if extra.contains(&"generated") {
            let (ok, out, err) = embedyn_cached(&all, input);
            assert!(ok, "{all:?}: {err}");
            serde_json::from_str(&out).unwrap()
        } else {
            json_of(&all, input)
        }
    };
    // A floating arm (nq 14, nv 13): a rotation of the base by 3 rad, beyond π/2 and below π.
    let (nq, nv) = (14, 13);
    let s = (0.5f64).sqrt();
    let mut q = vec![0.3, -0.2, 0.1, 0.0, 0.0, s, s];
    q.extend((0..7).map(|i| 0.1 * i as f64 - 0.3));
    let mut v: Vec<f64> = (0..nv).map(|i| 0.05 * i as f64 - 0.2).collect();
    v[3..6].copy_from_slice(&[0.0, 1.8, 2.4]);
    let input = json!({"samples": [{"q": q, "v": v}]}).to_string();
    let integrated = run(args("integrate"), &[], &input);
    let q1 = numbers(&integrated["samples"][0]["q"]);
    assert_eq!(q1.len(), nq);
    // Joint coordinates add.
    assert!((q1[7] - (q[7] + v[6])).abs() < 1e-15);
    let input = json!({"samples": [{"q": q, "q1": q1}]}).to_string();
    let back = run(args("difference"), &[], &input);
    let w = numbers(&back["samples"][0]["v"]);
    assert_eq!(w.len(), nv);
    let e = w
        .iter()
        .zip(&v)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(e < 1e-12, "difference(q, integrate(q, v)) = v to {e:e}");

    // The generated engine agrees.
    let input_i = json!({"samples": [{"q": q, "v": v}]}).to_string();
    let generated = run(args("integrate"), &["--engine", "generated"], &input_i);
    let g = numbers(&generated["samples"][0]["q"]);
    let e = g
        .iter()
        .zip(&q1)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(e < 1e-13, "generated integrate: {e:e}");
    let generated = run(
        args("difference"),
        &["--engine", "generated", "--scalar", "f32"],
        &input,
    );
    let g = numbers(&generated["samples"][0]["v"]);
    let e = g
        .iter()
        .zip(&v)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(e < 1e-5, "generated f32 difference: {e:e}");

    // A quaternion that is not of unit norm in `q1` is refused, naming it.
    let mut bad = q1.clone();
    bad[6] *= 2.0;
    let input = json!({"samples": [{"q": q, "q1": bad}]}).to_string();
    let (ok, _, err) = embedyn(
        &["eval", &model, "--floating", "--algo", "difference"],
        &input,
    );
    assert!(!ok && err.contains("unit quaternion"), "{err}");
}
