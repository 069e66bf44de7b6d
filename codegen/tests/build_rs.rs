//! The `build.rs` entry point writes the same code the macro expands to (one generator for all three
//! ways in), and the formatted file parses as Rust.

use embedyn_codegen::{format_tokens, generate_file, generate_tokens, load, GenerateOptions};
use std::path::PathBuf;

#[test]
fn generate_file_matches_the_macro_expansion() {
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/arm7.urdf");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("arm7_build_rs.rs");
    let options = GenerateOptions::default();
    generate_file(&model, &options, &out).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    let expected =
        format_tokens(&generate_tokens(&load(&model).unwrap(), &options).unwrap()).unwrap();
    assert_eq!(written, expected);
    let file: syn::File = syn::parse_str(&written).unwrap();
    let names: Vec<String> = file
        .items
        .iter()
        .filter_map(|i| match i {
            syn::Item::Mod(m) => Some(m.ident.to_string()),
            _ => None,
        })
        .collect();
    assert_eq!(
        names,
        ["joints", "q_index", "v_index", "frames", "f64", "f32"]
    );
    assert!(written.contains("pub const JOINT4: usize = 3;"));
    assert!(written.contains("pub const LOWER: [S; super::NQ]"));
    for f in [
        "pub fn aba(",
        "pub fn rnea(",
        "pub fn crba(",
        "::embedyn::codegen_support::sincos",
    ] {
        assert!(written.contains(f), "missing {f}");
    }
}

#[test]
fn loop_models_generate_with_their_embedding_inline() {
    // The aggregate link's X_G and κ_G are part of the generated `aba`: its Y1 is factored in the code.
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/loops/slider_crank.urdf");
    let text = format_tokens(
        &generate_tokens(&load(&model).unwrap(), &GenerateOptions::default()).unwrap(),
    )
    .unwrap();
    assert!(text.contains("pub fn aba("));
}
