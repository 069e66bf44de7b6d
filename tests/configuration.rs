//! The configuration space: `integrate(q, v)` and `difference(q0, q1)` against Pinocchio 4.1
//! (tests/data/pinocchio/configuration.py), interpreted and generated, to 1e-9; their invariants on random
//! trees (q0 ⊕ (q1 ⊖ q0) = q1, (q ⊕ v) ⊖ q = v, q ⊖ q = 0, at tiny angles and near π); and the derivative
//! of every body's pose along integrate(q, ε v) against the body velocities of forward kinematics.

use crate::common::{self, load_model, Rng};
use crate::pinocchio_reference::{coordinate_maps, vecf};
use embedyn::random::SplitMix64;
use embedyn::{
    difference, forward_kinematics, integrate, random_configuration, JointType, Model, Workspace,
};
use serde_json::Value;
use std::f64::consts::PI;

mod solo12_floating {
    embedyn::robot!(
        "tests/data/pinocchio/solo12_floating.urdf",
        floating,
        only(integrate, difference)
    );
}
mod ur5 {
    embedyn::robot!(
        "tests/data/pinocchio/ur5.urdf",
        f64_only,
        only(integrate, difference)
    );
}

const TOL: f64 = 1e-9;

/// The largest difference of two configurations, each floating joint's quaternion up to its sign,
/// relative as docs/conventions.md defines it.
fn configuration_error(model: &Model<f64>, a: &[f64], b: &[f64]) -> f64 {
    let mut a = a.to_vec();
    for j in &model.joints {
        if j.joint_type == JointType::Floating {
            let r = j.q_index + 3..j.q_index + 7;
            let dot: f64 = a[r.clone()]
                .iter()
                .zip(&b[r.clone()])
                .map(|(x, y)| x * y)
                .sum();
            if dot < 0.0 {
                a[r].iter_mut().for_each(|x| *x = -*x);
            }
        }
    }
    embedyn::relative_error(&a, b)
}

/// The interpreted and generated answers for one robot of configuration.json.
#[derive(Clone, Copy)]
struct Engines {
    integrate: fn(&[f64], &[f64]) -> Vec<f64>,
    difference: fn(&[f64], &[f64]) -> Vec<f64>,
}

fn check_against_pinocchio(name: &str, floating: bool, generated: Engines) {
    let json: Value = serde_json::from_str(
        &std::fs::read_to_string(common::repo_path("tests/data/pinocchio/configuration.json"))
            .unwrap(),
    )
    .unwrap();
    assert_eq!(json["pinocchio_version"], "4.1.0");
    let robot = &json["robots"][name];
    let model = load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), floating);
    let (q_map, v_map) =
        coordinate_maps(name, &model, &crate::pinocchio_reference::reference(name));
    let pick = |x: &[f64], map: &[usize]| -> Vec<f64> { map.iter().map(|&i| x[i]).collect() };
    let mut worst = [0.0f64; 4];
    let samples = robot["integrate"].as_array().unwrap();
    assert!(samples.len() >= 10);
    for s in samples {
        let q = pick(&vecf(&s["q"]), &q_map);
        let v = pick(&vecf(&s["v"]), &v_map);
        let want = pick(&vecf(&s["q_out"]), &q_map);
        let mut got = vec![0.0; model.nq()];
        integrate(&model, &q, &v, &mut got).unwrap();
        let e = configuration_error(&model, &got, &want);
        assert!(e < TOL, "{name}: integrate at angle {}: {e:e}", s["angle"]);
        worst[0] = worst[0].max(e);
        // Pinocchio's sign of the quaternion too (the one nearer q's).
        assert!(embedyn::relative_error(&got, &want) < TOL, "{name}: sign");
        let g = (generated.integrate)(&q, &v);
        let e = configuration_error(&model, &g, &want);
        assert!(
            e < TOL,
            "{name}: generated integrate at {}: {e:e}",
            s["angle"]
        );
        worst[1] = worst[1].max(e);
    }
    for s in robot["difference"].as_array().unwrap() {
        let q0 = pick(&vecf(&s["q0"]), &q_map);
        let q1 = pick(&vecf(&s["q1"]), &q_map);
        let want = pick(&vecf(&s["v"]), &v_map);
        let mut got = vec![0.0; model.nv()];
        difference(&model, &q0, &q1, &mut got).unwrap();
        let e = embedyn::relative_error(&got, &want);
        assert!(e < TOL, "{name}: difference at angle {}: {e:e}", s["angle"]);
        worst[2] = worst[2].max(e);
        let g = (generated.difference)(&q0, &q1);
        let e = embedyn::relative_error(&g, &want);
        assert!(
            e < TOL,
            "{name}: generated difference at {}: {e:e}",
            s["angle"]
        );
        worst[3] = worst[3].max(e);
    }
    println!(
        "{name}: integrate {:.1e} (generated {:.1e}), difference {:.1e} (generated {:.1e})",
        worst[0], worst[1], worst[2], worst[3]
    );
}

