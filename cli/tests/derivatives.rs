//! `eval --algo aba_derivatives` and `rnea_derivatives` (CONTRACT §3) through the command line: against
//! Pinocchio 4.1's analytical derivatives (tests/data/pinocchio/derivatives.py: a fixed UR5 and a floating
//! ANYmal B, with the contact references' external wrenches) to 1e-9 relative; the manifold fields of a
//! loop model; the generated engine against the interpreted one, and its refusals.

use crate::cli::{embedyn_cached, flat, json_of, repo};
use crate::contact::{flat_rows, refused, relative_error, vecf, Robot};
use serde_json::{json, Value};

const TOL: f64 = 1e-9;

fn robots() -> [Robot; 2] {
    [
        Robot::with_reference("ur5", "tests/data/pinocchio/ur5.urdf", false, "derivatives"),
        Robot::with_reference(
            "anymal_b_floating",
            "tests/data/pinocchio/anymal_b.urdf",
            true,
            "derivatives",
        ),
    ]
}

#[test]
fn derivatives_match_pinocchio() {
    for r in robots() {
        let samples = r.samples();
        let state = |s: &Value, key: &str, field: &str| json!({"q": r.q(s), "v": r.v(&s["v"]), key: r.v(&s[field]), "f_ext": s["f_ext"].clone()});
        let aba = r.eval(
            &["--algo", "aba_derivatives"],
            samples.iter().map(|s| state(s, "tau", "tau")).collect(),
        );
        let rnea = r.eval(
            &["--algo", "rnea_derivatives"],
            samples
                .iter()
                .map(|s| state(s, "qdd", "qdd_for_rnea"))
                .collect(),
        );
        let mut worst = 0.0f64;
        for (k, s) in samples.iter().enumerate() {
            worst = worst.max(relative_error(&vecf(&aba[k]["qdd"]), &r.v(&s["qdd"])));
            worst = worst.max(relative_error(&vecf(&rnea[k]["tau"]), &r.v(&s["tau_rnea"])));
            for field in ["dqdd_dq", "dqdd_dv", "dqdd_dtau"] {
                worst = worst.max(relative_error(
                    &flat_rows(&aba[k][field]),
                    &r.square(&s[field]),
                ));
            }
            for field in ["dtau_dq", "dtau_dv", "dtau_dqdd"] {
                worst = worst.max(relative_error(
                    &flat_rows(&rnea[k][field]),
                    &r.square(&s[field]),
                ));
            }
            // A tree has no manifold fields.
            assert!(aba[k].get("dqdd_independent_dq_independent").is_none());
        }
        println!("{}: derivatives {worst:.1e}", r.name);
        assert!(worst < TOL, "{}: {worst:e}", r.name);
    }
}

/// A four-bar: the spanning-tree matrices (nv × nv), the manifold ones (ni × ni, ni × nv), and
/// `∂q̈_I/∂τ` equal to the independent rows of `∂q̈/∂τ` (the same derivative).
#[test]
fn loop_models_report_manifold_derivatives() {
    let model = repo("models/loops/four_bar_internal.urdf");
    let info = json_of(&["info", &model], "");
    let nv = info["nv"].as_u64().unwrap() as usize;
    let ni = info["independent_nv"].as_u64().unwrap() as usize;
    let independent: Vec<usize> = info["joints"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|j| j["independent"] == json!(true))
        .map(|j| j["v_index"].as_u64().unwrap() as usize)
        .collect();
    // A consistent state from `complete`.
    let guess = json!({"samples": [{"q": vec![0.2; nv], "v": vec![0.3; nv]}]});
    let state = json_of(&["complete", &model], &guess.to_string())["samples"][0].clone();
    let input = json!({"samples": [{"q": state["q"], "v": state["v"], "tau": vec![0.5; nv]}]});
    let out = &json_of(
        &["eval", &model, "--algo", "aba_derivatives"],
        &input.to_string(),
    )["samples"][0];
    let shape = |v: &Value| (v.as_array().unwrap().len(), v[0].as_array().unwrap().len());
    assert_eq!(shape(&out["dqdd_dq"]), (nv, nv));
    assert_eq!(shape(&out["dqdd_independent_dq_independent"]), (ni, ni));
    assert_eq!(shape(&out["dqdd_independent_dv_independent"]), (ni, ni));
    assert_eq!(shape(&out["dqdd_independent_dtau"]), (ni, nv));
    for (r, &i) in independent.iter().enumerate() {
        let a = vecf(&out["dqdd_independent_dtau"][r]);
        let b = vecf(&out["dqdd_dtau"][i]);
        assert!(relative_error(&a, &b) < 1e-14, "{a:?} {b:?}");
    }
}

