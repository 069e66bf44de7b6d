//! Constraint embedding (aggregate links) against independent oracles, on the loop models in
//! models/loops and GRBDA's URDF+ files: the Lagrange-multiplier (KKT) solve of the same system, the loop
//! equations at acceleration level, RNEA of the result, the reduced mass matrix, and the constraint
//! Jacobian and J̇v against finite differences of the position constraint.

use crate::common;

use common::{load_model, Rng};
use embedyn::constraints::{self, complete_configuration, complete_velocity, constraint_violation};
use embedyn::linalg::cholesky_in_place;
use embedyn::nalgebra::DMatrix;
use embedyn::{
    aba, constraint_kinematics, embedding_map, forward_kinematics, kkt_forward_dynamics,
    reduced_mass_matrix, relative_error, rnea, JointType, Model, Workspace,
};

/// Every model with loops, couplings or mimic joints the tests run on: (path, --floating).
pub const LOOP_MODELS: [(&str, bool); 17] = [
    ("models/loops/four_bar_internal.urdf", false),
    ("models/loops/four_bar_terminal.urdf", false),
    ("models/loops/slider_crank.urdf", false),
    ("models/loops/geared_motor.urdf", false),
    ("models/loops/rotor_chain_10.urdf", false),
    ("models/loops/differential_wrist.urdf", false),
    ("models/loops/six_bar.urdf", false),
    ("models/loops/parallel_gripper.urdf", false),
    ("models/loops/biped_floating.urdf", false),
    ("models/loops/rotor_chain_10.urdf", true),
    ("tests/data/grbda/four_bar.urdf", false),
    ("tests/data/grbda/six_bar.urdf", false),
    ("tests/data/grbda/planar_leg_linkage.urdf", false),
    ("tests/data/grbda/revolute_rotor_chain.urdf", false),
    ("tests/data/grbda/mini_cheetah.urdf", false),
    ("tests/data/grbda/mit_humanoid.urdf", false),
    ("tests/data/grbda/jvrc1_humanoid.urdf", false),
];

/// A consistent random state near the zero configuration: independent coordinates perturbed by up to
/// ±0.4 (rad or m·0.4), dependent ones completed, velocities random and projected.
pub fn consistent_state(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    rng: &mut Rng,
) -> (Vec<f64>, Vec<f64>) {
    let mut q = model.neutral_configuration();
    for (j, joint) in model.joints.iter().enumerate() {
        match joint.joint_type {
            JointType::Floating => {
                for k in 0..3 {
                    q[joint.q_index + k] = rng.uniform(-1.0, 1.0);
                }
                let quat = rng.vec(4, -1.0, 1.0);
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                for k in 0..4 {
                    q[joint.q_index + 3 + k] = quat[k] / n;
                }
            }
            JointType::Prismatic if model.is_independent(j) => {
                q[joint.q_index] = rng.uniform(-0.05, 0.05)
            }
            _ if model.is_independent(j) => q[joint.q_index] = rng.uniform(-0.4, 0.4),
            _ => {}
        }
    }
    let residual = complete_configuration(model, ws, &mut q).unwrap();
    assert!(
        residual <= 1e-12,
        "{}: position completion left {residual:e}",
        model.name
    );
    let mut v = rng.vec(model.nv(), -1.0, 1.0);
    complete_velocity(model, ws, &q, &mut v).unwrap();
    let (pos, vel) = constraint_violation(model, ws, &q, &v).unwrap();
    assert!(
        pos <= 1e-12 && vel <= 1e-12,
        "{}: residuals {pos:e} {vel:e}",
        model.name
    );
    (q, v)
}

#[test]
fn embedding_matches_the_lagrange_multiplier_solution() {
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        assert!(model.has_constraints(), "{path}");
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(31);
        let mut worst = 0.0f64;
        for _ in 0..5 {
            let (q, v) = consistent_state(&model, &mut ws, &mut rng);
            let tau = rng.vec(model.nv(), -5.0, 5.0);
            let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
            let qdd_kkt = kkt_forward_dynamics(&model, &mut ws, &q, &v, &tau).unwrap();
            worst = worst.max(relative_error(&qdd, &qdd_kkt));
        }
        eprintln!("{path}: embedded ABA vs KKT {worst:.1e}");
        assert!(
            worst <= 1e-9,
            "{path}: embedded ABA differs from the KKT solution by {worst:e}"
        );
    }
}

