//! Generated `aba_derivatives` and `rnea_derivatives` (issue 12): against Pinocchio 4.1's analytical
//! derivatives on the UR5 (tests/data/pinocchio/ur5_derivatives.json: the states without their wrenches,
//! f64 to 1e-9 relative and f32 to 1e-3; with them through `aba_derivatives_ext`, f64); against the
//! interpreted derivatives on a four-bar (the spanning tree's derivatives of the embedded dynamics, and
//! `aba_derivatives_independent` along the constraint manifold, each returning the singularity measure);
//! the generated `step` and its Jacobian against the interpreted ones on the UR5.

use crate::common::{load_model, repo_path, Rng, UNWRITTEN};
use embedyn::constraints::constraint_condition;
use embedyn::constraints::{complete_configuration, complete_velocity};
use embedyn::nalgebra::DMatrix;
use embedyn::{
    aba_derivatives, aba_derivatives_independent, rnea_derivatives, step_derivatives,
    AbaDerivatives, DerivativeWorkspace, ManifoldDerivatives, Model, RneaDerivatives,
    StepDerivatives, Workspace,
};
use serde_json::Value;

mod z1_both_scalars {
    // f64 and f32 from one trace: forward dynamics' q̈ and M⁻¹ stay on aba (see the test below).
    embedyn::robot!("models/peers/z1.urdf", only(aba_derivatives));
}
mod ur5 {
    embedyn::robot!(
        "tests/data/pinocchio/ur5.urdf",
        only(aba_derivatives, rnea_derivatives)
    );
}
mod ur5_step {
    embedyn::robot!(
        "tests/data/pinocchio/ur5.urdf",
        f64_only,
        only(step, step_derivatives, aba_derivatives_ext),
        wrenches(tool0, wrist_2_link),
        // (the AVX twins are tested on `solo12_free` and `ur5`; leaving them out here spares the test
        // build their compile time)
        avx_twins = none
    );
}
// A floating base: the step's derivatives of the base configuration go through the logarithm of the
// step's rotation against itself (the identity), where a square root's derivative was 0 · ∞ = NaN in
// generated code (attacker's trial).
mod pendulum_free_step {
    embedyn::robot!(
        "tests/data/pinocchio/double_pendulum.urdf",
        floating,
        f64_only,
        only(step_derivatives),
        avx_twins = none
    );
}
mod four_bar {
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(aba_derivatives, aba_derivatives_independent),
        avx_twins = none
    );
}

// Every function with an AVX twin (`avx_twins = all`), whatever its size: the loop model's `complete`
// (a hand-written wrapper naming `super::NQ`, which one module deeper did not resolve: attacker's trial on
// a 300-rotor chain, whose `complete_step` passed the size for a twin) and the constrained `aba` (returns
// its singularity measure).
mod four_bar_twins {
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(complete, aba),
        avx_twins = all
    );
}

// A wide tree (34 joints, from `dispatch::AVX512_MIN_NV`): its two smallest functions get an AVX-512
// twin besides the AVX one by default.
mod humanoid34_twins {
    embedyn::robot!("models/humanoid34.urdf", f64_only, only(kinematics, crba));
}

// The floating humanoid's `com`, in two parts, twinned: its output is named `com` like the function,
// which once kept its parts out of the bodies the twins share and failed to compile (E0603, an
// attacker's trial of codegen/src/shared_bodies.rs).
mod humanoid34_com {
    embedyn::robot!("models/humanoid34.urdf", floating, f64_only, only(com));
}

// A quadruped's derivatives are paired (its left and right legs side by side), under the generator's
// pairing limit of 60k operations; `aba_derivatives` is traced as factors with the product `−M⁻¹ ∂τ` in
// a loop after them, here with two lanes: the lane module's loop product as well (`rnea_derivatives`
// without lanes, in a module of its own: a lane copy costs the test build about four times a scalar one).
mod solo12_free {
    embedyn::robot!(
        "tests/data/pinocchio/solo12.urdf",
        floating,
        f64_only,
        only(aba_derivatives),
        lanes = 2
    );
}
mod solo12_inverse {
    embedyn::robot!(
        "tests/data/pinocchio/solo12.urdf",
        floating,
        f64_only,
        only(rnea_derivatives),
        avx_twins = none
    );
}

