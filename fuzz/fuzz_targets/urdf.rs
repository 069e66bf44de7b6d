//! Arbitrary bytes as a URDF file (and, after a NUL byte, a state): load, build in f64 and f32 with and
//! without `--floating`, run the interpreted algorithms, generate code for tiny models. The properties
//! are in `../harness.rs`.
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| harness::urdf(data));
