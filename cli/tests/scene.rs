//! Scene options that change the model on the command line (`--lock`, `--rotors`) and `embedyn tradeoff`
//! (docs/command-line.md, docs/model-format.md).

use crate::cli::{embedyn, embedyn_cached, repo};
use serde_json::Value;

fn json(text: &str) -> Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// `--lock` removes the joint's coordinate everywhere (info and eval agree); `--rotors reflected` removes
/// the geared rotors, whose couplings `info` no longer lists and names under `scene`.
#[test]
fn lock_and_rotors_change_the_model_every_command_sees() {
    let ur5 = repo("tests/data/pinocchio/ur5.urdf");
    let (ok, out, err) = embedyn(
        &[
            "info",
            &ur5,
            "--lock",
            "elbow_joint=-0.7",
            "--lock",
            "wrist_3_joint=1.1",
        ],
        "",
    );
    assert!(ok, "{err}");
    let info = json(&out);
    assert_eq!(info["nv"], 4);
    let names: Vec<&str> = info["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "shoulder_pan_joint",
            "shoulder_lift_joint",
            "wrist_1_joint",
            "wrist_2_joint"
        ]
    );
    assert_eq!(info["scene"]["locked"][0]["joint"], "elbow_joint");
    assert_eq!(info["scene"]["locked"][0]["value"], -0.7);
    // eval takes states of the locked model's size, and refuses the full model's.
    let state =
        r#"{"samples": [{"q": [0.1, 0.2, 0.3, 0.4], "v": [0, 0, 0, 0], "tau": [0, 0, 0, 0]}]}"#;
    let (ok, out, err) = embedyn(
        &[
            "eval",
            &ur5,
            "--algo",
            "aba",
            "--lock",
            "elbow_joint=-0.7",
            "--lock",
            "wrist_3_joint=1.1",
        ],
        state,
    );
    assert!(ok, "{err}");
    assert_eq!(json(&out)["samples"][0]["qdd"].as_array().unwrap().len(), 4);
    let (ok, _, err) = embedyn(
        &["eval", &ur5, "--algo", "aba", "--lock", "elbow_joint=-0.7"],
        state,
    );
    assert!(!ok && err.contains("`q`"), "{err}");

    let cheetah = repo("tests/data/grbda/mini_cheetah.urdf");
    let (ok, out, err) = embedyn(&["info", &cheetah, "--rotors", "reflected"], "");
    assert!(ok, "{err}");
    let info = json(&out);
    assert_eq!(
        (info["nv"].as_u64(), info["independent_nv"].as_u64()),
        (Some(18), Some(18))
    );
    assert_eq!(info["couplings"].as_array().unwrap().len(), 0);
    assert_eq!(info["scene"]["rotors"], "reflected");
    assert_eq!(
        info["scene"]["reflected_rotors"].as_array().unwrap().len(),
        12
    );
    let (ok, out, _) = embedyn(&["info", &cheetah], "");
    assert!(ok);
    assert_eq!(json(&out)["couplings"].as_array().unwrap().len(), 12);
}