/// `--engine generated` runs the generated derivatives and agrees with the interpreted engine (the same
/// dual-number passes, traced: to rounding) on the UR5, f64 and f32 (to 1e-3 relative, the f32 answer of
/// the same states): `aba_derivatives` with the reference's wrenches (the generated
/// `aba_derivatives_ext`, for the links the samples name), `rnea_derivatives` without.
#[test]
fn the_generated_engine_agrees_with_the_interpreted() {
    let r = Robot::with_reference("ur5", "tests/data/pinocchio/ur5.urdf", false, "derivatives");
    let model = repo("tests/data/pinocchio/ur5.urdf");
    for (algo, key, field, wrenches) in [
        ("aba_derivatives", "tau", "tau", true),
        ("rnea_derivatives", "qdd", "qdd_for_rnea", false),
    ] {
        let samples: Vec<Value> = r
            .samples()
            .iter()
            .map(|s| {
                let mut sample = json!({"q": r.q(s), "v": r.v(&s["v"]), key: r.v(&s[field])});
                if wrenches {
                    assert!(s["f_ext"].as_object().is_some_and(|w| !w.is_empty()));
                    sample["f_ext"] = s["f_ext"].clone();
                }
                sample
            })
            .collect();
        let input = json!({ "samples": samples }).to_string();
        let interpreted = json_of(&["eval", &model, "--algo", algo], &input);
        for (scalar, tol) in [("f64", 1e-12), ("f32", 1e-3)] {
            let (ok, out, err) = embedyn_cached(
                &[
                    "eval",
                    &model,
                    "--algo",
                    algo,
                    "--engine",
                    "generated",
                    "--scalar",
                    scalar,
                ],
                &input,
            );
            assert!(ok, "{algo} {scalar}: {err}");
            let generated: Value = serde_json::from_str(&out).unwrap();
            for (g, i) in generated["samples"]
                .as_array()
                .unwrap()
                .iter()
                .zip(interpreted["samples"].as_array().unwrap())
            {
                for (field, reference) in i.as_object().unwrap() {
                    let e = relative_error(&flat(&g[field]), &flat(reference));
                    assert!(e < tol, "{algo} {scalar} {field}: {e:e}");
                }
            }
        }
    }
}

/// The command line's derivatives of a model with constraints add the manifold fields, which need a
/// second generated function: the generated engine refuses them with a usage error (exit 2) saying what
/// to use, before building anything.
#[test]
fn the_generated_engine_refuses_loop_models() {
    let four_bar = repo("models/loops/four_bar_internal.urdf");
    let guess = json!({"samples": [{"q": vec![0.2; 4], "v": vec![0.3; 4]}]});
    let state = json_of(&["complete", &four_bar], &guess.to_string())["samples"][0].clone();
    let input = json!({"samples": [{"q": state["q"], "v": state["v"], "tau": vec![0.1; 4]}]});
    let stderr = refused(
        &[
            "eval",
            &four_bar,
            "--algo",
            "aba_derivatives",
            "--engine",
            "generated",
        ],
        &input.to_string(),
        2,
    );
    assert!(
        stderr.contains("loops") && stderr.contains("--engine interpreted"),
        "{stderr}"
    );
}

/// A model without coordinates (one link, no joint): the generated engine's derivatives are 0 × 0, as the
/// interpreted engine's, instead of a panic on rows of length 0 (attacker trial, issue 12).
#[test]
fn derivatives_of_a_model_without_coordinates_are_empty_in_both_engines() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lone-link");
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("lone.urdf");
    std::fs::write(
        &model,
        r#"<robot name="lone"><link name="base"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>"#,
    )
    .unwrap();
    let model = model.to_string_lossy().to_string();
    let input = json!({"samples": [{"q": [], "v": [], "tau": []}]}).to_string();
    let interpreted = json_of(&["eval", &model, "--algo", "aba_derivatives"], &input);
    let (ok, out, err) = embedyn_cached(
        &[
            "eval",
            &model,
            "--algo",
            "aba_derivatives",
            "--engine",
            "generated",
        ],
        &input,
    );
    assert!(ok, "{err}");
    let generated: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(generated, interpreted);
    assert_eq!(generated["samples"][0]["dqdd_dq"], json!([]));
}
