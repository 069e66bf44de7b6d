//! Scene options that change the model (issue 10): locked joints against Pinocchio's `buildReducedModel`
//! and against the same joint fixed in the file; the reflected-rotor approximation against the exact
//! model where nothing is dropped, and against the terms it is documented to drop where it differs.

use crate::common;
use crate::constraint_embedding::consistent_state;
use crate::generated_functions;
use crate::pinocchio_reference::{check_generated, check_model, recorded_locks, reference};

use common::{load_model, repo_path, Rng};
use embedyn::codegen::{parse_urdf, LoadErrorKind};
use embedyn::{
    aba, crba, kkt_forward_dynamics, reduced_mass_matrix, relative_error, rnea, LockedJoint, Model,
    ModelOptions, Rotors, Workspace,
};
use serde_json::Value;
use std::path::Path;

mod ur5_locked {
    embedyn::robot!(
        "tests/data/pinocchio/ur5.urdf",
        lock(elbow_joint = -0.7, wrist_3_joint = 1.1),
        f64_only,
        only(aba, rnea, crba)
    );
}
mod solo12_locked {
    embedyn::robot!(
        "tests/data/pinocchio/solo12.urdf",
        floating,
        lock(
            FL_HAA = 0.1,
            FR_HAA = -0.1,
            HL_HAA = 0.2,
            HR_HAA = -0.2,
            HR_KFE = -1.3
        ),
        f64_only,
        only(aba, rnea, crba)
    );
}
mod mini_cheetah_reflected {
    embedyn::robot!(
        "tests/data/grbda/mini_cheetah.urdf",
        rotors = reflected,
        f64_only,
        only(aba, crba)
    );
}

fn options_of(json: &Value, floating: bool) -> ModelOptions {
    ModelOptions {
        floating,
        locks: recorded_locks(json),
        ..Default::default()
    }
}

fn model_with(path: &str, options: &ModelOptions) -> Result<Model<f64>, embedyn::LoadError> {
    embedyn::load(&repo_path(path))
        .unwrap_or_else(|e| panic!("{e}"))
        .model::<f64>(options)
}

/// `--lock` gives Pinocchio's reduced model (`buildReducedModel` at the locked values): aba, rnea, nle,
/// crba and the generalized gravity to 1e-9 relative, on a fixed arm (elbow and last wrist joint locked)
/// and a floating quadruped (four hip abductions and a knee locked).
#[test]
fn locked_joints_match_pinocchio() {
    for (name, urdf, floating) in [
        ("ur5_locked", "tests/data/pinocchio/ur5.urdf", false),
        (
            "solo12_locked_floating",
            "tests/data/pinocchio/solo12.urdf",
            true,
        ),
    ] {
        let json = reference(name);
        let model = model_with(urdf, &options_of(&json, floating)).unwrap();
        check_model(name, &model, &json);
    }
}

/// The generated code of a locked model (`lock(…)` in the macro) against Pinocchio's reduced model:
/// aba, rnea and crba to 1e-9 relative.
#[test]
fn generated_locked_code_matches_pinocchio() {
    for (name, urdf, floating, functions) in [
        (
            "ur5_locked",
            "tests/data/pinocchio/ur5.urdf",
            false,
            generated_functions!(ur5_locked),
        ),
        (
            "solo12_locked_floating",
            "tests/data/pinocchio/solo12.urdf",
            true,
            generated_functions!(solo12_locked),
        ),
    ] {
        let json = reference(name);
        let model = model_with(urdf, &options_of(&json, floating)).unwrap();
        check_generated(name, &model, &json, functions);
    }
}

/// Locking a joint at 0 is the file with that joint fixed (its origin unchanged): the same model, by
/// another path through the loader.
#[test]
fn locking_at_zero_equals_fixing_the_joint_in_the_file() {
    let text = std::fs::read_to_string(repo_path("models/arm7.urdf")).unwrap();
    let loaded = embedyn::load(&repo_path("models/arm7.urdf")).unwrap();
    let names: Vec<String> = loaded
        .robot
        .joints
        .iter()
        .filter(|j| j.kind.is_one_dof())
        .map(|j| j.name.clone())
        .collect();
    let mut rng = Rng::new(5);
    for name in [&names[1], &names[4]] {
        let locked = loaded
            .model::<f64>(&ModelOptions {
                locks: vec![LockedJoint {
                    joint: name.clone(),
                    value: 0.0,
                }],
                ..Default::default()
            })
            .unwrap();
        let pattern = format!("<joint name=\"{name}\" type=\"revolute\"");
        assert!(text.contains(&pattern), "{pattern}");
        let fixed_text = text.replace(&pattern, &format!("<joint name=\"{name}\" type=\"fixed\""));
        let fixed = parse_urdf(&fixed_text, Path::new("arm7_fixed.urdf"))
            .unwrap()
            .model::<f64>(&ModelOptions::default())
            .unwrap();
        assert_eq!(
            locked.nv(),
            loaded.model::<f64>(&ModelOptions::default()).unwrap().nv() - 1
        );
        assert_eq!(locked.nv(), fixed.nv());
        let (mut wl, mut wf) = (Workspace::new(&locked), Workspace::new(&fixed));
        for _ in 0..5 {
            let q = rng.configuration(&locked);
            let v = rng.vec(locked.nv(), -1.0, 1.0);
            let tau = rng.vec(locked.nv(), -1.0, 1.0);
            let a = aba(&locked, &mut wl, &q, &v, &tau).unwrap().to_vec();
            let b = aba(&fixed, &mut wf, &q, &v, &tau).unwrap().to_vec();
            assert!(relative_error(&a, &b) <= 1e-13, "{name}: {a:?} {b:?}");
            let ma = crba(&locked, &mut wl, &q).unwrap().clone();
            let mb = crba(&fixed, &mut wf, &q).unwrap().clone();
            assert!(relative_error(ma.as_slice(), mb.as_slice()) <= 1e-13);
        }
    }
}