/// Malformed or impossible scene options end in a clear error and an exit status below 128.
#[test]
fn bad_scene_options_are_refused_clearly() {
    let ur5 = repo("tests/data/pinocchio/ur5.urdf");
    let four_bar = repo("models/loops/four_bar_internal.urdf");
    for (args, expected) in [
        (vec!["info", &ur5, "--lock", "elbow_joint"], "JOINT=VALUE"),
        (
            vec!["info", &ur5, "--lock", "elbow_joint=fast"],
            "JOINT=VALUE",
        ),
        (vec!["info", &ur5, "--lock", "elbow_joint=inf"], "finite"),
        (vec!["info", &ur5, "--lock", "=0.1"], "JOINT=VALUE"),
        (
            vec!["info", &ur5, "--lock", "knee=0.1"],
            "no joint \"knee\" to lock",
        ),
        // A name with a control character is shown escaped, not sent to the terminal as it is.
        (
            vec!["info", &ur5, "--lock", "kn\u{1b}[31mee=0.1"],
            "no joint \"kn\\u{1b}[31mee\" to lock",
        ),
        (
            vec!["info", &ur5, "--rotors", "approximate"],
            "exact or reflected",
        ),
        (
            vec!["info", &four_bar, "--lock", "crank_joint=0.3"],
            "loop \"coupler_rocker_pin\"",
        ),
    ] {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_embedyn"));
        let out = cmd.args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code().unwrap_or(-1);
        assert!(
            (1..128).contains(&code) && code != 101,
            "{args:?}: exit {code}: {err}"
        );
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

/// `tradeoff --json` (CONTRACT §3) on bundled models: the geared arm has rotors (four variants), the
/// plain arm none (two); generated f64 with exact rotors agrees with the double-double reference to
/// 1e-12, f32 to 1e-4; the reflected variants' error is reported (not asserted small) and the SVG drawn.
#[test]
fn tradeoff_reports_every_variant_with_its_error_and_time() {
    let svg = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tradeoff.svg");
    for (model, variants) in [
        ("models/loops/geared_motor.urdf", 4),
        ("models/arm7.urdf", 2),
    ] {
        let path = repo(model);
        let (ok, out, err) = embedyn_cached(
            &["tradeoff", &path, "--json", "--svg", svg.to_str().unwrap()],
            "",
        );
        assert!(ok, "{model}: {err}");
        assert!(
            err.contains("embedyn tradeoff: timing"),
            "progress on stderr: {err}"
        );
        let result = json(&out);
        let list = result["variants"].as_array().unwrap();
        assert_eq!(list.len(), variants, "{model}: {out}");
        for v in list {
            assert_eq!(v["engine"], "generated");
            assert!(v["aba_ns"].as_f64().unwrap() > 0.0, "{v}");
            let e = v["rel_error"].as_f64().unwrap();
            match (v["scalar"].as_str().unwrap(), v["rotors"].as_str().unwrap()) {
                ("f64", "exact") => assert!(e <= 1e-12, "{model}: {v}"),
                ("f32", "exact") => assert!(e <= 1e-4, "{model}: {v}"),
                (_, "reflected") => {
                    assert!(e > 1e-8, "{model}: the approximation should show: {v}")
                }
                other => panic!("{other:?}"),
            }
        }
        let drawn = std::fs::read_to_string(&svg).unwrap();
        roxmltree::Document::parse(&drawn).unwrap();
        assert!(drawn.contains("f32 exact rotors"));
    }
    // The table names each variant.
    let (ok, out, err) = embedyn_cached(&["tradeoff", &repo("models/arm7.urdf")], "");
    assert!(ok, "{err}");
    assert!(
        out.contains("f32     exact") && out.contains("correct digits"),
        "{out}"
    );
}

/// The standalone crate of a locked, reflected model says so in its README, with the gravity it folded.
#[test]
fn standalone_readme_states_the_scene() {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scene-standalone");
    let _ = std::fs::remove_dir_all(&out);
    let model = repo("models/loops/geared_motor.urdf");
    let (ok, _, err) = embedyn(
        &[
            "generate",
            &model,
            "--out",
            out.to_str().unwrap(),
            "--rotors",
            "reflected",
            "--lock",
            "elbow=0.25",
            "--gravity",
            "0,0,-1.62",
        ],
        "",
    );
    assert!(ok, "{err}");
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(readme.contains("nq = 1, nv = 1"), "{readme}");
    assert!(readme.contains("gravity (0, 0, -1.62) m/s²"), "{readme}");
    assert!(readme.contains("`elbow` locked at 0.25"), "{readme}");
    assert!(readme.contains("geared rotors reflected"), "{readme}");
}

/// `tradeoff` on a geared arm whose file declares no independent joints (embedyn picks the rotors as
/// independent, the reflected model keeps the driving joints): every variant is compared on the
/// coordinates it has, none is missing (a tester found a panic here).
#[test]
fn tradeoff_compares_reflected_rotors_on_the_joints_they_keep() {
    let text = std::fs::read_to_string(repo("models/loops/geared_motor.urdf"))
        .unwrap()
        .replace(" independent=\"true\"", "")
        .replace(" independent=\"false\"", "");
    let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("geared_undeclared.urdf");
    std::fs::write(&path, text).unwrap();
    let (ok, out, err) = embedyn_cached(&["tradeoff", path.to_str().unwrap(), "--json"], "");
    assert!(ok, "{err}");
    let result = json(&out);
    let list = result["variants"].as_array().unwrap();
    assert_eq!(list.len(), 4, "{out}");
    for v in list {
        let e = v["rel_error"].as_f64().unwrap();
        if v["rotors"] == "exact" {
            assert!(e <= if v["scalar"] == "f64" { 1e-12 } else { 1e-4 }, "{v}");
        } else {
            assert!(e > 1e-8 && e < 1.0, "{v}");
        }
    }
}

/// `info` lists the frames: every link of the file by name, in file order, merged links and links fixed
/// to the world included (a locked joint's child stays a frame: only its coordinate goes).
#[test]
fn info_lists_every_link_as_a_frame() {
    let ur5 = repo("tests/data/pinocchio/ur5.urdf");
    let text = std::fs::read_to_string(&ur5).unwrap();
    let written: Vec<&str> = text
        .match_indices("<link name=\"")
        .map(|(at, m)| {
            let rest = &text[at + m.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect();
    for args in [
        vec!["info", &ur5],
        vec!["info", &ur5, "--lock", "elbow_joint=0.3"],
    ] {
        let (ok, out, err) = embedyn(&args, "");
        assert!(ok, "{err}");
        let frames: Vec<String> = json(&out)["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_str().unwrap().to_string())
            .collect();
        assert_eq!(frames, written, "{args:?}");
    }
}
