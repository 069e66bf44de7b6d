//! Generalized gravity `g(q)` and nonlinear effects `C(q, v) v + g(q)` (issue 10), interpreted and
//! generated, against oracles that do not share their code path: Pinocchio 4.1's
//! `computeGeneralizedGravity` and `nonLinearEffects` (tests/data/pinocchio: `gravity_torque`, `nle`) to
//! 1e-9 relative; on models with loops, couplings and mimic joints `rnea(q, 0, 0)` and `rnea(q, v, 0)`,
//! tree torques and their projection `Xᵀ τ`; and armature, which multiplies `qdd = 0`, changing neither.

use crate::common::{load_model, Rng};
use crate::constraint_embedding::{consistent_state, LOOP_MODELS};
use crate::pinocchio_reference::vecf;
use embedyn::{embedding_map, gravity, nle, relative_error, rnea, Model, Workspace};
use serde_json::Value;

/// Agreement with Pinocchio asked of both engines (the bound).
const TOL: f64 = 1e-9;

/// The generated `gravity` and `nle` of one model, over slices (the macro's functions take arrays of the
/// model's sizes).
struct Generated {
    gravity: fn(&[f64], &mut [f64]),
    nle: fn(&[f64], &[f64], &mut [f64]),
}

/// `robot!(PATH, f64_only, only(gravity, nle) …)` in a module of its own, and its [`Generated`].
macro_rules! generated {
    ($($m:ident: $path:literal $(, $opt:ident)?;)*) => {
        $(mod $m {
            embedyn::robot!($path, f64_only, only(gravity, nle) $(, $opt)?);
        })*
        /// The generated functions of the model of this reference file (`None`: not generated here).
        fn generated_for(name: &str) -> Option<Generated> {
            match name {
                $(stringify!($m) => Some(Generated {
                    gravity: |q, tau| $m::f64::gravity(q.try_into().unwrap(), tau.try_into().unwrap()),
                    nle: |q, v, tau| {
                        $m::f64::nle(q.try_into().unwrap(), v.try_into().unwrap(), tau.try_into().unwrap())
                    },
                }),)*
                _ => None,
            }
        }
    };
}

generated! {
    double_pendulum: "tests/data/pinocchio/double_pendulum.urdf";
    double_pendulum_continuous: "tests/data/pinocchio/double_pendulum_continuous.urdf";
    ur5: "tests/data/pinocchio/ur5.urdf";
    panda: "tests/data/pinocchio/panda.urdf";
    solo12: "tests/data/pinocchio/solo12.urdf";
    solo12_floating: "tests/data/pinocchio/solo12_floating.urdf", floating;
    armature_arm: "tests/data/pinocchio/armature_arm.urdf";
    solo12_armature_floating: "tests/data/pinocchio/solo12_armature_floating.urdf", floating;
}

/// Both engines' `gravity` and `nle` against Pinocchio's on every sample of `tests/data/pinocchio/NAME.json`
/// (`gravity_torque` where the file has it: the armature files have `nle` only); returns how many
/// numbers were compared.
fn check_against_pinocchio(name: &str, floating: bool) -> usize {
    let json = crate::pinocchio_reference::reference(name);
    let model = load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), floating);
    let generated = generated_for(name).expect("a generated module per reference file");
    // Pinocchio's joint order may differ: map by name.
    let (q_map, v_map) = crate::pinocchio_reference::coordinate_maps(name, &model, &json);
    let pick = |x: &Value, map: &[usize]| -> Vec<f64> {
        let x = vecf(x);
        map.iter().map(|&i| x[i]).collect()
    };
    let mut ws = Workspace::new(&model);
    let mut out = vec![0.0; model.nv()];
    // interpreted gravity, generated gravity, interpreted nle, generated nle
    let mut worst = [0.0f64; 4];
    let mut compared = 0;
    for s in json["samples"].as_array().unwrap() {
        let (q, v) = (pick(&s["q_angle"], &q_map), pick(&s["v"], &v_map));
        if !s["gravity_torque"].is_null() {
            let want = pick(&s["gravity_torque"], &v_map);
            let g = gravity(&model, &mut ws, &q).unwrap();
            worst[0] = worst[0].max(relative_error(g, &want));
            (generated.gravity)(&q, &mut out);
            worst[1] = worst[1].max(relative_error(&out, &want));
            compared += 2 * want.len();
        }
        let want = pick(&s["nle"], &v_map);
        let h = nle(&model, &mut ws, &q, &v).unwrap();
        worst[2] = worst[2].max(relative_error(h, &want));
        (generated.nle)(&q, &v, &mut out);
        worst[3] = worst[3].max(relative_error(&out, &want));
        compared += 2 * want.len();
    }
    let gravity_compared = json["samples"][0]["gravity_torque"].is_array();
    eprintln!(
        "{name}: against Pinocchio, gravity interpreted {:.1e} generated {:.1e}{}, nle interpreted {:.1e} generated {:.1e}",
        worst[0],
        worst[1],
        if gravity_compared { "" } else { " (not in the file)" },
        worst[2],
        worst[3]
    );
    for (what, w) in [
        "interpreted gravity",
        "generated gravity",
        "interpreted nle",
        "generated nle",
    ]
    .iter()
    .zip(worst)
    {
        assert!(
            w <= TOL,
            "{name}: {what} differs from Pinocchio by {w:e} (relative)"
        );
    }
    compared
}