/// What `--lock` refuses, each with its own error: a joint the model lacks, a fixed joint, the free
/// flyer `--floating` adds, a joint locked twice, a non-finite value, and joints whose coordinate a loop,
/// a coupling or a mimic joint relates to others (on either side of the constraint).
#[test]
fn lock_refusals_name_the_joint_and_the_reason() {
    let lock = |path: &str, floating: bool, locks: &[(&str, f64)]| {
        model_with(
            path,
            &ModelOptions {
                floating,
                locks: locks
                    .iter()
                    .map(|&(joint, value)| LockedJoint {
                        joint: joint.into(),
                        value,
                    })
                    .collect(),
                ..Default::default()
            },
        )
        .unwrap_err()
    };
    type Expected = fn(&LoadErrorKind) -> bool;
    type Case<'a> = (&'a str, bool, &'a [(&'a str, f64)], Expected);
    let cases: [Case; 6] = [
        (
            "models/arm7.urdf",
            false,
            &[("no_such_joint", 0.1)],
            |k| matches!(k, LoadErrorKind::LockUnknownJoint { joint } if joint == "no_such_joint"),
        ),
        (
            "tests/data/pinocchio/solo12.urdf",
            true,
            &[("root_joint", 0.1)],
            |k| matches!(k, LoadErrorKind::LockNotOneDof { kind: "floating" }),
        ),
        (
            "tests/data/pinocchio/ur5.urdf",
            false,
            &[("ee_fixed_joint", 0.1)],
            |k| matches!(k, LoadErrorKind::LockNotOneDof { kind: "fixed" }),
        ),
        (
            "models/loops/biped_floating.urdf",
            false,
            &[("floating_base", 0.0)],
            |k| matches!(k, LoadErrorKind::LockNotOneDof { kind: "floating" }),
        ),
        (
            "tests/data/pinocchio/ur5.urdf",
            false,
            &[("elbow_joint", 0.1), ("elbow_joint", 0.2)],
            |k| matches!(k, LoadErrorKind::LockedTwice { first, second } if *first == 0.1 && *second == 0.2),
        ),
        (
            "tests/data/pinocchio/ur5.urdf",
            false,
            &[("elbow_joint", f64::NAN)],
            |k| matches!(k, LoadErrorKind::LockValueNotFinite { .. }),
        ),
    ];
    for (path, floating, locks, expected) in cases {
        let e = lock(path, floating, locks);
        assert!(expected(&e.kind), "{path} {locks:?}: {e}");
    }
    let e = lock(
        "tests/data/pinocchio/ur5.urdf",
        false,
        &[("elbow_joint", f64::NAN)],
    );
    assert!(e.to_string().contains("joint \"elbow_joint\""), "{e}");
    use embedyn::codegen::ConstraintElement as C;
    for (path, joint, what, name) in [
        (
            "models/loops/four_bar_internal.urdf",
            "crank_joint",
            C::Loop,
            "coupler_rocker_pin",
        ),
        (
            "models/loops/four_bar_internal.urdf",
            "rocker_joint",
            C::Loop,
            "coupler_rocker_pin",
        ),
        (
            "models/loops/rotor_chain_10.urdf",
            "joint_3",
            C::Coupling,
            "gear_3",
        ),
        (
            "models/loops/rotor_chain_10.urdf",
            "rotor_joint_3",
            C::Coupling,
            "gear_3",
        ),
    ] {
        let e = lock(path, false, &[(joint, 0.0)]);
        match &e.kind {
            LoadErrorKind::LockedJointInConstraint { what: w, name: n } => {
                assert_eq!((*w, n.as_str()), (what, name), "{path} {joint}: {e}")
            }
            other => panic!("{path} {joint}: {other:?}"),
        }
        assert!(e.to_string().contains(&format!("joint \"{joint}\"")), "{e}");
    }
}

