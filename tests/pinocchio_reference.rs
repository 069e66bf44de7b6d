//! Reproduces reference answers computed with Pinocchio 4.1.0 on example-robot-data 6.0.0 URDFs
//! (tests/data/pinocchio/README.md): ABA, RNEA, non-linear effects and the mass matrix, to 1e-9 relative;
//! the world pose of every link frame, interpreted and generated, to 2e-11 m / 2e-11 (quarter turns,
//! below).

use crate::common;

use common::{load_model, repo_path};
use embedyn::{aba, crba, forward_kinematics, link_poses, relative_error, rnea, Workspace};
use serde_json::Value;

const TOL: f64 = 1e-9;

/// A JSON array of numbers (the reference files' vectors).
pub fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn check_robot(name: &str, floating: bool) {
    let json = reference(name);
    let model = load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), floating);
    check_model(name, &model, &json);
}

/// The reference data `tests/data/pinocchio/{name}.json`.
pub fn reference(name: &str) -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(repo_path(&format!("tests/data/pinocchio/{name}.json"))).unwrap(),
    )
    .unwrap()
}

/// The locks a reference file records (`locked`: joint and value), as `--lock` options.
pub fn recorded_locks(json: &Value) -> Vec<embedyn::LockedJoint> {
    json["locked"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| embedyn::LockedJoint {
            joint: l["joint"].as_str().unwrap().to_string(),
            value: l["value"].as_f64().unwrap(),
        })
        .collect()
}

/// Our coordinates in Pinocchio's order: (q map, v map), ours → theirs, matched by joint name.
pub fn coordinate_maps(
    name: &str,
    model: &embedyn::Model<f64>,
    json: &Value,
) -> (Vec<usize>, Vec<usize>) {
    assert_eq!(
        model.nq() as u64,
        json["nq_angle"].as_u64().unwrap(),
        "{name}: nq"
    );
    assert_eq!(
        model.nv() as u64,
        json["nv"].as_u64().unwrap(),
        "{name}: nv"
    );
    // Joint order: ours is depth-first in file order; map Pinocchio's by name anyway.
    let pin_joints = json["joints"].as_array().unwrap();
    let mut v_map = vec![0usize; model.nv()]; // our v index -> Pinocchio v index
    let mut q_map = vec![0usize; model.nq()];
    for j in &model.joints {
        let pj = pin_joints
            .iter()
            .find(|p| p["name"].as_str() == Some(j.name.as_str()))
            .unwrap_or_else(|| panic!("{name}: joint {} not in the reference", j.name));
        let (pv, pq) = (
            pj["idx_v"].as_u64().unwrap() as usize,
            pj["idx_q_angle"].as_u64().unwrap() as usize,
        );
        for k in 0..j.nv() {
            v_map[j.v_index + k] = pv + k;
        }
        for k in 0..j.nq() {
            q_map[j.q_index + k] = pq + k;
        }
    }
    (q_map, v_map)
}