#[test]
fn gravity_and_nle_match_pinocchio_on_arms_and_pendulums() {
    for name in [
        "double_pendulum",
        "double_pendulum_continuous",
        "ur5",
        "panda",
    ] {
        // 20 samples, gravity and nle, both engines.
        assert_eq!(
            check_against_pinocchio(name, false),
            80 * load_model::<f64>(&format!("tests/data/pinocchio/{name}.urdf"), false).nv()
        );
    }
}

#[test]
fn gravity_and_nle_match_pinocchio_on_a_quadruped_fixed_and_floating() {
    assert_eq!(check_against_pinocchio("solo12", false), 80 * 12);
    assert_eq!(check_against_pinocchio("solo12_floating", true), 80 * 18);
}

/// Pinocchio's `nonLinearEffects` with `model.armature` set (tests/data/pinocchio/armature.py) is the
/// same as without: armature is inertia on a joint's own axis, met only through `qdd`.
#[test]
fn nle_with_armature_matches_pinocchio() {
    assert_eq!(check_against_pinocchio("armature_arm", false), 40 * 3);
    assert_eq!(
        check_against_pinocchio("solo12_armature_floating", true),
        40 * 18
    );
}

/// `Xᵀ τ`: the generalized force on the independent coordinates.
fn projected(model: &Model<f64>, q: &[f64], tau: &[f64]) -> Vec<f64> {
    let x = embedding_map(model, &mut Workspace::new(model), q).unwrap();
    (0..x.ncols())
        .map(|c| (0..model.nv()).map(|r| x[(r, c)] * tau[r]).sum())
        .collect()
}

/// On every model with loops, couplings or mimic joints: `gravity(q)` = `rnea(q, 0, 0)` and
/// `nle(q, v)` = `rnea(q, v, 0)` on consistent states, the spanning tree's torques and their projection
/// onto the independent coordinates (what `eval` reports as `tau_independent`).
#[test]
fn gravity_and_nle_are_rnea_at_rest_on_models_with_loops() {
    let mut rng = Rng::new(1010);
    // Models whose gravity forces are not all zero (GRBDA's four-bar moves in a horizontal plane).
    let mut loaded_by_gravity = 0;
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        assert!(model.has_constraints(), "{path}");
        let mut ws = Workspace::new(&model);
        let zero = vec![0.0; model.nv()];
        let mut worst = 0.0f64;
        for _ in 0..5 {
            let (q, v) = consistent_state(&model, &mut ws, &mut rng);
            let g = gravity(&model, &mut ws, &q).unwrap().to_vec();
            let g_rnea = rnea(&model, &mut ws, &q, &zero, &zero).unwrap().to_vec();
            let h = nle(&model, &mut ws, &q, &v).unwrap().to_vec();
            let h_rnea = rnea(&model, &mut ws, &q, &v, &zero).unwrap().to_vec();
            if g.iter().any(|x| x.abs() > 1e-6) {
                loaded_by_gravity += 1;
            }
            for (ours, theirs) in [(&g, &g_rnea), (&h, &h_rnea)] {
                worst = worst.max(relative_error(ours, theirs));
                worst = worst.max(relative_error(
                    &projected(&model, &q, ours),
                    &projected(&model, &q, theirs),
                ));
            }
        }
        assert!(
            worst <= 1e-14,
            "{path}: gravity/nle differ from rnea at rest by {worst:e}"
        );
    }
    assert!(
        loaded_by_gravity >= 5 * LOOP_MODELS.len() / 2,
        "only {loaded_by_gravity} states with gravity forces"
    );
}

mod four_bar {
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        only(gravity, nle, embedding)
    );
}
mod geared_armature {
    embedyn::robot!(
        "tests/data/loops/four_bar_armature.urdf",
        only(gravity, nle)
    );
}

