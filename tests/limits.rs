//! Joint limits and name constants (issue 11, item 5): `<limit lower upper velocity effort>` read as Pinocchio
//! reads it (tests/data/pinocchio/limits.json, written by limits.py with Pinocchio 4.1), kept through scene
//! options, and emitted as `LOWER`/`UPPER`/`VELOCITY`/`EFFORT` equal to the interpreted model's; the
//! `joints`, `q_index`, `v_index` and `frames` constants index the names they stand for.

use crate::common;

use common::{load_model, repo_path};
use embedyn::{JointLimits, LockedJoint, Model, ModelOptions, Rotors};
use serde_json::Value;

mod panda {
    embedyn::robot!("tests/data/pinocchio/panda.urdf", only(aba));
}
mod panda_locked {
    embedyn::robot!(
        "tests/data/pinocchio/panda.urdf",
        f64_only,
        only(aba),
        lock(panda_joint4 = -1.0)
    );
}
mod solo {
    embedyn::robot!(
        "tests/data/pinocchio/solo12.urdf",
        floating,
        only(kinematics)
    );
}
mod pendulum {
    embedyn::robot!(
        "tests/data/pinocchio/double_pendulum_continuous.urdf",
        f32_only,
        only(aba)
    );
}

fn model_with(path: &str, options: &ModelOptions) -> Model<f64> {
    embedyn::load(&repo_path(path))
        .and_then(|l| l.model::<f64>(options))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Every limit Pinocchio reads from the file, embedyn reads alike (exactly: both parse the decimal text
/// to the nearest f64); where Pinocchio's number is no limit (a continuous joint's position, the
/// free-flyer root), embedyn has none.
#[test]
fn limits_are_pinocchios() {
    let text = std::fs::read_to_string(repo_path("tests/data/pinocchio/limits.json")).unwrap();
    let reference: Value = serde_json::from_str(&text).unwrap();
    let robots = reference["robots"].as_object().unwrap();
    assert_eq!(robots.len(), 6);
    let mut compared = 0;
    for (robot, r) in robots {
        let path = format!("tests/data/pinocchio/{}", r["urdf"].as_str().unwrap());
        let model: Model<f64> = load_model(&path, r["floating"].as_bool().unwrap());
        let joints = r["joints"].as_array().unwrap();
        assert_eq!(joints.len(), model.joints.len(), "{robot}");
        for j in joints {
            let name = j["name"].as_str().unwrap();
            let ours = model.joints[model.joint_index(name).unwrap()].limits;
            let attributes: Vec<&str> = j["attributes"]
                .as_array()
                .unwrap()
                .iter()
                .map(|a| a.as_str().unwrap())
                .collect();
            for (key, got) in [
                ("lower", ours.lower),
                ("upper", ours.upper),
                ("velocity", ours.velocity),
                ("effort", ours.effort),
            ] {
                let want = match j[key].as_f64() {
                    Some(x) if attributes.contains(&key) => Some(x),
                    _ => None,
                };
                assert_eq!(got, want, "{robot}: joint {name}: {key}");
                compared += usize::from(want.is_some());
            }
        }
    }
    // 2 + 2 (velocity, effort) + 9 + 6 + 12 + 3 joints with four limits each, less the continuous
    // pendulum's two position limits each.
    assert_eq!(compared, 4 * (2 + 2 + 9 + 6 + 12 + 3) - 4);
}

/// `LOWER`, `UPPER`, `VELOCITY` and `EFFORT` hold the interpreted model's limits per coordinate, in f64 and
/// (rounded once, as `Model::cast` rounds them) in f32; an absent bound is -∞ (`LOWER`) or +∞.
fn assert_tables<S: embedyn::Real + PartialEq + std::fmt::Debug>(
    model: &Model<f64>,
    tables: [&[S]; 4],
    what: &str,
) {
    let model: Model<S> = model.cast();
    let inf = S::from_f64(f64::INFINITY);
    let mut want: [Vec<S>; 4] = Default::default();
    for j in &model.joints {
        let JointLimits {
            lower,
            upper,
            velocity,
            effort,
        } = j.limits;
        for _ in 0..j.nq() {
            want[0].push(lower.unwrap_or(-inf));
            want[1].push(upper.unwrap_or(inf));
        }
        for _ in 0..j.nv() {
            want[2].push(velocity.unwrap_or(inf));
            want[3].push(effort.unwrap_or(inf));
        }
    }
    for (k, name) in ["LOWER", "UPPER", "VELOCITY", "EFFORT"].iter().enumerate() {
        assert_eq!(tables[k], &want[k][..], "{what}::{name}");
    }
}

#[test]
fn generated_limits_are_the_interpreted_models() {
    let panda_model = load_model::<f64>("tests/data/pinocchio/panda.urdf", false);
    use panda::{f32 as p32, f64 as p64};
    assert_tables(
        &panda_model,
        [&p64::LOWER, &p64::UPPER, &p64::VELOCITY, &p64::EFFORT],
        "panda::f64",
    );
    assert_tables(
        &panda_model,
        [&p32::LOWER, &p32::UPPER, &p32::VELOCITY, &p32::EFFORT],
        "panda::f32",
    );
    assert_eq!(panda::f64::LOWER[3], -3.0718);
    assert_eq!(panda::f32::UPPER[8], 0.04f32);
    assert_eq!(panda::f64::EFFORT[0], 87.0);

    let solo_model = load_model::<f64>("tests/data/pinocchio/solo12.urdf", true);
    use solo::f64 as s64;
    assert_tables(
        &solo_model,
        [&s64::LOWER, &s64::UPPER, &s64::VELOCITY, &s64::EFFORT],
        "solo::f64",
    );
    // The free-flyer root has no limits: ±∞ on all 7 coordinates and 6 velocities.
    assert!(solo::f64::LOWER[..7]
        .iter()
        .all(|&x| x == f64::NEG_INFINITY));
    assert!(solo::f32::EFFORT[..6].iter().all(|&x| x == f32::INFINITY));
    assert_eq!(solo::f64::UPPER[7], 10.0);

    // Continuous joints: no position limits, velocity and effort as written (0 in this file).
    let pendulum_model = load_model::<f64>(
        "tests/data/pinocchio/double_pendulum_continuous.urdf",
        false,
    );
    use pendulum::f32 as d32;
    assert_tables(
        &pendulum_model,
        [&d32::LOWER, &d32::UPPER, &d32::VELOCITY, &d32::EFFORT],
        "pendulum::f32",
    );
    assert_eq!(pendulum::f32::LOWER, [f32::NEG_INFINITY; 2]);
    assert_eq!(pendulum::f32::VELOCITY, [0.0; 2]);
}

/// A locked joint's limits leave with it, generated and interpreted; a reflected rotor's too.
#[test]
fn scene_options_drop_the_limits_of_the_joints_they_remove() {
    let locked = model_with(
        "tests/data/pinocchio/panda.urdf",
        &ModelOptions {
            locks: vec![LockedJoint {
                joint: "panda_joint4".into(),
                value: -1.0,
            }],
            ..Default::default()
        },
    );
    use panda_locked::f64 as l64;
    assert_tables(
        &locked,
        [&l64::LOWER, &l64::UPPER, &l64::VELOCITY, &l64::EFFORT],
        "panda_locked::f64",
    );
    let full = &panda::f64::LOWER;
    let mut without_4 = full.to_vec();
    without_4.remove(3);
    assert_eq!(panda_locked::f64::LOWER[..], without_4[..]);
    assert_eq!(
        panda_locked::JOINTS[panda_locked::joints::PANDA_JOINT5],
        "panda_joint5"
    );
    assert_eq!(panda_locked::q_index::PANDA_JOINT5, 3);

    let path = "tests/data/grbda/mini_cheetah.urdf";
    let exact = model_with(path, &Default::default());
    let reflected = model_with(
        path,
        &ModelOptions {
            rotors: Rotors::Reflected,
            ..Default::default()
        },
    );
    assert!(reflected.joints.len() < exact.joints.len());
    for j in &reflected.joints {
        let e = &exact.joints[exact.joint_index(&j.name).unwrap()];
        assert_eq!(j.limits, e.limits, "{}", j.name);
        let floating = j.joint_type == embedyn::JointType::Floating;
        assert_eq!(j.limits.lower.is_some(), !floating, "{}", j.name);
    }
}

/// `JOINTS[joints::X]`, `FRAMES[frames::X]`, `q_index::X` and `v_index::X` name and index what they
/// say, across a free-flyer root (7 coordinates, 6 velocities).
#[test]
fn index_constants_index_the_right_names() {
    assert_eq!(panda::JOINTS[panda::joints::PANDA_JOINT1], "panda_joint1");
    assert_eq!(
        panda::JOINTS[panda::joints::PANDA_FINGER_JOINT2],
        "panda_finger_joint2"
    );
    assert_eq!(panda::FRAMES[panda::frames::PANDA_LINK7], "panda_link7");
    assert_eq!(
        panda::FRAMES[panda::frames::PANDA_LEFTFINGER],
        "panda_leftfinger"
    );
    // panda_hand and panda_hand_tcp are fixed to panda_link7 (merged links are frames too).
    assert_eq!(
        panda::FRAMES[panda::frames::PANDA_HAND_TCP],
        "panda_hand_tcp"
    );

    assert_eq!(solo::joints::ROOT_JOINT, 0);
    assert_eq!(solo::JOINTS[solo::joints::HR_KFE], "HR_KFE");
    assert_eq!(solo::FRAMES[solo::frames::FL_FOOT], "FL_FOOT");
    assert_eq!(solo::FRAMES[solo::frames::BASE_LINK], "base_link");
    assert_eq!(
        (solo::q_index::ROOT_JOINT, solo::v_index::ROOT_JOINT),
        (0, 0)
    );
    assert_eq!((solo::q_index::FL_HAA, solo::v_index::FL_HAA), (7, 6));

    let model = load_model::<f64>("tests/data/pinocchio/solo12.urdf", true);
    for name in ["FL_HAA", "FR_KFE", "HL_HFE", "HR_KFE"] {
        let j = &model.joints[model.joint_index(name).unwrap()];
        let (i, q, v) = match name {
            "FL_HAA" => (
                solo::joints::FL_HAA,
                solo::q_index::FL_HAA,
                solo::v_index::FL_HAA,
            ),
            "FR_KFE" => (
                solo::joints::FR_KFE,
                solo::q_index::FR_KFE,
                solo::v_index::FR_KFE,
            ),
            "HL_HFE" => (
                solo::joints::HL_HFE,
                solo::q_index::HL_HFE,
                solo::v_index::HL_HFE,
            ),
            _ => (
                solo::joints::HR_KFE,
                solo::q_index::HR_KFE,
                solo::v_index::HR_KFE,
            ),
        };
        assert_eq!(solo::JOINTS[i], name);
        assert_eq!((q, v), (j.q_index, j.v_index), "{name}");
    }
    // The pose `kinematics` writes at `frames::FL_FOOT` is the interpreted pose of that link.
    let q: Vec<f64> = (0..solo::NQ)
        .map(|i| if i == 6 { 1.0 } else { 0.1 * i as f64 })
        .collect();
    let mut q = q;
    model.normalize_configuration(&mut q);
    let mut frames = [[0.0; 12]; solo::FRAMES.len()];
    solo::f64::kinematics(&q.clone().try_into().unwrap(), &mut frames);
    let mut ws = embedyn::Workspace::new(&model);
    embedyn::forward_kinematics(&model, &mut ws, &q, &vec![0.0; model.nv()]).unwrap();
    let foot = embedyn::link_poses(&model, &ws)
        .find(|(n, _)| *n == "FL_FOOT")
        .unwrap()
        .1;
    let p = foot.translation;
    let got = &frames[solo::frames::FL_FOOT][9..];
    assert!(
        (got[0] - p.x).abs() + (got[1] - p.y).abs() + (got[2] - p.z).abs() < 1e-12,
        "{got:?} vs {p:?}"
    );
}

/// A missing attribute is absent, not 0 and not an error; a continuous joint's `lower`/`upper` and every
/// limit of a fixed joint are not read (as in Pinocchio).
#[test]
fn missing_limits_are_absent() {
    let text = r#"<robot name="r">
      <link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="c"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="d"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="e"/>
      <joint name="upper_only" type="revolute"><parent link="a"/><child link="b"/><limit upper="1.5"/></joint>
      <joint name="wheel" type="continuous"><parent link="b"/><child link="c"/>
        <limit lower="not a number" upper="-7" effort="2.5"/></joint>
      <joint name="slide" type="prismatic"><parent link="c"/><child link="d"/><limit velocity="0.25"/></joint>
      <joint name="weld" type="fixed"><parent link="d"/><child link="e"/><limit lower="3" upper="-3"/></joint>
    </robot>"#;
    let loaded = embedyn::codegen::parse_urdf(text, "r.urdf".as_ref()).unwrap();
    let model = loaded.model::<f64>(&Default::default()).unwrap();
    let limits = |name: &str| model.joints[model.joint_index(name).unwrap()].limits;
    let none = JointLimits::none();
    assert_eq!(
        limits("upper_only"),
        JointLimits {
            upper: Some(1.5),
            ..none
        }
    );
    assert_eq!(
        limits("wheel"),
        JointLimits {
            effort: Some(2.5),
            ..none
        }
    );
    assert_eq!(
        limits("slide"),
        JointLimits {
            velocity: Some(0.25),
            ..none
        }
    );
    // f32 rounds each limit once.
    let m32 = loaded.model::<f32>(&Default::default()).unwrap();
    assert_eq!(m32.joints[2].limits.velocity, Some(0.25f32));
}

/// The runtime's builder checks what it is given, as the loader does.
#[test]
fn the_builder_refuses_bad_limits() {
    use embedyn::nalgebra::Vector3;
    use embedyn::{JointType, ModelError, SpatialInertia, Transform};
    let mut b = Model::<f64>::builder("r");
    let inertia = SpatialInertia::from_com(
        1.0,
        Vector3::zeros(),
        embedyn::nalgebra::Matrix3::identity(),
    );
    let hinge = b
        .add_body(
            None,
            "hinge",
            JointType::Revolute,
            Vector3::z(),
            Transform::identity(),
            "a",
            inertia,
        )
        .unwrap();
    let wheel = b
        .add_body(
            Some(hinge),
            "wheel",
            JointType::Continuous,
            Vector3::z(),
            Transform::identity(),
            "b",
            inertia,
        )
        .unwrap();
    let none = JointLimits::none();
    let bad = |e: Result<(), ModelError>| match e {
        Err(ModelError::BadLimit { limit, .. }) => limit,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        bad(b.set_limits(
            hinge,
            JointLimits {
                lower: Some(1.0),
                upper: Some(0.0),
                ..none
            }
        )),
        "lower"
    );
    assert_eq!(
        bad(b.set_limits(
            hinge,
            JointLimits {
                upper: Some(f64::NAN),
                ..none
            }
        )),
        "upper"
    );
    assert_eq!(
        bad(b.set_limits(
            hinge,
            JointLimits {
                effort: Some(-1.0),
                ..none
            }
        )),
        "effort"
    );
    assert_eq!(
        bad(b.set_limits(
            wheel,
            JointLimits {
                lower: Some(-1.0),
                ..none
            }
        )),
        "lower"
    );
    b.set_limits(
        wheel,
        JointLimits {
            velocity: Some(3.0),
            ..none
        },
    )
    .unwrap();
    b.set_limits(
        hinge,
        JointLimits {
            lower: Some(-1.0),
            upper: Some(1.0),
            ..none
        },
    )
    .unwrap();
    let model = b.build().unwrap();
    assert_eq!(model.joints[0].limits.upper, Some(1.0));
    assert_eq!(model.joints[1].limits.velocity, Some(3.0));
}
