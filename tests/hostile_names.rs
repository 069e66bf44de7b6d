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

mod cases {
    embedyn::robot!("tests/data/case_names.urdf", only(aba));
}

// A joint named like a part of `aba` plus its cosine's suffix (`aba_l1_to_x` of link `x_q_cos`: its cosine
// is `aba_l1_to_x_q_cos`, the name of `aba`'s second part), with every function twinned: the twins'
// shared bodies once took that value for a call and failed to compile (E0603, an attacker's trial).
mod part_names {
    embedyn::robot!(
        "tests/data/part_names.urdf",
        f64_only,
        only(aba),
        avx_twins = all
    );
}

// Links `x1` and `x_1` of a 43-link chain, whose frame functions are long enough for a scratch tuple:
// both were `FrameX1Scratch` once (E0428, an attacker's trial).
mod scratch_names {
    embedyn::robot!(
        "tests/data/scratch_names.urdf",
        f64_only,
        only(kinematics, frame),
        frames(x1, x_1)
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

/// The index constants of hostile names are clean SCREAMING_SNAKE_CASE identifiers (this file denies
/// warnings, `non_upper_case_globals` among them) that index the names they stand for; names that differ
/// only in case get distinct constants, in file order.
#[test]
fn hostile_names_get_index_constants() {
    use hostile::{frames, joints, q_index, v_index};
    let named = [
        (joints::Q_UOTE_158EF06C, "q\"uote"),
        (joints::BACK_SLASH_1498E0B5, "back\\slash"),
        (
            joints::NEW_LINE_BUILD_EVIL_RS_3323C11F,
            "new\nline\rbuild = \"evil.rs\"",
        ),
        (
            joints::COMPILE_ERROR_BOOM_D7C2B64F,
            "*/ compile_error!(\"boom\") /*",
        ),
        (joints::FN_0F1E18BB, "fn"),
        (joints::SELF_06C604B3, "self"),
        (joints::SELF_85BC0F95, "Self"),
        (joints::CRATE_F5FE331D, "crate"),
        (joints::JOINT_556C11E3, "肩 joint ✓"),
        (joints::A_B_D44362D6, "a-b"),
        (joints::A_B_2E7336DC, "a.b"),
        (joints::A_B_C8687A08, "a b"),
    ];
    for (i, name) in named {
        assert_eq!(JOINTS[i], name);
        assert_eq!(hostile::JOINTS[i], name);
    }
    assert_eq!(q_index::SELF_85BC0F95, 6);
    assert_eq!(v_index::A_B_C8687A08, 11);
    let frames = [
        (frames::L_1_E74E1FD8, "l\\1"),
        (frames::ROBOT_A8B053BB, "</robot>"),
        (frames::R_TYPE_F85499BE, "r#type"),
        (frames::LINK_D2E2ADF7, "_"),
        (frames::LINK_EFD5824F, "ロボット"),
        (frames::TAB_BED_B429F1DA, "tab\tbed"),
        (frames::BACK_TICK_PIPE_FE953C0C, "back`tick|pipe"),
        (frames::SUPER_73D1B1B1, "super"),
        (frames::LINK_1ST_E01DDF65, "1st"),
        (frames::X_Y_CC96FED8, "x-y"),
        (frames::X_Y_B24CA9B7, "x.y"),
        (frames::X_Y_887FCEA6, "x y"),
    ];
    for (i, name) in frames {
        assert_eq!(FRAMES[i], name);
    }
    assert_eq!(
        hostile::FRAMES[hostile::frames::MERGED_E81B53F6],
        "merged \"*/\""
    );
    // Names alike but for case: the first keeps the constant, the others take the next free suffix.
    assert_eq!(cases::JOINTS[cases::joints::KNEE], "knee");
    assert_eq!(cases::JOINTS[cases::joints::KNEE_3], "Knee");
    assert_eq!(cases::JOINTS[cases::joints::KNEE_2], "knee_2");
    assert_eq!(cases::FRAMES[cases::frames::FOOT], "Foot");
    assert_eq!(cases::FRAMES[cases::frames::FOOT_3], "foot");
    assert_eq!(cases::FRAMES[cases::frames::FOOT_2], "foot_2");
    assert_eq!(cases::f64::LOWER, [-1.0, f64::NEG_INFINITY, -0.1]);
    assert_eq!(cases::f32::UPPER, [1.0, f32::INFINITY, 0.3]);
    assert_eq!(cases::f64::VELOCITY, [2.0, f64::INFINITY, f64::INFINITY]);
    assert_eq!(cases::f64::EFFORT[0], 5.0);
    // The locked joints leave their constants: `fn`, `self` and `肩 joint ✓` are gone, `Self` moved up.
    assert_eq!(hostile_locked::joints::SELF_85BC0F95, 4);
    assert_eq!(
        hostile_locked::JOINTS[hostile_locked::joints::SELF_85BC0F95],
        "Self"
    );
    assert_eq!(hostile_locked::f64::LOWER.len(), 9);
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

/// Functions whose names meet other generated names compute what they should: the chain whose joint
/// takes the name of an `aba` part matches the interpreted `aba`, and the frame functions of `x1` and
/// `x_1` give the poses `kinematics` gives those links.
#[test]
fn names_that_meet_generated_names_compile_and_compute() {
    let model: Model<f64> = load_model("tests/data/part_names.urdf", false);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(21);
    const N: usize = part_names::NV;
    for _ in 0..5 {
        let q: [f64; N] = rng.configuration(&model).try_into().unwrap();
        let v: [f64; N] = rng.vec(N, -2.0, 2.0).try_into().unwrap();
        let tau: [f64; N] = rng.vec(N, -1.0, 1.0).try_into().unwrap();
        let want = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let mut qdd = [0.0; N];
        part_names::f64::aba(&q, &v, &tau, &mut qdd);
        let e = relative_error(&qdd, &want);
        assert!(e <= 1e-12, "generated vs interpreted: {e:e}");
    }
    const NQ: usize = scratch_names::NQ;
    const NF: usize = scratch_names::FRAMES.len();
    let q: [f64; NQ] = rng.vec(NQ, -2.0, 2.0).try_into().unwrap();
    let v = [0.5; NQ];
    let mut poses = [[0.0; 12]; NF];
    scratch_names::f64::kinematics(&q, &mut poses);
    type FrameFunction =
        fn(&[f64; NQ], &[f64; NQ], &mut [f64; 12], &mut [[f64; NQ]; 6], &mut [f64; 6]);
    let frames: [(usize, FrameFunction); 2] = [
        (scratch_names::frames::X1, scratch_names::f64::frame_x1),
        (scratch_names::frames::X_1, scratch_names::f64::frame_x_1),
    ];
    for (index, frame) in frames {
        let (mut pose, mut jacobian, mut bias) = ([0.0; 12], [[0.0; NQ]; 6], [0.0; 6]);
        frame(&q, &v, &mut pose, &mut jacobian, &mut bias);
        let e = relative_error(&pose, &poses[index]);
        assert!(e <= 1e-12, "frame {index}: {e:e}");
    }
    assert_ne!(
        scratch_names::FRAMES[scratch_names::frames::X1],
        scratch_names::FRAMES[scratch_names::frames::X_1]
    );
}