/// J, J̇v of the kept rows, and the residuals, at (q, v).
fn constraint_rows(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    q: &[f64],
    v: &[f64],
) -> (DMatrix<f64>, Vec<f64>, Vec<f64>) {
    constraint_kinematics(model, ws, q, v).unwrap();
    let raw = model.constraint_raw_rows();
    let mut jac = DMatrix::zeros(raw, model.nv());
    constraints::jacobian(model, ws, &mut jac);
    let mut bias = vec![0.0; raw];
    constraints::bias(model, ws, &mut bias);
    let mut r = vec![0.0; raw];
    constraints::residuals(model, ws, q, &mut r);
    (jac, bias, r)
}

#[test]
fn accelerations_satisfy_the_constraints_and_rnea_inverts_them() {
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(5);
        let (q, v) = consistent_state(&model, &mut ws, &mut rng);
        let tau = rng.vec(model.nv(), -5.0, 5.0);
        let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        // J qdd + J̇ v = 0 on every equation, redundant ones included.
        let (jac, bias, _) = constraint_rows(&model, &mut ws, &q, &v);
        let scale = qdd.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for row in 0..jac.nrows() {
            let s: f64 = (0..model.nv()).map(|c| jac[(row, c)] * qdd[c]).sum::<f64>() + bias[row];
            assert!(
                s.abs() <= 1e-9 * scale,
                "{path}: acceleration constraint row {row}: {s:e}"
            );
        }
        // RNEA of ABA's result gives back τ on the independent coordinates: Xᵀ τ' = Xᵀ τ.
        let tau_back = rnea(&model, &mut ws, &q, &v, &qdd).unwrap().to_vec();
        let x = embedding_map(&model, &mut ws, &q).unwrap();
        let project = |t: &[f64]| -> Vec<f64> {
            (0..x.ncols())
                .map(|c| (0..model.nv()).map(|r| x[(r, c)] * t[r]).sum())
                .collect()
        };
        let e = relative_error(&project(&tau_back), &project(&tau));
        assert!(e <= 1e-9, "{path}: Xᵀ RNEA(ABA) vs Xᵀ τ: {e:e}");
        // Xᵀ M X symmetric positive definite.
        let m = reduced_mass_matrix(&model, &mut ws, &q).unwrap();
        assert_eq!(m.nrows(), model.independent_nv());
        assert!(
            relative_error(m.as_slice(), m.transpose().as_slice()) <= 1e-14,
            "{path}: XᵀMX not symmetric"
        );
        let mut l = m.clone();
        assert!(
            cholesky_in_place(&mut l) > 0.0,
            "{path}: XᵀMX not positive definite"
        );
    }
}

