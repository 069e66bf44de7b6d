//! Derivatives of forward and inverse dynamics (issue 12) against independent oracles: central finite
//! differences along `integrate` (the free flyer moves on SE(3)), on trees and, along the constraint
//! manifold through `complete`, on every loop, coupling and mimic model; and the invariants
//! `∂q̈/∂τ · M = I`, `∂τ/∂q̈ = M` and `∂q̈/∂q = −M⁻¹ ∂τ/∂q` at `q̈ = aba(q, v, τ)` (and the same for `v`).

use crate::common::{load_model, random_tree, Rng};
use crate::constraint_embedding::{consistent_state, LOOP_MODELS};
use embedyn::constraints::{complete_configuration, complete_velocity};
use embedyn::nalgebra::{DMatrix, DVector, Vector3};
use embedyn::{
    aba, aba_derivative_factors, aba_derivatives, aba_derivatives_independent, aba_ext, crba,
    integrate, mass_matrix_inverse, rnea_derivatives, rnea_ext, step, step_derivatives,
    AbaDerivativeFactors, AbaDerivatives, DerivativeMethod, DerivativeWorkspace, DynamicsError,
    FrameId, LinkWrench, ManifoldDerivatives, Model, RneaDerivatives, StepDerivatives, Workspace,
};

/// A model with a state: (name, model, q, v, and τ or q̈).
type Case = (&'static str, Model<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// Trees: the quadruped and arm bundled, the floating ANYmal B with its merged feet, random branching
/// trees fixed and floating; a random state each.
pub fn trees() -> Vec<Case> {
    let mut rng = Rng::new(21);
    let mut out = Vec::new();
    for (path, floating) in [
        ("models/quadruped.urdf", false),
        ("models/arm7.urdf", false),
        ("tests/data/pinocchio/anymal_b.urdf", true),
    ] {
        let model = load_model::<f64>(path, floating);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.5, 1.5);
        let u = rng.vec(model.nv(), -3.0, 3.0);
        out.push((path, model, q, v, u));
    }
    for (name, n, floating) in [
        ("random tree", 9, false),
        ("random floating tree", 12, true),
    ] {
        let model = random_tree(&mut rng, n, floating);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.5, 1.5);
        let u = rng.vec(model.nv(), -3.0, 3.0);
        out.push((name, model, q, v, u));
    }
    out
}

/// Central-difference steps. The configuration enters nonlinearly: a small step (truncation ~h², rounding
/// ~ε/h). Accelerations and forces are quadratic in the velocities and affine in τ (and in `v_I` along
/// the manifold: the dependent velocities are linear in the independent ones at a fixed configuration),
/// where a central difference is exact for any step, so a large one keeps rounding small.
const H_Q: f64 = 1e-6;
const H_V: f64 = 1e-2;
const H_TAU: f64 = 1.0;

/// `q ⊕ s eₖ`.
fn moved(model: &Model<f64>, q: &[f64], k: usize, s: f64) -> Vec<f64> {
    let mut step = vec![0.0; model.nv()];
    step[k] = s;
    let mut out = vec![0.0; model.nq()];
    integrate(model, q, &step, &mut out).unwrap();
    out
}

fn with(x: &[f64], k: usize, s: f64) -> Vec<f64> {
    let mut y = x.to_vec();
    y[k] += s;
    y
}

/// Largest entry of `a − b` over the largest of `b` (at least 1).
fn rel<C: embedyn::nalgebra::Dim>(
    a: &embedyn::nalgebra::OMatrix<f64, embedyn::nalgebra::Dyn, C>,
    b: &embedyn::nalgebra::OMatrix<f64, embedyn::nalgebra::Dyn, C>,
) -> f64
where
    embedyn::nalgebra::DefaultAllocator:
        embedyn::nalgebra::allocator::Allocator<embedyn::nalgebra::Dyn, C>,
{
    (a - b).abs().max() / b.abs().max().max(1.0)
}

/// The central difference of `f` in each of `n` directions, as the columns of a matrix.
fn central(
    rows: usize,
    n: usize,
    h: f64,
    mut f: impl FnMut(usize, f64) -> Vec<f64>,
) -> DMatrix<f64> {
    let columns: Vec<_> = (0..n)
        .map(|k| {
            let (p, m) = (f(k, h), f(k, -h));
            DVector::from_iterator(rows, p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)))
        })
        .collect();
    DMatrix::from_columns(&columns)
}

