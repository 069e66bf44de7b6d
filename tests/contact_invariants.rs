//! Invariants of external wrenches, frame kinematics, centre of mass and centroidal momentum, where
//! Pinocchio has no answer too (loops, couplings, mimic joints) — issue 11's independent oracles:
//! `J v` is the frame velocity; Jacobians, `J̇ v`, `J_com` and `Ȧ_g v` against central finite differences
//! along `integrate` (the free flyer moves on SE(3)); a wrench is the generalized force `Jᵀ f`
//! (`rnea_ext = rnea − Σ Jᵀ f`, `aba_ext(τ) = aba(τ + Σ Jᵀ f)`); `A_g v = h_g`; and a free-floating robot's
//! momentum changes at the rate of gravity and the wrenches alone.

use crate::common::{load_model, random_tree, Rng};
use crate::constraint_embedding::{consistent_state, LOOP_MODELS};
use embedyn::nalgebra::{DMatrix, DVector, Matrix3, Matrix3xX, Matrix6xX, Vector3};
use embedyn::{
    aba, aba_ext, center_of_mass, centroidal_momentum, centroidal_momentum_matrix,
    centroidal_momentum_rate, com_jacobian, embedding_map, forward_kinematics,
    forward_kinematics_acceleration, frame_classical_acceleration, frame_jacobian, frame_placement,
    frame_velocity, integrate, relative_error, rnea, rnea_ext, FrameId, JointType, LinkWrench,
    Model, Motion, Reference, Workspace,
};

const REFERENCES: [Reference; 3] = [
    Reference::Local,
    Reference::LocalWorldAligned,
    Reference::World,
];

/// Tree models (merged feet on the quadruped, random branching trees fixed and floating) with a random
/// state each.
fn trees() -> Vec<(Model<f64>, Vec<f64>, Vec<f64>)> {
    let mut rng = Rng::new(11);
    let mut out = Vec::new();
    for (path, floating) in [
        ("models/quadruped.urdf", false),
        ("models/arm7.urdf", false),
        ("tests/data/pinocchio/anymal_b.urdf", true),
    ] {
        let model = load_model::<f64>(path, floating);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.5, 1.5);
        out.push((model, q, v));
    }
    for (n, floating) in [(9, false), (12, true)] {
        let model = random_tree(&mut rng, n, floating);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.5, 1.5);
        out.push((model, q, v));
    }
    out
}

/// Every loop, coupling and mimic model with a consistent state.
fn loops() -> Vec<(Model<f64>, Vec<f64>, Vec<f64>)> {
    let mut rng = Rng::new(12);
    LOOP_MODELS
        .iter()
        .map(|&(path, floating)| {
            let model = load_model::<f64>(path, floating);
            let mut ws = Workspace::new(&model);
            let (q, v) = consistent_state(&model, &mut ws, &mut rng);
            (model, q, v)
        })
        .collect()
}

fn motion6(m: &Motion<f64>) -> DVector<f64> {
    DVector::from_iterator(6, m.linear.iter().chain(m.angular.iter()).copied())
}

fn matrix6(j: &Matrix6xX<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(6, j.ncols(), |r, c| j[(r, c)])
}

/// `q ⊕ s v`.
fn moved(model: &Model<f64>, q: &[f64], v: &[f64], s: f64) -> Vec<f64> {
    let step: Vec<f64> = v.iter().map(|x| x * s).collect();
    let mut out = vec![0.0; model.nq()];
    integrate(model, q, &step, &mut out).unwrap();
    out
}

/// The world angular velocity that takes `r_minus` to `r_plus` in time `dt` (central difference).
fn angular_rate(r_plus: &Matrix3<f64>, r_minus: &Matrix3<f64>, dt: f64) -> Vector3<f64> {
    let d = r_plus * r_minus.transpose();
    // R₊ R₋ᵀ ≈ I + [2 dt ω]ₓ: its skew part holds 2 dt ω twice.
    Vector3::new(
        d[(2, 1)] - d[(1, 2)],
        d[(0, 2)] - d[(2, 0)],
        d[(1, 0)] - d[(0, 1)],
    ) / (4.0 * dt)
}

