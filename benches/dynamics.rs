//! Interpreted-solver benchmarks: ABA, RNEA, CRBA and the Eq. 6 inverse on bundled and public robots,
//! f64 and f32, and ABA on chains of 10, 100 and 1000 bodies (cost must grow linearly).
//!
//! `cargo bench --bench dynamics`; `bench/compare.sh` runs this and Pinocchio in one go and writes
//! the table in BENCHMARKS.md. Every call cycles through 64 pre-generated random states.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use embedyn::{aba, crba, load, mass_matrix_inverse, rnea, Model, ModelOptions, Real, Workspace};
use std::hint::black_box;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{chain, Rng};
use std::time::Duration;

/// Models benchmarked (name, path from the repo root, --floating).
pub const MODELS: [(&str, &str, bool); 8] = [
    ("ur5", "tests/data/pinocchio/ur5.urdf", false),
    ("z1", "models/peers/z1.urdf", false),
    ("arm7", "models/arm7.urdf", false),
    ("panda", "tests/data/pinocchio/panda.urdf", false),
    ("anymal_b", "models/peers/anymal_b.urdf", false),
    ("solo12_floating", "tests/data/pinocchio/solo12.urdf", true),
    ("quadruped", "models/quadruped.urdf", false),
    ("humanoid34", "models/humanoid34.urdf", false),
];

struct States<T> {
    q: Vec<Vec<T>>,
    v: Vec<Vec<T>>,
    x: Vec<Vec<T>>,
}

/// 64 deterministic pseudo-random states (angles in ±3 rad, quaternions normalized).
fn states<T: Real>(model: &Model<T>) -> States<T> {
    let mut rng = Rng(42);
    let mut out = States {
        q: vec![],
        v: vec![],
        x: vec![],
    };
    for _ in 0..64 {
        let mut q: Vec<T> = rng
            .vec(model.nq(), -3.0, 3.0)
            .into_iter()
            .map(T::from_f64)
            .collect();
        model.normalize_configuration(&mut q);
        out.q.push(q);
        out.v.push(
            rng.vec(model.nv(), -1.0, 1.0)
                .into_iter()
                .map(T::from_f64)
                .collect(),
        );
        out.x.push(
            rng.vec(model.nv(), -1.0, 1.0)
                .into_iter()
                .map(T::from_f64)
                .collect(),
        );
    }
    out
}

fn load_model<T: Real>(path: &str, floating: bool) -> Model<T> {
    let full = format!("{}/{path}", env!("CARGO_MANIFEST_DIR"));
    load(full.as_ref())
        .unwrap()
        .model(&ModelOptions {
            floating,
            ..Default::default()
        })
        .unwrap()
}

fn bench_algorithms<T: Real>(c: &mut Criterion, suffix: &str) {
    for (name, path, floating) in MODELS {
        let model = load_model::<T>(path, floating);
        let st = states(&model);
        let mut ws = Workspace::new(&model);
        ws.reserve_inverse(&model);
        let mut k = 0usize;
        let mut next = || {
            k = (k + 1) & 63;
            k
        };
        c.bench_function(&format!("aba{suffix}/{name}"), |b| {
            b.iter(|| {
                let i = next();
                black_box(aba(&model, &mut ws, &st.q[i], &st.v[i], &st.x[i]).unwrap()[0])
            })
        });
        c.bench_function(&format!("rnea{suffix}/{name}"), |b| {
            b.iter(|| {
                let i = next();
                black_box(rnea(&model, &mut ws, &st.q[i], &st.v[i], &st.x[i]).unwrap()[0])
            })
        });
        c.bench_function(&format!("crba{suffix}/{name}"), |b| {
            b.iter(|| {
                let i = next();
                black_box(crba(&model, &mut ws, &st.q[i]).unwrap()[(0, 0)])
            })
        });
        c.bench_function(&format!("minv{suffix}/{name}"), |b| {
            b.iter(|| {
                let i = next();
                black_box(mass_matrix_inverse(&model, &mut ws, &st.q[i]).unwrap()[(0, 0)])
            })
        });
    }
}

fn bench_scaling(c: &mut Criterion) {
    let mut g = c.benchmark_group("aba_chain");
    for n in [10usize, 100, 1000] {
        let model = chain(n);
        let st = states(&model);
        let mut ws = Workspace::new(&model);
        let mut k = 0usize;
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                k = (k + 1) & 63;
                black_box(aba(&model, &mut ws, &st.q[k], &st.v[k], &st.x[k]).unwrap()[0])
            })
        });
    }
    g.finish();
}

fn all(c: &mut Criterion) {
    bench_algorithms::<f64>(c, "");
    bench_algorithms::<f32>(c, "_f32");
    bench_scaling(c);
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
    targets = all
}
criterion_main!(benches);
