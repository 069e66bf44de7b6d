//! Generated code (through the `robot!` macro) against the interpreted solver, on bundled and public
//! models: f64 to 1e-12 relative, f32 to 1e-4 of the f64 answer. The interpreted solver is the oracle.

use crate::common;

use common::{load_model, Rng, UNWRITTEN};
use embedyn::{
    aba, crba, forward_kinematics, link_poses, mass_matrix_inverse, relative_error, rnea, Model,
    Workspace,
};

mod arm7 {
    embedyn::robot!("models/arm7.urdf", minv);
}
mod humanoid34 {
    embedyn::robot!("models/humanoid34.urdf", f64_only);
}
mod quadruped {
    embedyn::robot!("models/quadruped.urdf", minv, f64_only);
}
mod solo12_free {
    embedyn::robot!("tests/data/pinocchio/solo12.urdf", floating);
}
mod panda {
    embedyn::robot!("tests/data/pinocchio/panda.urdf", f64_only);
}
mod rotor_chain {
    embedyn::robot!("models/loops/rotor_chain_10.urdf", f64_only);
}
mod four_bar {
    embedyn::robot!("models/loops/four_bar_internal.urdf");
}
mod slider_crank {
    embedyn::robot!("models/loops/slider_crank.urdf");
}
mod biped {
    embedyn::robot!("models/loops/biped_floating.urdf", f64_only);
}
mod half_turn_arms {
    // Mirrored arms whose grippers hang turned by π against each other (as TALOS's do): pairs whose
    // second lane carries a sign (`negate_second`, packs of `-x`), in f64 and f32.
    embedyn::robot!("tests/data/scale/half_turn_arms.urdf");
}
mod four_bar_terminal {
    embedyn::robot!("models/loops/four_bar_terminal.urdf");
}
mod geared_motor {
    embedyn::robot!("models/loops/geared_motor.urdf");
}
mod differential_wrist {
    embedyn::robot!("models/loops/differential_wrist.urdf");
}
mod six_bar {
    embedyn::robot!("models/loops/six_bar.urdf", f64_only);
}
mod parallel_gripper {
    embedyn::robot!("models/loops/parallel_gripper.urdf");
}
mod armature_arm {
    embedyn::robot!("tests/data/armature.urdf", minv);
}
mod four_bar_armature {
    embedyn::robot!("tests/data/loops/four_bar_armature.urdf");
}
mod moon_arm {
    // The arm on the Moon, gravity folded into the code.
    embedyn::robot!(
        "models/arm7.urdf",
        gravity = [0.0, 0.0, -1.62],
        f64_only,
        only(rnea)
    );
}
mod four_bar_aba_only {
    // Exactly `aba` (no completion, embedding or XᵀMX): what a firmware loop that integrates needs.
    // Two `only(…)` lists add up (as repeated `--only` does), so this is `only(aba, kinematics)`.
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(aba),
        only(kinematics)
    );
}
mod singular_four_bar {
    embedyn::robot!("models/loops/singular_four_bar.urdf");
}
mod four_bar_geared_crank {
    embedyn::robot!(
        "tests/data/loops/four_bar_geared_crank.urdf",
        only(complete)
    );
}

