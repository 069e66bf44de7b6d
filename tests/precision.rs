//! Precision of the scalar types on the bundled models: f64 against the double-double reference
//! (1e-12 relative) and f32 against f64 (1e-4 relative), for ABA, RNEA and CRBA. Each model is built
//! from the file in f64 and converted to each scalar (its constants rounded once); f32 also rounds the
//! inputs, as firmware would.

use crate::common;

use common::{cast, load_model, to_f64, Rng};
use embedyn::{aba, crba, relative_error, rnea, DoubleDouble, Model, Real, Workspace};

struct Errors {
    aba: f64,
    rnea: f64,
    crba: f64,
}

fn run<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[f64],
    v: &[f64],
    x: &[f64],
) -> [Vec<f64>; 3] {
    let (q, v, x) = (cast::<T>(q), cast::<T>(v), cast::<T>(x));
    let a = to_f64(aba(model, ws, &q, &v, &x).unwrap());
    let r = to_f64(rnea(model, ws, &q, &v, &x).unwrap());
    let m = to_f64(crba(model, ws, &q).unwrap().as_slice());
    [a, r, m]
}

fn compare<T: Real, R: Real>(path: &str, floating: bool, samples: usize) -> Errors {
    let model_t = load_model::<T>(path, floating);
    let model_r = load_model::<R>(path, floating);
    let mut ws_t = Workspace::new(&model_t);
    let mut ws_r = Workspace::new(&model_r);
    let mut rng = Rng::new(23);
    let mut e = Errors {
        aba: 0.0,
        rnea: 0.0,
        crba: 0.0,
    };
    let model64 = load_model::<f64>(path, floating);
    for _ in 0..samples {
        let q = rng.configuration(&model64);
        let v = rng.vec(model64.nv(), -2.0, 2.0);
        let x = rng.vec(model64.nv(), -10.0, 10.0);
        let got = run(&model_t, &mut ws_t, &q, &v, &x);
        let want = run(&model_r, &mut ws_r, &q, &v, &x);
        e.aba = e.aba.max(relative_error(&got[0], &want[0]));
        e.rnea = e.rnea.max(relative_error(&got[1], &want[1]));
        e.crba = e.crba.max(relative_error(&got[2], &want[2]));
    }
    eprintln!(
        "{path}{}: {} vs {}: aba {:.1e}, rnea {:.1e}, crba {:.1e}",
        if floating { " --floating" } else { "" },
        T::NAME,
        R::NAME,
        e.aba,
        e.rnea,
        e.crba
    );
    e
}

const MODELS: [(&str, bool); 4] = [
    ("models/arm7.urdf", false),
    ("models/humanoid34.urdf", false),
    ("models/quadruped.urdf", false),
    ("models/humanoid34.urdf", true),
];

#[test]
fn f64_matches_double_double_to_1e_12() {
    for (path, floating) in MODELS {
        let e = compare::<f64, DoubleDouble>(path, floating, 10);
        for (what, err) in [("aba", e.aba), ("rnea", e.rnea), ("crba", e.crba)] {
            assert!(
                err <= 1e-12,
                "{path}: f64 {what} off the double-double answer by {err:e}"
            );
        }
    }
}

#[test]
fn f32_matches_f64_to_1e_4() {
    for (path, floating) in MODELS {
        let e = compare::<f32, f64>(path, floating, 20);
        for (what, err) in [("aba", e.aba), ("rnea", e.rnea), ("crba", e.crba)] {
            assert!(
                err <= 1e-4,
                "{path}: f32 {what} off the f64 answer by {err:e}"
            );
        }
    }
}

#[test]
fn double_double_model_is_more_precise_than_f64() {
    // Sanity of the reference itself: on the Pinocchio-checked UR5 the double-double ABA agrees with f64
    // to rounding, and its residual M qdd + nle − τ (evaluated in double-double) is far below f64's. The
    // model is built in f64 and converted (one structure for every scalar), so its rotations are
    // orthogonal only to f64 rounding and the two algorithms, which use that differently, agree to ~1e-22.
    use embedyn::linalg::solve_spd;
    let path = "tests/data/pinocchio/ur5.urdf";
    let m_dd = load_model::<DoubleDouble>(path, false);
    let mut ws = Workspace::new(&m_dd);
    let mut rng = Rng::new(2);
    let q = rng.configuration(&load_model::<f64>(path, false));
    let (q, v, tau) = (
        cast::<DoubleDouble>(&q),
        cast::<DoubleDouble>(&rng.vec(6, -1.0, 1.0)),
        cast::<DoubleDouble>(&rng.vec(6, -5.0, 5.0)),
    );
    let qdd = aba(&m_dd, &mut ws, &q, &v, &tau).unwrap().to_vec();
    let nle = rnea(&m_dd, &mut ws, &q, &v, &[DoubleDouble::from_f64(0.0); 6])
        .unwrap()
        .to_vec();
    let m = crba(&m_dd, &mut ws, &q).unwrap().clone();
    let rhs: Vec<DoubleDouble> = tau.iter().zip(&nle).map(|(t, n)| *t - *n).collect();
    let qdd_chol = solve_spd(&m, &rhs).unwrap();
    let diff = qdd
        .iter()
        .zip(&qdd_chol)
        .map(|(a, b)| (*a - *b).abs().to_f64())
        .fold(0.0, common::worse);
    assert!(diff < 1e-21, "double-double ABA vs CRBA+Cholesky: {diff:e}");
}