/// A wrench on one of the model's links (the last body's), so that the derivatives are taken with the
/// wrench held in the link's frame.
fn one_wrench(model: &Model<f64>) -> Vec<LinkWrench<f64>> {
    let body = model.nbodies() - 1;
    let frame = FrameId {
        body: Some(body),
        link: 0,
    };
    vec![LinkWrench::new(
        frame,
        Vector3::new(3.0, -2.0, 5.0),
        Vector3::new(0.4, 0.1, -0.3),
    )]
}

#[test]
fn aba_derivatives_match_finite_differences_on_trees() {
    for (name, model, q, v, tau) in trees() {
        let f_ext = one_wrench(&model);
        let nv = model.nv();
        let mut dws = DerivativeWorkspace::new(&model);
        let mut d = AbaDerivatives::new(&model);
        aba_derivatives(&model, &mut dws, &q, &v, &tau, &f_ext, &mut d).unwrap();
        let mut ws = Workspace::new(&model);
        let mut qdd = |q: &[f64], v: &[f64], t: &[f64]| {
            aba_ext(&model, &mut ws, q, v, t, &f_ext).unwrap().to_vec()
        };
        assert_eq!(d.qdd.as_slice(), qdd(&q, &v, &tau).as_slice(), "{name}");
        let dq = central(nv, nv, H_Q, |k, s| qdd(&moved(&model, &q, k, s), &v, &tau));
        let dv = central(nv, nv, H_V, |k, s| qdd(&q, &with(&v, k, s), &tau));
        let dt = central(nv, nv, H_TAU, |k, s| qdd(&q, &v, &with(&tau, k, s)));
        let errors = [
            rel(&d.dqdd_dq, &dq),
            rel(&d.dqdd_dv, &dv),
            rel(&d.dqdd_dtau, &dt),
        ];
        assert!(
            errors[0] < 1e-7 && errors[1] < 1e-11 && errors[2] < 1e-11,
            "{name}: {errors:?}"
        );
    }
}

#[test]
fn rnea_derivatives_match_finite_differences_and_the_mass_matrix() {
    for (name, model, q, v, qdd) in trees() {
        let f_ext = one_wrench(&model);
        let nv = model.nv();
        let mut dws = DerivativeWorkspace::new(&model);
        let mut d = RneaDerivatives::new(&model);
        rnea_derivatives(&model, &mut dws, &q, &v, &qdd, &f_ext, &mut d).unwrap();
        let mut ws = Workspace::new(&model);
        let mut tau = |q: &[f64], v: &[f64], a: &[f64]| {
            rnea_ext(&model, &mut ws, q, v, a, &f_ext).unwrap().to_vec()
        };
        let dq = central(nv, nv, H_Q, |k, s| tau(&moved(&model, &q, k, s), &v, &qdd));
        let dv = central(nv, nv, H_V, |k, s| tau(&q, &with(&v, k, s), &qdd));
        let errors = [rel(&d.dtau_dq, &dq), rel(&d.dtau_dv, &dv)];
        assert!(errors[0] < 1e-7 && errors[1] < 1e-11, "{name}: {errors:?}");
        let mut ws = Workspace::new(&model);
        let m = crba(&model, &mut ws, &q).unwrap().clone();
        assert!(rel(&d.dtau_dqdd, &m) < 1e-14, "{name}: ∂τ/∂q̈ is not M");
    }
}

/// `∂q̈/∂τ = M⁻¹`, and the derivatives of forward dynamics are those of inverse dynamics moved through
/// `M⁻¹` at the accelerations forward dynamics gives (`∂q̈/∂x = −M⁻¹ ∂τ/∂x`, differentiating
/// `τ = rnea(q, v, aba(q, v, τ))`): two algorithms, one answer.
#[test]
fn forward_derivatives_are_minus_m_inverse_times_inverse_derivatives() {
    for (name, model, q, v, tau) in trees() {
        let mut dws = DerivativeWorkspace::new(&model);
        let mut fd = AbaDerivatives::new(&model);
        aba_derivatives(&model, &mut dws, &q, &v, &tau, &[], &mut fd).unwrap();
        let mut id = RneaDerivatives::new(&model);
        let qdd = fd.qdd.as_slice().to_vec();
        rnea_derivatives(&model, &mut dws, &q, &v, &qdd, &[], &mut id).unwrap();
        let identity = DMatrix::identity(model.nv(), model.nv());
        assert!(
            rel(&(&fd.dqdd_dtau * &id.dtau_dqdd), &identity) < 1e-10,
            "{name}: M⁻¹ M ≠ I"
        );
        let dq = -&fd.dqdd_dtau * &id.dtau_dq;
        let dv = -&fd.dqdd_dtau * &id.dtau_dv;
        assert!(
            rel(&fd.dqdd_dq, &dq) < 1e-10,
            "{name}: ∂q̈/∂q {}",
            rel(&fd.dqdd_dq, &dq)
        );
        assert!(
            rel(&fd.dqdd_dv, &dv) < 1e-10,
            "{name}: ∂q̈/∂v {}",
            rel(&fd.dqdd_dv, &dv)
        );
    }
}