/// Compares one generated model with the interpreted one on random states. `f64_only` for a module
/// generated without `f32` (the f32 code is the same text with other constants; a few models check it,
/// and each scalar module costs the suite's build its own copy).
macro_rules! check {
    ($m:ident, $path:expr, $floating:expr) => {
        check!(@run $m, $path, $floating, [f32], [])
    };
    ($m:ident, $path:expr, $floating:expr, minv) => {
        check!(@run $m, $path, $floating, [f32], [minv])
    };
    ($m:ident, $path:expr, $floating:expr, f64_only) => {
        check!(@run $m, $path, $floating, [], [])
    };
    ($m:ident, $path:expr, $floating:expr, minv, f64_only) => {
        check!(@run $m, $path, $floating, [], [minv])
    };
    (@run $m:ident, $path:expr, $floating:expr, [$($f32:ident)?], [$($minv:ident)?]) => {{
        const NQ: usize = $m::NQ;
        const NV: usize = $m::NV;
        let model: Model<f64> = load_model($path, $floating);
        assert_eq!((model.nq(), model.nv()), (NQ, NV));
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, $m::JOINTS.to_vec());
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(99);
        let mut worst = [0.0f64; 9];
        for _ in 0..20 {
            let q: [f64; NQ] = rng.configuration(&model).try_into().unwrap();
            let v: [f64; NV] = rng.vec(NV, -2.0, 2.0).try_into().unwrap();
            let x: [f64; NV] = rng.vec(NV, -10.0, 10.0).try_into().unwrap();
            let mut out = [0.0; NV];
            let mut mat = [[UNWRITTEN; NV]; NV];
            // Consistent with couplings: project v onto the constraints; q of a gear is linear anyway.
            let (q, v) = if model.has_constraints() {
                // Near the zero pose, where every bundled loop assembles: independent coordinates within
                // ±0.3, dependent ones completed; a floating base keeps its random pose.
                let mut q = q.to_vec();
                for (j, joint) in model.joints.iter().enumerate() {
                    if joint.nq() == 1 {
                        q[joint.q_index] = if model.is_independent(j) { 0.3 * (q[joint.q_index] / std::f64::consts::PI) } else { 0.0 };
                    }
                }
                let mut v = v.to_vec();
                embedyn::constraints::complete_configuration(&model, &mut ws, &mut q).unwrap();
                embedyn::constraints::complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
                (<[f64; NQ]>::try_from(q).unwrap(), <[f64; NV]>::try_from(v).unwrap())
            } else {
                (q, v)
            };
            let want = aba(&model, &mut ws, &q, &v, &x).unwrap().to_vec();
            // (A model with constraints also returns its singularity measure; its own tests check it.)
            let _ = $m::f64::aba(&q, &v, &x, &mut out);
            worst[0] = worst[0].max(relative_error(&out, &want));
            $(
                let _ = stringify!($f32);
                let mut out32 = [0.0f32; NV];
                let _ = $m::f32::aba(&q.map(|a| a as f32), &v.map(|a| a as f32), &x.map(|a| a as f32), &mut out32);
                worst[4] = worst[4].max(relative_error(&out32.map(|a| a as f64), &want));
            )?

            let want = rnea(&model, &mut ws, &q, &v, &x).unwrap().to_vec();
            $m::f64::rnea(&q, &v, &x, &mut out);
            worst[1] = worst[1].max(relative_error(&out, &want));
            $(
                let _ = stringify!($f32);
                let mut out32 = [0.0f32; NV];
                $m::f32::rnea(&q.map(|a| a as f32), &v.map(|a| a as f32), &x.map(|a| a as f32), &mut out32);
                worst[5] = worst[5].max(relative_error(&out32.map(|a| a as f64), &want));
            )?

            let want = crba(&model, &mut ws, &q).unwrap().clone();
            $m::f64::crba(&q, &mut mat);
            let flat: Vec<f64> = (0..NV * NV).map(|k| mat[k / NV][k % NV]).collect();
            let want_flat: Vec<f64> = (0..NV * NV).map(|k| want[(k / NV, k % NV)]).collect();
            worst[2] = worst[2].max(relative_error(&flat, &want_flat));
            $(
                let _ = stringify!($f32);
                let mut mat32 = [[UNWRITTEN as f32; NV]; NV];
                $m::f32::crba(&q.map(|a| a as f32), &mut mat32);
                let flat32: Vec<f64> = (0..NV * NV).map(|k| mat32[k / NV][k % NV] as f64).collect();
                worst[6] = worst[6].max(relative_error(&flat32, &want_flat));
            )?

            // Link frames: rotation row-major, then the origin.
            forward_kinematics(&model, &mut ws, &q, &v).unwrap();
            let want: Vec<f64> = link_poses(&model, &ws)
                .flat_map(|(_, x)| {
                    let mut f: Vec<f64> = x.rotation.transpose().iter().copied().collect();
                    f.extend(x.translation.iter());
                    f
                })
                .collect();
            let names: Vec<&str> = link_poses(&model, &ws).map(|(n, _)| n).collect();
            assert_eq!(names, $m::FRAMES.to_vec());
            let mut frames = [[UNWRITTEN; 12]; $m::FRAMES.len()];
            $m::f64::kinematics(&q, &mut frames);
            worst[7] = worst[7].max(relative_error(frames.as_flattened(), &want));
            $(
                let _ = stringify!($f32);
                let mut frames32 = [[UNWRITTEN as f32; 12]; $m::FRAMES.len()];
                $m::f32::kinematics(&q.map(|a| a as f32), &mut frames32);
                let f32_as_f64: Vec<f64> = frames32.as_flattened().iter().map(|&a| a as f64).collect();
                worst[8] = worst[8].max(relative_error(&f32_as_f64, &want));
            )?

            $(
                let _ = stringify!($minv);
                let want = mass_matrix_inverse(&model, &mut ws, &q).unwrap().clone();
                check_minv!($m, q, want, worst, NV);
            )?
        }
        eprintln!(
            "{}: generated f64 vs interpreted: aba {:.1e} rnea {:.1e} crba {:.1e} minv {:.1e} kinematics {:.1e}; f32: aba {:.1e} rnea {:.1e} crba {:.1e} kinematics {:.1e}",
            $path, worst[0], worst[1], worst[2], worst[3], worst[7], worst[4], worst[5], worst[6], worst[8]
        );
        for k in [0, 1, 2, 3, 7] {
            assert!(worst[k] <= 1e-12, "{}: generated f64 differs by {:e} (index {k})", $path, worst[k]);
        }
        for k in [4, 5, 6, 8] {
            assert!(worst[k] <= 1e-4, "{}: generated f32 differs by {:e} (index {k})", $path, worst[k]);
        }
    }};
}

