//! Derivatives of the dynamics (issue 12's targets), generated code: `aba`, `aba_derivatives` and
//! `rnea_derivatives` on the Z1 arm (fixed) and the floating ANYmal B, each call cycling through 64
//! pre-generated random states.
//!
//! `cargo bench --bench derivatives`; `bench/derivatives.sh` runs it beside Pinocchio's
//! `computeABADerivatives` and `computeRNEADerivatives` (bench/peers/pinocchio_bench.cpp `--derivatives`),
//! each side from fresh copies of its binary, and writes the table in BENCHMARKS.md.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{load_model, Rng};

#[path = "shared/derivatives.rs"]
#[macro_use]
mod derivatives_macro;

mod z1 {
    embedyn::robot!(
        "models/peers/z1.urdf",
        f64_only,
        only(aba, aba_derivatives, rnea_derivatives)
    );
}
mod anymal {
    embedyn::robot!(
        "models/peers/anymal_b.urdf",
        floating,
        f64_only,
        only(aba, aba_derivatives, rnea_derivatives)
    );
}

fn all(c: &mut Criterion) {
    bench_robot!(c, z1, "z1", "models/peers/z1.urdf", false);
    bench_robot!(
        c,
        anymal,
        "anymal_b_floating",
        "models/peers/anymal_b.urdf",
        true
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
    targets = all
}
criterion_main!(benches);