/// The methods, the world-frame recursion (the default on trees; the chain rule for `step`), the same with
/// forward dynamics from the factorized mass matrix, and dual numbers through `aba`, `rnea` and `step`,
/// share no arithmetic (the recursion computes its values in the root's frame, dual numbers in the
/// bodies'): they agree to rounding, with a wrench on a link.
#[test]
fn the_analytical_recursion_and_dual_numbers_agree() {
    for (name, model, q, v, u) in trees() {
        let f_ext = one_wrench(&model);
        let mut results = Vec::new();
        for method in [
            DerivativeMethod::DualNumbers,
            DerivativeMethod::Analytical,
            DerivativeMethod::MassMatrixFactorization,
        ] {
            let mut dws = DerivativeWorkspace::new(&model);
            dws.set_method(method);
            let mut fd = AbaDerivatives::new(&model);
            aba_derivatives(&model, &mut dws, &q, &v, &u, &f_ext, &mut fd).unwrap();
            let mut id = RneaDerivatives::new(&model);
            rnea_derivatives(&model, &mut dws, &q, &v, &u, &f_ext, &mut id).unwrap();
            let mut sd = StepDerivatives::new(&model);
            step_derivatives(&model, &mut dws, &q, &v, &u, 0.01, &f_ext, &mut sd).unwrap();
            results.push((method, fd, id, sd));
        }
        let (_, fb, ib, sb) = &results[0];
        for (method, fa, ia, sa) in &results[1..] {
            let errors = [
                rel(&sa.q_next, &sb.q_next),
                rel(&sa.v_next, &sb.v_next),
                rel(&sa.dq_next_dq, &sb.dq_next_dq),
                rel(&sa.dq_next_dv, &sb.dq_next_dv),
                rel(&sa.dq_next_dtau, &sb.dq_next_dtau),
                rel(&sa.dv_next_dq, &sb.dv_next_dq),
                rel(&sa.dv_next_dv, &sb.dv_next_dv),
                rel(&sa.dv_next_dtau, &sb.dv_next_dtau),
                rel(&fa.qdd, &fb.qdd),
                rel(&ia.tau, &ib.tau),
                rel(&fa.dqdd_dq, &fb.dqdd_dq),
                rel(&fa.dqdd_dv, &fb.dqdd_dv),
                rel(&fa.dqdd_dtau, &fb.dqdd_dtau),
                rel(&ia.dtau_dq, &ib.dtau_dq),
                rel(&ia.dtau_dv, &ib.dtau_dv),
                rel(&ia.dtau_dqdd, &ib.dtau_dqdd),
            ];
            assert!(
                errors.iter().fold(0.0, |a, &b| crate::common::worse(a, b)) < 1e-12,
                "{name}, {method:?}: {errors:?}"
            );
        }
    }
}