/// A `<mimic>` joint is not locked by itself (the joints it follows would have to move with it): the
/// refusal names the joints to lock instead, those at the top of its chains of mimics, all of them where
/// it follows several, and says when they are locked already. A joint that mimics itself gets the file's
/// own error, not a refusal of the lock (an attacker's trial: "lock \"a\" instead" for joint a).
#[test]
fn a_mimic_joint_is_refused_with_the_joints_to_lock_instead() {
    let refusal = |path: &str, locks: &[&str]| {
        let locks = locks
            .iter()
            .map(|&joint| LockedJoint {
                joint: joint.into(),
                value: 0.01,
            })
            .collect();
        model_with(
            path,
            &ModelOptions {
                locks,
                ..Default::default()
            },
        )
        .unwrap_err()
    };
    let gripper = "models/loops/parallel_gripper.urdf";
    let e = refusal(gripper, &["finger2_joint"]);
    assert!(
        matches!(&e.kind, LoadErrorKind::LockedMimicJoint { drivers, already_locked: false } if drivers == &["finger1_joint"]),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("joint \"finger2_joint\"") && text.contains("lock \"finger1_joint\" instead"),
        "{text}"
    );
    let e = refusal(gripper, &["finger1_joint", "finger2_joint"]);
    assert!(
        matches!(
            &e.kind,
            LoadErrorKind::LockedMimicJoint {
                already_locked: true,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("fixed already"), "{e}");
    // The differential wrist's rotor follows both wrist joints: locking one would not fix it.
    let e = refusal("models/loops/differential_wrist.urdf", &["rotor1_joint"]);
    assert!(
        matches!(&e.kind, LoadErrorKind::LockedMimicJoint { drivers, .. } if drivers == &["wrist_pitch", "wrist_roll"]),
        "{e}"
    );
    assert!(
        e.to_string().contains("\"wrist_pitch\" and \"wrist_roll\""),
        "{e}"
    );
    // Locking the third finger of a gripper whose fingers follow `finger2` and `finger3`.
    let lock_third_finger = |finger2: &str, finger3: &str| {
        parse_urdf(
            &gripper_with_third_finger(finger2, finger3),
            Path::new("gripper3.urdf"),
        )
        .unwrap()
        .model::<f64>(&ModelOptions {
            locks: vec![LockedJoint {
                joint: "finger3_joint".into(),
                value: 0.0,
            }],
            ..Default::default()
        })
        .unwrap_err()
    };
    // A chain: the third finger follows the second, which follows the first; the first is to lock.
    let e = lock_third_finger(
        r#"<mimic joint="finger1_joint"/>"#,
        r#"<mimic joint="finger2_joint" multiplier="2" offset="0"/>"#,
    );
    assert!(
        matches!(&e.kind, LoadErrorKind::LockedMimicJoint { drivers, .. } if drivers == &["finger1_joint"]),
        "{e}"
    );
    let e = parse_urdf(
        &gripper_with_third_finger("", r#"<mimic joint="finger3_joint"/>"#),
        Path::new("gripper3.urdf"),
    )
    .unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::MimicSelf), "{e}");
}

/// Where a lock cannot be carried into a joint that mimics the locked one, the error is at that joint
/// and names the lock (an attacker's trial: the error spoke of the mimic joint as if it had been locked,
/// and a term whose constant overflowed the offset of a remaining one crashed the loader).
#[test]
fn a_lock_that_cannot_reach_a_mimic_joint_says_which_lock() {
    let model = |joints: &str, lock: &str, value: f64| {
        // The links the joints name.
        let links: String = ["l1", "l2", "l3", "rotor"]
            .iter()
            .filter(|l| joints.contains(&format!("\"{l}\"")))
            .map(|l| format!(r#"<link name="{l}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"#))
            .collect();
        let text = format!(r#"<robot name="m"><link name="base"/>{links}{joints}</robot>"#);
        parse_urdf(&text, Path::new("m.urdf"))
            .unwrap_or_else(|e| panic!("{e}"))
            .model::<f64>(&ModelOptions {
                locks: vec![LockedJoint {
                    joint: lock.into(),
                    value,
                }],
                ..Default::default()
            })
    };
    let joint = |name: &str, parent: &str, child: &str, extra: &str| {
        format!(
            r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/><axis xyz="0 1 0"/>{extra}</joint>"#
        )
    };
    // f follows d (× 1e300) and e: locking d at 1e10 overflows the offset of e's term.
    let joints = [
        joint("d", "base", "l1", ""),
        joint("e", "l1", "l2", ""),
        joint(
            "f",
            "l2",
            "l3",
            r#"<mimic joint="d" multiplier="1e300"/><mimic joint="e"/>"#,
        ),
    ]
    .concat();
    assert!(model(&joints, "d", 1e7).is_ok());
    let e = model(&joints, "d", 1e10).unwrap_err();
    match &e.kind {
        LoadErrorKind::LockFixesMimicJoint { driver, reason } => {
            assert_eq!(driver, "d");
            assert!(
                matches!(**reason, LoadErrorKind::MimicOffsetNotFinite { .. }),
                "{e}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("joint \"f\""), "{e}");
    // f follows d alone: fixed at 1e300 × 1e10, which overflows.
    let joints = [
        joint("d", "base", "l1", ""),
        joint("f", "l1", "l2", r#"<mimic joint="d" multiplier="1e300"/>"#),
    ]
    .concat();
    let e = model(&joints, "d", 1e10).unwrap_err();
    assert!(
        matches!(&e.kind, LoadErrorKind::LockFixesMimicJoint { reason, .. } if matches!(**reason, LoadErrorKind::LockValueNotFinite { .. })),
        "{e}"
    );
    // f follows drv and is geared to a rotor: fixing it would change the coupling.
    let joints = [
        joint("drv", "base", "l1", ""),
        joint("f", "base", "l2", r#"<mimic joint="drv"/>"#),
        r#"<joint name="rotor_joint" type="revolute" independent="false"><parent link="base"/><child link="rotor"/><axis xyz="0 1 0"/></joint>
<coupling name="gear"><predecessor link="l2"/><successor link="rotor"/><ratio value="6"/></coupling>"#
            .to_string(),
    ]
    .concat();
    let e = model(&joints, "drv", 0.2).unwrap_err();
    assert!(
        matches!(&e.kind, LoadErrorKind::LockFixesMimicJoint { driver, reason } if driver == "drv" && matches!(**reason, LoadErrorKind::LockedJointInConstraint { .. })),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("joint \"f\"")
            && text.contains("locking joint \"drv\"")
            && text.contains("coupling \"gear\""),
        "{text}"
    );
}

/// The parallel gripper with a third finger on the second that follows it in turn, and `extra` `<mimic>`
/// elements on that third finger: the text of the model file.
fn gripper_with_third_finger(finger2_mimic: &str, finger3_mimics: &str) -> String {
    let text = std::fs::read_to_string(repo_path("models/loops/parallel_gripper.urdf")).unwrap();
    let mimic = r#"<mimic joint="finger1_joint" multiplier="1" offset="0"/>"#;
    assert!(text.contains(mimic) && text.contains(r#"independent="false""#));
    text.replace(mimic, finger2_mimic)
        .replace(r#" independent="false""#, "")
        .replace(
            "</robot>",
            &format!(
                r#"  <link name="finger3">
    <inertial><origin xyz="0.01 0 -0.02"/><mass value="0.05"/>
      <inertia ixx="2e-5" iyy="1e-5" izz="1.5e-5" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="finger3_joint" type="revolute">
    <origin xyz="0 0 -0.05" rpy="0.1 0 0"/>
    <parent link="finger2"/>
    <child link="finger3"/>
    <axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
    {finger3_mimics}
  </joint>
</robot>
"#
            ),
        )
}

/// Locking the joint that mimic joints follow fixes them too, at `Σ m x + o` of their drivers, through a
/// chain of mimics (finger 3 follows finger 2, which follows finger 1): the same model as the file without
/// the `<mimic>` elements and each joint locked at that value, by hand. And a mimic joint that also
/// follows a joint that is not locked keeps that term, the locked ones' constant in its offset.
#[test]
fn locking_a_driver_fixes_the_mimic_joints_that_follow_it() {
    let x = 0.013;
    let (m2, o2, m3, o3) = (-0.5, 0.02, 3.0, -0.1);
    let finger2 = format!(r#"<mimic joint="finger1_joint" multiplier="{m2:?}" offset="{o2:?}"/>"#);
    let finger3 = format!(r#"<mimic joint="finger2_joint" multiplier="{m3:?}" offset="{o3:?}"/>"#);
    let lock = |joint: &str, value: f64| LockedJoint {
        joint: joint.into(),
        value,
    };
    let model = |text: String, locks: Vec<LockedJoint>| {
        parse_urdf(&text, Path::new("gripper3.urdf"))
            .unwrap_or_else(|e| panic!("{e}"))
            .model::<f64>(&ModelOptions {
                locks,
                ..Default::default()
            })
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let locked = model(
        gripper_with_third_finger(&finger2, &finger3),
        vec![lock("finger1_joint", x)],
    );
    let (x2, x3) = (0.0 + (m2 * x + o2), 0.0 + (m3 * (0.0 + (m2 * x + o2)) + o3));
    let by_hand = model(
        gripper_with_third_finger("", ""),
        vec![
            lock("finger1_joint", x),
            lock("finger2_joint", x2),
            lock("finger3_joint", x3),
        ],
    );
    assert_eq!((locked.nv(), by_hand.nv()), (1, 1));
    assert!(!locked.has_constraints());
    // Not the spanning tree unchanged: the fingers' poses moved with their values.
    let unlocked_fingers = model(
        gripper_with_third_finger("", ""),
        vec![
            lock("finger1_joint", x),
            lock("finger2_joint", 0.0),
            lock("finger3_joint", 0.0),
        ],
    );
    let mut rng = Rng::new(17);
    let (mut wl, mut wh, mut wu) = (
        Workspace::new(&locked),
        Workspace::new(&by_hand),
        Workspace::new(&unlocked_fingers),
    );
    for _ in 0..5 {
        let q = rng.configuration(&locked);
        let v = rng.vec(1, -2.0, 2.0);
        let tau = rng.vec(1, -1.0, 1.0);
        let a = aba(&locked, &mut wl, &q, &v, &tau).unwrap().to_vec();
        let b = aba(&by_hand, &mut wh, &q, &v, &tau).unwrap().to_vec();
        assert!(relative_error(&a, &b) <= 1e-14, "{a:?} {b:?}");
        let c = aba(&unlocked_fingers, &mut wu, &q, &v, &tau)
            .unwrap()
            .to_vec();
        assert!(
            relative_error(&a, &c) > 1e-6,
            "the fingers' values changed nothing: {a:?} {c:?}"
        );
    }
    // Finger 3 follows finger 2 and the wrist: with finger 1 locked only the wrist's term stays, the rest
    // a constant in its offset.
    let (mw, ow) = (2.0, 0.05);
    let wrist = format!(r#"<mimic joint="wrist" multiplier="{mw:?}" offset="{ow:?}"/>"#);
    let locked = model(
        gripper_with_third_finger(&finger2, &format!("{finger3}{wrist}")),
        vec![lock("finger1_joint", x)],
    );
    let offset = ow + (0.0 + (m3 * x2 + o3));
    let by_hand = model(
        gripper_with_third_finger(
            "",
            &format!(r#"<mimic joint="wrist" multiplier="{mw:?}" offset="{offset:?}"/>"#),
        ),
        vec![lock("finger1_joint", x), lock("finger2_joint", x2)],
    );
    assert!(locked.has_constraints());
    assert_eq!(format!("{locked:?}"), format!("{by_hand:?}"));
    assert_eq!((locked.nv(), locked.independent_nv()), (2, 1));
}

/// A joint outside every loop can be locked in a model with loops: the loops stay, the coordinate goes,
/// and constraint embedding still agrees with the Lagrange-multiplier (KKT) solve.
#[test]
fn locking_outside_a_loop_keeps_the_loops() {
    let full: Model<f64> = load_model("models/loops/biped_floating.urdf", false);
    let locks = [("l_ankle", 0.2), ("r_hip_yaw", -0.1)];
    let model = model_with(
        "models/loops/biped_floating.urdf",
        &ModelOptions {
            locks: locks
                .iter()
                .map(|&(joint, value)| LockedJoint {
                    joint: joint.into(),
                    value,
                })
                .collect(),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(model.nv(), full.nv() - 2);
    assert_eq!(model.independent_nv(), full.independent_nv() - 2);
    assert_eq!(model.constraints.len(), full.constraints.len());
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(8);
    for _ in 0..5 {
        let (q, v) = consistent_state(&model, &mut ws, &mut rng);
        let tau = rng.vec(model.nv(), -1.0, 1.0);
        let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let kkt = kkt_forward_dynamics(&model, &mut ws, &q, &v, &tau).unwrap();
        assert!(relative_error(&qdd, &kkt) <= 1e-9, "{qdd:?} {kkt:?}");
    }
}

/// The exact model's state restricted to the joints the reflected model keeps (matched by name).
fn restrict(
    exact: &Model<f64>,
    reflected: &Model<f64>,
    q: &[f64],
    v: &[f64],
) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
    let (mut qr, mut vr, mut v_of) = (Vec::new(), Vec::new(), Vec::new());
    for j in &reflected.joints {
        let e = &exact.joints[exact.joint_index(&j.name).unwrap()];
        qr.extend_from_slice(&q[e.q_index..e.q_index + e.nq()]);
        vr.extend_from_slice(&v[e.v_index..e.v_index + e.nv()]);
        v_of.extend(e.v_index..e.v_index + e.nv());
    }
    (qr, vr, v_of)
}

/// `--rotors reflected` on GRBDA's robots: the reflected model's joints are exactly the exact model's
/// independent joints, in order, and each driving joint carries ratio² × its rotor's axial inertia
/// (mini_cheetah's knee: 9.33² × 6.3e-5 kg·m²; mit_humanoid_leg's belt-driven ankle rotor, 12² ×
/// 1.6841e-4 kg·m², on both the knee and the ankle it drives).
#[test]
fn reflected_rotors_leave_exactly_the_independent_coordinates() {
    let reflected_options = ModelOptions {
        rotors: Rotors::Reflected,
        ..Default::default()
    };
    for path in [
        "tests/data/grbda/mini_cheetah.urdf",
        "tests/data/grbda/mit_humanoid.urdf",
        "tests/data/grbda/mit_humanoid_leg.urdf",
        "tests/data/grbda/revolute_rotor_chain.urdf",
    ] {
        let exact: Model<f64> = load_model(path, false);
        let reflected = model_with(path, &reflected_options).unwrap();
        let independent: Vec<&str> = exact
            .independent_joints()
            .iter()
            .map(|&j| exact.joints[j].name.as_str())
            .collect();
        let kept: Vec<&str> = reflected.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(kept, independent, "{path}");
        assert!(!reflected.has_constraints(), "{path}");
        assert_eq!(reflected.nv(), exact.independent_nv(), "{path}");
    }
    let armature = |path: &str, joint: &str| {
        let m = model_with(path, &reflected_options).unwrap();
        m.joints[m.joint_index(joint).unwrap()].armature
    };
    let knee = armature("tests/data/grbda/mini_cheetah.urdf", "FR_hip_to_knee_j");
    assert!((knee - 9.33f64.powi(2) * 6.3e-5).abs() <= 1e-15, "{knee}");
    let leg = "tests/data/grbda/mit_humanoid_leg.urdf";
    let ankle_rotor = 144.0 * 1.6841e-4;
    let ankle = armature(leg, "knee_to_ankle");
    assert!((ankle - ankle_rotor).abs() <= 1e-15, "{ankle}");
    // The knee: its own rotor and the ankle's belt-driven one.
    let knee = armature(leg, "hipy_to_knee_link");
    let knee_rotor = knee - ankle_rotor;
    assert!(knee_rotor > 0.0 && knee_rotor < knee, "{knee}");
}

/// Where the approximation drops nothing it equals the exact model: the geared-motor arm whose shoulder
/// rotor sits on a link fixed to the world (no carrier rotation, so no gyroscopic term) and whose elbow
/// rotor has no rotational inertia (a point mass on the upper arm). aba over the independent
/// coordinates and the mass matrix XᵀMX agree to 1e-12.
#[test]
fn reflected_equals_exact_where_nothing_is_dropped() {
    let text = std::fs::read_to_string(repo_path("models/loops/geared_motor.urdf")).unwrap();
    // The elbow rotor's inertia (the second rotor inertia line of the file) set to zero, mass kept.
    let start = text.find("<link name=\"elbow_rotor\">").unwrap();
    let line =
        "<inertia ixx=\"5.2e-05\" ixy=\"0\" ixz=\"0\" iyy=\"9e-05\" iyz=\"0\" izz=\"5.2e-05\"/>";
    let at = start + text[start..].find(line).unwrap();
    let text = format!(
        "{}<inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/>{}",
        &text[..at],
        &text[at + line.len()..]
    );
    let loaded = parse_urdf(&text, Path::new("geared_motor_point_rotor.urdf")).unwrap();
    let exact = loaded.model::<f64>(&ModelOptions::default()).unwrap();
    let reflected = loaded
        .model::<f64>(&ModelOptions {
            rotors: Rotors::Reflected,
            ..Default::default()
        })
        .unwrap();
    assert_eq!(reflected.nv(), 2);
    let (mut we, mut wr) = (Workspace::new(&exact), Workspace::new(&reflected));
    let mut rng = Rng::new(11);
    for _ in 0..10 {
        let (q, v) = consistent_state(&exact, &mut we, &mut rng);
        let (qr, vr, v_of) = restrict(&exact, &reflected, &q, &v);
        let tau_r = rng.vec(2, -1.0, 1.0);
        let mut tau = vec![0.0; exact.nv()];
        for (k, &i) in v_of.iter().enumerate() {
            tau[i] = tau_r[k];
        }
        let qdd = aba(&exact, &mut we, &q, &v, &tau).unwrap().to_vec();
        let qdd_exact: Vec<f64> = v_of.iter().map(|&i| qdd[i]).collect();
        let qdd_reflected = aba(&reflected, &mut wr, &qr, &vr, &tau_r).unwrap().to_vec();
        assert!(
            relative_error(&qdd_reflected, &qdd_exact) <= 1e-12,
            "{qdd_reflected:?} {qdd_exact:?}"
        );
        let m_exact = reduced_mass_matrix(&exact, &mut we, &q).unwrap();
        let m_reflected = crba(&reflected, &mut wr, &qr).unwrap().clone();
        assert!(relative_error(m_reflected.as_slice(), m_exact.as_slice()) <= 1e-12);
        // And inverse dynamics: the reflected torques are the exact ones projected (Xᵀτ).
        let zero = vec![0.0; 2];
        let t = rnea(&reflected, &mut wr, &qr, &vr, &zero).unwrap().to_vec();
        let nle_exact = {
            // XᵀC: the exact model's bias forces at the consistent qdd of zero independent acceleration,
            // read through aba: τ_ind = −(XᵀMX) qdd(τ=0) at that state.
            let qdd0 = aba(&exact, &mut we, &q, &v, &vec![0.0; exact.nv()])
                .unwrap()
                .to_vec();
            let qdd0: Vec<f64> = v_of.iter().map(|&i| qdd0[i]).collect();
            (0..2)
                .map(|r| -(0..2).map(|c| m_exact[(r, c)] * qdd0[c]).sum::<f64>())
                .collect::<Vec<f64>>()
        };
        assert!(
            relative_error(&t, &nle_exact) <= 1e-12,
            "{t:?} {nle_exact:?}"
        );
    }
}

/// Where the approximation does drop terms, it drops exactly those it is documented to: the mass
/// matrix's diagonal is the exact XᵀMX's (axisymmetric rotors, every carrier above its driving joints),
/// and on mit_humanoid_leg the knee–ankle entry differs by the belt drive's r² I of the ankle rotor (the
/// off-diagonal term of a rotor spanning two joints). The acceleration error is reported, not bounded.
#[test]
fn reflected_drops_exactly_the_documented_terms() {
    let reflected_options = ModelOptions {
        rotors: Rotors::Reflected,
        ..Default::default()
    };
    for path in [
        "tests/data/grbda/mini_cheetah.urdf",
        "tests/data/grbda/mit_humanoid_leg.urdf",
        "tests/data/grbda/mit_humanoid.urdf",
    ] {
        let exact: Model<f64> = load_model(path, false);
        let reflected = model_with(path, &reflected_options).unwrap();
        let (mut we, mut wr) = (Workspace::new(&exact), Workspace::new(&reflected));
        let mut rng = Rng::new(13);
        let (mut worst_qdd, mut worst_offdiag) = (0.0f64, 0.0f64);
        for _ in 0..5 {
            let (q, v) = consistent_state(&exact, &mut we, &mut rng);
            let (qr, vr, v_of) = restrict(&exact, &reflected, &q, &v);
            let m_exact = reduced_mass_matrix(&exact, &mut we, &q).unwrap();
            let m_reflected = crba(&reflected, &mut wr, &qr).unwrap().clone();
            let n = reflected.nv();
            let scale = (0..n).map(|i| m_exact[(i, i)]).fold(1.0f64, f64::max);
            for i in 0..n {
                let d = (m_exact[(i, i)] - m_reflected[(i, i)]).abs();
                assert!(d <= 1e-12 * scale, "{path}: diagonal {i} differs by {d:e}");
                for j in 0..n {
                    worst_offdiag =
                        common::worse(worst_offdiag, (m_exact[(i, j)] - m_reflected[(i, j)]).abs());
                }
            }
            if path.ends_with("mit_humanoid_leg.urdf") {
                let k = reflected.joint_index("hipy_to_knee_link").unwrap();
                let a = reflected.joint_index("knee_to_ankle").unwrap();
                let (k, a) = (reflected.joints[k].v_index, reflected.joints[a].v_index);
                let dropped = m_exact[(k, a)] - m_reflected[(k, a)];
                assert!((dropped - 144.0 * 1.6841e-4).abs() <= 1e-12, "{dropped}");
            }
            let tau_r = rng.vec(n, -1.0, 1.0);
            let mut tau = vec![0.0; exact.nv()];
            for (k, &i) in v_of.iter().enumerate() {
                tau[i] = tau_r[k];
            }
            let qdd = aba(&exact, &mut we, &q, &v, &tau).unwrap().to_vec();
            let qdd_exact: Vec<f64> = v_of.iter().map(|&i| qdd[i]).collect();
            let qdd_reflected = aba(&reflected, &mut wr, &qr, &vr, &tau_r).unwrap().to_vec();
            worst_qdd = worst_qdd.max(relative_error(&qdd_reflected, &qdd_exact));
        }
        eprintln!("{path}: reflected rotors: qdd relative error up to {worst_qdd:.2e}, mass matrix off-diagonal up to {worst_offdiag:.2e}");
        assert!(
            worst_offdiag > 0.0,
            "{path}: the approximation should drop something"
        );
    }
}

/// The generated code of the reflected mini_cheetah (`rotors = reflected`) is the interpreted reflected
/// model's: aba and crba to 1e-12.
#[test]
fn generated_reflected_code_matches_interpreted() {
    let model = model_with(
        "tests/data/grbda/mini_cheetah.urdf",
        &ModelOptions {
            rotors: Rotors::Reflected,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(mini_cheetah_reflected::NV, model.nv());
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(17);
    const NV: usize = mini_cheetah_reflected::NV;
    for _ in 0..10 {
        let q = rng.configuration(&model);
        let v = rng.vec(NV, -1.0, 1.0);
        let tau = rng.vec(NV, -1.0, 1.0);
        let mut qdd = [0.0; NV];
        mini_cheetah_reflected::f64::aba(
            q[..].try_into().unwrap(),
            v[..].try_into().unwrap(),
            tau[..].try_into().unwrap(),
            &mut qdd,
        );
        let interpreted = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        assert!(relative_error(&qdd, &interpreted) <= 1e-12);
        let mut m = [[0.0; NV]; NV];
        mini_cheetah_reflected::f64::crba(q[..].try_into().unwrap(), &mut m);
        let mi = crba(&model, &mut ws, &q).unwrap().clone();
        let interpreted: Vec<f64> = (0..NV * NV).map(|k| mi[(k / NV, k % NV)]).collect();
        assert!(relative_error(m.as_flattened(), &interpreted) <= 1e-12);
    }
}

fn geared_motor_with(edits: &[(&str, &str)]) -> embedyn::Loaded {
    crate::common::edited_model("models/loops/geared_motor.urdf", edits).unwrap()
}

/// Which side of a coupling is the rotor: the faster one, however the file writes the coupling or
/// declares its joints. The same mechanism written with the rotor as the predecessor (ratio 1/6), or
/// with no `independent` declarations (embedyn then picks the rotors as independent), reflects the same
/// rotors and gives the same accelerations; the driven link is never taken for a rotor. (A tester found
/// the driven forearm frozen as a "rotor", a quiet wrong answer.)
#[test]
fn the_rotor_is_the_faster_side_however_the_coupling_is_written() {
    let reflected = ModelOptions {
        rotors: Rotors::Reflected,
        ..Default::default()
    };
    let plain = geared_motor_with(&[]).model::<f64>(&reflected).unwrap();
    let swapped = geared_motor_with(&[(
        "<predecessor link=\"forearm\"/>\n    <successor link=\"elbow_rotor\"/>\n    <ratio value=\"6\"/>",
        "<predecessor link=\"elbow_rotor\"/>\n    <successor link=\"forearm\"/>\n    <ratio value=\"0.16666666666666666\"/>",
    )]);
    let undeclared = geared_motor_with(&[
        (" independent=\"true\"", ""),
        (" independent=\"false\"", ""),
    ]);
    let names = |m: &Model<f64>| m.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&plain), ["shoulder", "elbow"]);
    let mut rng = Rng::new(23);
    for loaded in [swapped, undeclared] {
        let model = loaded.model::<f64>(&reflected).unwrap();
        assert_eq!(names(&model), names(&plain));
        let (mut wa, mut wb) = (Workspace::new(&plain), Workspace::new(&model));
        for _ in 0..5 {
            let (q, v, tau) = (
                rng.vec(2, -1.0, 1.0),
                rng.vec(2, -1.0, 1.0),
                rng.vec(2, -1.0, 1.0),
            );
            let a = aba(&plain, &mut wa, &q, &v, &tau).unwrap().to_vec();
            let b = aba(&model, &mut wb, &q, &v, &tau).unwrap().to_vec();
            assert!(relative_error(&b, &a) <= 1e-12, "{a:?} {b:?}");
        }
    }
    // A faster side that carries a moving joint is no rotor: nothing is reflected.
    let path = "tests/data/scenes/rotor_with_children.urdf";
    let exact: Model<f64> = load_model(path, false);
    let model = model_with(path, &reflected).unwrap();
    assert_eq!(names(&model), names(&exact));
    assert!(model.has_constraints());
}

/// A ratio whose square times the rotor inertia overflows is an error naming the coupling, not an
/// armature of infinity.
#[test]
fn a_reflected_inertia_that_overflows_is_refused_at_the_coupling() {
    let loaded = geared_motor_with(&[(
        "<successor link=\"elbow_rotor\"/>\n    <ratio value=\"6\"/>",
        "<successor link=\"elbow_rotor\"/>\n    <ratio value=\"1e300\"/>",
    )]);
    let e = loaded
        .model::<f64>(&ModelOptions {
            rotors: Rotors::Reflected,
            ..Default::default()
        })
        .unwrap_err();
    assert!(
        matches!(e.kind, LoadErrorKind::ReflectedInertiaOverflow { ratio, .. } if ratio == 1e300),
        "{e}"
    );
    assert!(e.to_string().contains("coupling \"elbow_gear\""), "{e}");
}

/// A chain of 2,000 joints each mimicking the one above, written leaf first, locked at its top: every
/// joint is fixed at its value through the chain (the same model as the file without mimics, locked by
/// hand). Found by an attacker's trial of the first version, which passed over all joints until nothing
/// changed, looking each driver up by name: a 3,000-joint chain written so took 24.7 s (now 0.07 s).
#[test]
fn a_long_chain_of_mimic_joints_locks_from_its_top() {
    let n = 2000;
    let chain = |mimics: bool| {
        let mut links = String::from(
            r#"<link name="l0"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>"#,
        );
        let mut joints = Vec::new();
        for k in 1..=n {
            links += &format!(
                r#"<link name="l{k}"><inertial><origin xyz="0.01 0 0"/><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>"#
            );
            let mimic = if mimics && k > 1 {
                format!(
                    r#"<mimic joint="j{}" multiplier="0.99" offset="0.001"/>"#,
                    k - 1
                )
            } else {
                String::new()
            };
            joints.push(format!(
                r#"<joint name="j{k}" type="revolute"><origin xyz="0 0 0.1"/><parent link="l{}"/><child link="l{k}"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/>{mimic}</joint>"#,
                k - 1
            ));
        }
        joints.reverse();
        format!(
            r#"<robot name="mimic_chain">{links}{}</robot>"#,
            joints.concat()
        )
    };
    let lock = |joint: String, value: f64| LockedJoint { joint, value };
    let mut values = vec![0.3];
    for _ in 1..n {
        let above = *values.last().unwrap();
        values.push(0.0 + (0.99 * above + 0.001));
    }
    let model = |text: String, locks: Vec<LockedJoint>| {
        parse_urdf(&text, Path::new("mimic_chain.urdf"))
            .unwrap()
            .model::<f64>(&ModelOptions {
                locks,
                ..Default::default()
            })
            .unwrap()
    };
    let locked = model(chain(true), vec![lock("j1".into(), values[0])]);
    let by_hand = model(
        chain(false),
        values
            .iter()
            .enumerate()
            .map(|(k, &v)| lock(format!("j{}", k + 1), v))
            .collect(),
    );
    assert_eq!((locked.nv(), locked.nbodies()), (0, by_hand.nbodies()));
    assert_eq!(format!("{locked:?}"), format!("{by_hand:?}"));
}