/// `model` against the reference `json` (named `name` in messages): aba, rnea, nle, crba and, where the
/// file has it, the generalized gravity.
pub fn check_model(name: &str, model: &embedyn::Model<f64>, json: &Value) {
    let (q_map, v_map) = coordinate_maps(name, model, json);
    let pick = |x: &[f64], map: &[usize]| -> Vec<f64> { map.iter().map(|&i| x[i]).collect() };
    let mut ws = Workspace::new(model);
    let samples = json["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 20);
    let mut worst = [0.0f64; 5];
    for s in samples {
        let q = pick(&vecf(&s["q_angle"]), &q_map);
        let v = pick(&vecf(&s["v"]), &v_map);
        let tau = pick(&vecf(&s["tau"]), &v_map);
        let qdd_ref = pick(&vecf(&s["qdd"]), &v_map);
        let qdd = aba(model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        worst[0] = worst[0].max(relative_error(&qdd, &qdd_ref));

        let a = pick(&vecf(&s["qdd_for_rnea"]), &v_map);
        let tau_ref = pick(&vecf(&s["tau_rnea"]), &v_map);
        let t = rnea(model, &mut ws, &q, &v, &a).unwrap().to_vec();
        worst[1] = worst[1].max(relative_error(&t, &tau_ref));

        let nle_ref = pick(&vecf(&s["nle"]), &v_map);
        let nle = rnea(model, &mut ws, &q, &v, &vec![0.0; model.nv()])
            .unwrap()
            .to_vec();
        worst[2] = worst[2].max(relative_error(&nle, &nle_ref));
        if let Some(g) = s.get("gravity_torque") {
            let g_ref = pick(&vecf(g), &v_map);
            let zeros = vec![0.0; model.nv()];
            let g = rnea(model, &mut ws, &q, &zeros, &zeros).unwrap().to_vec();
            worst[4] = worst[4].max(relative_error(&g, &g_ref));
        }

        let m_ref: Vec<Vec<f64>> = s["M"].as_array().unwrap().iter().map(vecf).collect();
        let m = crba(model, &mut ws, &q).unwrap();
        let mut ours = Vec::new();
        let mut theirs = Vec::new();
        for r in 0..model.nv() {
            for c in 0..model.nv() {
                ours.push(m[(r, c)]);
                theirs.push(m_ref[v_map[r]][v_map[c]]);
            }
        }
        worst[3] = worst[3].max(relative_error(&ours, &theirs));
    }
    eprintln!(
        "{name}: worst relative error aba {:.1e} rnea {:.1e} nle {:.1e} crba {:.1e} gravity {:.1e}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    for (what, w) in ["aba", "rnea", "nle", "crba", "gravity"].iter().zip(worst) {
        assert!(
            w <= TOL,
            "{name}: {what} differs from Pinocchio by {w:e} (relative)"
        );
    }
}

#[test]
fn double_pendulum() {
    check_robot("double_pendulum", false);
}

#[test]
fn double_pendulum_continuous() {
    check_robot("double_pendulum_continuous", false);
}

#[test]
fn ur5() {
    check_robot("ur5", false);
}

#[test]
fn panda() {
    check_robot("panda", false);
}

#[test]
fn solo12() {
    check_robot("solo12", false);
}

#[test]
fn solo12_floating_base() {
    check_robot("solo12_floating", true);
}

/// Armature (issue 10) against Pinocchio with `model.armature` set (tests/data/pinocchio/armature.py): a
/// three-joint arm whose armature comes from `<dynamics>` and from transmissions (so the loader's
/// reading is checked too), and a floating Solo-12 with armature on its twelve joints.
#[test]
fn armature_matches_pinocchio() {
    check_robot("armature_arm", false);
    check_robot("solo12_armature_floating", true);
}

mod ur5_generated {
    embedyn::robot!("tests/data/pinocchio/ur5.urdf", f64_only);
}

/// Link frames against Pinocchio's `framesForwardKinematics` (tests/data/pinocchio/frames.py): every link
/// on a moving body, interpreted (`link_poses`) on UR5, Panda and a floating Solo-12, and the generated
/// `kinematics` on UR5.
#[test]
fn link_frames_match_pinocchio() {
    for (name, floating) in [("ur5", false), ("panda", false), ("solo12_floating", true)] {
        let json: Value = serde_json::from_str(
            &std::fs::read_to_string(repo_path(&format!(
                "tests/data/pinocchio/{name}_frames.json"
            )))
            .unwrap(),
        )
        .unwrap();
        let model = load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), floating);
        let mut ws = Workspace::new(&model);
        let mut worst = 0.0f64;
        let mut compared = 0;
        for s in json["samples"].as_array().unwrap() {
            // No continuous joints in these robots: Pinocchio's q is ours, joint by joint in the same
            // depth-first file order (checked by name through the reference test above).
            let q = vecf(&s["q"]);
            assert_eq!(q.len(), model.nq());
            forward_kinematics(&model, &mut ws, &q, &vec![0.0; model.nv()]).unwrap();
            let frames = s["frames"].as_object().unwrap();
            let mut generated = [[0.0; 12]; ur5_generated::FRAMES.len()];
            if name == "ur5" {
                ur5_generated::f64::kinematics(&q.clone().try_into().unwrap(), &mut generated);
            }
            for (k, (link, x)) in link_poses(&model, &ws).enumerate() {
                let f = &frames[link];
                let (r, p) = (vecf(&f["R"]), vecf(&f["p"]));
                let ours: Vec<f64> = x
                    .rotation
                    .transpose()
                    .iter()
                    .chain(x.translation.iter())
                    .copied()
                    .collect();
                let theirs: Vec<f64> = r.iter().chain(&p).copied().collect();
                let e = ours
                    .iter()
                    .zip(&theirs)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, common::worse);
                worst = worst.max(e);
                if name == "ur5" {
                    assert_eq!(ur5_generated::FRAMES[k], link);
                    let g = generated[k]
                        .iter()
                        .zip(&theirs)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, common::worse);
                    worst = worst.max(g);
                }
                compared += 1;
            }
        }
        // Every link on a moving body is compared (Pinocchio also lists the world-fixed ones).
        let listed = model.bodies.iter().map(|b| b.links.len()).sum::<usize>();
        assert_eq!(compared, 5 * listed, "{name}");
        eprintln!("{name}: {listed} link frames, worst difference from Pinocchio {worst:.1e}");
        // The files write quarter turns to 11 digits (`1.57079632679`, 4.9e-12 rad short of π/2), which
        // embedyn reads as exact quarter turns and Pinocchio literally (docs/model-format.md): over the
        // UR5's reach of about 1 m that moves its frames by up to 1e-11 m (measured 9.9e-12; 1e-16 with
        // the literal reading). Everything else agrees to rounding.
        assert!(
            worst <= 2e-11,
            "{name}: link frames differ from Pinocchio by {worst:e}"
        );
    }
}