macro_rules! generated_engines {
    ($module:ident) => {
        Engines {
            integrate: |q, v| {
                let mut out = [0.0; $module::NQ];
                $module::f64::integrate(q.try_into().unwrap(), v.try_into().unwrap(), &mut out);
                out.to_vec()
            },
            difference: |q0, q1| {
                let mut out = [0.0; $module::NV];
                $module::f64::difference(q0.try_into().unwrap(), q1.try_into().unwrap(), &mut out);
                out.to_vec()
            },
        }
    };
}

#[test]
fn integrate_and_difference_match_pinocchio_on_a_floating_quadruped() {
    check_against_pinocchio("solo12_floating", true, generated_engines!(solo12_floating));
}

#[test]
fn integrate_and_difference_match_pinocchio_on_an_arm() {
    check_against_pinocchio("ur5", false, generated_engines!(ur5));
}

/// A velocity whose floating joints (if any) rotate by `angle` about a random axis.
fn velocity_with_angle(rng: &mut Rng, model: &Model<f64>, angle: Option<f64>) -> Vec<f64> {
    let mut v = rng.vec(model.nv(), -2.0, 2.0);
    if let Some(angle) = angle {
        for j in &model.joints {
            if j.joint_type == JointType::Floating {
                let axis = rng.vec(3, -1.0, 1.0);
                let n = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
                for k in 0..3 {
                    v[j.v_index + 3 + k] = angle * axis[k] / n;
                }
            }
        }
    }
    v
}

#[test]
fn difference_inverts_integrate_at_every_angle() {
    let mut rng = Rng::new(11);
    let angles = [
        None,
        Some(0.0),
        Some(1e-300),
        Some(1e-12),
        Some(1e-8),
        Some(1e-4),
        Some(0.099),
        Some(0.1),
        Some(0.101),
        Some(1.0),
        Some(PI / 2.0),
        Some(3.0),
        Some(PI - 1e-6),
        Some(PI - 1e-9),
    ];
    for n in [1, 3, 8] {
        let model = common::random_tree(&mut rng, n, true);
        let (nq, nv) = (model.nq(), model.nv());
        for angle in angles {
            for _ in 0..5 {
                let q = rng.configuration(&model);
                let v = velocity_with_angle(&mut rng, &model, angle);
                let (mut q1, mut back) = (vec![0.0; nq], vec![0.0; nv]);
                integrate(&model, &q, &v, &mut q1).unwrap();
                difference(&model, &q, &q1, &mut back).unwrap();
                let e = embedyn::relative_error(&back, &v);
                assert!(e < 1e-9, "n {n}, angle {angle:?}: (q ⊕ v) ⊖ q = v to {e:e}");
                // Of the quaternion's sign: q1 with its quaternion negated is the same configuration.
                for j in &model.joints {
                    if j.joint_type == JointType::Floating {
                        q1[j.q_index + 3..j.q_index + 7]
                            .iter_mut()
                            .for_each(|x| *x = -*x);
                    }
                }
                difference(&model, &q, &q1, &mut back).unwrap();
                assert!(embedyn::relative_error(&back, &v) < 1e-9, "n {n}: sign");
                // q ⊖ q = 0 exactly.
                difference(&model, &q, &q, &mut back).unwrap();
                assert!(back.iter().all(|&x| x == 0.0), "q ⊖ q = {back:?}");
            }
        }
    }
}

#[test]
fn integrate_inverts_difference_and_takes_the_least_rotation() {
    let mut rng = Rng::new(12);
    for n in [1, 4, 9] {
        let model = common::random_tree(&mut rng, n, true);
        let (nq, nv) = (model.nq(), model.nv());
        for _ in 0..50 {
            let q0 = rng.configuration(&model);
            let q1 = rng.configuration(&model);
            let (mut v, mut back) = (vec![0.0; nv], vec![0.0; nq]);
            difference(&model, &q0, &q1, &mut v).unwrap();
            integrate(&model, &q0, &v, &mut back).unwrap();
            let e = configuration_error(&model, &back, &q1);
            assert!(e < 1e-12, "n {n}: q0 ⊕ (q1 ⊖ q0) = q1 to {e:e}");
            for j in &model.joints {
                if j.joint_type == JointType::Floating {
                    let w = &v[j.v_index + 3..j.v_index + 6];
                    let angle = w.iter().map(|x| x * x).sum::<f64>().sqrt();
                    assert!(angle <= PI + 1e-12, "rotation by {angle} > π");
                }
            }
        }
    }
}