macro_rules! check_minv {
    ($m:ident, $q:expr, $want:expr, $worst:expr, $nv:expr) => {{
        let mut mat = [[UNWRITTEN; $nv]; $nv];
        $m::f64::minv(&$q, &mut mat);
        let flat: Vec<f64> = (0..$nv * $nv).map(|k| mat[k / $nv][k % $nv]).collect();
        let want_flat: Vec<f64> = (0..$nv * $nv).map(|k| $want[(k / $nv, k % $nv)]).collect();
        $worst[3] = $worst[3].max(relative_error(&flat, &want_flat));
    }};
}

#[test]
fn arm7_generated_matches_interpreted() {
    check!(arm7, "models/arm7.urdf", false, minv);
}

#[test]
fn humanoid34_generated_matches_interpreted() {
    check!(humanoid34, "models/humanoid34.urdf", false, f64_only);
}

#[test]
fn quadruped_generated_matches_interpreted() {
    check!(quadruped, "models/quadruped.urdf", false, minv, f64_only);
}

#[test]
fn solo12_floating_generated_matches_interpreted() {
    check!(solo12_free, "tests/data/pinocchio/solo12.urdf", true);
}

#[test]
fn panda_generated_matches_interpreted() {
    check!(panda, "tests/data/pinocchio/panda.urdf", false, f64_only);
}

#[test]
fn geared_rotor_chain_generated_matches_interpreted() {
    check!(
        rotor_chain,
        "models/loops/rotor_chain_10.urdf",
        false,
        f64_only
    );
}

#[test]
fn four_bar_generated_matches_interpreted() {
    check!(four_bar, "models/loops/four_bar_internal.urdf", false);
}

#[test]
fn slider_crank_generated_matches_interpreted() {
    check!(slider_crank, "models/loops/slider_crank.urdf", false);
}

/// Mirrored arms whose right gripper hangs turned by π against the left (net wrist turns of π and 0, written
/// to 11 digits): the right gripper's values are the left's up to signs, paired with signed second lanes.
#[test]
fn half_turned_mirror_branches_generated_matches_interpreted() {
    check!(
        half_turn_arms,
        "tests/data/scale/half_turn_arms.urdf",
        false
    );
}

#[test]
fn floating_biped_with_knee_linkages_generated_matches_interpreted() {
    check!(biped, "models/loops/biped_floating.urdf", false, f64_only);
}

