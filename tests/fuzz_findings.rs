//! Regressions found by fuzzing (fuzz/README.md), each pinning the fix of its root cause. The fuzz corpus
//! itself is replayed by tests/fuzz_corpus.rs.

use crate::common;

use common::repo_path;
use embedyn::codegen::{format_tokens, generate_tokens, parse_urdf, Algorithm, GenerateOptions};
use embedyn::constraints::{
    complete_configuration, complete_velocity, constraint_condition, singularity_threshold,
    ConstraintKind,
};
use embedyn::nalgebra::Vector3;
use embedyn::{
    aba, embedding_map, load, reduced_mass_matrix, DynamicsError, ModelOptions, Workspace,
};

/// Generated code folds constants in f64 and writes them as literals of the module's scalar. A coupling
/// ratio of 1e20 fits f32, but `crba_independent` folds Xᵀ M X, whose rotor entry is about ratio² = 1e40:
/// the f32 module held the literal 1e40, and the crate did not compile. Now generation refuses it, saying
/// to generate f64 only; the f64 functions generate, and the f32 model itself still loads.
#[test]
fn a_folded_constant_beyond_f32_is_refused_in_f32_code() {
    let loaded = load(&repo_path(
        "tests/data/bad/coupling_ratio_squared_too_large_for_f32.urdf",
    ))
    .unwrap();
    assert!(loaded.model::<f32>(&ModelOptions::default()).is_ok());
    let only_crba = |f32| GenerateOptions {
        algorithms: vec![Algorithm::CrbaIndependent],
        exact: true,
        f32,
        ..Default::default()
    };
    let err = generate_tokens(&loaded, &only_crba(true))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    for needle in [
        "coupling_ratio_squared_too_large_for_f32.urdf",
        "`crba_independent`",
        "beyond the range of the scalar type",
        "generate the f64 functions only",
    ] {
        assert!(err.contains(needle), "`{needle}` not in: {err}");
    }
    let tokens = generate_tokens(&loaded, &only_crba(false)).unwrap();
    let text = format_tokens(&tokens).unwrap();
    assert!(text.contains("pub fn crba_independent"), "{text}");
}

/// The four-bar of `models/loops/four_bar_internal.urdf` with every axis (the joints' and the loop's)
/// written as `0 s 0`.
fn four_bar_with_axes_scaled(s: &str) -> embedyn::Model<f64> {
    let path = repo_path("models/loops/four_bar_internal.urdf");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("<axis xyz=\"0 1 0\"/>", &format!("<axis xyz=\"0 {s} 0\"/>"));
    assert_eq!(text.matches(&format!("\"0 {s} 0\"")).count(), 5);
    parse_urdf(&text, &path)
        .unwrap_or_else(|e| panic!("{e}"))
        .model::<f64>(&ModelOptions::default())
        .unwrap_or_else(|e| panic!("axes 0 {s} 0: {e}"))
}

/// An axis is a direction: `0 1e-200 0` and `0 1e200 0` are the y axis. Normalizing by the Euclidean
/// norm squared the components first, which underflowed to 0 or overflowed to infinity: a joint axis was
/// refused as "not a non-zero finite vector", and a loop axis was silently replaced by the x axis (the
/// four-bar then lost its planar redundancy and was refused for a dependent-joint mismatch). Unit
/// vectors are now computed scaled by the largest component.
#[test]
fn tiny_and_huge_axes_are_directions() {
    let reference = four_bar_with_axes_scaled("1");
    let y = Vector3::new(0.0, 1.0, 0.0);
    for s in ["1e-200", "1e200", "5e-324"] {
        let model = four_bar_with_axes_scaled(s);
        for j in &model.joints {
            assert_eq!(j.axis, y, "axes 0 {s} 0: joint {}", j.name);
        }
        let ConstraintKind::Loop(l) = &model.constraints[0].kind else {
            panic!("the four-bar's constraint is a loop")
        };
        assert_eq!(l.axis, y, "axes 0 {s} 0: the loop's axis");
        assert_eq!(model.independent_nv(), reference.independent_nv());
        // Same model, same dynamics.
        let (q, v, tau) = ([0.2, -0.3, 0.1, 0.4], [0.5, -0.2, 0.3, 0.1], [0.3; 4]);
        let mut ws = Workspace::new(&model);
        let mut ws_ref = Workspace::new(&reference);
        let mut q1 = q;
        complete_configuration(&reference, &mut ws_ref, &mut q1).unwrap();
        let mut v1 = v;
        complete_velocity(&reference, &mut ws_ref, &q1, &mut v1).unwrap();
        let expected = aba(&reference, &mut ws_ref, &q1, &v1, &tau)
            .unwrap()
            .to_vec();
        assert_eq!(aba(&model, &mut ws, &q1, &v1, &tau).unwrap(), &expected[..]);
    }
}

/// At the neutral configuration of this four-bar (crank and rocker on one ground pivot, every angle 0)
/// the loop's Y1 is exactly singular and its computed inverse is NaN. The condition number's column-sum
/// norm took a `max` that skips NaN, reported cond(Y1) = 0, and `embedding_map` returned Ok with NaN in
/// X. NaN is now sticky in that norm (and in completion's worst residual), so every call that uses X
/// refuses with the singular-constraint error there, and the measure generated code returns is past the
/// threshold.
#[test]
fn an_exactly_singular_loop_is_refused_not_nan() {
    let loaded = load(&repo_path(
        "tests/data/loops/coincident_pivots_four_bar.urdf",
    ))
    .unwrap();
    let model = loaded.model::<f64>(&ModelOptions::default()).unwrap();
    let mut ws = Workspace::new(&model);
    let q = model.neutral_configuration();
    let singular = |e: DynamicsError| {
        matches!(e, DynamicsError::SingularConstraint { ref group, condition, .. }
            if group == "loop1" && condition >= singularity_threshold::<f64>())
    };
    let x = embedding_map(&model, &mut ws, &q);
    assert!(x.clone().is_err_and(singular), "{x:?}");
    assert!(constraint_condition(&ws) >= singularity_threshold::<f64>());
    let m = reduced_mass_matrix(&model, &mut ws, &q);
    assert!(m.clone().is_err_and(singular), "{m:?}");
    let qdd = aba(&model, &mut ws, &q, &[0.0; 3], &[0.0; 3]).map(|x| x.to_vec());
    assert!(qdd.clone().is_err_and(singular), "{qdd:?}");
    // Assembled (from a guess on the branch), the mechanism is regular and X is finite.
    let mut q = vec![0.3, 0.0, 0.0];
    complete_configuration(&model, &mut ws, &mut q).unwrap();
    let x = embedding_map(&model, &mut ws, &q).unwrap();
    assert!(x.iter().all(|v| v.is_finite()), "{x}");
}
