//! Armature — a joint's rotor inertia, felt only along its own coordinate — in every algorithm, checked
//! against oracles that see it only through `M`: CRBA's diagonal, ABA against CRBA + Cholesky, RNEA of
//! ABA's result, M times the operator inverse, and for models with loops the Lagrange-multiplier (KKT)
//! solve, which meets armature only in CRBA's `M`.

use crate::common::{load_model, Rng};
use crate::constraint_embedding::{consistent_state, LOOP_MODELS};
use crate::dynamics_oracles::{check_model, MODELS};
use embedyn::{
    aba, crba, kkt_forward_dynamics, relative_error, JointType, Model, ModelError, SpatialInertia,
    Transform, Workspace,
};

/// `model` with armature on every one-coordinate joint, from 1e-3 to 1 (a rotor of 1e-5 kg·m² behind
/// gears of 10:1 to 300:1).
fn with_armature(model: &Model<f64>, rng: &mut Rng) -> Model<f64> {
    let mut model = model.clone();
    for joint in &mut model.joints {
        if joint.joint_type != JointType::Floating {
            joint.armature = 10f64.powf(rng.uniform(-3.0, 0.0));
        }
    }
    model
}

#[test]
fn armature_adds_to_the_diagonal_of_the_mass_matrix_and_nowhere_else() {
    let mut rng = Rng::new(11);
    for (path, floating) in MODELS {
        let plain = load_model::<f64>(path, floating);
        let geared = with_armature(&plain, &mut rng);
        let q = rng.configuration(&plain);
        let m0 = crba(&plain, &mut Workspace::new(&plain), &q)
            .unwrap()
            .clone();
        let m1 = crba(&geared, &mut Workspace::new(&geared), &q)
            .unwrap()
            .clone();
        let mut expected = m0.clone();
        for joint in &geared.joints {
            for k in 0..joint.nv() {
                expected[(joint.v_index + k, joint.v_index + k)] += joint.armature;
            }
        }
        let err = relative_error(m1.as_slice(), expected.as_slice());
        assert!(err <= 1e-14, "{path}: M with armature off by {err:e}");
    }
}

#[test]
fn tree_algorithms_agree_with_each_other_with_armature() {
    let mut rng = Rng::new(12);
    for (path, floating) in MODELS {
        let geared = with_armature(&load_model::<f64>(path, floating), &mut rng);
        // ABA vs CRBA + Cholesky, RNEA(ABA) = τ, M · M⁻¹ = I (Eq. 6), M⁻¹ symmetric.
        check_model(&geared, 13, 10);
    }
}

#[test]
fn loops_with_armature_on_members_match_the_kkt_solution() {
    let mut rng = Rng::new(14);
    for (path, floating) in LOOP_MODELS {
        let plain = load_model::<f64>(path, floating);
        // Armature on independent and dependent members alike (a rotor behind a four-bar's coupler).
        let geared = with_armature(&plain, &mut rng);
        let mut ws = Workspace::new(&geared);
        let mut worst = 0.0f64;
        let mut moved = 0.0f64;
        for _ in 0..5 {
            let (q, v) = consistent_state(&geared, &mut ws, &mut rng);
            let tau = rng.vec(geared.nv(), -5.0, 5.0);
            let qdd = aba(&geared, &mut ws, &q, &v, &tau).unwrap().to_vec();
            let qdd_kkt = kkt_forward_dynamics(&geared, &mut ws, &q, &v, &tau).unwrap();
            worst = worst.max(relative_error(&qdd, &qdd_kkt));
            // The armature matters: the plain model moves otherwise.
            let qdd_plain = aba(&plain, &mut Workspace::new(&plain), &q, &v, &tau)
                .unwrap()
                .to_vec();
            moved = moved.max(relative_error(&qdd_plain, &qdd));
        }
        eprintln!("{path}: with armature, embedded ABA vs KKT {worst:.1e} (armature changes qdd by {moved:.1e})");
        assert!(
            worst <= 1e-9,
            "{path}: embedded ABA with armature vs KKT {worst:e}"
        );
        assert!(
            moved >= 1e-6,
            "{path}: armature changed nothing ({moved:e})"
        );
    }
}

#[test]
fn armature_must_be_finite_and_not_negative() {
    let mut b = Model::<f64>::builder("one");
    let body = b
        .add_body(
            None,
            "j",
            JointType::Revolute,
            embedyn::nalgebra::Vector3::z(),
            Transform::identity(),
            "link",
            SpatialInertia::from_com(
                1.0,
                embedyn::nalgebra::Vector3::zeros(),
                embedyn::nalgebra::Matrix3::identity(),
            ),
        )
        .unwrap();
    for bad in [-1e-3, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(
                b.set_armature(body, bad),
                Err(ModelError::BadArmature { .. })
            ),
            "{bad} accepted"
        );
    }
    assert!(matches!(
        b.set_armature(body + 1, 0.1),
        Err(ModelError::UnknownBody { .. })
    ));
    b.set_armature(body, 0.25).unwrap();
    let model = b.build().unwrap();
    assert_eq!(model.joints[0].armature, 0.25);
    // One free rotor: (I_zz + armature) qdd = τ.
    let qdd = aba(&model, &mut Workspace::new(&model), &[0.0], &[0.0], &[2.5]).unwrap()[0];
    assert!((qdd - 2.5 / 1.25).abs() <= 1e-15, "{qdd}");
}