/// Loop models: the generated position completion (a fixed count of Newton steps) lands where the
/// interpreted completion does, from a guess a little off the assembly, and the generated embedding map
/// equals the interpreted one, as do its pivot ratio and `crba_independent` (`Xᵀ M X`).
#[test]
#[allow(clippy::modulo_one)] // NI = 1 for the one-DoF mechanisms
fn generated_completion_and_embedding_match_interpreted() {
    macro_rules! case {
        ($m:ident, $path:expr) => {{
            const NQ: usize = $m::NQ;
            const NV: usize = $m::NV;
            const NI: usize = $m::NI;
            let model: Model<f64> = load_model($path, false);
            assert_eq!(model.independent_nv(), NI);
            let mut ws = Workspace::new(&model);
            let mut rng = Rng::new(5);
            let (mut worst_q, mut worst_x) = (0.0f64, 0.0f64);
            for _ in 0..10 {
                let mut q = model.neutral_configuration();
                for (j, joint) in model.joints.iter().enumerate() {
                    if joint.nq() == 1 && model.is_independent(j) {
                        q[joint.q_index] = rng.uniform(-0.3, 0.3);
                    }
                }
                if let Some(f) = model.joints.iter().find(|j| j.nq() == 7) {
                    q[f.q_index + 6] = 1.0;
                }
                embedyn::constraints::complete_configuration(&model, &mut ws, &mut q).unwrap();
                // A guess 0.02 off on every dependent coordinate.
                let mut guess = q.clone();
                for (j, joint) in model.joints.iter().enumerate() {
                    if !model.is_independent(j) {
                        guess[joint.q_index] += 0.02;
                    }
                }
                let mut q_gen = [0.0; NQ];
                let residual = $m::f64::complete(&guess.clone().try_into().unwrap(), &mut q_gen);
                assert!(
                    residual <= 64.0 * f64::EPSILON,
                    "{}: generated completion's residual {residual:e}",
                    $path
                );
                worst_q = worst_q.max(relative_error(&q_gen, &q));
                let mut x = [[UNWRITTEN; NI]; NV];
                let cond = $m::f64::embedding(&q.clone().try_into().unwrap(), &mut x);
                let want = embedyn::embedding_map(&model, &mut ws, &q).unwrap();
                let flat: Vec<f64> = x.iter().flatten().copied().collect();
                let want_flat: Vec<f64> = (0..NV * NI).map(|k| want[(k / NI, k % NI)]).collect();
                worst_x = worst_x.max(relative_error(&flat, &want_flat));
                // The same condition number as the interpreted embedding (same arithmetic), and as an
                // independent LU-based cond₁(Y1) of the worst group; small near the zero pose.
                let want_cond = embedyn::constraints::constraint_condition(&ws);
                assert!(
                    (cond - want_cond).abs() <= 1e-12 * want_cond,
                    "{cond} vs {want_cond}"
                );
                let lu_cond = (0..model.groups.len())
                    .map(|g| embedyn::constraints::y1_condition(&model, &mut ws, &q, g).unwrap())
                    .fold(1.0f64, f64::max);
                assert!(
                    (cond - lu_cond).abs() <= 1e-10 * lu_cond,
                    "{cond} vs LU {lu_cond}"
                );
                assert!(cond < 1e3, "{}: cond(Y1) {cond:e} near the zero pose", $path);
                // Xᵀ M X over the independent coordinates, with the same measure.
                let mut m = [[UNWRITTEN; NI]; NI];
                let cond_m = $m::f64::crba_independent(&q.clone().try_into().unwrap(), &mut m);
                assert_eq!(cond_m, cond);
                let want = embedyn::reduced_mass_matrix(&model, &mut ws, &q).unwrap();
                let flat: Vec<f64> = m.iter().flatten().copied().collect();
                let want_flat: Vec<f64> = (0..NI * NI).map(|k| want[(k / NI, k % NI)]).collect();
                worst_x = worst_x.max(relative_error(&flat, &want_flat));
            }
            eprintln!(
                "{}: generated completion {:.1e}, embedding {:.1e}",
                $path, worst_q, worst_x
            );
            assert!(
                worst_q <= 1e-12,
                "{}: generated completion off by {:e}",
                $path,
                worst_q
            );
            assert!(
                worst_x <= 1e-12,
                "{}: generated embedding off by {:e}",
                $path,
                worst_x
            );
        }};
    }
    case!(four_bar, "models/loops/four_bar_internal.urdf");
    case!(slider_crank, "models/loops/slider_crank.urdf");
    case!(biped, "models/loops/biped_floating.urdf");
}

