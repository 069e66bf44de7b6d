//! Property tests over random trees (random branching, axes, joint types, placements and inertias, up to
//! 60 bodies, fixed and floating roots): ABA against CRBA + Cholesky, RNEA of ABA's result, and M times
//! the operator inverse of Eq. 6. The tolerance scales with cond(M), the factor a backward-stable solve
//! is allowed: tol = max(1e-10, 1e-14 · nv · cond(M)). It is fixed here, before any case ran.

use crate::common;

use common::{chain, condition_number, random_tree, Rng};
use embedyn::linalg::solve_spd;
use embedyn::nalgebra::DMatrix;
use embedyn::{aba, crba, mass_matrix_inverse, relative_error, rnea, Workspace};
use proptest::prelude::*;

fn tolerance(nv: usize, cond: f64) -> f64 {
    1e-10f64.max(1e-14 * nv as f64 * cond)
}

fn check(seed: u64, n: usize, floating: bool) -> Result<(), TestCaseError> {
    let mut rng = Rng::new(seed);
    let model = random_tree(&mut rng, n, floating);
    let nv = model.nv();
    let mut ws = Workspace::new(&model);
    let q = rng.configuration(&model);
    let v = rng.vec(nv, -2.0, 2.0);
    let tau = rng.vec(nv, -10.0, 10.0);
    let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
    let nle = rnea(&model, &mut ws, &q, &v, &vec![0.0; nv])
        .unwrap()
        .to_vec();
    let m = crba(&model, &mut ws, &q).unwrap().clone();
    let cond = condition_number(&m);
    let tol = tolerance(nv, cond);
    let rhs: Vec<f64> = tau.iter().zip(&nle).map(|(t, n)| t - n).collect();
    let qdd_chol = solve_spd(&m, &rhs).expect("M positive definite");
    let e_aba = relative_error(&qdd, &qdd_chol);
    prop_assert!(
        e_aba <= tol,
        "ABA vs CRBA+Cholesky: {e_aba:e} > {tol:e} (cond {cond:e}, n {n}, seed {seed})"
    );
    let back = rnea(&model, &mut ws, &q, &v, &qdd).unwrap().to_vec();
    let e_rnea = relative_error(&back, &tau);
    // τ = M qdd + nle: an error δ in qdd shows up as M δ, so the bound carries |M| as well.
    let m_norm = m.iter().fold(1.0f64, |a, x| a.max(x.abs()));
    prop_assert!(
        e_rnea <= tol * m_norm,
        "RNEA(ABA) vs tau: {e_rnea:e} (cond {cond:e}, seed {seed})"
    );
    let minv = mass_matrix_inverse(&model, &mut ws, &q).unwrap().clone();
    let e_inv = relative_error(
        (&m * &minv).as_slice(),
        DMatrix::<f64>::identity(nv, nv).as_slice(),
    );
    prop_assert!(
        e_inv <= tol,
        "M·Minv vs I: {e_inv:e} > {tol:e} (cond {cond:e}, seed {seed})"
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_fixed_base_trees(seed in any::<u64>(), n in 1usize..=60) {
        check(seed, n, false)?;
    }

    #[test]
    fn random_floating_base_trees(seed in any::<u64>(), n in 1usize..=60) {
        check(seed, n, true)?;
    }
}

#[test]
fn long_chain_of_200_bodies() {
    // Deep recursion depth, no branching: the O(N) sweeps must stay accurate down a long chain.
    let mut rng = Rng::new(5);
    let model = chain(200);
    check_chain(&model, &mut rng);
}

fn check_chain(model: &embedyn::Model<f64>, rng: &mut Rng) {
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    let q = rng.configuration(model);
    let v = rng.vec(nv, -1.0, 1.0);
    let tau = rng.vec(nv, -1.0, 1.0);
    let qdd = aba(model, &mut ws, &q, &v, &tau).unwrap().to_vec();
    let back = rnea(model, &mut ws, &q, &v, &qdd).unwrap().to_vec();
    let m = crba(model, &mut ws, &q).unwrap().clone();
    let cond = condition_number(&m);
    let m_norm = m.iter().fold(1.0f64, |a, x| a.max(x.abs()));
    let e = relative_error(&back, &tau);
    eprintln!("chain of {nv}: cond(M) {cond:.2e}, RNEA(ABA) error {e:.2e}");
    assert!(e <= tolerance(nv, cond) * m_norm, "{e:e}");
}
