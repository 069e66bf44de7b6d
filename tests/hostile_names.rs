//! Names are data through the `robot!` macro too (docs/model-format.md, "Names are data"): a model whose robot,
//! link and joint names carry quotes, backslashes, newlines, `*/`, `compile_error!`, Rust keywords,
//! unicode and names that collide after sanitizing expands to code that compiles without a warning (this
//! file denies warnings), lists the names exactly, and computes what the interpreted solver computes.
#![deny(warnings)]

mod common;

use common::{load_model, Rng};
use embedyn::{aba, relative_error, Model, Workspace};

mod hostile {
    embedyn::robot!("tests/data/hostile_names.urdf", f64_only);
}

mod hostile_locked {
    // Joints named like keywords and with spaces, locked: by keyword, raw identifier and string literal.
    embedyn::robot!(
        "tests/data/hostile_names.urdf",
        f64_only,
        only(aba),
        lock(r#fn = 0.1, self = -0.2, "肩 joint ✓" = 0.3)
    );
}

#[path = "data/hostile_names.rs"]
mod names;
use names::{FRAMES, JOINTS};

#[test]
fn hostile_names_through_the_macro_mean_what_the_model_says() {
    assert_eq!(hostile::JOINTS, JOINTS);
    assert_eq!(hostile::FRAMES, FRAMES);
    let model: Model<f64> = load_model("tests/data/hostile_names.urdf", false);
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, JOINTS);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(8);
    for _ in 0..5 {
        let q: [f64; 12] = rng.configuration(&model).try_into().unwrap();
        let v: [f64; 12] = rng.vec(12, -2.0, 2.0).try_into().unwrap();
        let tau: [f64; 12] = rng.vec(12, -1.0, 1.0).try_into().unwrap();
        let want = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let mut qdd = [0.0; 12];
        hostile::f64::aba(&q, &v, &tau, &mut qdd);
        let e = relative_error(&qdd, &want);
        assert!(e <= 1e-12, "generated vs interpreted: {e:e}");
    }
}

/// `lock(…)` names joints as the file does: a raw identifier (`r#fn`, the joint `fn`), a keyword (`self`)
/// and a string literal (any name) lock those joints, and the code is the interpreted model's with
/// the same locks.
#[test]
fn hostile_names_lock_the_joints_they_name() {
    let locks = [("fn", 0.1), ("self", -0.2), ("肩 joint ✓", 0.3)];
    let loaded = embedyn::load(&common::repo_path("tests/data/hostile_names.urdf")).unwrap();
    let model = loaded
        .model::<f64>(&embedyn::ModelOptions {
            locks: locks
                .iter()
                .map(|&(joint, value)| embedyn::LockedJoint {
                    joint: joint.into(),
                    value,
                })
                .collect(),
            ..Default::default()
        })
        .unwrap();
    assert_eq!(hostile_locked::NV, 9);
    assert!(locks.iter().all(|(j, _)| model.joint_index(j).is_none()));
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(9);
    for _ in 0..5 {
        let q: [f64; 9] = rng.configuration(&model).try_into().unwrap();
        let v: [f64; 9] = rng.vec(9, -2.0, 2.0).try_into().unwrap();
        let tau: [f64; 9] = rng.vec(9, -1.0, 1.0).try_into().unwrap();
        let want = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let mut qdd = [0.0; 9];
        hostile_locked::f64::aba(&q, &v, &tau, &mut qdd);
        assert!(relative_error(&qdd, &want) <= 1e-12);
    }
}

/// Messages are for a terminal: a control character in a file name (or in a name written `&#13;` in the
/// XML) is shown as an escape, never written raw, so a hostile file cannot recolour, clear or forge
/// lines on the reader's screen.
#[test]
fn messages_show_control_characters_as_escapes() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let missing = dir.join("no\u{1b}[2J\rsuch.urdf");
    let e = embedyn::load(&missing).unwrap_err().to_string();
    assert!(!e.contains('\u{1b}') && !e.contains('\r'), "{e:?}");
    assert!(e.contains("no\\u{1b}[2J\\rsuch.urdf"), "{e:?}");
    let text = r#"<robot name="r"><link name="a"/><link name="b"/>
      <joint name="j&#13;forged" type="revolute"><parent link="a"/><child link="zz"/></joint></robot>"#;
    let e = embedyn::codegen::parse_urdf(text, "r.urdf".as_ref())
        .and_then(|l| l.model::<f64>(&Default::default()))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(!e.contains('\r') && e.contains("j\\rforged"), "{e:?}");
}