/// `J v` equals the frame velocity, for every frame of every model in each reference; on loop models over
/// the spanning coordinates and, through `X`, over the independent ones (`J X v_R = J v` for `v = X v_R`).
#[test]
fn jacobian_times_velocity_is_the_frame_velocity() {
    let mut worst = 0.0f64;
    let mut worst_independent = 0.0f64;
    for (model, q, v) in trees().into_iter().chain(loops()) {
        let mut ws = Workspace::new(&model);
        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let mut j = Matrix6xX::zeros(model.nv());
        let x = model
            .has_constraints()
            .then(|| embedding_map(&model, &mut Workspace::new(&model), &q).unwrap());
        let frames: Vec<FrameId> = model.frames().collect();
        for &frame in &frames {
            for reference in REFERENCES {
                frame_jacobian(&model, &ws, frame, reference, &mut j).unwrap();
                let jv = matrix6(&j) * DVector::from_column_slice(&v);
                let vel = motion6(&frame_velocity(&model, &ws, frame, reference).unwrap());
                let e = relative_error(jv.as_slice(), vel.as_slice());
                assert!(
                    e < 1e-12,
                    "{} {:?} {reference:?}: {e:e}",
                    model.name,
                    model.frame_name(frame)
                );
                worst = worst.max(e);
                if let Some(x) = &x {
                    // The independent velocities of a consistent v: v = X v_R exactly on independent rows.
                    let v_r: Vec<f64> = model.independent_coordinates().map(|i| v[i]).collect();
                    let jxv = matrix6(&j) * x * DVector::from_column_slice(&v_r);
                    let e = relative_error(jxv.as_slice(), vel.as_slice());
                    assert!(e < 1e-10, "{}: J X v_R {e:e}", model.name);
                    worst_independent = worst_independent.max(e);
                }
            }
        }
    }
    println!("J v vs frame velocity: {worst:.1e}; J X v_R: {worst_independent:.1e}");
}

/// Each Jacobian column against central differences of the frame pose along `integrate(q, ±h eₖ)`, and
/// the bias `J̇ v` (local_world_aligned) against differences of `J(q) v` along `v`.
#[test]
fn frame_jacobian_and_bias_match_finite_differences() {
    let h = 1e-6;
    let (mut worst_j, mut worst_bias) = (0.0f64, 0.0f64);
    let mut models = trees();
    models.extend(loops().into_iter().step_by(4));
    for (model, q, v) in models {
        let mut ws = Workspace::new(&model);
        let nv = model.nv();
        let frames: Vec<FrameId> = model.frames().filter(|f| f.body.is_some()).collect();
        let mut j = Matrix6xX::zeros(nv);
        let mut j_plus = Matrix6xX::zeros(nv);
        let mut j_minus = Matrix6xX::zeros(nv);
        for &frame in frames.iter().step_by(2) {
            forward_kinematics_acceleration(&model, &mut ws, &q, &v, &vec![0.0; nv]).unwrap();
            frame_jacobian(&model, &ws, frame, Reference::LocalWorldAligned, &mut j).unwrap();
            let bias =
                frame_classical_acceleration(&model, &ws, frame, Reference::LocalWorldAligned)
                    .unwrap();
            for k in 0..nv {
                let mut e = vec![0.0; nv];
                e[k] = 1.0;
                let mut pose = |s: f64| {
                    forward_kinematics(&model, &mut ws, &moved(&model, &q, &e, s), &vec![0.0; nv])
                        .unwrap();
                    frame_placement(&model, &ws, frame).unwrap()
                };
                let (p, m) = (pose(h), pose(-h));
                let linear = (p.translation - m.translation) / (2.0 * h);
                let angular = angular_rate(&p.rotation, &m.rotation, h);
                for r in 0..3 {
                    let scale = 1.0f64.max(j.column(k).amax());
                    worst_j = worst_j
                        .max((linear[r] - j[(r, k)]).abs() / scale)
                        .max((angular[r] - j[(r + 3, k)]).abs() / scale);
                }
            }
            // J̇ v = d/dt (J v) at fixed v, along q̇ = v.
            for (s, out) in [(h, &mut j_plus), (-h, &mut j_minus)] {
                forward_kinematics(&model, &mut ws, &moved(&model, &q, &v, s), &vec![0.0; nv])
                    .unwrap();
                frame_jacobian(&model, &ws, frame, Reference::LocalWorldAligned, out).unwrap();
            }
            let vv = DVector::from_column_slice(&v);
            let djv = (matrix6(&j_plus) - matrix6(&j_minus)) * &vv / (2.0 * h);
            let e = relative_error(djv.as_slice(), motion6(&bias).as_slice());
            worst_bias = worst_bias.max(e);
        }
        assert!(
            worst_j < 1e-6 && worst_bias < 1e-6,
            "{}: J {worst_j:e}, J̇v {worst_bias:e}",
            model.name
        );
    }
    println!("finite differences: J {worst_j:.1e}, J̇ v {worst_bias:.1e}");
}