#[test]
fn jacobian_and_bias_match_finite_differences_of_the_position_constraint() {
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(77);
        let (q, v) = consistent_state(&model, &mut ws, &mut rng);
        let (jac, bias, _) = constraint_rows(&model, &mut ws, &q, &v);
        // A direction in the 1-DoF joints only (a floating base would need the quaternion map).
        let dir: Vec<f64> = model
            .joints
            .iter()
            .flat_map(|j| {
                if j.nq() == 1 {
                    vec![rng.uniform(-1.0, 1.0)]
                } else {
                    vec![0.0; j.nv()]
                }
            })
            .collect();
        let shifted = |s: f64| -> Vec<f64> {
            let mut qs = q.clone();
            for j in &model.joints {
                if j.nq() == 1 {
                    qs[j.q_index] += s * dir[j.v_index];
                }
            }
            qs
        };
        let h = 1e-6;
        let zeros = vec![0.0; model.nv()];
        let r_plus = constraint_rows(&model, &mut ws, &shifted(h), &zeros).2;
        let r_minus = constraint_rows(&model, &mut ws, &shifted(-h), &zeros).2;
        let mut worst_j = 0.0f64;
        for row in 0..jac.nrows() {
            let fd = (r_plus[row] - r_minus[row]) / (2.0 * h);
            let an: f64 = (0..model.nv()).map(|c| jac[(row, c)] * dir[c]).sum();
            worst_j = common::worse(worst_j, (fd - an).abs());
        }
        // J̇ v: the derivative of J along v (1-DoF joints moving; a floating base held still).
        let mut vv = v.clone();
        for j in &model.joints {
            if j.nq() != 1 {
                for k in 0..j.nv() {
                    vv[j.v_index + k] = 0.0;
                }
            }
        }
        let (_, bias_vv, _) = constraint_rows(&model, &mut ws, &q, &vv);
        let move_q = |s: f64| -> Vec<f64> {
            let mut qs = q.clone();
            for j in &model.joints {
                if j.nq() == 1 {
                    qs[j.q_index] += s * vv[j.v_index];
                }
            }
            qs
        };
        let (j_plus, _, _) = constraint_rows(&model, &mut ws, &move_q(h), &vv);
        let (j_minus, _, _) = constraint_rows(&model, &mut ws, &move_q(-h), &vv);
        let mut worst_b = 0.0f64;
        for row in 0..jac.nrows() {
            let fd: f64 = (0..model.nv())
                .map(|c| (j_plus[(row, c)] - j_minus[(row, c)]) / (2.0 * h) * vv[c])
                .sum();
            worst_b = common::worse(worst_b, (fd - bias_vv[row]).abs());
        }
        let _ = bias;
        eprintln!("{path}: |J − FD| {worst_j:.1e}, |J̇v − FD| {worst_b:.1e}");
        assert!(
            worst_j <= 1e-7,
            "{path}: constraint Jacobian off its finite difference by {worst_j:e}"
        );
        assert!(
            worst_b <= 1e-6,
            "{path}: J̇v off its finite difference by {worst_b:e}"
        );
    }
}

#[test]
fn position_completion_reaches_machine_precision_and_keeps_the_branch() {
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(9);
    let (q, _) = consistent_state(&model, &mut ws, &mut rng);
    // Perturb the dependent coordinates a little: Newton must come back to the same assembly.
    let mut guess = q.clone();
    for j in 0..model.joints.len() {
        if !model.is_independent(j) {
            guess[model.joints[j].q_index] += 0.05;
        }
    }
    let residual = complete_configuration(&model, &mut ws, &mut guess).unwrap();
    assert!(residual <= 1e-12, "{residual:e}");
    assert!(
        relative_error(&guess, &q) <= 1e-10,
        "completion moved to another branch: {guess:?} vs {q:?}"
    );
    forward_kinematics(&model, &mut ws, &guess, &vec![0.0; model.nv()]).unwrap();
}

/// Completion from many starts on every loop model: each either assembles (finite coordinates, residual
/// ≤ 1e-12, velocity projection succeeds) or reports a residual above the tolerance — never NaN coordinates
/// with a small reported residual (a bug once: an exactly zero pivot made the Newton step NaN, and the
/// residual's maximum dropped the NaN).
#[test]
fn completion_from_many_starts_assembles_or_says_so() {
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(7);
        let mut assembled = 0;
        for _ in 0..100 {
            let mut q = model.neutral_configuration();
            for j in 0..model.joints.len() {
                if model.is_independent(j) && model.joints[j].nq() == 1 {
                    q[model.joints[j].q_index] = rng.uniform(-0.3, 0.3);
                }
            }
            let residual = complete_configuration(&model, &mut ws, &mut q).unwrap();
            if residual <= 1e-12 {
                assert!(
                    q.iter().all(|x| x.is_finite()),
                    "{path}: residual {residual:e} with {q:?}"
                );
                let (pos, _) =
                    constraint_violation(&model, &mut ws, &q, &vec![0.0; model.nv()]).unwrap();
                assert!(
                    pos <= 1e-12,
                    "{path}: reported {residual:e}, actual violation {pos:e}"
                );
                let mut v = rng.vec(model.nv(), -1.0, 1.0);
                complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
                assembled += 1;
            } else {
                assert!(!residual.is_nan() || q.iter().any(|x| x.is_nan()), "{path}");
            }
        }
        // Near the zero pose every bundled mechanism assembles from (nearly) every start.
        assert!(
            assembled >= 95,
            "{path}: only {assembled} of 100 starts assembled"
        );
    }
}