mod armature_arm_generated {
    embedyn::robot!(
        "tests/data/pinocchio/armature_arm.urdf",
        f64_only,
        only(aba, rnea, crba)
    );
}
mod solo12_armature_generated {
    embedyn::robot!(
        "tests/data/pinocchio/solo12_armature_floating.urdf",
        floating,
        f64_only,
        only(aba, rnea, crba)
    );
}

/// Generated code with armature (read from `<dynamics>` and from transmissions) against Pinocchio with
/// `model.armature` set: aba, rnea and crba to 1e-9 on the arm and the floating Solo-12.
#[test]
fn generated_armature_matches_pinocchio() {
    use crate::pinocchio_reference::{check_generated, reference};
    for (name, floating, functions) in [
        (
            "armature_arm",
            false,
            crate::generated_functions!(armature_arm_generated),
        ),
        (
            "solo12_armature_floating",
            true,
            crate::generated_functions!(solo12_armature_generated),
        ),
    ] {
        let model = load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), floating);
        check_generated(name, &model, &reference(name), functions);
    }
}

fn armature_file_with(edits: &[(&str, &str)]) -> Result<embedyn::Loaded, embedyn::LoadError> {
    crate::common::edited_model("tests/data/armature.urdf", edits)
}

fn armature_of(loaded: &embedyn::Loaded, joint: &str) -> f64 {
    let model = loaded.model::<f64>(&Default::default()).unwrap();
    model.joints[model.joint_index(joint).unwrap()].armature
}

/// What a new user's transmissions found, each pinned: an undeclared `drake:` prefix loads (as Pinocchio
/// does) with a warning saying what to declare; a gear ratio of 0, a rotor inertia without `value` and a
/// negative one are errors naming the element; a rotor on a fixed joint and a transmission of several
/// joints add nothing, with a warning, instead of silently vanishing or landing on the first joint.
#[test]
fn transmission_edge_cases_are_read_or_reported() {
    use embedyn::codegen::{LoadErrorKind, WarningKind};
    let undeclared = armature_file_with(&[(" xmlns:drake=\"http://drake.mit.edu\"", "")]).unwrap();
    assert!((armature_of(&undeclared, "j1") - 0.02).abs() < 1e-15);
    assert!(undeclared.warnings.iter().any(
        |w| matches!(&w.kind, WarningKind::UndeclaredNamespace { prefix } if prefix == "drake")
    ));

    let zero = armature_file_with(&[(
        "<drake:gear_ratio value=\"10\"/>",
        "<drake:gear_ratio value=\"0\"/>",
    )])
    .unwrap_err();
    assert!(matches!(zero.kind, LoadErrorKind::ZeroGearRatio), "{zero}");
    assert!(zero.to_string().contains("<gear_ratio>"), "{zero}");
    let missing = armature_file_with(&[(
        "<drake:rotor_inertia value=\"2e-4\"/>",
        "<drake:rotor_inertia/>",
    )])
    .unwrap_err();
    assert!(
        matches!(missing.kind, LoadErrorKind::MissingAttribute { .. }),
        "{missing}"
    );
    let negative = armature_file_with(&[(
        "<drake:rotor_inertia value=\"2e-4\"/>",
        "<drake:rotor_inertia value=\"-2e-4\"/>",
    )])
    .unwrap_err();
    assert!(
        negative.to_string().contains("<rotor_inertia>"),
        "{negative}"
    );

    let fixed = armature_file_with(&[(
        "<joint name=\"j1\" type=\"revolute\">",
        "<joint name=\"j1\" type=\"fixed\">",
    )])
    .unwrap();
    assert!(fixed
        .warnings
        .iter()
        .any(|w| matches!(&w.kind, WarningKind::RotorOnFixedJoint { joint } if joint == "j1")));
    let two = armature_file_with(&[(
        "<joint name=\"j2\"/>",
        "<joint name=\"j2\"/><joint name=\"j1\"/>",
    )])
    .unwrap();
    assert!(two
        .warnings
        .iter()
        .any(|w| matches!(w.kind, WarningKind::MultiJointTransmission { joints: 2 })));
    // j2 keeps its <dynamics armature> only, j1 only its own transmission's.
    assert!((armature_of(&two, "j2") - 0.5).abs() < 1e-15);
    assert!((armature_of(&two, "j1") - 0.02).abs() < 1e-15);
}