/// A wrench on a link is the generalized force `Jᵀ f` of that link's local Jacobian: `rnea_ext = rnea −
/// Σ Jᵀ f` and `aba_ext(τ) = aba(τ + Σ Jᵀ f)`, on trees (merged feet included) and on every loop model.
#[test]
fn a_wrench_is_the_generalized_force_j_transpose_f() {
    let mut rng = Rng::new(13);
    let (mut worst_rnea, mut worst_aba) = (0.0f64, 0.0f64);
    for (model, q, v) in trees().into_iter().chain(loops()) {
        let nv = model.nv();
        let mut ws = Workspace::new(&model);
        let frames: Vec<FrameId> = model.frames().collect();
        let wrenches: Vec<LinkWrench<f64>> = (0..3)
            .map(|_| {
                let f = rng.vec(6, -20.0, 20.0);
                LinkWrench::new(
                    frames[(rng.next_u64() % frames.len() as u64) as usize],
                    Vector3::new(f[0], f[1], f[2]),
                    Vector3::new(f[3], f[4], f[5]),
                )
            })
            .collect();
        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let mut jt_f = DVector::zeros(nv);
        let mut j = Matrix6xX::zeros(nv);
        for w in &wrenches {
            frame_jacobian(&model, &ws, w.frame, Reference::Local, &mut j).unwrap();
            let f = DVector::from_iterator(6, w.force.iter().chain(w.torque.iter()).copied());
            jt_f += matrix6(&j).transpose() * f;
        }
        let qdd = rng.vec(nv, -2.0, 2.0);
        let plain = rnea(&model, &mut ws, &q, &v, &qdd).unwrap().to_vec();
        let with = rnea_ext(&model, &mut ws, &q, &v, &qdd, &wrenches)
            .unwrap()
            .to_vec();
        let expected: Vec<f64> = plain.iter().zip(jt_f.iter()).map(|(t, f)| t - f).collect();
        let e = relative_error(&with, &expected);
        assert!(e < 1e-12, "{}: rnea_ext {e:e}", model.name);
        worst_rnea = worst_rnea.max(e);

        let mut tau = rng.vec(nv, -5.0, 5.0);
        for jt in model
            .joints
            .iter()
            .filter(|j| j.joint_type == JointType::Floating)
        {
            tau[jt.v_index..jt.v_index + 6].fill(0.0);
        }
        let with = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches)
            .unwrap()
            .to_vec();
        let moved_tau: Vec<f64> = tau.iter().zip(jt_f.iter()).map(|(t, f)| t + f).collect();
        let expected = aba(&model, &mut ws, &q, &v, &moved_tau).unwrap().to_vec();
        let e = relative_error(&with, &expected);
        assert!(e < 1e-10, "{}: aba_ext {e:e}", model.name);
        worst_aba = worst_aba.max(e);
    }
    println!("rnea_ext vs rnea − Jᵀf {worst_rnea:.1e}; aba_ext vs aba(τ + Jᵀf) {worst_aba:.1e}");
}