/// Models of example-robot-data 6.0.0 that embedyn once refused while Pinocchio loads them
/// (tests/data/erd/README.md): they load, with only the warnings their data deserve, and agree with
/// Pinocchio's ABA, RNEA, non-linear effects and mass matrix (as M·w) to 1e-9 relative.
fn check_formerly_refused(name: &str, expected_warnings: &[&str]) {
    let path = repo_path(&format!("tests/data/erd/{name}.urdf"));
    let loaded = embedyn::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let warnings: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings.len(),
        expected_warnings.len(),
        "{name}: {warnings:#?}"
    );
    for (w, expected) in warnings.iter().zip(expected_warnings) {
        assert!(w.contains(expected), "{name}: `{expected}` not in {w}");
    }
    let model = loaded
        .model::<f64>(&embedyn::ModelOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let json: Value = serde_json::from_str(
        &std::fs::read_to_string(repo_path(&format!("tests/data/erd/{name}.json"))).unwrap(),
    )
    .unwrap();
    let (q_map, v_map) = coordinate_maps(name, &model, &json);
    let pick = |x: &Value, map: &[usize]| -> Vec<f64> {
        let x = vecf(x);
        map.iter().map(|&i| x[i]).collect()
    };
    let mut ws = Workspace::new(&model);
    let mut worst = [0.0f64; 4];
    let samples = json["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 4);
    for s in samples {
        let (q, v) = (pick(&s["q_angle"], &q_map), pick(&s["v"], &v_map));
        let qdd = aba(&model, &mut ws, &q, &v, &pick(&s["tau"], &v_map))
            .unwrap()
            .to_vec();
        worst[0] = worst[0].max(relative_error(&qdd, &pick(&s["qdd"], &v_map)));
        let tau = rnea(&model, &mut ws, &q, &v, &pick(&s["qdd_for_rnea"], &v_map))
            .unwrap()
            .to_vec();
        worst[1] = worst[1].max(relative_error(&tau, &pick(&s["tau_rnea"], &v_map)));
        let nle = rnea(&model, &mut ws, &q, &v, &vec![0.0; model.nv()])
            .unwrap()
            .to_vec();
        worst[2] = worst[2].max(relative_error(&nle, &pick(&s["nle"], &v_map)));
        let w = pick(&s["w"], &v_map);
        let m = crba(&model, &mut ws, &q).unwrap();
        let m_w: Vec<f64> = (0..model.nv())
            .map(|r| (0..model.nv()).map(|c| m[(r, c)] * w[c]).sum())
            .collect();
        worst[3] = worst[3].max(relative_error(&m_w, &pick(&s["M_w"], &v_map)));
    }
    eprintln!(
        "{name}: worst relative error aba {:.1e} rnea {:.1e} nle {:.1e} crba·w {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    for (what, w) in ["aba", "rnea", "nle", "crba"].iter().zip(worst) {
        assert!(
            w <= TOL,
            "{name}: {what} differs from Pinocchio by {w:e} (relative)"
        );
    }
}

/// icub: inertias such as the head's (zeros and 2.4e-35 off the diagonal, for a 1.3 kg link whose
/// centre of mass is 11 cm from its frame) are rounding residue, not a non-PSD tensor: no warning but
/// the one for the joints' ignored damping and friction.
#[test]
fn icub_loads_without_inertia_warnings_and_matches_pinocchio() {
    check_formerly_refused("icub", &["<dynamics damping/friction> of 32 joint(s)"]);
}

/// tiago's antenna inertia (1e-6 kg, smallest eigenvalue −58 % of its largest entry) is not positive
/// semi-definite: it loads with a warning naming both links that carry it (one warning: the message is
/// the same for both), also where it enters the dynamics.
#[test]
fn tiago_antenna_inertia_loads_with_a_warning_and_matches_pinocchio() {
    check_formerly_refused(
        "mobile_manipulator_antenna",
        &["link \"base_antenna_link\" <inertial> <inertia>: the inertia tensor is not positive semi-definite (ixx=0.00000002371, iyy=0.00000002833, izz=0.00000003849, ixy=0.00000006119, ixz=0.00000001179, iyz=0.00000000774; smallest eigenvalue -3.535e-8): no rigid body has it; loaded as given (the same for link \"torso_antenna_link\" <inertial> <inertia>)"],
    );
}

/// romeo and romeo_laas_small: the hand joints move massless links (romeo's `RHand` and the finger
/// joints that mimic it: the whole aggregate link has no inertia), so their accelerations are
/// undetermined; embedyn refuses them naming the joint (docs/model-format.md), as the only example-robot-data
/// models besides alex_psyonic_hands it refuses.
#[test]
fn romeo_hands_are_refused_naming_the_joint() {
    for (name, joint) in [
        ("romeo", "joint \"RHand\""),
        ("romeo_laas_small", "joint \"r_gripper_joint\""),
    ] {
        let path = repo_path(&format!("tests/data/erd/{name}.urdf"));
        let err = embedyn::load(&path)
            .and_then(|l| l.model::<f64>(&embedyn::ModelOptions::default()))
            .map(|_| ())
            .expect_err(name)
            .to_string();
        assert!(
            err.contains(&format!("{name}.urdf:"))
                && err.contains(joint)
                && err.contains("no inertia about its axis"),
            "{err}"
        );
    }
}

/// A generated module's f64 `aba`, `rnea` and `crba` (M row-major) behind slices, for
/// [`check_generated`].
pub type GeneratedFunctions = (
    fn(&[f64], &[f64], &[f64], &mut [f64]),
    fn(&[f64], &[f64], &[f64], &mut [f64]),
    fn(&[f64], &mut Vec<f64>),
);

/// The [`GeneratedFunctions`] of the module `robot!` expanded into `$m` (with `only(aba, rnea, crba)`).
#[macro_export]
macro_rules! generated_functions {
    ($m:ident) => {{
        let functions: $crate::pinocchio_reference::GeneratedFunctions = (
            |q, v, t, out| {
                $m::f64::aba(
                    q.try_into().unwrap(),
                    v.try_into().unwrap(),
                    t.try_into().unwrap(),
                    out.try_into().unwrap(),
                )
            },
            |q, v, a, out| {
                $m::f64::rnea(
                    q.try_into().unwrap(),
                    v.try_into().unwrap(),
                    a.try_into().unwrap(),
                    out.try_into().unwrap(),
                )
            },
            |q, out| {
                let mut m = [[0.0; $m::NV]; $m::NV];
                $m::f64::crba(q.try_into().unwrap(), &mut m);
                *out = m.iter().flatten().copied().collect();
            },
        );
        functions
    }};
}

/// Generated code against the reference `json`: aba, rnea and crba to 1e-9 relative; `model` is the
/// interpreted model of the same file and options (for the coordinate order).
pub fn check_generated(
    name: &str,
    model: &embedyn::Model<f64>,
    json: &Value,
    (aba_g, rnea_g, crba_g): GeneratedFunctions,
) {
    let (q_map, v_map) = coordinate_maps(name, model, json);
    let pick = |x: &Value, map: &[usize]| -> Vec<f64> {
        let x = vecf(x);
        map.iter().map(|&i| x[i]).collect()
    };
    let nv = model.nv();
    let mut worst = [0.0f64; 3];
    for s in json["samples"].as_array().unwrap() {
        let q = pick(&s["q_angle"], &q_map);
        let v = pick(&s["v"], &v_map);
        let mut out = vec![0.0; nv];
        aba_g(&q, &v, &pick(&s["tau"], &v_map), &mut out);
        worst[0] = worst[0].max(relative_error(&out, &pick(&s["qdd"], &v_map)));
        rnea_g(&q, &v, &pick(&s["qdd_for_rnea"], &v_map), &mut out);
        worst[1] = worst[1].max(relative_error(&out, &pick(&s["tau_rnea"], &v_map)));
        let mut m = Vec::new();
        crba_g(&q, &mut m);
        let rows: Vec<Vec<f64>> = s["M"].as_array().unwrap().iter().map(vecf).collect();
        let theirs: Vec<f64> = (0..nv * nv)
            .map(|k| rows[v_map[k / nv]][v_map[k % nv]])
            .collect();
        worst[2] = worst[2].max(relative_error(&m, &theirs));
    }
    eprintln!(
        "{name} generated: aba {:.1e} rnea {:.1e} crba {:.1e}",
        worst[0], worst[1], worst[2]
    );
    assert!(worst.iter().all(|&w| w <= TOL), "{name}: {worst:?}");
}