const N: usize = ur5::NV;

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// `max|a − b| / max(1, max|b|)` over a generated matrix and a reference one ([`rel_vec`]'s rule: a NaN
/// on one side only is an infinite error).
fn rel<const R: usize, const C: usize>(a: &[[f64; C]; R], b: &DMatrix<f64>) -> f64 {
    assert_eq!(b.shape(), (R, C));
    // `a` row by row; the transpose's column-major storage is `b` row by row.
    rel_vec(a.as_flattened(), b.transpose().as_slice())
}

fn rel_vec(a: &[f64], b: &[f64]) -> f64 {
    embedyn::relative_error(a, b)
}

/// A generated `step_derivatives`: (q, v, τ, dt) → q_next, v_next and the six Jacobian blocks.
type GeneratedStep<const NQ: usize, const NV: usize> = fn(
    &[f64; NQ],
    &[f64; NV],
    &[f64; NV],
    f64,
    &mut [f64; NQ],
    &mut [f64; NV],
    &mut [[f64; NV]; NV],
    &mut [[f64; NV]; NV],
    &mut [[f64; NV]; NV],
    &mut [[f64; NV]; NV],
    &mut [[f64; NV]; NV],
    &mut [[f64; NV]; NV],
);

/// Runs a generated `step_derivatives` at (q, v, τ, dt), its outputs pre-filled with NaN (an entry it does
/// not write fails), and returns its next state and the worst relative error against the interpreted
/// `d` at the same inputs.
fn step_error<const NQ: usize, const NV: usize>(
    generated: GeneratedStep<NQ, NV>,
    (q, v, tau, dt): (&[f64], &[f64], &[f64], f64),
    d: &StepDerivatives<f64>,
) -> ([f64; NQ], [f64; NV], f64) {
    let (mut q1, mut v1) = ([f64::NAN; NQ], [f64::NAN; NV]);
    let mut blocks = [[[f64::NAN; NV]; NV]; 6];
    let [a, b, c, e, f, g] = &mut blocks;
    let q_arr: [f64; NQ] = std::array::from_fn(|i| q[i]);
    let arr = |x: &[f64]| -> [f64; NV] { std::array::from_fn(|i| x[i]) };
    generated(
        &q_arr,
        &arr(v),
        &arr(tau),
        dt,
        &mut q1,
        &mut v1,
        a,
        b,
        c,
        e,
        f,
        g,
    );
    let expected = [
        &d.dq_next_dq,
        &d.dq_next_dv,
        &d.dq_next_dtau,
        &d.dv_next_dq,
        &d.dv_next_dv,
        &d.dv_next_dtau,
    ];
    let mut worst = rel_vec(&q1, d.q_next.as_slice()).max(rel_vec(&v1, d.v_next.as_slice()));
    for (generated, interpreted) in blocks.iter().zip(expected) {
        worst = worst.max(rel(generated, interpreted));
    }
    (q1, v1, worst)
}

/// The worst relative error of a generated vector and matrices against the interpreted ones.
fn worst_of<const N: usize>(
    vector: &[f64],
    reference: &[f64],
    matrices: &[[[f64; N]; N]],
    references: [&DMatrix<f64>; 3],
) -> f64 {
    matrices
        .iter()
        .zip(references)
        .map(|(m, r)| rel(m, r))
        .fold(rel_vec(vector, reference), f64::max)
}

/// The reference matrix `m` (rows of Pinocchio's v order) in ours (`map[ours] = theirs`).
fn matrix(m: &Value, map: &[usize]) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = m.as_array().unwrap().iter().map(numbers).collect();
    DMatrix::from_fn(map.len(), map.len(), |r, c| rows[map[r]][map[c]])
}

fn widen<const R: usize, const C: usize>(m: &[[f32; C]; R]) -> [[f64; C]; R] {
    m.map(|row| row.map(f64::from))
}