#[test]
fn integrate_beyond_half_a_turn_wraps_to_the_least_rotation() {
    // Rotating by 2π − α about an axis is rotating by α about the opposite one.
    let mut rng = Rng::new(13);
    let model = common::random_tree(&mut rng, 2, true);
    let q = rng.configuration(&model);
    let mut v = vec![0.0; model.nv()];
    v[5] = 2.0 * PI - 0.25;
    let (mut q1, mut back) = (vec![0.0; model.nq()], vec![0.0; model.nv()]);
    integrate(&model, &q, &v, &mut q1).unwrap();
    difference(&model, &q, &q1, &mut back).unwrap();
    assert!((back[5] + 0.25).abs() < 1e-12, "{back:?}");
    assert!(back[3].abs() < 1e-12 && back[4].abs() < 1e-12);
}

/// d/dt of every body's pose along integrate(q, t v) at t = 0, by central differences, is the body
/// velocity forward kinematics gives (in the body frame: ω from Rᵀ Ṙ, the linear part Rᵀ ṗ).
#[test]
fn the_pose_moves_along_integrate_at_the_joint_velocity() {
    let mut rng = Rng::new(14);
    for floating in [true, false] {
        let model = common::random_tree(&mut rng, 6, floating);
        let mut ws = Workspace::new(&model);
        for _ in 0..10 {
            let q = rng.configuration(&model);
            let v = rng.vec(model.nv(), -1.0, 1.0);
            forward_kinematics(&model, &mut ws, &q, &v).unwrap();
            let velocity = ws.kinematics().velocity.to_vec();
            let h = 1e-6;
            let poses = |t: f64, ws: &mut Workspace<f64>| {
                let scaled: Vec<f64> = v.iter().map(|x| x * t).collect();
                let mut qt = vec![0.0; model.nq()];
                integrate(&model, &q, &scaled, &mut qt).unwrap();
                forward_kinematics(&model, ws, &qt, &vec![0.0; model.nv()]).unwrap();
                ws.kinematics().world_placement.to_vec()
            };
            let (plus, minus) = (poses(h, &mut ws), poses(-h, &mut ws));
            let now = poses(0.0, &mut ws);
            for (b, x) in now.iter().enumerate() {
                let r_dot = (plus[b].rotation - minus[b].rotation) / (2.0 * h);
                let p_dot = (plus[b].translation - minus[b].translation) / (2.0 * h);
                let w = x.rotation.transpose() * r_dot;
                let omega = [w[(2, 1)], w[(0, 2)], w[(1, 0)]];
                let linear = x.rotation.transpose() * p_dot;
                for k in 0..3 {
                    assert!(
                        (omega[k] - velocity[b].angular[k]).abs() < 1e-7,
                        "body {b}: ω {omega:?} vs {:?}",
                        velocity[b].angular
                    );
                    assert!(
                        (linear[k] - velocity[b].linear[k]).abs() < 1e-7,
                        "body {b}: v {linear:?} vs {:?}",
                        velocity[b].linear
                    );
                }
            }
        }
    }
}

#[test]
fn random_configurations_stay_within_their_bounds() {
    let mut rng = Rng::new(15);
    let model = common::random_tree(&mut rng, 7, true);
    let nq = model.nq();
    let mut lower = vec![f64::NEG_INFINITY; nq];
    let mut upper = vec![f64::INFINITY; nq];
    // Bounds on some coordinates, none (the defaults) on the others.
    for j in model.joints.iter().skip(1).step_by(2) {
        lower[j.q_index] = -0.25;
        upper[j.q_index] = 0.5;
    }
    let mut draws = SplitMix64::new(5);
    let mut q = vec![0.0; nq];
    let mut again = vec![0.0; nq];
    for _ in 0..200 {
        random_configuration(&model, &mut draws, &lower, &upper, &mut q).unwrap();
        for j in &model.joints {
            let i = j.q_index;
            let (lo, hi) = match j.joint_type {
                _ if lower[i].is_finite() => (lower[i], upper[i]),
                JointType::Revolute | JointType::Continuous => (-PI, PI),
                _ => (-1.0, 1.0),
            };
            for k in 0..if j.joint_type == JointType::Floating {
                3
            } else {
                1
            } {
                assert!((lo..hi).contains(&q[i + k]), "{}: {}", j.name, q[i + k]);
            }
            if j.joint_type == JointType::Floating {
                let n: f64 = q[i + 3..i + 7].iter().map(|x| x * x).sum();
                assert!((n - 1.0).abs() < 1e-15, "quaternion norm² {n}");
            }
        }
    }
    // The same seed, the same configuration.
    random_configuration(&model, &mut SplitMix64::new(9), &lower, &upper, &mut q).unwrap();
    random_configuration(&model, &mut SplitMix64::new(9), &lower, &upper, &mut again).unwrap();
    assert_eq!(q, again);
    // Lengths are checked.
    assert!(random_configuration(&model, &mut draws, &lower[1..], &upper, &mut q).is_err());
}

