//! Arbitrary bytes as the JSON input of `embedyn eval` / `embedyn complete` (interpreted engine) on the
//! bundled models; the first byte picks model, command and `--floating`. The properties are in
//! `../harness.rs`.
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| harness::eval_input(data));