#[test]
fn generated_derivatives_match_pinocchio_on_the_ur5() {
    let text =
        std::fs::read_to_string(repo_path("tests/data/pinocchio/ur5_derivatives.json")).unwrap();
    let json: Value = serde_json::from_str(&text).unwrap();
    // Our joint order by name → Pinocchio's v index (a fixed arm: q and v alike).
    let model: Model<f64> = load_model("tests/data/pinocchio/ur5.urdf", false);
    let map: Vec<usize> = model
        .joints
        .iter()
        .map(|j| {
            json["joints"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"].as_str() == Some(j.name.as_str()))
                .unwrap()["idx_v"]
                .as_u64()
                .unwrap() as usize
        })
        .collect();
    let ours = |x: Vec<f64>| -> [f64; N] { std::array::from_fn(|i| x[map[i]]) };
    let samples = json["samples"].as_array().unwrap();
    assert!(!samples.is_empty());
    for (k, s) in samples.iter().enumerate() {
        let reference = &s["without_f_ext"];
        let (q, v) = (ours(numbers(&s["q"])), ours(numbers(&s["v"])));
        let (tau, a) = (ours(numbers(&s["tau"])), ours(numbers(&s["qdd_for_rnea"])));
        let mut qdd = [0.0; N];
        let (mut dq, mut dv, mut dt) = (
            [[UNWRITTEN; N]; N],
            [[UNWRITTEN; N]; N],
            [[UNWRITTEN; N]; N],
        );
        ur5::f64::aba_derivatives(&q, &v, &tau, &mut qdd, &mut dq, &mut dv, &mut dt);
        let mut t = [0.0; N];
        let (mut tq, mut tv, mut m) = (
            [[UNWRITTEN; N]; N],
            [[UNWRITTEN; N]; N],
            [[UNWRITTEN; N]; N],
        );
        ur5::f64::rnea_derivatives(&q, &v, &a, &mut t, &mut tq, &mut tv, &mut m);
        let errors = [
            rel_vec(&qdd, &ours(numbers(&reference["qdd"]))),
            rel(&dq, &matrix(&reference["dqdd_dq"], &map)),
            rel(&dv, &matrix(&reference["dqdd_dv"], &map)),
            rel(&dt, &matrix(&reference["dqdd_dtau"], &map)),
            rel_vec(&t, &ours(numbers(&reference["tau_rnea"]))),
            rel(&tq, &matrix(&reference["dtau_dq"], &map)),
            rel(&tv, &matrix(&reference["dtau_dv"], &map)),
            rel(&m, &matrix(&reference["dtau_dqdd"], &map)),
        ];
        assert!(errors.iter().all(|&e| e < 1e-9), "sample {k}: {errors:?}");

        // f32: the same functions in single precision, to 1e-3 of Pinocchio's answer.
        let narrow = |x: &[f64; N]| -> [f32; N] { x.map(|y| y as f32) };
        let mut qdd32 = [0.0f32; N];
        let (mut dq32, mut dv32, mut dt32) = (
            [[UNWRITTEN as f32; N]; N],
            [[UNWRITTEN as f32; N]; N],
            [[UNWRITTEN as f32; N]; N],
        );
        ur5::f32::aba_derivatives(
            &narrow(&q),
            &narrow(&v),
            &narrow(&tau),
            &mut qdd32,
            &mut dq32,
            &mut dv32,
            &mut dt32,
        );
        let errors32 = [
            rel(&widen(&dq32), &matrix(&reference["dqdd_dq"], &map)),
            rel(&widen(&dv32), &matrix(&reference["dqdd_dv"], &map)),
            rel(&widen(&dt32), &matrix(&reference["dqdd_dtau"], &map)),
        ];
        assert!(
            errors32.iter().all(|&e| e < 1e-3),
            "sample {k}, f32: {errors32:?}"
        );
        // q̈ and M⁻¹ in f32 keep aba's digits: with f32 code the generator does not take them from the
        // factorized mass matrix, whose rounding grows as cond(M) ε (attacker's trial: the Z1's f32 M⁻¹
        // 1.2e-7 by aba, 4.1e-5 by the factorization).
        let qdd_reference = numbers(&reference["qdd"]);
        let accurate = [
            rel_vec(&qdd32.map(f64::from), &ours(qdd_reference)),
            rel(&widen(&dt32), &matrix(&reference["dqdd_dtau"], &map)),
        ];
        assert!(
            accurate.iter().all(|&e| e < 1e-5),
            "sample {k}, f32 q̈ and M⁻¹: {accurate:?}"
        );

        // With the sample's wrenches on the links generated for (the one on the fixed base_link moves
        // nothing), against Pinocchio's derivatives with them.
        let mut f_ext = [[0.0; 6]; 2];
        for (row, link) in f_ext.iter_mut().zip(ur5_step::WRENCH_LINKS) {
            let w = &s["f_ext"][link];
            let wrench = [numbers(&w["force"]), numbers(&w["torque"])].concat();
            row.copy_from_slice(&wrench);
        }
        ur5_step::f64::aba_derivatives_ext(
            &q, &v, &tau, &f_ext, &mut qdd, &mut dq, &mut dv, &mut dt,
        );
        let errors_ext = [
            rel_vec(&qdd, &ours(numbers(&s["qdd"]))),
            rel(&dq, &matrix(&s["dqdd_dq"], &map)),
            rel(&dv, &matrix(&s["dqdd_dv"], &map)),
            rel(&dt, &matrix(&s["dqdd_dtau"], &map)),
        ];
        assert!(
            errors_ext.iter().all(|&e| e < 1e-9),
            "sample {k}, with wrenches: {errors_ext:?}"
        );
        // The wrenches change the answer (the test would hold without them otherwise).
        assert!(rel(&dq, &matrix(&reference["dqdd_dq"], &map)) > 1e-6);
    }
}

/// On a four-bar the generated spanning-tree derivatives and the manifold ones equal the interpreted ones
/// (the same dual-number passes, traced) at consistent states, and both return the singularity measure
/// of the interpreted value pass.
#[test]
fn generated_derivatives_match_the_interpreted_on_a_loop() {
    const NV: usize = four_bar::NV;
    let model: Model<f64> = load_model("models/loops/four_bar_internal.urdf", false);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(5);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = AbaDerivatives::new(&model);
    let mut m = ManifoldDerivatives::new(&model);
    const NI: usize = four_bar::NI;
    for _ in 0..4 {
        let mut q = model.neutral_configuration();
        q[0] = rng.uniform(-0.5, 0.5);
        complete_configuration(&model, &mut ws, &mut q).unwrap();
        let mut v = rng.vec(NV, -1.0, 1.0);
        complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
        let tau = rng.vec(NV, -1.0, 1.0);
        aba_derivatives(&model, &mut dws, &q, &v, &tau, &[], &mut d).unwrap();
        let arr = |x: &[f64]| -> [f64; NV] { std::array::from_fn(|i| x[i]) };
        let condition = constraint_condition(dws.value_workspace());
        let mut qdd = [0.0; NV];
        let (mut dq, mut dv, mut dt) = (
            [[UNWRITTEN; NV]; NV],
            [[UNWRITTEN; NV]; NV],
            [[UNWRITTEN; NV]; NV],
        );
        let generated_condition = four_bar::f64::aba_derivatives(
            &arr(&q),
            &arr(&v),
            &arr(&tau),
            &mut qdd,
            &mut dq,
            &mut dv,
            &mut dt,
        );
        let errors = [
            rel_vec(&qdd, d.qdd.as_slice()),
            rel(&dq, &d.dqdd_dq),
            rel(&dv, &d.dqdd_dv),
            rel(&dt, &d.dqdd_dtau),
        ];
        assert!(errors.iter().all(|&e| e < 1e-12), "{errors:?}");
        assert!(condition > 1.0 && condition < four_bar::f64::DERIVATIVE_SINGULARITY_THRESHOLD);
        assert!((generated_condition - condition).abs() <= 1e-12 * condition);

        aba_derivatives_independent(&model, &mut dws, &q, &v, &tau, &[], &mut m).unwrap();
        let mut qdd_i = [0.0; NI];
        let (mut mq, mut mv, mut mt) = (
            [[UNWRITTEN; NI]; NI],
            [[UNWRITTEN; NI]; NI],
            [[UNWRITTEN; NV]; NI],
        );
        let generated_condition = four_bar::f64::aba_derivatives_independent(
            &arr(&q),
            &arr(&v),
            &arr(&tau),
            &mut qdd_i,
            &mut mq,
            &mut mv,
            &mut mt,
        );
        let errors = [
            rel_vec(&qdd_i, m.qdd_independent.as_slice()),
            rel(&mq, &m.dqdd_dq),
            rel(&mv, &m.dqdd_dv),
            rel(&mt, &m.dqdd_dtau),
        ];
        assert!(errors.iter().all(|&e| e < 1e-12), "manifold: {errors:?}");
        assert!((generated_condition - condition).abs() <= 1e-12 * condition);
    }
}

/// The paired derivatives of a floating quadruped equal the interpreted ones (the unpaired dual-number
/// passes): pairing changes no rounding.
#[test]
fn paired_derivatives_of_a_floating_quadruped_match_the_interpreted() {
    const NQ: usize = solo12_free::NQ;
    const NV: usize = solo12_free::NV;
    let model: Model<f64> = load_model("tests/data/pinocchio/solo12.urdf", true);
    let mut rng = Rng::new(12);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = AbaDerivatives::new(&model);
    let mut r = RneaDerivatives::new(&model);
    for _ in 0..4 {
        let q = rng.configuration(&model);
        let (v, u) = (rng.vec(NV, -2.0, 2.0), rng.vec(NV, -5.0, 5.0));
        let q_arr: [f64; NQ] = std::array::from_fn(|i| q[i]);
        let arr = |x: &[f64]| -> [f64; NV] { std::array::from_fn(|i| x[i]) };
        aba_derivatives(&model, &mut dws, &q, &v, &u, &[], &mut d).unwrap();
        // Outputs start as NaN: an entry the generated code does not write fails.
        let (mut x, mut blocks) = ([f64::NAN; NV], [[[f64::NAN; NV]; NV]; 3]);
        let [b0, b1, b2] = &mut blocks;
        solo12_free::f64::aba_derivatives(&q_arr, &arr(&v), &arr(&u), &mut x, b0, b1, b2);
        let expected = [&d.dqdd_dq, &d.dqdd_dv, &d.dqdd_dtau];
        let worst = worst_of(&x, d.qdd.as_slice(), &blocks, expected);
        assert!(worst < 1e-12, "aba_derivatives: {worst:e}");
        rnea_derivatives(&model, &mut dws, &q, &v, &u, &[], &mut r).unwrap();
        let (mut x, mut blocks) = ([f64::NAN; NV], [[[f64::NAN; NV]; NV]; 3]);
        let [b0, b1, b2] = &mut blocks;
        solo12_inverse::f64::rnea_derivatives(&q_arr, &arr(&v), &arr(&u), &mut x, b0, b1, b2);
        let expected = [&r.dtau_dq, &r.dtau_dv, &r.dtau_dqdd];
        let worst = worst_of(&x, r.tau.as_slice(), &blocks, expected);
        assert!(worst < 1e-12, "rnea_derivatives: {worst:e}");
    }
}

/// The lane module's `aba_derivatives` (factors unrolled, the product `−M⁻¹ ∂τ` in a loop on lanes) gives
/// each state the scalar function's bits, over a batch of three states (a chunk and a partial one).
#[test]
fn lane_derivatives_of_a_floating_quadruped_are_the_scalar_ones() {
    const NQ: usize = solo12_free::NQ;
    const NV: usize = solo12_free::NV;
    let model: Model<f64> = load_model("tests/data/pinocchio/solo12.urdf", true);
    let mut rng = Rng::new(13);
    let mut q = [[0.0; NQ]; 3];
    let (mut v, mut u) = ([[0.0; NV]; 3], [[0.0; NV]; 3]);
    for k in 0..3 {
        q[k].copy_from_slice(&rng.configuration(&model));
        v[k].copy_from_slice(&rng.vec(NV, -2.0, 2.0));
        u[k].copy_from_slice(&rng.vec(NV, -5.0, 5.0));
    }
    let mut qdd = [[f64::NAN; NV]; 3];
    let mut blocks = [[[[f64::NAN; NV]; NV]; 3]; 3];
    let [b0, b1, b2] = &mut blocks;
    assert!(solo12_free::f64x2::aba_derivatives_batch(
        &q, &v, &u, &mut qdd, b0, b1, b2
    ));
    for k in 0..3 {
        let mut x = [f64::NAN; NV];
        let mut single = [[[f64::NAN; NV]; NV]; 3];
        let [s0, s1, s2] = &mut single;
        solo12_free::f64::aba_derivatives(&q[k], &v[k], &u[k], &mut x, s0, s1, s2);
        assert_eq!(qdd[k].map(f64::to_bits), x.map(f64::to_bits), "state {k}");
        for (m, block) in single.iter().enumerate() {
            let lanes = blocks[m][k];
            for r in 0..NV {
                assert_eq!(
                    lanes[r].map(f64::to_bits),
                    block[r].map(f64::to_bits),
                    "state {k}, matrix {m}, row {r}"
                );
            }
        }
    }
}

/// A large function's AVX twin (docs/generated-code.md, "AVX where the CPU has it") gives the bits of its
/// baseline copy: the UR5's `aba_derivatives` and `rnea_derivatives`, the floating Solo-12's factored
/// `aba_derivatives`, a four-bar's `complete` and `aba` (every function twinned), a 34-joint humanoid's
/// `kinematics` and `crba` (with AVX-512 twins too) and the batch of 32 sines and cosines, each run with
/// the twins allowed, with the AVX-512 ones forbidden and with all forbidden, on finite states (a NaN's sign and payload
/// may differ between the copies, as x86 passes on the first operand's NaN). (On a CPU without AVX, or a build
/// that enables AVX itself, both runs take the same copy and the test passes trivially; the CI machines
/// have AVX.)
#[test]
fn avx_twins_give_the_bits_of_the_baseline_code() {
    use embedyn::codegen_support::dispatch::{use_avx, use_avx512};
    // Runs of every copy, each state computed with the twins allowed (the AVX-512 one where the function
    // and the CPU have it), with the AVX-512 ones forbidden, then with all forbidden.
    fn both<T: PartialEq + std::fmt::Debug>(mut run: impl FnMut() -> T) {
        use_avx(true);
        let with_twin = run();
        use_avx512(false);
        let with_avx = run();
        use_avx512(true);
        use_avx(false);
        let baseline = run();
        use_avx(true);
        assert_eq!(with_twin, baseline);
        assert_eq!(with_avx, baseline);
    }
    let bits = |m: &[[f64; N]; N]| m.map(|row| row.map(f64::to_bits));
    // The batch of sines and cosines every generated function starts with has its own AVX copy.
    let angles: [f64; 32] = std::array::from_fn(|i| (i as f64 - 15.5) * 0.7391);
    both(|| {
        let (s, c) = embedyn::codegen_support::sincos_batch_f64(angles);
        (s.map(f64::to_bits), c.map(f64::to_bits))
    });
    let ur5_model: Model<f64> = load_model("tests/data/pinocchio/ur5.urdf", false);
    let solo: Model<f64> = load_model("tests/data/pinocchio/solo12.urdf", true);
    let mut rng = Rng::new(14);
    for _ in 0..3 {
        let q: [f64; N] = std::array::from_fn(|_| rng.uniform(-3.0, 3.0));
        let v: [f64; N] = std::array::from_fn(|_| rng.uniform(-2.0, 2.0));
        let u: [f64; N] = std::array::from_fn(|_| rng.uniform(-5.0, 5.0));
        assert_eq!(ur5_model.nq(), N);
        both(|| {
            let (mut x, mut blocks) = ([f64::NAN; N], [[[f64::NAN; N]; N]; 3]);
            let [b0, b1, b2] = &mut blocks;
            ur5::f64::aba_derivatives(&q, &v, &u, &mut x, b0, b1, b2);
            (x.map(f64::to_bits), blocks.each_ref().map(bits))
        });
        both(|| {
            let (mut x, mut blocks) = ([f64::NAN; N], [[[f64::NAN; N]; N]; 3]);
            let [b0, b1, b2] = &mut blocks;
            ur5::f64::rnea_derivatives(&q, &v, &u, &mut x, b0, b1, b2);
            (x.map(f64::to_bits), blocks.each_ref().map(bits))
        });
        let four_bar_q: [f64; four_bar_twins::NQ] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        let four_bar_v: [f64; four_bar_twins::NV] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        let four_bar_u: [f64; four_bar_twins::NV] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        both(|| {
            let mut completed = [f64::NAN; four_bar_twins::NQ];
            let residual = four_bar_twins::f64::complete(&four_bar_q, &mut completed);
            let mut qdd = [f64::NAN; four_bar_twins::NV];
            let measure = four_bar_twins::f64::aba(&completed, &four_bar_v, &four_bar_u, &mut qdd);
            (
                residual.to_bits(),
                completed.map(f64::to_bits),
                measure.to_bits(),
                qdd.map(f64::to_bits),
            )
        });
        const HQ: usize = humanoid34_twins::NQ;
        const HV: usize = humanoid34_twins::NV;
        const FRAMES: usize = humanoid34_twins::FRAMES.len();
        let humanoid_q: [f64; HQ] = std::array::from_fn(|_| rng.uniform(-3.0, 3.0));
        both(|| {
            let mut frames = [[f64::NAN; 12]; FRAMES];
            humanoid34_twins::f64::kinematics(&humanoid_q, &mut frames);
            let mut m = [[f64::NAN; HV]; HV];
            humanoid34_twins::f64::crba(&humanoid_q, &mut m);
            (
                frames.map(|frame| frame.map(f64::to_bits)),
                m.map(|row| row.map(f64::to_bits)),
            )
        });
        const CQ: usize = humanoid34_com::NQ;
        const CV: usize = humanoid34_com::NV;
        let com_q: [f64; CQ] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
        let com_v: [f64; CV] = std::array::from_fn(|_| rng.uniform(-2.0, 2.0));
        both(|| {
            let (mut c, mut vc, mut j) = ([f64::NAN; 3], [f64::NAN; 3], [[f64::NAN; CV]; 3]);
            humanoid34_com::f64::com(&com_q, &com_v, &mut c, &mut vc, &mut j);
            (
                c.map(f64::to_bits),
                vc.map(f64::to_bits),
                j.map(|row| row.map(f64::to_bits)),
            )
        });
        const NQ: usize = solo12_free::NQ;
        const NV: usize = solo12_free::NV;
        let configuration = rng.configuration(&solo);
        let q: [f64; NQ] = std::array::from_fn(|i| configuration[i]);
        let v: [f64; NV] = std::array::from_fn(|_| rng.uniform(-2.0, 2.0));
        let u: [f64; NV] = std::array::from_fn(|_| rng.uniform(-5.0, 5.0));
        both(|| {
            let (mut x, mut blocks) = ([f64::NAN; NV], [[[f64::NAN; NV]; NV]; 3]);
            let [b0, b1, b2] = &mut blocks;
            solo12_free::f64::aba_derivatives(&q, &v, &u, &mut x, b0, b1, b2);
            (
                x.map(f64::to_bits),
                blocks.map(|m| m.map(|row| row.map(f64::to_bits))),
            )
        });
    }
}

/// The generated `step_derivatives` (semi-implicit Euler and its Jacobian) equals the interpreted one on
/// random UR5 states.
#[test]
fn generated_step_matches_the_interpreted() {
    let model: Model<f64> = load_model("tests/data/pinocchio/ur5.urdf", false);
    let mut rng = Rng::new(8);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = StepDerivatives::new(&model);
    let dt = 0.005;
    for _ in 0..4 {
        let q = rng.configuration(&model);
        let v = rng.vec(N, -2.0, 2.0);
        let tau = rng.vec(N, -5.0, 5.0);
        step_derivatives(&model, &mut dws, &q, &v, &tau, dt, &[], &mut d).unwrap();
        let (q1, v1, worst) = step_error(ur5_step::f64::step_derivatives, (&q, &v, &tau, dt), &d);
        assert!(worst < 1e-12, "{worst:e}");
        // The plain step is the same next state, to rounding: the generator may take the derivatives'
        // q̈ from the factorized mass matrix, the plain step's from the articulated-body pass.
        let (mut q2, mut v2) = ([0.0; N], [0.0; N]);
        let arr = |x: &[f64]| -> [f64; N] { std::array::from_fn(|i| x[i]) };
        ur5_step::f64::step(&arr(&q), &arr(&v), &arr(&tau), dt, &mut q2, &mut v2);
        let (dq, dv) = (rel_vec(&q2, &q1), rel_vec(&v2, &v1));
        assert!(dq < 1e-13 && dv < 1e-13, "q' {dq:e}, v' {dv:e}");
    }
}

/// The generated `step_derivatives` of a floating base equals the interpreted one, base rows included
/// (they were NaN: the square root's derivative at zero, 0 · ∞ in traced code, `Dual::sqrt`).
#[test]
fn generated_step_of_a_floating_base_matches_the_interpreted() {
    const NQ: usize = pendulum_free_step::NQ;
    const NV: usize = pendulum_free_step::NV;
    let model: Model<f64> = load_model("tests/data/pinocchio/double_pendulum.urdf", true);
    let mut rng = Rng::new(9);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = StepDerivatives::new(&model);
    let dt = 0.005;
    for _ in 0..4 {
        let q = rng.configuration(&model);
        let (v, tau) = (rng.vec(NV, -2.0, 2.0), rng.vec(NV, -5.0, 5.0));
        step_derivatives(&model, &mut dws, &q, &v, &tau, dt, &[], &mut d).unwrap();
        let interpreted = [&d.dq_next_dq, &d.dq_next_dv, &d.dq_next_dtau];
        assert!(interpreted.iter().all(|m| m.iter().all(|x| x.is_finite())));
        let generated: GeneratedStep<NQ, NV> = pendulum_free_step::f64::step_derivatives;
        let (_, _, worst) = step_error(generated, (&q, &v, &tau, dt), &d);
        assert!(worst < 1e-12, "{worst:e}");
    }
}

/// Generated f32 `aba_derivatives` keeps `aba`'s digits in `q̈` and `M⁻¹` (attacker's trial, 2026-12-04:
/// with `q̈` and `M⁻¹` from the factorized mass matrix, traced once for both scalar modules, the Z1's f32
/// `q̈` was off by 6.0e-5 and its `M⁻¹` by 4.1e-5, against 2.1e-7 and 1.2e-7 by `aba`), and its
/// derivatives stay within f32's reach, against the interpreted f64 solver on random states.
#[test]
fn generated_f32_forward_derivatives_keep_their_digits() {
    use z1_both_scalars as z1;
    const N: usize = z1::NV;
    let model: Model<f64> = load_model("models/peers/z1.urdf", false);
    let mut dws = DerivativeWorkspace::new(&model);
    let mut d = AbaDerivatives::new(&model);
    let mut rng = Rng::new(99);
    let mut worst = [0.0f64; 4];
    for _ in 0..20 {
        let q: [f64; N] = rng.vec(N, -3.0, 3.0).try_into().unwrap();
        let v: [f64; N] = rng.vec(N, -2.0, 2.0).try_into().unwrap();
        let tau: [f64; N] = rng.vec(N, -5.0, 5.0).try_into().unwrap();
        // The reference at the f32 inputs, so that only the arithmetic differs.
        let (q32, v32, t32) = (
            q.map(|x| x as f32),
            v.map(|x| x as f32),
            tau.map(|x| x as f32),
        );
        let wide = |x: [f32; N]| x.map(f64::from);
        aba_derivatives(
            &model,
            &mut dws,
            &wide(q32),
            &wide(v32),
            &wide(t32),
            &[],
            &mut d,
        )
        .unwrap();
        let mut qdd = [0.0f32; N];
        let (mut dq, mut dv, mut dt) = (
            [[UNWRITTEN as f32; N]; N],
            [[UNWRITTEN as f32; N]; N],
            [[UNWRITTEN as f32; N]; N],
        );
        z1::f32::aba_derivatives(&q32, &v32, &t32, &mut qdd, &mut dq, &mut dv, &mut dt);
        let errors = [
            rel_vec(&wide(qdd), d.qdd.as_slice()),
            rel(&widen(&dt), &d.dqdd_dtau),
            rel(&widen(&dq), &d.dqdd_dq),
            rel(&widen(&dv), &d.dqdd_dv),
        ];
        for (w, e) in worst.iter_mut().zip(errors) {
            *w = crate::common::worse(*w, e);
        }
    }
    assert!(
        worst[0] < 2e-6 && worst[1] < 2e-6 && worst[2] < 1e-3 && worst[3] < 1e-3,
        "f32 q̈, M⁻¹, ∂q̈/∂q, ∂q̈/∂v: {worst:?}"
    );
}
