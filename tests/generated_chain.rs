//! Generated code long enough to be split into several functions (parts that pass values through a
//! scratch tuple, single-use values nested into expressions, results written by the part that computes
//! them) against the interpreted solver: f64 to 1e-12 relative, f32 to 1e-4 of the f64 answer.

use crate::common;

use common::{load_model, Rng, UNWRITTEN};
use embedyn::{
    aba, crba, forward_kinematics, link_poses, mass_matrix_inverse, relative_error, rnea, Model,
    Workspace,
};

mod chain24 {
    // Also exercises the macro's limit option (the default would do for this size).
    embedyn::robot!(
        "tests/data/scale/chain24.urdf",
        minv,
        max_compile_memory = 4096,
        // (the AVX twins are tested in generated_derivatives.rs; these four would add their compile time)
        avx_twins = none
    );
}

const NQ: usize = chain24::NQ;
const NV: usize = chain24::NV;

fn flat(m: &[[f64; NV]; NV]) -> Vec<f64> {
    m.as_flattened().to_vec()
}

fn flat32(m: &[[f32; NV]; NV]) -> Vec<f64> {
    m.as_flattened().iter().map(|&x| x as f64).collect()
}

fn dense(m: &embedyn::nalgebra::DMatrix<f64>) -> Vec<f64> {
    (0..NV * NV).map(|k| m[(k / NV, k % NV)]).collect()
}

#[test]
fn split_chain_generated_matches_interpreted() {
    let model: Model<f64> = load_model("tests/data/scale/chain24.urdf", false);
    assert_eq!((model.nq(), model.nv()), (NQ, NV));
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(7);
    // worst relative error: f64 aba, rnea, crba, minv, kinematics; then f32 aba, rnea, crba, minv.
    let mut worst = [0.0f64; 9];
    for _ in 0..10 {
        let q: [f64; NQ] = rng.configuration(&model).try_into().unwrap();
        let v: [f64; NV] = rng.vec(NV, -2.0, 2.0).try_into().unwrap();
        let x: [f64; NV] = rng.vec(NV, -10.0, 10.0).try_into().unwrap();
        let (q32, v32, x32) = (
            q.map(|a| a as f32),
            v.map(|a| a as f32),
            x.map(|a| a as f32),
        );
        let mut out = [0.0; NV];
        let mut out32 = [0.0f32; NV];
        let mut mat = [[UNWRITTEN; NV]; NV];
        let mut mat32 = [[UNWRITTEN as f32; NV]; NV];

        let want = aba(&model, &mut ws, &q, &v, &x).unwrap().to_vec();
        chain24::f64::aba(&q, &v, &x, &mut out);
        worst[0] = worst[0].max(relative_error(&out, &want));
        chain24::f32::aba(&q32, &v32, &x32, &mut out32);
        worst[5] = worst[5].max(relative_error(&out32.map(|a| a as f64), &want));

        let want = rnea(&model, &mut ws, &q, &v, &x).unwrap().to_vec();
        chain24::f64::rnea(&q, &v, &x, &mut out);
        worst[1] = worst[1].max(relative_error(&out, &want));
        chain24::f32::rnea(&q32, &v32, &x32, &mut out32);
        worst[6] = worst[6].max(relative_error(&out32.map(|a| a as f64), &want));

        let want = dense(crba(&model, &mut ws, &q).unwrap());
        chain24::f64::crba(&q, &mut mat);
        worst[2] = worst[2].max(relative_error(&flat(&mat), &want));
        chain24::f32::crba(&q32, &mut mat32);
        worst[7] = worst[7].max(relative_error(&flat32(&mat32), &want));

        let want = dense(mass_matrix_inverse(&model, &mut ws, &q).unwrap());
        chain24::f64::minv(&q, &mut mat);
        worst[3] = worst[3].max(relative_error(&flat(&mat), &want));
        chain24::f32::minv(&q32, &mut mat32);
        worst[8] = worst[8].max(relative_error(&flat32(&mat32), &want));

        forward_kinematics(&model, &mut ws, &q, &v).unwrap();
        let want: Vec<f64> = link_poses(&model, &ws)
            .flat_map(|(_, x)| {
                let mut f: Vec<f64> = x.rotation.transpose().iter().copied().collect();
                f.extend(x.translation.iter());
                f
            })
            .collect();
        let mut frames = [[UNWRITTEN; 12]; chain24::FRAMES.len()];
        chain24::f64::kinematics(&q, &mut frames);
        worst[4] = worst[4].max(relative_error(frames.as_flattened(), &want));
    }
    eprintln!(
        "chain24 generated vs interpreted (aba rnea crba minv kinematics f64; aba rnea crba minv \
         f32): {}",
        worst.map(|w| format!("{w:.1e}")).join(" ")
    );
    for (k, w) in worst.iter().enumerate() {
        let tolerance = if k < 5 { 1e-12 } else { 1e-4 };
        assert!(
            *w <= tolerance,
            "chain24: generated function {k} differs by {w:e}"
        );
    }
}

mod twin_arms {
    // Two identical 26-link arms: `crba` (17,498 operations, 8,849 statements with the arms side by side)
    // is a paired body of five parts, whose values cross between parts as scalars (`s`) and pairs (`sp`).
    embedyn::robot!(
        "tests/data/scale/twin_arms.urdf",
        f64_only,
        only(crba),
        avx_twins = none
    );
}

/// A paired body cut into parts computes the interpreted mass matrix (1e-12 relative).
#[test]
fn paired_parts_of_twin_arms_match_interpreted() {
    const NQ: usize = twin_arms::NQ;
    const NV: usize = twin_arms::NV;
    let model: Model<f64> = load_model("tests/data/scale/twin_arms.urdf", false);
    assert_eq!((model.nq(), model.nv()), (NQ, NV));
    let mut ws = Workspace::new(&model);
    let mut rng = Rng::new(11);
    let mut worst = 0.0f64;
    for _ in 0..10 {
        let q: [f64; NQ] = rng.configuration(&model).try_into().unwrap();
        let want = crba(&model, &mut ws, &q).unwrap().clone();
        let mut mat = [[UNWRITTEN; NV]; NV];
        twin_arms::f64::crba(&q, &mut mat);
        let want: Vec<f64> = (0..NV * NV).map(|k| want[(k / NV, k % NV)]).collect();
        worst = worst.max(relative_error(mat.as_flattened(), &want));
    }
    eprintln!("twin arms generated crba vs interpreted: {worst:.1e}");
    assert!(
        worst <= 1e-12,
        "twin arms: generated crba differs by {worst:e}"
    );
}