/// The remaining bundled mechanisms: the four-bar's terminal cut, a two-stage geared arm, a bevel-gear
/// differential (two mimics per rotor), a six-bar (two loops, one aggregate link) and a mimic gripper.
#[test]
fn other_bundled_mechanisms_generated_match_interpreted() {
    check!(
        four_bar_terminal,
        "models/loops/four_bar_terminal.urdf",
        false
    );
    check!(geared_motor, "models/loops/geared_motor.urdf", false);
    check!(
        differential_wrist,
        "models/loops/differential_wrist.urdf",
        false
    );
    check!(six_bar, "models/loops/six_bar.urdf", false, f64_only);
    check!(
        parallel_gripper,
        "models/loops/parallel_gripper.urdf",
        false
    );
}

/// `gravity = [x, y, z]` is folded into the generated code: its `rnea` at rest is the interpreted gravity
/// torque of the model loaded with that gravity, which is the Earth's scaled by 1.62 / 9.81 (gravity
/// torques are linear in g).
#[test]
fn gravity_option_is_folded_into_generated_code() {
    let loaded = embedyn::load(&common::repo_path("models/arm7.urdf")).unwrap();
    let moon = loaded
        .model::<f64>(&embedyn::ModelOptions {
            gravity: [0.0, 0.0, -1.62],
            ..Default::default()
        })
        .unwrap();
    let earth: Model<f64> = load_model("models/arm7.urdf", false);
    let mut rng = Rng::new(21);
    let zeros = [0.0; moon_arm::NV];
    for _ in 0..10 {
        let q = rng.configuration(&moon);
        let mut generated = [0.0; moon_arm::NV];
        moon_arm::f64::rnea(q[..].try_into().unwrap(), &zeros, &zeros, &mut generated);
        let interpreted = rnea(&moon, &mut Workspace::new(&moon), &q, &zeros, &zeros)
            .unwrap()
            .to_vec();
        let scaled: Vec<f64> = rnea(&earth, &mut Workspace::new(&earth), &q, &zeros, &zeros)
            .unwrap()
            .iter()
            .map(|t| t * 1.62 / 9.81)
            .collect();
        assert!(relative_error(&generated, &interpreted) <= 1e-13);
        assert!(
            relative_error(&interpreted, &scaled) <= 1e-13,
            "{interpreted:?} {scaled:?}"
        );
    }
}

/// Armature read from `<dynamics>` and transmissions, in generated aba, rnea, crba and minv of a tree
/// and in a four-bar's aggregate link (on an independent and a dependent member).
#[test]
fn armature_generated_matches_interpreted() {
    check!(armature_arm, "tests/data/armature.urdf", false, minv);
    check!(
        four_bar_armature,
        "tests/data/loops/four_bar_armature.urdf",
        false
    );
}