/// The derivatives do not depend on where the robot stands: a floating tree 10 km from the world origin
/// and an arm mounted there (the recursion's inertias about the world origin lost digits as `ε d²`:
/// 6e-7 at 10 km in f64, 4 % at 100 m in f32, attacker's trial) agree with dual numbers, which work in
/// body frames, as near the origin; and f32 keeps its digits 100 m out.
#[test]
fn derivatives_far_from_the_world_origin_keep_their_digits() {
    let mut rng = Rng::new(31);
    let floating = random_tree(&mut rng, 9, true);
    let mut arm = load_model::<f64>("models/arm7.urdf", false);
    arm.joints[0].placement.translation += Vector3::new(1e4, -5e3, 3e3);
    for (name, model, far) in [("floating tree", floating, true), ("arm", arm, false)] {
        let mut q = rng.configuration(&model);
        if far {
            q[0] += 1e4;
            q[1] -= 5e3;
            q[2] += 3e3;
        }
        let v = rng.vec(model.nv(), -1.5, 1.5);
        let tau = rng.vec(model.nv(), -3.0, 3.0);
        let mut results = Vec::new();
        for method in [DerivativeMethod::Analytical, DerivativeMethod::DualNumbers] {
            let mut dws = DerivativeWorkspace::new(&model);
            dws.set_method(method);
            let mut d = AbaDerivatives::new(&model);
            aba_derivatives(&model, &mut dws, &q, &v, &tau, &[], &mut d).unwrap();
            results.push(d);
        }
        let errors = [
            rel(&results[0].dqdd_dq, &results[1].dqdd_dq),
            rel(&results[0].dqdd_dv, &results[1].dqdd_dv),
        ];
        assert!(errors[0] < 1e-12 && errors[1] < 1e-12, "{name}: {errors:?}");
    }
    // f32, 100 m out, against f64.
    let model = random_tree(&mut Rng::new(32), 9, true);
    let mut rng = Rng::new(33);
    let mut q = rng.configuration(&model);
    q[0] += 100.0;
    let (v, tau) = (
        rng.vec(model.nv(), -1.5, 1.5),
        rng.vec(model.nv(), -3.0, 3.0),
    );
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = AbaDerivatives::new(&model);
    aba_derivatives(&model, &mut dws, &q, &v, &tau, &[], &mut d).unwrap();
    let model32: Model<f32> = model.cast();
    let to32 = |x: &[f64]| x.iter().map(|&y| y as f32).collect::<Vec<f32>>();
    let mut dws = DerivativeWorkspace::new(&model32);
    let mut d32 = AbaDerivatives::new(&model32);
    aba_derivatives(
        &model32,
        &mut dws,
        &to32(&q),
        &to32(&v),
        &to32(&tau),
        &[],
        &mut d32,
    )
    .unwrap();
    let widen = |m: &DMatrix<f32>| m.map(f64::from);
    let errors = [
        rel(&widen(&d32.dqdd_dq), &d.dqdd_dq),
        rel(&widen(&d32.dqdd_dv), &d.dqdd_dv),
    ];
    assert!(errors[0] < 1e-3 && errors[1] < 1e-3, "f32: {errors:?}");
}

/// A `DerivativeWorkspace` made for a model that differs only in an armature, a turned joint placement
/// or a merged link's placement is refused (dual numbers run on the workspace's copy of the model and
/// would differentiate the old one; attacker's trial).
#[test]
fn a_workspace_of_a_slightly_different_model_is_refused() {
    let model = load_model::<f64>("models/arm7.urdf", false);
    let mut rng = Rng::new(41);
    let q = rng.configuration(&model);
    let v = rng.vec(model.nv(), -1.0, 1.0);
    let mut changed = Vec::new();
    let mut m = model.clone();
    m.joints[2].armature = 0.1;
    changed.push(("armature", m));
    let mut m = model.clone();
    m.joints[1].placement = m.joints[1]
        .placement
        .compose(&embedyn::Transform::from_xyz_rpy([0.0; 3], [0.3, 0.0, 0.0]));
    changed.push(("placement", m));
    let mut m = model.clone();
    let last = m.bodies.len() - 1;
    if let Some(link) = m.bodies[last].link_placements.last_mut() {
        link.translation.x += 0.1;
    }
    changed.push(("link placement", m));
    for (what, other) in changed {
        for method in [DerivativeMethod::Analytical, DerivativeMethod::DualNumbers] {
            let mut dws = DerivativeWorkspace::new(&other);
            dws.set_method(method);
            let mut d = AbaDerivatives::new(&model);
            let e = aba_derivatives(&model, &mut dws, &q, &v, &v, &[], &mut d);
            assert!(
                matches!(e, Err(DynamicsError::WrongLength { .. })),
                "{what}, {method:?}: {e:?}"
            );
        }
    }
}

