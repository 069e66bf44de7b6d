//! Golden files (as prost-build's fixtures): the generated module of two small models is checked in
//! (`tests/golden/*.rs`, the `f64` module of what `build.rs` writes) and compared byte for byte, so that
//! every change in emitted code (names, order of operations, docs) shows in review.
//!
//! After an intended change of the generator, rewrite them and review the diff:
//!
//! ```text
//! EMBEDYN_BLESS=1 cargo test -p embedyn-codegen --test golden
//! ```

use embedyn_codegen::{generate_source, load, GenerateOptions};
use std::path::PathBuf;

/// Generates `model` (a path from the codegen crate) and compares it with `tests/golden/{golden}`.
fn check_golden(model: &str, golden: &str) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let loaded = load(&root.join(model)).unwrap();
    let options = GenerateOptions {
        f32: false,
        ..GenerateOptions::default()
    };
    let text = generate_source(&loaded, &options).unwrap();
    syn::parse_file(&text).expect("generated code parses");
    let path = root.join("tests/golden").join(golden);
    if std::env::var_os("EMBEDYN_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; write it with EMBEDYN_BLESS=1 cargo test -p embedyn-codegen --test golden",
            path.display()
        )
    });
    if text != want {
        let (line, (got, expected)) = text
            .lines()
            .zip(want.lines())
            .enumerate()
            .find(|(_, (a, b))| a != b)
            .map_or(
                (text.lines().count().min(want.lines().count()), ("", "")),
                |(i, p)| (i, p),
            );
        panic!(
            "the generated code of {model} differs from {} from line {}:\n  generated: {got}\n  golden:    {expected}\nIf the change is intended: EMBEDYN_BLESS=1 cargo test -p embedyn-codegen --test golden, and review the diff.",
            path.display(),
            line + 1
        );
    }
}

/// A three-joint leg (a tree): `kinematics`, `aba`, `rnea`, `crba`.
#[test]
fn leg_matches_its_golden_file() {
    check_golden("tests/golden/leg.urdf", "leg.rs");
}

/// A four-bar linkage (a loop, constraint embedding): also `complete`, `embedding`, `crba_independent`,
/// and the `#[must_use]` singularity measures.
#[test]
fn four_bar_matches_its_golden_file() {
    check_golden(
        "../models/loops/four_bar_internal.urdf",
        "four_bar_internal.rs",
    );
}

/// Two mirrored legs (isomorphic branches): the legs' steps computed side by side as pairs
/// (`let p3: P = p1 * p2;`, codegen/src/pairing.rs).
#[test]
fn biped_matches_its_golden_file() {
    check_golden("tests/golden/biped.urdf", "biped.rs");
}
