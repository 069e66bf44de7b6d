//! The interpreted algorithms checked against each other on the bundled models:
//! ABA against CRBA + Cholesky, RNEA of ABA's result, M symmetric positive definite, M times the
//! operator inverse of Eq. 6 equal to I. All to 1e-10 relative (CONTRACT §2's definition).

mod common;

use common::{load_model, Rng};
use embedyn::linalg::{cholesky_in_place, solve_spd};
use embedyn::nalgebra::DMatrix;
use embedyn::{aba, crba, mass_matrix_inverse, relative_error, rnea, Model, Workspace};

const TOL: f64 = 1e-10;

const MODELS: [(&str, bool); 4] = [
    ("models/arm7.urdf", false),
    ("models/humanoid34.urdf", false),
    ("models/quadruped.urdf", false),
    // The humanoid made free with --floating: a floating root with a 34-DoF branching tree below.
    ("models/humanoid34.urdf", true),
];

fn check_model(model: &Model<f64>, seed: u64, samples: usize) {
    let mut rng = Rng(seed);
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
    assert_eq!(sizes, vec![(7, 7), (34, 34), (19, 18), (41, 40)]);
}

#[test]
fn gravity_torque_matches_a_static_balance() {
    // At rest with τ = g(q) (RNEA with v = qdd = 0) the robot does not accelerate.
    for (path, floating) in MODELS {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng(11);
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
