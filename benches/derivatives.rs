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

macro_rules! bench_robot {
    ($c:expr, $robot:ident, $name:literal, $path:literal, $floating:expr) => {{
        const NQ: usize = $robot::NQ;
        const NV: usize = $robot::NV;
        let model = load_model::<f64>($path, $floating);
        let mut rng = Rng::new(7);
        let q: Vec<[f64; NQ]> = (0..64)
            .map(|_| rng.configuration(&model).try_into().unwrap())
            .collect();
        let v: Vec<[f64; NV]> = (0..64)
            .map(|_| rng.vec(NV, -1.0, 1.0).try_into().unwrap())
            .collect();
        let u: Vec<[f64; NV]> = (0..64)
            .map(|_| rng.vec(NV, -1.0, 1.0).try_into().unwrap())
            .collect();
        let mut k = 0usize;
        let mut out = [0.0; NV];
        let (mut a, mut b, mut m) = ([[0.0; NV]; NV], [[0.0; NV]; NV], [[0.0; NV]; NV]);
        $c.bench_function(concat!("gen_aba/", $name), |bench| {
            bench.iter(|| {
                k = (k + 1) & 63;
                $robot::f64::aba(black_box(&q[k]), &v[k], &u[k], &mut out);
                black_box(out[0])
            })
        });
        $c.bench_function(concat!("gen_aba_derivatives/", $name), |bench| {
            bench.iter(|| {
                k = (k + 1) & 63;
                $robot::f64::aba_derivatives(
                    black_box(&q[k]),
                    &v[k],
                    &u[k],
                    &mut out,
                    &mut a,
                    &mut b,
                    &mut m,
                );
                black_box(a[0][0] + b[0][0] + m[0][0])
            })
        });
        $c.bench_function(concat!("gen_rnea_derivatives/", $name), |bench| {
            bench.iter(|| {
                k = (k + 1) & 63;
                $robot::f64::rnea_derivatives(
                    black_box(&q[k]),
                    &v[k],
                    &u[k],
                    &mut out,
                    &mut a,
                    &mut b,
                    &mut m,
                );
                black_box(a[0][0] + b[0][0] + m[0][0])
            })
        });
    }};
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
