//! Generates the arm's dynamics into `OUT_DIR/arm7.rs` (and tells cargo to rerun when the model changes).

fn main() {
    let out = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("arm7.rs");
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/arm7.urdf");
    if let Err(e) = embedyn_codegen::generate_file(&model, &Default::default(), &out) {
        panic!("{e}");
    }
}
