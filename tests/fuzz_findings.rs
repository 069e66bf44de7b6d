//! Regressions found by fuzzing (fuzz/README.md), each pinning the fix of its root cause. The fuzz corpus
//! itself is replayed by tests/fuzz_corpus.rs.

mod common;

use common::repo_path;
use embedyn::codegen::{format_tokens, generate_tokens, Algorithm, GenerateOptions};
use embedyn::{load, ModelOptions};

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