/// Generated loop code pivots at run time (the row order is not frozen at generation time) and reports
/// how close the mechanism is to a singular configuration: along the parallelogram four-bar's branch up
/// to 1e-7 rad from its toggle, the generated `aba` matches the interpreted one to the accuracy the
/// conditioning allows and returns the interpreted embedding's condition number, which equals an
/// independent LU-based cond₁(Y1); at the toggle it returns a condition number past the threshold.
#[test]
fn generated_loop_code_pivots_and_reports_singular_configurations() {
    use embedyn::constraints::{
        complete_configuration, constraint_condition, singularity_threshold, y1_condition,
    };
    const NQ: usize = singular_four_bar::NQ;
    let model: Model<f64> = load_model("models/loops/singular_four_bar.urdf", false);
    let mut ws = Workspace::new(&model);
    let crank = model.joint_index("crank_joint").unwrap();
    let toggle = std::f64::consts::FRAC_PI_3;
    let mut q = model.neutral_configuration();
    let (mut worst, mut max_cond) = (0.0f64, 0.0f64);
    let v = vec![0.4; model.nv()];
    let tau = vec![0.3; model.nv()];
    // From 1 rad below the toggle to 1e-7 rad from it, closer and closer (continuation keeps the branch).
    let gaps: Vec<f64> = (0..=60)
        .map(|k| 10f64.powf(-7.0 * k as f64 / 60.0))
        .collect();
    for gap in gaps {
        q[model.joints[crank].q_index] = toggle - gap;
        complete_configuration(&model, &mut ws, &mut q).unwrap();
        let mut v = v.clone();
        embedyn::constraints::complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
        let lu_cond = y1_condition(&model, &mut ws, &q, 0).unwrap();
        let want = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let want_cond = constraint_condition(&ws);
        let mut qdd = [0.0; NQ];
        let cond = singular_four_bar::f64::aba(
            &q.clone().try_into().unwrap(),
            &v.clone().try_into().unwrap(),
            &tau.clone().try_into().unwrap(),
            &mut qdd,
        );
        let e = relative_error(&qdd, &want);
        // Both are accurate to about cond · eps; they differ by no more.
        assert!(
            e <= 1e-13 * lu_cond.max(1.0),
            "{gap:e} rad from the toggle: generated off by {e:e} (cond {lu_cond:e})"
        );
        // A measure of a near-singular matrix: relative accuracy about cond · eps.
        for (what, other) in [("interpreted", want_cond), ("LU", lu_cond)] {
            assert!(
                (cond - other).abs() <= 1e-13 * lu_cond.max(1.0) * other,
                "cond {cond:e} vs {what} {other:e}"
            );
        }
        worst = worst.max(e / lu_cond.max(1.0));
        max_cond = max_cond.max(cond);
    }
    eprintln!("singular_four_bar: generated vs interpreted ≤ {worst:.1e} · cond(Y1); largest cond {max_cond:.1e}");
    assert!(
        max_cond > 1e6,
        "the sweep gets close to the toggle: cond {max_cond:e}"
    );
    // At the toggle (exact coordinates of the flat parallelogram): past the threshold, in both scalars.
    let q_at = common::parallelogram_toggle(&model);
    let mut qdd = [0.0; NQ];
    let cond = singular_four_bar::f64::aba(
        &q_at.clone().try_into().unwrap(),
        &[0.0; NQ],
        &[0.3; NQ],
        &mut qdd,
    );
    assert!(cond >= singularity_threshold::<f64>(), "cond {cond:e}");
    assert!(cond >= singular_four_bar::f64::SINGULARITY_THRESHOLD);
    let q32: Vec<f32> = q_at.iter().map(|&x| x as f32).collect();
    let mut qdd32 = [0.0f32; NQ];
    let cond32 =
        singular_four_bar::f32::aba(&q32.try_into().unwrap(), &[0.0; NQ], &[0.3; NQ], &mut qdd32);
    assert!(cond32 >= singular_four_bar::f32::SINGULARITY_THRESHOLD);
}

