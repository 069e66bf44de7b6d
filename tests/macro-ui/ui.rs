//! Compile-time errors of `embedyn::robot!` point at the macro call and name the model element. The
//! models live in the facade's tests/data/bad; `EMBEDYN_MODEL_DIR` points the macro there, because under trybuild
//! `CARGO_MANIFEST_DIR` is trybuild's own project.

#[test]
fn robot_macro_errors() {
    let bad = concat!(env!("CARGO_MANIFEST_DIR"), "/../data");
    std::env::set_var("EMBEDYN_MODEL_DIR", bad);
    // trybuild builds the fixtures' dependencies in a dev profile of its own, with full debug info by
    // default; no fixture runs, so none is needed (measured: the suite's ui test 40 s → 38 s).
    std::env::set_var("CARGO_PROFILE_DEV_DEBUG", "false");
    let t = trybuild::TestCases::new();
    t.compile_fail("ui/*.rs");
}