/// `aba_derivative_factors` gives the factors `aba_derivatives` multiplies: `q̈` of `aba`, `∂τ` of
/// `rnea_derivatives` at that `q̈`, `M⁻¹` of `mass_matrix_inverse`, and `−M⁻¹ ∂τ` is `aba_derivatives`'
/// result; a model with loops is refused (its derivatives are not that product).
#[test]
fn forward_derivative_factors_multiply_to_the_derivatives() {
    for (name, model, q, v, tau) in trees() {
        let f_ext = one_wrench(&model);
        let mut dws = DerivativeWorkspace::new(&model);
        let mut f = AbaDerivativeFactors::new(&model);
        aba_derivative_factors(&model, &mut dws, &q, &v, &tau, &f_ext, &mut f).unwrap();
        let mut ws = Workspace::new(&model);
        let qdd = aba_ext(&model, &mut ws, &q, &v, &tau, &f_ext)
            .unwrap()
            .to_vec();
        assert_eq!(f.qdd.as_slice(), qdd.as_slice(), "{name}");
        let mut id = RneaDerivatives::new(&model);
        rnea_derivatives(&model, &mut dws, &q, &v, &qdd, &f_ext, &mut id).unwrap();
        assert_eq!(f.dtau_dq, id.dtau_dq, "{name}");
        assert_eq!(f.dtau_dv, id.dtau_dv, "{name}");
        let minv = mass_matrix_inverse(&model, &mut ws, &q).unwrap().clone();
        assert_eq!(f.minv, minv, "{name}");
        let mut fd = AbaDerivatives::new(&model);
        aba_derivatives(&model, &mut dws, &q, &v, &tau, &f_ext, &mut fd).unwrap();
        let errors = [
            rel(&fd.dqdd_dq, &(-&f.minv * &f.dtau_dq)),
            rel(&fd.dqdd_dv, &(-&f.minv * &f.dtau_dv)),
        ];
        assert!(errors[0] < 1e-13 && errors[1] < 1e-13, "{name}: {errors:?}");
    }
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    let mut ws = Workspace::new(&model);
    let (q, v) = consistent_state(&model, &mut ws, &mut Rng::new(5));
    let mut dws = DerivativeWorkspace::new(&model);
    let mut f = AbaDerivativeFactors::new(&model);
    let tau = vec![0.0; model.nv()];
    assert_eq!(
        aba_derivative_factors(&model, &mut dws, &q, &v, &tau, &[], &mut f),
        Err(DynamicsError::TreeOnly {
            function: "aba_derivative_factors"
        })
    );
}

/// Along the constraint manifold: the independent coordinates moved, the dependent ones completed
/// (`complete_configuration` from the unmoved state, then `complete_velocity` with the independent
/// velocities held), on every loop, coupling and mimic model.
#[test]
fn manifold_derivatives_match_finite_differences_through_complete() {
    let mut rng = Rng::new(22);
    for &(path, floating) in LOOP_MODELS.iter() {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let (q, v) = consistent_state(&model, &mut ws, &mut rng);
        let tau = rng.vec(model.nv(), -2.0, 2.0);
        let (nv, ni) = (model.nv(), model.independent_nv());
        let independent: Vec<usize> = model.independent_coordinates().collect();
        let mut dws = DerivativeWorkspace::new(&model);
        let mut d = ManifoldDerivatives::new(&model);
        aba_derivatives_independent(&model, &mut dws, &q, &v, &tau, &[], &mut d).unwrap();

        let mut qdd_independent = |q: &[f64], v: &[f64], t: &[f64]| -> Vec<f64> {
            let qdd = aba(&model, &mut ws, q, v, t).unwrap();
            independent.iter().map(|&i| qdd[i]).collect()
        };
        let mut ws2 = Workspace::new(&model);
        // The state moved along independent coordinate r by s: q_I ⊕ s e_r, q_D completed, v_D following.
        let mut on_manifold = |r: usize, s: f64, move_velocity: bool| -> (Vec<f64>, Vec<f64>) {
            let k = independent[r];
            let (mut q1, mut v1) = if move_velocity {
                (q.clone(), with(&v, k, s))
            } else {
                (moved(&model, &q, k, s), v.clone())
            };
            let residual = complete_configuration(&model, &mut ws2, &mut q1).unwrap();
            assert!(residual < 1e-12, "{path}: completion residual {residual}");
            complete_velocity(&model, &mut ws2, &q1, &mut v1).unwrap();
            (q1, v1)
        };
        let dq = central(ni, ni, H_Q, |r, s| {
            let (q1, v1) = on_manifold(r, s, false);
            qdd_independent(&q1, &v1, &tau)
        });
        let dv = central(ni, ni, H_V, |r, s| {
            let (q1, v1) = on_manifold(r, s, true);
            qdd_independent(&q1, &v1, &tau)
        });
        let dt = central(ni, nv, H_TAU, |k, s| {
            qdd_independent(&q, &v, &with(&tau, k, s))
        });
        let errors = [
            rel(&d.dqdd_dq, &dq),
            rel(&d.dqdd_dv, &dv),
            rel(&d.dqdd_dtau, &dt),
        ];
        assert!(
            errors[0] < 1e-6 && errors[1] < 1e-9 && errors[2] < 1e-10,
            "{path} (floating {floating}): {errors:?}"
        );
    }
}

/// The reference robots of tests/data/pinocchio/derivatives.py: (reference name, URDF, floating).
pub const PINOCCHIO_ROBOTS: [(&str, &str, bool); 4] = [
    ("ur5", "tests/data/pinocchio/ur5.urdf", false),
    (
        "solo12_floating",
        "tests/data/pinocchio/solo12_floating.urdf",
        true,
    ),
    (
        "anymal_b_floating",
        "tests/data/pinocchio/anymal_b.urdf",
        true,
    ),
    (
        "talos_reduced_floating",
        "tests/data/erd/talos_reduced.urdf",
        true,
    ),
];