/// The generated `gravity` and `nle` of loop models (one with armature) against the interpreted ones,
/// f64 to 1e-12 and f32 to 1e-4; the generated `embedding` projects them as the interpreted map does.
#[test]
fn generated_gravity_and_nle_match_interpreted_on_loop_models() {
    macro_rules! check {
        ($m:ident, $path:literal) => {{
            const NQ: usize = $m::NQ;
            const NV: usize = $m::NV;
            let model = load_model::<f64>($path, false);
            assert_eq!((model.nq(), model.nv()), (NQ, NV));
            let mut ws = Workspace::new(&model);
            let mut rng = Rng::new(1011);
            let mut worst = [0.0f64; 2];
            for _ in 0..10 {
                let (q, v) = consistent_state(&model, &mut ws, &mut rng);
                let (q, v): ([f64; NQ], [f64; NV]) = (q.try_into().unwrap(), v.try_into().unwrap());
                let (q32, v32) = (q.map(|x| x as f32), v.map(|x| x as f32));
                let (mut out, mut out32) = ([0.0; NV], [0.0f32; NV]);
                let want = gravity(&model, &mut ws, &q).unwrap().to_vec();
                $m::f64::gravity(&q, &mut out);
                worst[0] = worst[0].max(relative_error(&out, &want));
                $m::f32::gravity(&q32, &mut out32);
                worst[1] = worst[1].max(relative_error(&out32.map(f64::from), &want));
                let want = nle(&model, &mut ws, &q, &v).unwrap().to_vec();
                $m::f64::nle(&q, &v, &mut out);
                worst[0] = worst[0].max(relative_error(&out, &want));
                $m::f32::nle(&q32, &v32, &mut out32);
                worst[1] = worst[1].max(relative_error(&out32.map(f64::from), &want));
            }
            eprintln!(
                "{}: generated gravity and nle vs interpreted: f64 {:.1e}, f32 {:.1e}",
                $path, worst[0], worst[1]
            );
            assert!(worst[0] <= 1e-12, "{}: f64 off by {:e}", $path, worst[0]);
            assert!(worst[1] <= 1e-4, "{}: f32 off by {:e}", $path, worst[1]);
        }};
    }
    check!(four_bar, "models/loops/four_bar_internal.urdf");
    check!(geared_armature, "tests/data/loops/four_bar_armature.urdf");

    // Xᵀ g with the generated X is the interpreted projection.
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    let (q, _) = consistent_state(&model, &mut Workspace::new(&model), &mut Rng::new(1012));
    let q: [f64; four_bar::NQ] = q.try_into().unwrap();
    let mut g = [0.0; four_bar::NV];
    four_bar::f64::gravity(&q, &mut g);
    let mut x = [[0.0; four_bar::NI]; four_bar::NV];
    let cond = four_bar::f64::embedding(&q, &mut x);
    assert!(cond < four_bar::f64::SINGULARITY_THRESHOLD);
    let generated: Vec<f64> = (0..four_bar::NI)
        .map(|c| (0..four_bar::NV).map(|r| x[r][c] * g[r]).sum())
        .collect();
    let err = relative_error(&generated, &projected(&model, &q, &g));
    assert!(err <= 1e-12, "generated Xᵀ g off by {err:e}");
}

/// Armature multiplies `qdd`, which is 0 in both: the same `gravity` and `nle`, interpreted and
/// generated, with and without it, while `rnea` at `qdd ≠ 0` does see it.
#[test]
fn armature_changes_neither_gravity_nor_nle() {
    let geared = load_model::<f64>("tests/data/pinocchio/armature_arm.urdf", false);
    assert!(geared.joints.iter().any(|j| j.armature > 0.0));
    let mut plain = geared.clone();
    for joint in &mut plain.joints {
        joint.armature = 0.0;
    }
    let (mut ws_g, mut ws_p) = (Workspace::new(&geared), Workspace::new(&plain));
    let generated = generated_for("armature_arm").unwrap();
    let mut rng = Rng::new(1013);
    let mut out = vec![0.0; geared.nv()];
    for _ in 0..10 {
        let q = rng.configuration(&geared);
        let v = rng.vec(geared.nv(), -2.0, 2.0);
        let qdd = rng.vec(geared.nv(), -5.0, 5.0);
        let g = gravity(&plain, &mut ws_p, &q).unwrap().to_vec();
        assert_eq!(gravity(&geared, &mut ws_g, &q).unwrap(), &g[..]);
        (generated.gravity)(&q, &mut out);
        assert!(relative_error(&out, &g) <= 1e-12);
        let h = nle(&plain, &mut ws_p, &q, &v).unwrap().to_vec();
        assert_eq!(nle(&geared, &mut ws_g, &q, &v).unwrap(), &h[..]);
        (generated.nle)(&q, &v, &mut out);
        assert!(relative_error(&out, &h) <= 1e-12);
        // The armature is there: rnea with an acceleration differs by exactly armature · qdd.
        let t_plain = rnea(&plain, &mut ws_p, &q, &v, &qdd).unwrap().to_vec();
        let t_geared = rnea(&geared, &mut ws_g, &q, &v, &qdd).unwrap().to_vec();
        for (k, joint) in geared.joints.iter().enumerate() {
            let i = joint.v_index;
            assert!(
                (t_geared[i] - t_plain[i] - joint.armature * qdd[i]).abs() <= 1e-12,
                "joint {k}"
            );
        }
    }
}

/// `gravity` and `nle` check their inputs as `rnea` does.
#[test]
fn gravity_and_nle_check_their_inputs() {
    let model = load_model::<f64>("models/arm7.urdf", false);
    let mut ws = Workspace::new(&model);
    let q = vec![0.1; model.nq()];
    let e = gravity(&model, &mut ws, &q[1..]).unwrap_err().to_string();
    assert!(e.contains("`q` has length 6, the model needs 7"), "{e}");
    let mut v = vec![0.0; model.nv()];
    v[2] = f64::NAN;
    let e = nle(&model, &mut ws, &q, &v).unwrap_err().to_string();
    assert!(e.contains("`v`[2] is not a finite number"), "{e}");
}