/// One singularity verdict in every engine and scalar (docs/conventions.md "Singular loops"): approaching the
/// toggle, the interpreted and generated solvers refuse at the same configurations in f64 (cond₁(Y1) ≥
/// 1e10) and in f32 (≥ 10⁻³/ε ≈ 8.4e3, where f32 keeps about three digits). The f32 generated code once
/// never reported a toggle (the f64 threshold cannot be reached in f32).
#[test]
fn the_singularity_verdict_is_the_same_in_every_engine_and_scalar() {
    use embedyn::constraints::{complete_configuration, complete_velocity, singularity_threshold};
    const NQ: usize = singular_four_bar::NQ;
    let model: Model<f64> = load_model("models/loops/singular_four_bar.urdf", false);
    let model32: Model<f32> = load_model("models/loops/singular_four_bar.urdf", false);
    let (mut ws, mut ws32) = (Workspace::new(&model), Workspace::new(&model32));
    let crank = model.joints[model.joint_index("crank_joint").unwrap()].q_index;
    let toggle = std::f64::consts::FRAC_PI_3;
    let (thr64, thr32) = (
        singularity_threshold::<f64>(),
        singularity_threshold::<f32>(),
    );
    assert_eq!(thr64, 1e10);
    assert!((thr32 - 8388.608).abs() < 1e-6, "{thr32}");
    let mut q = model.neutral_configuration();
    let mut refused = [0usize; 4];
    for k in 0..=80 {
        let gap = 10f64.powf(-12.0 * k as f64 / 80.0);
        q[crank] = toggle - gap;
        if complete_configuration(&model, &mut ws, &mut q).unwrap() > 1e-12 {
            continue;
        }
        let mut v = vec![0.2; NQ];
        if complete_velocity(&model, &mut ws, &q, &mut v).is_err() {
            v = vec![0.0; NQ];
        }
        let tau = [0.3; NQ];
        let lu = embedyn::constraints::y1_condition(&model, &mut ws, &q, 0).unwrap();
        // Rounding may flip a verdict within a hair of a threshold: judge clear cases only.
        let clear = |thr: f64| (lu / thr).ln().abs() > 0.05;
        let interpreted64 = aba(&model, &mut ws, &q, &v, &tau).is_err();
        let mut qdd = [0.0; NQ];
        let cond64 = singular_four_bar::f64::aba(
            &q.clone().try_into().unwrap(),
            &v.clone().try_into().unwrap(),
            &tau,
            &mut qdd,
        );
        let generated64 =
            cond64.is_nan() || cond64 >= singular_four_bar::f64::SINGULARITY_THRESHOLD;
        let (q32, v32): (Vec<f32>, Vec<f32>) = (
            q.iter().map(|&x| x as f32).collect(),
            v.iter().map(|&x| x as f32).collect(),
        );
        let tau32 = [0.3f32; NQ];
        let interpreted32 = aba(&model32, &mut ws32, &q32, &v32, &tau32).is_err();
        let mut qdd32 = [0.0f32; NQ];
        let cond32 = singular_four_bar::f32::aba(
            &q32.clone().try_into().unwrap(),
            &v32.clone().try_into().unwrap(),
            &tau32,
            &mut qdd32,
        );
        let generated32 =
            cond32.is_nan() || cond32 >= singular_four_bar::f32::SINGULARITY_THRESHOLD;
        if clear(thr64) {
            assert_eq!(
                interpreted64,
                lu >= thr64,
                "f64 at {gap:e} rad (cond {lu:e})"
            );
            assert_eq!(
                generated64, interpreted64,
                "f64 at {gap:e} rad (cond {lu:e})"
            );
        }
        if clear(thr32) {
            assert_eq!(
                interpreted32,
                lu >= thr32,
                "f32 at {gap:e} rad (cond {lu:e})"
            );
            assert_eq!(
                generated32, interpreted32,
                "f32 at {gap:e} rad (cond {lu:e})"
            );
        }
        for (n, r) in
            refused
                .iter_mut()
                .zip([interpreted64, generated64, interpreted32, generated32])
        {
            *n += r as usize;
        }
    }
    eprintln!(
        "refused (interpreted f64, generated f64, interpreted f32, generated f32): {refused:?}"
    );
    // Near a toggle cond₁(Y1) grows like gap^(-1/2): within 1e-12 rad it passes f32's threshold, not f64's.
    assert!(refused[2] > 10 && refused[0] == 0, "{refused:?}");
    // At the toggle itself every engine and scalar refuses.
    let q_at = common::parallelogram_toggle(&model);
    let q32: Vec<f32> = q_at.iter().map(|&x| x as f32).collect();
    let err = aba(&model, &mut ws, &q_at, &[0.0; NQ], &[0.3; NQ]).unwrap_err();
    assert!(err.to_string().contains("≥ 1.0e10"), "{err}");
    let err = aba(&model32, &mut ws32, &q32, &[0.0; NQ], &[0.3; NQ]).unwrap_err();
    assert!(err.to_string().contains("≥ 8.4e3"), "{err}");
}