/// One reference sample in our coordinates: (q, v, τ, q̈ for rnea, wrenches) and a reader of its
/// matrices (`field` → our row and column order).
pub struct PinocchioSample {
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    pub tau: Vec<f64>,
    pub qdd_for_rnea: Vec<f64>,
    pub f_ext: Vec<LinkWrench<f64>>,
    json: serde_json::Value,
    v_map: Vec<usize>,
}

impl PinocchioSample {
    /// The reference matrix `field` (Pinocchio's v order) in ours.
    pub fn matrix(&self, field: &str) -> DMatrix<f64> {
        let rows = self.json[field].as_array().unwrap();
        let n = self.v_map.len();
        DMatrix::from_fn(n, n, |i, k| {
            rows[self.v_map[i]][self.v_map[k]].as_f64().unwrap()
        })
    }

    /// The reference vector `field` in our order.
    pub fn vector(&self, field: &str) -> Vec<f64> {
        let x = crate::pinocchio_reference::vecf(&self.json[field]);
        self.v_map.iter().map(|&p| x[p]).collect()
    }
}

/// The samples of `<name>_derivatives.json` for `model`.
pub fn pinocchio_samples(name: &str, model: &Model<f64>) -> Vec<PinocchioSample> {
    use crate::pinocchio_reference::{coordinate_maps, vecf};
    let path = crate::common::repo_path(&format!("tests/data/pinocchio/{name}_derivatives.json"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let (q_map, v_map) = coordinate_maps(name, model, &json);
    json["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let in_q = |x: Vec<f64>| q_map.iter().map(|&p| x[p]).collect::<Vec<f64>>();
            let in_v = |x: Vec<f64>| v_map.iter().map(|&p| x[p]).collect::<Vec<f64>>();
            let f_ext = s["f_ext"]
                .as_object()
                .map(|links| {
                    links
                        .iter()
                        .map(|(link, w)| {
                            // A link fixed to the world is a frame too: its wrench has no effect.
                            let frame = model
                                .frame(link)
                                .unwrap_or_else(|| panic!("{name}: no link {link}"));
                            let f = vecf(&w["force"]);
                            let t = vecf(&w["torque"]);
                            LinkWrench::new(
                                frame,
                                Vector3::new(f[0], f[1], f[2]),
                                Vector3::new(t[0], t[1], t[2]),
                            )
                        })
                        .collect()
                })
                .unwrap_or_default();
            PinocchioSample {
                q: in_q(vecf(&s["q"])),
                v: in_v(vecf(&s["v"])),
                tau: in_v(vecf(&s["tau"])),
                qdd_for_rnea: in_v(vecf(&s["qdd_for_rnea"])),
                f_ext,
                json: s.clone(),
                v_map: v_map.clone(),
            }
        })
        .collect()
}

/// Against Pinocchio 4.1's analytical derivatives (`computeABADerivatives`, `computeRNEADerivatives`, with
/// the external wrenches of the contact references): a fixed arm, two floating quadrupeds and a floating
/// humanoid, every matrix to 1e-9 relative (observed about 1e-13).
#[test]
fn derivatives_match_pinocchio() {
    for (name, urdf, floating) in PINOCCHIO_ROBOTS {
        let model = load_model::<f64>(urdf, floating);
        let mut dws = DerivativeWorkspace::new(&model);
        let mut fd = AbaDerivatives::new(&model);
        let mut id = RneaDerivatives::new(&model);
        for (k, s) in pinocchio_samples(name, &model).iter().enumerate() {
            aba_derivatives(&model, &mut dws, &s.q, &s.v, &s.tau, &s.f_ext, &mut fd).unwrap();
            rnea_derivatives(
                &model,
                &mut dws,
                &s.q,
                &s.v,
                &s.qdd_for_rnea,
                &s.f_ext,
                &mut id,
            )
            .unwrap();
            let qdd = DMatrix::from_column_slice(model.nv(), 1, &s.vector("qdd"));
            let tau = DMatrix::from_column_slice(model.nv(), 1, &s.vector("tau_rnea"));
            let checks = [
                (
                    "qdd",
                    rel(
                        &DMatrix::from_column_slice(model.nv(), 1, fd.qdd.as_slice()),
                        &qdd,
                    ),
                ),
                ("dqdd_dq", rel(&fd.dqdd_dq, &s.matrix("dqdd_dq"))),
                ("dqdd_dv", rel(&fd.dqdd_dv, &s.matrix("dqdd_dv"))),
                ("dqdd_dtau", rel(&fd.dqdd_dtau, &s.matrix("dqdd_dtau"))),
                (
                    "tau",
                    rel(
                        &DMatrix::from_column_slice(model.nv(), 1, id.tau.as_slice()),
                        &tau,
                    ),
                ),
                ("dtau_dq", rel(&id.dtau_dq, &s.matrix("dtau_dq"))),
                ("dtau_dv", rel(&id.dtau_dv, &s.matrix("dtau_dv"))),
                ("dtau_dqdd", rel(&id.dtau_dqdd, &s.matrix("dtau_dqdd"))),
            ];
            for (field, e) in checks {
                assert!(
                    e < 1e-9,
                    "{name} sample {k}: {field} differs from Pinocchio by {e:e}"
                );
            }
        }
    }
}

/// `step`'s Jacobian against central differences of `step` itself (configurations compared by
/// `difference` against the undisturbed next configuration), on trees fixed and floating with a wrench;
/// and its τ block `∂v'/∂τ = dt M⁻¹`.
#[test]
fn step_jacobian_matches_finite_differences_of_step() {
    let dt = 0.01;
    for (name, model, q, v, tau) in trees() {
        let f_ext = one_wrench(&model);
        let (nq, nv) = (model.nq(), model.nv());
        let mut dws = DerivativeWorkspace::new(&model);
        let mut d = StepDerivatives::new(&model);
        step_derivatives(&model, &mut dws, &q, &v, &tau, dt, &f_ext, &mut d).unwrap();
        let mut ws = Workspace::new(&model);
        let q0 = d.q_next.as_slice().to_vec();
        // The next state as one vector: [q' ⊖ q'₀; v'].
        let mut next = |q: &[f64], v: &[f64], t: &[f64]| -> Vec<f64> {
            let (mut q1, mut v1) = (vec![0.0; nq], vec![0.0; nv]);
            step(&model, &mut ws, q, v, t, dt, &f_ext, &mut q1, &mut v1).unwrap();
            let mut dq = vec![0.0; nv];
            embedyn::difference(&model, &q0, &q1, &mut dq).unwrap();
            dq.into_iter().chain(v1).collect()
        };
        assert!(next(&q, &v, &tau).iter().take(nv).all(|x| x.abs() < 1e-15));
        let stacked = |top: &DMatrix<f64>, bottom: &DMatrix<f64>| {
            let mut m = DMatrix::zeros(2 * nv, nv);
            m.rows_mut(0, nv).copy_from(top);
            m.rows_mut(nv, nv).copy_from(bottom);
            m
        };
        let fq = central(2 * nv, nv, H_Q, |k, s| {
            next(&moved(&model, &q, k, s), &v, &tau)
        });
        let fv = central(2 * nv, nv, 1e-5, |k, s| next(&q, &with(&v, k, s), &tau));
        let ft = central(2 * nv, nv, 1e-3, |k, s| next(&q, &v, &with(&tau, k, s)));
        let errors = [
            rel(&stacked(&d.dq_next_dq, &d.dv_next_dq), &fq),
            rel(&stacked(&d.dq_next_dv, &d.dv_next_dv), &fv),
            rel(&stacked(&d.dq_next_dtau, &d.dv_next_dtau), &ft),
        ];
        assert!(errors.iter().all(|&e| e < 1e-7), "{name}: {errors:?}");
        let mut ws = Workspace::new(&model);
        let m = crba(&model, &mut ws, &q).unwrap().clone();
        let identity = DMatrix::<f64>::identity(nv, nv);
        assert!(
            rel(&(&d.dv_next_dtau * &m / dt), &identity) < 1e-10,
            "{name}: ∂v'/∂τ ≠ dt M⁻¹"
        );
    }
}

/// Inputs the derivatives refuse rather than answer wrongly or panic on: a workspace made for another
/// model, a non-finite time step, and the errors of `aba` itself (a NaN velocity).
#[test]
fn derivatives_refuse_bad_inputs() {
    let arm: Model<f64> = load_model("models/arm7.urdf", false);
    let quadruped: Model<f64> = load_model("models/quadruped.urdf", false);
    let mut other = DerivativeWorkspace::new(&quadruped);
    let mut d = AbaDerivatives::new(&arm);
    let (q, v, tau) = (vec![0.1; 7], vec![0.0; 7], vec![0.0; 7]);
    let e = aba_derivatives(&arm, &mut other, &q, &v, &tau, &[], &mut d).unwrap_err();
    assert!(
        matches!(e, embedyn::DynamicsError::WrongLength { .. }),
        "{e}"
    );
    let mut dws = DerivativeWorkspace::new(&arm);
    let mut s = StepDerivatives::new(&arm);
    for dt in [f64::NAN, f64::INFINITY] {
        let e = step_derivatives(&arm, &mut dws, &q, &v, &tau, dt, &[], &mut s).unwrap_err();
        assert!(
            e.to_string().starts_with("`dt` is not a finite number"),
            "{e}"
        );
        assert!(
            matches!(
                e,
                embedyn::DynamicsError::NonFiniteScalar { name: "dt", .. }
            ),
            "{e}"
        );
    }
    // A finite dt whose step overflows names the step, not the input velocity.
    let e = step_derivatives(&arm, &mut dws, &q, &v, &tau, 1e308, &[], &mut s).unwrap_err();
    assert!(
        matches!(
            e,
            embedyn::DynamicsError::NonFiniteInput {
                name: "dt · v_next",
                ..
            }
        ),
        "{e}"
    );
    // One output of the wrong size (the struct otherwise right) is an error too, not a panic.
    let mut wrong = AbaDerivatives::new(&arm);
    wrong.dqdd_dv = DMatrix::zeros(2, 2);
    let e = aba_derivatives(&arm, &mut dws, &q, &v, &tau, &[], &mut wrong).unwrap_err();
    assert!(
        matches!(e, embedyn::DynamicsError::WrongLength { .. }),
        "{e}"
    );
    let mut wrong = StepDerivatives::new(&arm);
    wrong.dv_next_dtau = DMatrix::zeros(1, 1);
    let e = step_derivatives(&arm, &mut dws, &q, &v, &tau, 0.01, &[], &mut wrong).unwrap_err();
    assert!(
        matches!(e, embedyn::DynamicsError::WrongLength { .. }),
        "{e}"
    );
    let mut wrong = ManifoldDerivatives::new(&arm);
    wrong.dqdd_dv = DMatrix::zeros(7, 2);
    let e = aba_derivatives_independent(&arm, &mut dws, &q, &v, &tau, &[], &mut wrong).unwrap_err();
    assert!(
        matches!(e, embedyn::DynamicsError::WrongLength { .. }),
        "{e}"
    );
    // A workspace of a model with the same sizes but other numbers (here: no gravity) is refused.
    let loaded = embedyn::load(&crate::common::repo_path("models/arm7.urdf")).unwrap();
    let weightless: Model<f64> = loaded
        .model(&embedyn::ModelOptions {
            gravity: [0.0, 0.0, 0.0],
            ..Default::default()
        })
        .unwrap();
    let mut theirs = DerivativeWorkspace::new(&weightless);
    let e = aba_derivatives(&arm, &mut theirs, &q, &v, &tau, &[], &mut d).unwrap_err();
    assert!(
        matches!(e, embedyn::DynamicsError::WrongLength { .. }),
        "{e}"
    );
    let mut bad_v = v.clone();
    bad_v[3] = f64::NAN;
    let e = aba_derivatives(&arm, &mut dws, &q, &bad_v, &tau, &[], &mut d).unwrap_err();
    assert!(
        matches!(
            e,
            embedyn::DynamicsError::NonFiniteInput {
                name: "v",
                index: 3,
                ..
            }
        ),
        "{e}"
    );
}

/// Near a four-bar's toggle the derivatives lose digits as cond₁(Y1)² (the derivative of `Y1⁻¹`): they are
/// refused from the square root of the values' threshold, where `aba` itself still answers, and answered
/// (matching finite differences) away from it.
#[test]
fn derivatives_near_a_toggle_are_refused_not_wrong() {
    let model: Model<f64> = load_model("models/loops/singular_four_bar.urdf", false);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = ManifoldDerivatives::new(&model);
    let mut ws = Workspace::new(&model);
    let toggle = std::f64::consts::FRAC_PI_3;
    for (distance, refused) in [(1e-9, true), (1e-6, true), (0.2, false)] {
        let th = toggle + distance;
        let q = vec![th, -th, th];
        let v = vec![0.7, -0.7, 0.7];
        let tau = vec![0.1, 0.0, 0.0];
        // `aba` answers at all three (its own threshold is 1e10).
        aba(&model, &mut ws, &q, &v, &tau).unwrap();
        let result = aba_derivatives_independent(&model, &mut dws, &q, &v, &tau, &[], &mut d);
        match (refused, result) {
            (true, Err(embedyn::DynamicsError::SingularConstraint { .. })) => {}
            (false, Ok(())) => {}
            (_, other) => panic!("{distance}: {other:?}"),
        }
    }
}
