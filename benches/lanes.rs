//! Many states per call (issue 13): the generated lane functions (`lanes = 4`: module `f64x4`, four
//! states per call) against the scalar generated functions, per state, on the Z1 arm (fixed base) and
//! the floating ANYmal B: `aba`, `rnea`, `crba` and `aba_derivatives`.
//!
//! `cargo bench --bench lanes` (the baseline x86-64 target: the lane functions' AVX twins where the CPU
//! has AVX, their AVX-512 twins where it has AVX-512 F and VL; with `EMBEDYN_AVX_TWINS_ONLY=1` the AVX
//! twins; with `EMBEDYN_BASELINE_COPIES=1` their SSE2 copies, two f64 per instruction);
//! `RUSTFLAGS="-C target-cpu=native" cargo bench --bench lanes` for the host's widest SIMD.
//! `bench/lanes.sh` runs both beside Pinocchio and writes BENCHMARKS.md's table. Every call cycles
//! through 64 pre-generated random states; a lane call's time is divided by its 4 states.

use criterion::{criterion_group, criterion_main, Criterion};
use embedyn::codegen_support::F64x4;
use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{load_model, Rng};

mod z1 {
    embedyn::robot!(
        "models/peers/z1.urdf",
        f64_only,
        only(aba, rnea, crba, aba_derivatives),
        lanes = 4
    );
}
mod anymal {
    embedyn::robot!(
        "models/peers/anymal_b.urdf",
        floating,
        f64_only,
        only(aba, rnea, crba, aba_derivatives),
        lanes = 4
    );
}

/// Entry `i`, lane `k` is state `k`'s entry `i`.
fn pack<const N: usize>(states: &[[f64; N]]) -> [F64x4; N] {
    std::array::from_fn(|i| F64x4::new(std::array::from_fn(|k| states[k][i])))
}

macro_rules! bench_robot {
    ($c:ident, $m:ident, $name:literal, $path:literal, $floating:literal) => {{
        use $m::{NQ, NV};
        let model = load_model::<f64>($path, $floating);
        let mut rng = Rng::new(42);
        let (q, v, u) = rng.states::<_, NQ, NV>(&model, 64);
        // Sixteen packs of four states.
        let ql: Vec<_> = q.chunks(4).map(pack).collect();
        let vl: Vec<_> = v.chunks(4).map(pack).collect();
        let ul: Vec<_> = u.chunks(4).map(pack).collect();
        let mut k = 0usize;
        let mut out = [0.0; NV];
        let mut m = [[0.0; NV]; NV];
        let mut out4 = [F64x4::splat(0.0); NV];
        let mut m4 = [[F64x4::splat(0.0); NV]; NV];
        $c.bench_function(concat!("gen_aba/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 63;
                $m::f64::aba(black_box(&q[k]), &v[k], &u[k], &mut out);
                black_box(out[0])
            })
        });
        $c.bench_function(concat!("gen_aba_x4/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                $m::f64x4::aba(black_box(&ql[k]), &vl[k], &ul[k], &mut out4);
                black_box(out4[0])
            })
        });
        // The batch form over all 64 states (transposition included), per call of 64.
        let mut out64 = vec![[0.0; NV]; 64];
        $c.bench_function(concat!("gen_aba_batch64/", $name), |b| {
            b.iter(|| {
                assert!($m::f64x4::aba_batch(black_box(&q), &v, &u, &mut out64));
                black_box(out64[0][0])
            })
        });
        // Threads over a batch: 1024 states, one thread (`aba_batch`) against rayon's pool
        // (`embedyn::parallel::par_batch`, pieces of 64 states), per call of 1024.
        let q1k: Vec<[f64; NQ]> = (0..1024).map(|s| q[s & 63]).collect();
        let v1k: Vec<[f64; NV]> = (0..1024).map(|s| v[s & 63]).collect();
        let u1k: Vec<[f64; NV]> = (0..1024).map(|s| u[s & 63]).collect();
        let mut out1k = vec![[0.0; NV]; 1024];
        $c.bench_function(concat!("gen_aba_batch1024/", $name), |b| {
            b.iter(|| {
                assert!($m::f64x4::aba_batch(
                    black_box(&q1k),
                    &v1k,
                    &u1k,
                    &mut out1k
                ));
                black_box(out1k[0][0])
            })
        });
        $c.bench_function(concat!("gen_aba_par1024/", $name), |b| {
            b.iter(|| {
                let slices = (black_box(&q1k[..]), &v1k[..], &u1k[..], &mut out1k[..]);
                assert!(embedyn::parallel::par_batch(
                    slices,
                    64,
                    |(q, v, u, out)| {
                        assert!($m::f64x4::aba_batch(q, v, u, out));
                    }
                ));
                black_box(out1k[0][0])
            })
        });
        $c.bench_function(concat!("gen_rnea/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 63;
                $m::f64::rnea(black_box(&q[k]), &v[k], &u[k], &mut out);
                black_box(out[0])
            })
        });
        $c.bench_function(concat!("gen_rnea_x4/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                $m::f64x4::rnea(black_box(&ql[k]), &vl[k], &ul[k], &mut out4);
                black_box(out4[0])
            })
        });
        $c.bench_function(concat!("gen_crba/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 63;
                $m::f64::crba(black_box(&q[k]), &mut m);
                black_box(m[0][0])
            })
        });
        $c.bench_function(concat!("gen_crba_x4/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                $m::f64x4::crba(black_box(&ql[k]), &mut m4);
                black_box(m4[0][0])
            })
        });
        let (mut dq, mut dv, mut dt) = (m, m, m);
        $c.bench_function(concat!("gen_aba_derivatives/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 63;
                $m::f64::aba_derivatives(
                    black_box(&q[k]),
                    &v[k],
                    &u[k],
                    &mut out,
                    &mut dq,
                    &mut dv,
                    &mut dt,
                );
                black_box(dq[0][0])
            })
        });
        let (mut dq4, mut dv4, mut dt4) = (m4, m4, m4);
        $c.bench_function(concat!("gen_aba_derivatives_x4/", $name), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                $m::f64x4::aba_derivatives(
                    black_box(&ql[k]),
                    &vl[k],
                    &ul[k],
                    &mut out4,
                    &mut dq4,
                    &mut dv4,
                    &mut dt4,
                );
                black_box(dq4[0][0])
            })
        });
    }};
}

fn all(c: &mut Criterion) {
    // `bench/lanes.sh` times the baseline build twice: as it runs (AVX twins where the CPU has AVX) and
    // with its baseline copies alone.
    if std::env::var_os("EMBEDYN_BASELINE_COPIES").is_some() {
        embedyn::codegen_support::dispatch::use_avx(false);
    }
    if std::env::var_os("EMBEDYN_AVX_TWINS_ONLY").is_some() {
        embedyn::codegen_support::dispatch::use_avx512(false);
    }
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
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = all
}
criterion_main!(benches);
