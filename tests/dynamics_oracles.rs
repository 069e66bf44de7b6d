//! The interpreted algorithms checked against each other on the bundled models:
//! ABA against CRBA + Cholesky, RNEA of ABA's result, M symmetric positive definite, M times the
//! operator inverse of Eq. 6 equal to I. All to 1e-10 relative (docs/conventions.md's definition).

use crate::common;

use common::{load_model, Rng};
use embedyn::linalg::{cholesky_in_place, solve_spd};
use embedyn::nalgebra::DMatrix;
use embedyn::{aba, crba, mass_matrix_inverse, relative_error, rnea, Model, Workspace};

const TOL: f64 = 1e-10;

pub const MODELS: [(&str, bool); 5] = [
    ("models/arm7.urdf", false),
    ("models/humanoid34.urdf", false),
    ("models/quadruped.urdf", false),
    // The humanoid made free with --floating: a floating root with a 34-DoF branching tree below.
    ("models/humanoid34.urdf", true),
    // Two floating roots in one scene (a free-based arm and a free box): each joint has its own D factor.
    ("tests/data/scenes/two_free_bodies.urdf", false),
];

pub fn check_model(model: &Model<f64>, seed: u64, samples: usize) {
    let mut rng = Rng::new(seed);
    let mut ws = Workspace::new(model);
    let nv = model.nv();
    let mut worst = [0.0f64; 4];
    for _ in 0..samples {
        let q = rng.configuration(model);
        let v = rng.vec(nv, -2.0, 2.0);
        let tau = rng.vec(nv, -20.0, 20.0);

        let qdd = aba(model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let nle = rnea(model, &mut ws, &q, &v, &vec![0.0; nv])
            .unwrap()
            .to_vec();
        let m = crba(model, &mut ws, &q).unwrap().clone();

        // M symmetric (exactly: both triangles are written from one value) and positive definite.
        assert_eq!(m, m.transpose(), "{}: M not symmetric", model.name);
        let mut l = m.clone();
        assert!(
            cholesky_in_place(&mut l) > 0.0,
            "{}: M not positive definite",
            model.name
        );

        // ABA against M⁻¹ (τ − nle) by Cholesky.
        let rhs: Vec<f64> = tau.iter().zip(&nle).map(|(t, n)| t - n).collect();
        let qdd_chol = solve_spd(&m, &rhs).unwrap();
        worst[0] = worst[0].max(relative_error(&qdd, &qdd_chol));

        // RNEA inverts ABA.
        let tau_back = rnea(model, &mut ws, &q, &v, &qdd).unwrap().to_vec();
        worst[1] = worst[1].max(relative_error(&tau_back, &tau));

        // M · (Eq. 6 inverse) = I.
        let minv = mass_matrix_inverse(model, &mut ws, &q).unwrap().clone();
        let prod = &m * &minv;
        let eye = DMatrix::<f64>::identity(nv, nv);
        worst[2] = worst[2].max(relative_error(prod.as_slice(), eye.as_slice()));
        worst[3] = worst[3].max(relative_error(minv.as_slice(), minv.transpose().as_slice()));
    }
    eprintln!(
        "{} (nv {nv}): aba vs crba+chol {:.1e}, rnea(aba) {:.1e}, M·Minv−I {:.1e}, Minv asym {:.1e}",
        model.name, worst[0], worst[1], worst[2], worst[3]
    );
    for (what, w) in [
        "ABA vs CRBA+Cholesky",
        "RNEA(ABA) vs tau",
        "M·Minv vs I",
        "Minv symmetry",
    ]
    .iter()
    .zip(worst)
    {
        assert!(
            w <= TOL,
            "{}: {what}: relative error {w:e} > {TOL:e}",
            model.name
        );
    }
}

#[test]
fn bundled_models_agree_across_algorithms() {
    for (path, floating) in MODELS {
        let model = load_model::<f64>(path, floating);
        check_model(&model, 7, 25);
    }
}

#[test]
fn bundled_models_have_the_expected_size() {
    let sizes: Vec<(usize, usize)> = MODELS
        .iter()
        .map(|(p, f)| {
            let m = load_model::<f64>(p, *f);
            (m.nq(), m.nv())
        })
        .collect();
    assert_eq!(sizes, vec![(7, 7), (34, 34), (19, 18), (41, 40), (16, 14)]);
}

#[test]
fn gravity_torque_matches_a_static_balance() {
    // At rest with τ = g(q) (RNEA with v = qdd = 0) the robot does not accelerate.
    for (path, floating) in MODELS {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(11);
        let q = rng.configuration(&model);
        let zero = vec![0.0; model.nv()];
        let g = rnea(&model, &mut ws, &q, &zero, &zero).unwrap().to_vec();
        let qdd = aba(&model, &mut ws, &q, &zero, &g).unwrap();
        assert!(qdd.iter().all(|x| x.abs() < 1e-10), "{path}: {qdd:?}");
    }
}

#[test]
fn wrong_lengths_are_errors_not_panics() {
    let model = load_model::<f64>("models/arm7.urdf", false);
    let mut ws = Workspace::new(&model);
    let err = aba(&model, &mut ws, &[0.0; 6], &[0.0; 7], &[0.0; 7]).unwrap_err();
    assert_eq!(err.to_string(), "`q` has length 6, the model needs 7");
    assert!(rnea(&model, &mut ws, &[0.0; 7], &[0.0; 7], &[0.0; 8]).is_err());
    assert!(crba(&model, &mut ws, &[0.0; 3]).is_err());
}

#[test]
fn a_nan_input_is_named_not_blamed_on_a_joint() {
    // Once reported as `SingularJoint { joint: "root_joint" }`: the input at fault is named instead.
    let model = load_model::<f64>("models/humanoid34.urdf", true);
    let mut ws = Workspace::new(&model);
    let mut q = model.neutral_configuration();
    let (v, tau) = (vec![0.0; model.nv()], vec![0.0; model.nv()]);
    q[7] = f64::NAN;
    let err = aba(&model, &mut ws, &q, &v, &tau).unwrap_err();
    assert_eq!(err.to_string(), "`q`[7] is not a finite number (NaN)");
    let mut tau_bad = tau.clone();
    tau_bad[3] = f64::INFINITY;
    let err = aba(
        &model,
        &mut ws,
        &model.neutral_configuration(),
        &v,
        &tau_bad,
    )
    .unwrap_err();
    assert_eq!(err.to_string(), "`tau`[3] is not a finite number (inf)");
    // A zero quaternion is no rotation: refused, naming the joint and the entries.
    let mut q0 = model.neutral_configuration();
    q0[3..7].fill(0.0);
    for err in [
        aba(&model, &mut ws, &q0, &v, &tau).unwrap_err(),
        rnea(&model, &mut ws, &q0, &v, &tau).unwrap_err(),
        crba(&model, &mut ws, &q0).unwrap_err(),
        mass_matrix_inverse(&model, &mut ws, &q0).unwrap_err(),
    ] {
        assert!(
            err.to_string()
                .starts_with("joint `root_joint`: its quaternion `q`[3..7] has norm 0e0"),
            "{err}"
        );
    }
}

#[test]
fn each_floating_root_of_a_scene_is_independent() {
    // The box is free and touches nothing: its acceleration is gravity alone, whatever the arm does, and
    // the arm's does not depend on the box (once the second root overwrote the first root's factor).
    let model = load_model::<f64>("tests/data/scenes/two_free_bodies.urdf", false);
    let box_joint = &model.joints[model.joint_index("box_free").unwrap()];
    let (bq, bv) = (box_joint.q_index, box_joint.v_index);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(5);
    let q = rng.configuration(&model);
    let mut v = rng.vec(model.nv(), -1.0, 1.0);
    v[bv..bv + 6].fill(0.0);
    let tau = rng.vec(model.nv(), -5.0, 5.0);
    let mut tau_free_box = tau.clone();
    tau_free_box[bv..bv + 6].fill(0.0);
    let qdd = aba(&model, &mut ws, &q, &v, &tau_free_box)
        .unwrap()
        .to_vec();
    // A box at rest under gravity alone: linear acceleration Rᵀ g in its own frame, no rotation.
    let quat = &q[bq + 3..bq + 7];
    let r = embedyn::nalgebra::UnitQuaternion::from_quaternion(embedyn::nalgebra::Quaternion::new(
        quat[3], quat[0], quat[1], quat[2],
    ));
    let placement = &box_joint.placement.rotation;
    let g_local = (placement * r.to_rotation_matrix().matrix()).transpose() * model.gravity;
    let want = [g_local.x, g_local.y, g_local.z, 0.0, 0.0, 0.0];
    assert!(
        relative_error(&qdd[bv..bv + 6], &want) < 1e-13,
        "{:?} vs {want:?}",
        &qdd[bv..bv + 6]
    );
    // The arm's accelerations do not change when the box is pushed.
    let mut tau_pushed = tau_free_box.clone();
    tau_pushed[bv..bv + 6].copy_from_slice(&[3.0, -1.0, 2.0, 0.1, 0.2, -0.3]);
    let qdd_pushed = aba(&model, &mut ws, &q, &v, &tau_pushed).unwrap().to_vec();
    assert!(relative_error(&qdd_pushed[..bv], &qdd[..bv]) < 1e-14);
}