/// `only(…)` generates exactly the functions named, and they are the same functions: the four-bar's
/// `aba` alone matches the full module's (bit for bit: the same trace) and the interpreted solver.
#[test]
fn only_generates_the_functions_named_and_the_same_code() {
    const NQ: usize = four_bar::NQ;
    let model: Model<f64> = load_model("models/loops/four_bar_internal.urdf", false);
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(3);
    for _ in 0..5 {
        let mut q = model.neutral_configuration();
        for (j, joint) in model.joints.iter().enumerate() {
            if model.is_independent(j) {
                q[joint.q_index] = rng.uniform(-0.3, 0.3);
            }
        }
        embedyn::constraints::complete_configuration(&model, &mut ws, &mut q).unwrap();
        let mut v = rng.vec(NQ, -1.0, 1.0);
        embedyn::constraints::complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
        let tau = rng.vec(NQ, -1.0, 1.0);
        let (q, v, tau): ([f64; NQ], [f64; NQ], [f64; NQ]) = (
            q.try_into().unwrap(),
            v.try_into().unwrap(),
            tau.try_into().unwrap(),
        );
        let (mut a, mut b) = ([0.0; NQ], [0.0; NQ]);
        let ra = four_bar_aba_only::f64::aba(&q, &v, &tau, &mut a);
        let rb = four_bar::f64::aba(&q, &v, &tau, &mut b);
        assert_eq!((a, ra), (b, rb));
        let want = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        assert!(relative_error(&a, &want) <= 1e-12);
        let mut frames = [[UNWRITTEN; 12]; four_bar_aba_only::FRAMES.len()];
        four_bar_aba_only::f64::kinematics(&q, &mut frames);
        assert_eq!(four_bar_aba_only::FRAMES, four_bar::FRAMES);
    }
}

/// Position completion solves gear equations exactly and iterates to the tolerance: a four-bar whose crank
/// drives a 20:1 rotor, from an all-zero guess at crank = 0.2 rad. (The generated `complete` once ran five
/// clamped Newton steps and returned what it had: 1.5 rad off, violating the linear gear equation.)
#[test]
fn completion_solves_a_geared_four_bar_from_a_zero_guess() {
    use embedyn::constraints::{complete_configuration, constraint_violation};
    const NQ: usize = four_bar_geared_crank::NQ;
    let model: Model<f64> = load_model("tests/data/loops/four_bar_geared_crank.urdf", false);
    let mut ws = Workspace::new(&model);
    let index = |name: &str| model.joints[model.joint_index(name).unwrap()].q_index;
    let (crank, rotor) = (index("crank_joint"), index("crank_rotor_joint"));
    for crank_angle in [0.2, -0.5, 1.0] {
        let mut guess = [0.0; NQ];
        guess[crank] = crank_angle;
        guess[index("tip_joint")] = 0.1;
        let mut q_gen = [0.0; NQ];
        let residual = four_bar_geared_crank::f64::complete(&guess, &mut q_gen);
        let mut q = guess.to_vec();
        let residual_interpreted = complete_configuration(&model, &mut ws, &mut q).unwrap();
        for r in [residual, residual_interpreted] {
            assert!(
                r <= 64.0 * f64::EPSILON,
                "crank {crank_angle}: residual {r:e}"
            );
        }
        assert_eq!(q_gen[crank], crank_angle, "the independent entry is kept");
        assert!(
            (q_gen[rotor] - 20.0 * crank_angle).abs() <= 4.0 * f64::EPSILON * 20.0,
            "crank {crank_angle}: the gear equation holds: rotor {} vs {}",
            q_gen[rotor],
            20.0 * crank_angle
        );
        assert!(relative_error(&q_gen, &q) <= 1e-13, "{q_gen:?} vs {q:?}");
        let (pos, _) = constraint_violation(&model, &mut ws, &q_gen, &[0.0; NQ]).unwrap();
        // (All equations, the redundant ones Newton does not drive included.)
        assert!(pos <= 1e-13, "crank {crank_angle}: loop residual {pos:e}");
    }
}
