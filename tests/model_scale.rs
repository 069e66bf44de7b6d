//! Load-time checks are relative to the scale of what they check and to the precision of the scalar type
//! (docs/model-format.md "Tolerances"): models at unusual scales load in f64 and f32 and their dynamics are right;
//! the structure of a model (redundant equations, independent coordinates) is decided once, in f64, for
//! every scalar; a constant that does not fit the scalar is an error naming it, not another model.

use crate::common;

use common::{cast, load_model, repo_path, to_f64, Rng};
use embedyn::codegen::{generate_tokens, GenerateOptions};
use embedyn::linalg::{cholesky_in_place, cholesky_solve_in_place};
use embedyn::{aba, crba, load, relative_error, rnea, Model, ModelOptions, Real, Workspace};

/// The largest relative error (docs/conventions.md) between ABA and a CRBA + Cholesky solve of M qdd = τ − h over
/// random states, in `T`, with each τ_k scaled by the joint's own M_kk so that accelerations are O(1)
/// whatever the model's units.
fn aba_against_crba_solve<T: Real>(model: &Model<T>, samples: usize) -> f64 {
    let mut ws = Workspace::new(model);
    let mut rng = Rng::new(5);
    let mut worst = 0.0f64;
    for _ in 0..samples {
        let q: Vec<T> = cast(&rng.configuration(model));
        let v: Vec<T> = cast(&rng.vec(model.nv(), -2.0, 2.0));
        let mut m = crba(model, &mut ws, &q).unwrap().clone();
        let tau: Vec<T> = (0..model.nv())
            .map(|k| T::from_f64(rng.uniform(-1.0, 1.0)) * m[(k, k)])
            .collect();
        let h = rnea(model, &mut ws, &q, &v, &vec![T::zero(); model.nv()])
            .unwrap()
            .to_vec();
        let mut solved: Vec<T> = tau.iter().zip(&h).map(|(&t, &h)| t - h).collect();
        assert!(cholesky_in_place(&mut m).is_positive_finite());
        cholesky_solve_in_place(&m, &mut solved);
        let qdd = aba(model, &mut ws, &q, &v, &tau).unwrap();
        worst = worst.max(relative_error(&to_f64(qdd), &to_f64(&solved)));
    }
    worst
}

/// A milligram arm and a gram probe on a tonne carriage: both were refused ("no inertia about its axis")
/// by an absolute tolerance, max(1, Σ(m + tr I))·1e-12.
#[test]
fn milligram_and_tonne_scale_models_load_and_their_dynamics_agree() {
    for file in [
        "tests/data/scale/milligram_arm.urdf",
        "tests/data/scale/gram_probe_on_carriage.urdf",
    ] {
        let warnings = load(&repo_path(file)).unwrap().warnings;
        assert!(warnings.is_empty(), "{file}: {warnings:?}");
        let e64 = aba_against_crba_solve(&load_model::<f64>(file, false), 20);
        let e32 = aba_against_crba_solve(&load_model::<f32>(file, false), 20);
        eprintln!("{file}: ABA vs CRBA + Cholesky: f64 {e64:.1e}, f32 {e32:.1e}");
        assert!(e64 <= 1e-9, "{file}: f64 ABA off the CRBA solve by {e64:e}");
        assert!(e32 <= 1e-4, "{file}: f32 ABA off the CRBA solve by {e32:e}");
    }
}

/// The terminal-cut four-bar failed to load as f32 when its redundant loop rows and independent
/// coordinates were decided in f32; now both scalars get the structure decided in f64.
#[test]
fn f32_model_has_the_structure_decided_in_f64() {
    for file in [
        "models/loops/four_bar_terminal.urdf",
        "models/loops/four_bar_internal.urdf",
        "models/loops/six_bar.urdf",
        "models/loops/geared_motor.urdf",
        "models/loops/differential_wrist.urdf",
    ] {
        let m64 = load_model::<f64>(file, false);
        let m32 = load_model::<f32>(file, false);
        assert_eq!(m32.groups, m64.groups, "{file}");
        assert_eq!(m32.independent_nv(), m64.independent_nv(), "{file}");
    }
}