/// The same physical four-bar cut two ways (the paper's Eqs. 43 and 44): at the coupler–rocker pin, with
/// crank and rocker both children of the ground (the *internal* cut, Eq. 44), and at the rocker's ground
/// pivot, the spanning tree a chain ground → crank → coupler → rocker closed back onto the ground (the
/// *terminal* cut, Eq. 43; a `<loop>` whose successor is an ancestor). Coordinates map by
/// q_terminal = T q_internal, T = [[1,0,0,0],[0,1,0,0],[0,0,1,0],[−1,−1,0,1]] (models/loops/README.md),
/// velocities and accelerations likewise; torques on the independent joints are the same in both.
#[test]
fn four_bar_cut_at_terminal_and_internal_joints_agree() {
    let term = load_model::<f64>("models/loops/four_bar_internal.urdf", false); // Eq. 44 cut
    let int = load_model::<f64>("models/loops/four_bar_terminal.urdf", false); // Eq. 43 cut
    let names = ["crank_joint", "coupler_joint", "tip_joint", "rocker_joint"];
    let vi = |m: &Model<f64>, n: &str| m.joints[m.joint_index(n).unwrap()].v_index;
    let map = |m_from: &Model<f64>, m_to: &Model<f64>, x: &[f64]| -> Vec<f64> {
        let g = |n: &str| x[vi(m_from, n)];
        let mut out = vec![0.0; m_to.nv()];
        out[vi(m_to, "crank_joint")] = g("crank_joint");
        out[vi(m_to, "coupler_joint")] = g("coupler_joint");
        out[vi(m_to, "tip_joint")] = g("tip_joint");
        out[vi(m_to, "rocker_joint")] = g("rocker_joint") - g("crank_joint") - g("coupler_joint");
        out
    };
    let (mut ws_t, mut ws_i) = (Workspace::new(&term), Workspace::new(&int));
    let mut rng = Rng::new(12);
    let mut worst = 0.0f64;
    for _ in 0..5 {
        let (q_t, v_t) = consistent_state(&term, &mut ws_t, &mut rng);
        let (q_i, v_i) = (map(&term, &int, &q_t), map(&term, &int, &v_t));
        let (pos, vel) = constraint_violation(&int, &mut ws_i, &q_i, &v_i).unwrap();
        assert!(
            pos <= 1e-12 && vel <= 1e-12,
            "mapped state off the internal cut's constraints: {pos:e} {vel:e}"
        );
        // Torques on the independent joints only: identical in both coordinate sets (τ_term = Tᵀ τ_int).
        let mut tau = vec![0.0; 4];
        tau[vi(&term, "crank_joint")] = rng.uniform(-2.0, 2.0);
        tau[vi(&term, "tip_joint")] = rng.uniform(-0.5, 0.5);
        let tau_i = {
            let mut t = vec![0.0; 4];
            for n in names {
                t[vi(&int, n)] = tau[vi(&term, n)];
            }
            t
        };
        let qdd_t = aba(&term, &mut ws_t, &q_t, &v_t, &tau).unwrap().to_vec();
        let qdd_i = aba(&int, &mut ws_i, &q_i, &v_i, &tau_i).unwrap().to_vec();
        worst = worst.max(relative_error(&map(&term, &int, &qdd_t), &qdd_i));
    }
    eprintln!("four-bar internal (Eq. 44) vs terminal (Eq. 43) cut: {worst:.1e}");
    assert!(worst <= 1e-9, "the two cuts disagree by {worst:e}");
}