/// `vcom = J_com v`, `J_com` against differences of the centre of mass, `h_g = A_g v` (over the
/// independent coordinates too: `A_g X v_R`), and `Ȧ_g v` against differences of `A_g(q) v`.
#[test]
fn center_of_mass_and_momentum_invariants() {
    let h = 1e-6;
    let mut worst = [0.0f64; 4];
    for (model, q, v) in trees().into_iter().chain(loops()) {
        let nv = model.nv();
        let mut ws = Workspace::new(&model);
        let vv = DVector::from_column_slice(&v);
        let mut j_com = Matrix3xX::zeros(nv);
        let mut a_g = Matrix6xX::zeros(nv);
        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let c = center_of_mass(&model, &ws).unwrap();
        com_jacobian(&model, &mut ws, &mut j_com).unwrap();
        let jv = DMatrix::from_fn(3, nv, |r, k| j_com[(r, k)]) * &vv;
        worst[0] = worst[0].max(relative_error(jv.as_slice(), c.vcom.as_slice()));
        // Finite differences of the centre of mass along v.
        let mut com_at = |s: f64| {
            forward_kinematics(&model, &mut ws, &moved(&model, &q, &v, s), &vec![0.0; nv]).unwrap();
            center_of_mass(&model, &ws).unwrap().com
        };
        let fd = (com_at(h) - com_at(-h)) / (2.0 * h);
        worst[1] = worst[1].max(relative_error(fd.as_slice(), c.vcom.as_slice()));

        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let h_g = motion_like(&centroidal_momentum(&model, &mut ws).unwrap());
        centroidal_momentum_matrix(&model, &mut ws, &mut a_g).unwrap();
        let agv = matrix6(&a_g) * &vv;
        worst[2] = worst[2].max(relative_error(agv.as_slice(), h_g.as_slice()));
        if model.has_constraints() {
            let x = embedding_map(&model, &mut Workspace::new(&model), &q).unwrap();
            let v_r: Vec<f64> = model.independent_coordinates().map(|i| v[i]).collect();
            let e = relative_error(
                (matrix6(&a_g) * x * DVector::from_column_slice(&v_r)).as_slice(),
                h_g.as_slice(),
            );
            assert!(e < 1e-10, "{}: A_g X v_R {e:e}", model.name);
        }
        // Ȧ_g v = d/dt (A_g(q) v) at fixed v.
        forward_kinematics_acceleration(&model, &mut ws, &q, &v, &vec![0.0; nv]).unwrap();
        let rate = motion_like(&centroidal_momentum_rate(&model, &mut ws).unwrap());
        let mut agv_at = |s: f64| {
            forward_kinematics(&model, &mut ws, &moved(&model, &q, &v, s), &vec![0.0; nv]).unwrap();
            centroidal_momentum_matrix(&model, &mut ws, &mut a_g).unwrap();
            matrix6(&a_g) * &vv
        };
        let fd = (agv_at(h) - agv_at(-h)) / (2.0 * h);
        worst[3] = worst[3].max(relative_error(fd.as_slice(), rate.as_slice()));
        assert!(
            worst[0] < 1e-12 && worst[1] < 1e-6 && worst[2] < 1e-12 && worst[3] < 1e-6,
            "{}: {worst:?}",
            model.name
        );
    }
    println!(
        "J_com v {:.1e}; d/dt com {:.1e}; A_g v {:.1e}; d/dt (A_g v) {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

/// `[linear; angular]` of a momentum-like force.
fn motion_like(f: &embedyn::Force<f64>) -> DVector<f64> {
    DVector::from_iterator(6, f.linear.iter().chain(f.angular.iter()).copied())
}

/// A free-floating robot (unactuated base, any joint torques) touched only by gravity changes its
/// centroidal momentum at `(m g, 0)`; with wrenches on its feet, by their resultant about the centre of
/// mass too. `ḣ_g = A_g q̈ + Ȧ_g v` from the forward dynamics, on the floating ANYmal B, a random floating
/// tree and the floating biped with closed-loop knees.
#[test]
fn free_floating_momentum_changes_at_the_rate_of_gravity_and_wrenches() {
    let mut rng = Rng::new(14);
    let mut worst = 0.0f64;
    let models = [
        load_model::<f64>("tests/data/pinocchio/anymal_b.urdf", true),
        random_tree(&mut rng, 10, true),
        load_model::<f64>("models/loops/biped_floating.urdf", false),
    ];
    for model in models {
        let nv = model.nv();
        let mut ws = Workspace::new(&model);
        let (q, v) = if model.has_constraints() {
            consistent_state(&model, &mut ws, &mut rng)
        } else {
            (rng.configuration(&model), rng.vec(nv, -1.5, 1.5))
        };
        let mut tau = rng.vec(nv, -5.0, 5.0);
        let base = model
            .joints
            .iter()
            .find(|j| j.joint_type == JointType::Floating)
            .expect("a floating base");
        tau[base.v_index..base.v_index + 6].fill(0.0);
        // (Links fixed to the world are frames too, but nothing there moves.)
        let frames: Vec<FrameId> = model.frames().filter(|f| f.body.is_some()).collect();
        for with_wrenches in [false, true] {
            let wrenches: Vec<LinkWrench<f64>> = if with_wrenches {
                (0..2)
                    .map(|i| {
                        let f = rng.vec(6, -20.0, 20.0);
                        LinkWrench::new(
                            frames[frames.len() - 1 - i],
                            Vector3::new(f[0], f[1], f[2]),
                            Vector3::new(f[3], f[4], f[5]),
                        )
                    })
                    .collect()
            } else {
                Vec::new()
            };
            let qdd = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches)
                .unwrap()
                .to_vec();
            forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
            let rate = motion_like(&centroidal_momentum_rate(&model, &mut ws).unwrap());
            let c = center_of_mass(&model, &ws).unwrap();
            let mut expected_linear = model.gravity * c.mass;
            let mut expected_angular = Vector3::zeros();
            for w in &wrenches {
                let x = frame_placement(&model, &ws, w.frame).unwrap();
                let f = x.rotation * w.force;
                expected_linear += f;
                expected_angular += x.rotation * w.torque + (x.translation - c.com).cross(&f);
            }
            let expected = DVector::from_iterator(
                6,
                expected_linear
                    .iter()
                    .chain(expected_angular.iter())
                    .copied(),
            );
            let e = relative_error(rate.as_slice(), expected.as_slice());
            assert!(
                e < 1e-10,
                "{} (wrenches: {with_wrenches}): {e:e}",
                model.name
            );
            worst = worst.max(e);
        }
    }
    println!("free-floating momentum rate vs m g + Σ wrenches: {worst:.1e}");
}