#[test]
fn the_neutral_configuration_is_the_identity_of_integrate() {
    let mut rng = Rng::new(16);
    let model = common::random_tree(&mut rng, 5, true);
    let mut q = model.neutral_configuration();
    let mut out = vec![0.0; model.nq()];
    integrate(&model, &q, &vec![0.0; model.nv()], &mut out).unwrap();
    assert_eq!(out, q);
    // normalize_configuration rescales quaternions and leaves the rest.
    q[3..7].copy_from_slice(&[0.0, 0.0, 0.0, 2.0]);
    q[7] = 3.0;
    model.normalize_configuration(&mut q);
    assert_eq!(&q[3..8], &[0.0, 0.0, 0.0, 1.0, 3.0]);
    // Bad input is an error, not a panic.
    assert!(integrate(&model, &q[1..], &vec![0.0; model.nv()], &mut out).is_err());
    let mut nan = q.clone();
    nan[0] = f64::NAN;
    let mut v = vec![0.0; model.nv()];
    assert!(difference(&model, &q, &nan, &mut v).is_err());
}

#[test]
fn f32_integrate_and_difference_keep_f32_precision() {
    let mut rng = Rng::new(17);
    let model = common::random_tree(&mut rng, 4, true);
    let m32 = model.cast::<f32>();
    for angle in [Some(1e-6), Some(0.05), Some(1.0), Some(3.0), None] {
        let q = rng.configuration(&model);
        let v = velocity_with_angle(&mut rng, &model, angle);
        let mut q1 = vec![0.0; model.nq()];
        integrate(&model, &q, &v, &mut q1).unwrap();
        let (q32, v32) = (common::cast::<f32>(&q), common::cast::<f32>(&v));
        let mut q1_32 = vec![0.0f32; model.nq()];
        integrate(&m32, &q32, &v32, &mut q1_32).unwrap();
        let e = configuration_error(&model, &common::to_f64(&q1_32), &q1);
        assert!(e < 1e-5, "f32 integrate: {e:e}");
        let mut back = vec![0.0f32; model.nv()];
        difference(&m32, &q32, &common::cast::<f32>(&q1), &mut back).unwrap();
        let e = embedyn::relative_error(&common::to_f64(&back), &v);
        assert!(e < 1e-4, "f32 difference at {angle:?}: {e:e}");
    }
}

/// `random_configuration_within_limits` draws within the `<limit>`s the file gives (Panda: every joint
/// limited, fingers in [0, 0.04] m) and within the defaults where it gives none (the continuous double
/// pendulum), and draws what `random_configuration` draws with those bounds passed by hand.
#[test]
fn random_configurations_within_the_models_limits() {
    use embedyn::random_configuration_within_limits;
    for (path, limited) in [
        ("tests/data/pinocchio/panda.urdf", true),
        (
            "tests/data/pinocchio/double_pendulum_continuous.urdf",
            false,
        ),
    ] {
        let model: embedyn::Model<f64> = common::load_model(path, false);
        let nq = model.nq();
        let lower: Vec<f64> = model
            .joints
            .iter()
            .map(|j| j.limits.lower.unwrap_or(f64::NEG_INFINITY))
            .collect();
        let upper: Vec<f64> = model
            .joints
            .iter()
            .map(|j| j.limits.upper.unwrap_or(f64::INFINITY))
            .collect();
        assert_eq!(lower.len(), nq);
        assert_eq!(lower.iter().all(|x| x.is_finite()), limited, "{path}");
        let (mut a, mut b) = (SplitMix64::new(3), SplitMix64::new(3));
        let (mut q, mut by_hand) = (vec![0.0; nq], vec![0.0; nq]);
        for _ in 0..100 {
            random_configuration_within_limits(&model, &mut a, &mut q).unwrap();
            random_configuration(&model, &mut b, &lower, &upper, &mut by_hand).unwrap();
            assert_eq!(q, by_hand);
            for i in 0..nq {
                let (lo, hi) = if limited {
                    (lower[i], upper[i])
                } else {
                    (-PI, PI)
                };
                assert!((lo..hi).contains(&q[i]), "{path}: q[{i}] = {}", q[i]);
            }
        }
    }
}