/// Every public function taking a state checks it as `aba` does (trial 9): a short `v` made
/// `complete_velocity` index out of bounds, a long one and NaN entries were accepted (and the NaN written
/// into the dependent entries); a model without loops skipped the checks of `constraint_violation` and
/// position completion altogether.
#[test]
fn completion_and_constraint_functions_check_their_inputs_as_aba_does() {
    use embedyn::constraints::{completion_step, y1_condition};
    use embedyn::{reduced_mass_matrix, DynamicsError};
    for path in ["models/loops/four_bar_internal.urdf", "models/arm7.urdf"] {
        let model = load_model(path, false);
        let mut ws = Workspace::new(&model);
        let (nq, nv) = (model.nq(), model.nv());
        let q = model.neutral_configuration();
        let v = vec![0.1; nv];
        let wrong = |name: &'static str, got: usize, expected: usize| DynamicsError::WrongLength {
            name,
            got,
            expected,
        };
        let not_finite = |name: &'static str, index: usize| DynamicsError::NonFiniteInput {
            name,
            index,
            value: f64::INFINITY,
        };
        let mut inf_v = v.clone();
        inf_v[nv - 1] = f64::INFINITY;
        let mut inf_q = q.clone();
        inf_q[nq - 1] = f64::INFINITY;
        // (The reference: what `aba` answers.)
        let tau = vec![0.0; nv];
        assert_eq!(
            aba(&model, &mut ws, &q, &v[1..], &tau).unwrap_err(),
            wrong("v", nv - 1, nv)
        );
        for bad_v in [&v[1..], &[v.clone(), vec![0.0]].concat()[..], &inf_v] {
            let expected = if bad_v.len() == nv {
                not_finite("v", nv - 1)
            } else {
                wrong("v", bad_v.len(), nv)
            };
            let mut out = bad_v.to_vec();
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                complete_velocity(&model, &mut ws, &q, &mut out)
            }))
            .unwrap_or_else(|_| {
                panic!(
                    "{path}: complete_velocity panicked on v of length {}",
                    bad_v.len()
                )
            });
            assert_eq!(result.unwrap_err(), expected, "{path}: complete_velocity");
            assert_eq!(out.len(), bad_v.len());
            assert_eq!(
                constraint_violation(&model, &mut ws, &q, bad_v).unwrap_err(),
                expected,
                "{path}: constraint_violation"
            );
            assert_eq!(
                kkt_forward_dynamics(&model, &mut ws, &q, bad_v, &tau).unwrap_err(),
                expected,
                "{path}: kkt_forward_dynamics"
            );
        }
        for (bad_q, expected) in [
            (&q[1..], wrong("q", nq - 1, nq)),
            (&inf_q[..], not_finite("q", nq - 1)),
        ] {
            let mut out = bad_q.to_vec();
            assert_eq!(
                complete_configuration(&model, &mut ws, &mut out).unwrap_err(),
                expected,
                "{path}: complete_configuration"
            );
            assert_eq!(
                completion_step(&model, &mut ws, &mut out).unwrap_err(),
                expected,
                "{path}: completion_step"
            );
            let mut v2 = v.clone();
            assert_eq!(
                complete_velocity(&model, &mut ws, bad_q, &mut v2).unwrap_err(),
                expected,
                "{path}: complete_velocity"
            );
            assert_eq!(
                constraint_violation(&model, &mut ws, bad_q, &v).unwrap_err(),
                expected,
                "{path}: constraint_violation"
            );
            assert_eq!(
                embedding_map(&model, &mut ws, bad_q).unwrap_err(),
                expected,
                "{path}: embedding_map"
            );
            assert_eq!(
                reduced_mass_matrix(&model, &mut ws, bad_q).unwrap_err(),
                expected,
                "{path}: reduced_mass_matrix"
            );
            // q is checked before tau, as in aba.
            assert_eq!(
                kkt_forward_dynamics(&model, &mut ws, bad_q, &v, &tau[1..]).unwrap_err(),
                expected,
                "{path}: kkt_forward_dynamics"
            );
            if !model.groups.is_empty() {
                assert_eq!(
                    y1_condition(&model, &mut ws, bad_q, 0).unwrap_err(),
                    expected,
                    "{path}: y1_condition"
                );
            }
        }
        // The good state still answers.
        let mut v2 = v.clone();
        complete_velocity(&model, &mut ws, &q, &mut v2).unwrap();
        constraint_violation(&model, &mut ws, &q, &v2).unwrap();
    }
}