/// A coupling ratio of 1e300 is a valid f64 model (rotor1 = 1e300 × joint1); f32 cannot represent it.
/// It used to give f32 another model (three independent coordinates instead of two) and generated f32 code
/// that does not compile; now the f32 model and the f32 generation are refused naming the coupling.
#[test]
fn a_constant_that_does_not_fit_f32_is_an_error_naming_it() {
    let file = "tests/data/bad/coupling_ratio_too_large_for_f32.urdf";
    let loaded = load(&repo_path(file)).unwrap();
    let m64 = loaded.model::<f64>(&ModelOptions::default()).unwrap();
    assert_eq!((m64.nv(), m64.independent_nv()), (3, 2));
    let expect = |err: String| {
        for needle in [
            "coupling_ratio_too_large_for_f32.urdf:11:",
            "coupling \"gear\"",
            "coefficient 1e300",
            "too large for f32",
        ] {
            assert!(err.contains(needle), "`{needle}` not in: {err}");
        }
    };
    expect(
        loaded
            .model::<f32>(&ModelOptions::default())
            .map(|_| ())
            .unwrap_err()
            .to_string(),
    );
    expect(
        generate_tokens(&loaded, &GenerateOptions::default())
            .map(|_| ())
            .unwrap_err()
            .to_string(),
    );
    let f64_only = GenerateOptions {
        f32: false,
        ..Default::default()
    };
    assert!(generate_tokens(&loaded, &f64_only).is_ok());
}

/// `Model::try_cast` names the element whose constant does not fit: a joint placement beyond f32's range,
/// and a model whose masses all fall below f32's normal range (significant at the model's own scale, so
/// converting would lose them), while an insignificant tiny offset next to metre-sized ones may flush.
#[test]
fn try_cast_names_what_does_not_fit() {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, ModelElement, ModelError, SpatialInertia, Transform};
    let chain = |offset: f64, mass: f64| {
        let mut b = Model::<f64>::builder("chain");
        let inertia = SpatialInertia::from_com(
            mass,
            Vector3::new(0.0, 0.0, 0.1),
            Matrix3::identity() * mass * 1e-3,
        );
        let link = |z: f64| Transform::new(Matrix3::identity(), Vector3::new(offset, 0.0, z));
        b.add_body(
            None,
            "j1",
            JointType::Revolute,
            Vector3::y(),
            Transform::identity(),
            "l1",
            inertia,
        )
        .unwrap();
        b.add_body(
            Some(0),
            "j2",
            JointType::Revolute,
            Vector3::y(),
            link(0.2),
            "l2",
            inertia,
        )
        .unwrap();
        b.build().unwrap()
    };
    match chain(1e39, 1.0).try_cast::<f32>() {
        Err(ModelError::ConstantDoesNotFit {
            element: ModelElement::Joint(j),
            what: "placement translation",
            too_large: true,
            ..
        }) => assert_eq!(j, "j2"),
        other => panic!("{other:?}"),
    }
    match chain(0.0, 1e-40).try_cast::<f32>() {
        Err(ModelError::ConstantDoesNotFit {
            element: ModelElement::Body(b),
            what: "mass",
            too_large: false,
            ..
        }) => assert_eq!(b, "l1"),
        other => panic!("{other:?}"),
    }
    // 1e-45 m beside a 0.2 m offset: below what f32 resolves at the model's scale, so it may flush to zero.
    let m32 = chain(1e-45, 1.0).try_cast::<f32>().unwrap();
    assert_eq!(m32.joints[1].placement.translation.z, 0.2f32);
}

#[path = "../codegen/tests/support/chain_urdf.rs"]
mod chain_urdf;

/// A long chain of free joints is a valid f32 model: a joint's articulated inertia is a small fraction of
/// its composite inertia there (the composite carries the lever arms of every link below), and judging
/// it against that refused a 100-link chain in f32. It is judged against what it is computed from, and the
/// f32 dynamics agree with an f32 CRBA + Cholesky solve to f32's accuracy for the conditioning.
#[test]
fn a_long_chain_loads_in_f32() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("chain100_f32.urdf");
    std::fs::write(&path, chain_urdf::chain_urdf(100)).unwrap();
    let loaded = load(&path).unwrap();
    let m64 = loaded.model::<f64>(&ModelOptions::default()).unwrap();
    let m32 = loaded.model::<f32>(&ModelOptions::default()).unwrap();
    assert_eq!(m32.nv(), 100);
    let e64 = aba_against_crba_solve(&m64, 3);
    assert!(e64 <= 1e-8, "f64 ABA off the CRBA solve by {e64:e}");
    let e32 = aba_against_crba_solve(&m32, 3);
    eprintln!("100-link chain: ABA vs CRBA + Cholesky: f64 {e64:.1e}, f32 {e32:.1e}");
    // cond(M) of a 100-link chain is ~1e5: f32 keeps about two digits of the accelerations.
    assert!(e32 <= 5e-2, "f32 ABA off the CRBA solve by {e32:e}");
}
