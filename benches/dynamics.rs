//! Interpreted-solver benchmarks: ABA, RNEA, CRBA and the Eq. 6 inverse on bundled and public robots,
//! f64 and f32, and ABA on chains of 10, 100 and 1000 bodies (cost must grow linearly).
//!
//! `cargo bench --bench dynamics`; `bench/compare.sh` runs this and Pinocchio in one go and writes
//! the table in BENCHMARKS.md. Every call cycles through 64 pre-generated random states.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use embedyn::nalgebra::{Matrix3, Vector3};
use embedyn::{
    aba, crba, load, mass_matrix_inverse, rnea, JointType, Model, ModelOptions, Real,
    SpatialInertia, Transform, Workspace,
};
use std::hint::black_box;
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

/// Deterministic pseudo-random states (SplitMix64), quaternions normalized.
fn states<T: Real>(model: &Model<T>) -> States<T> {
    let mut s: u64 = 42;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut out = States {
        q: vec![],
        v: vec![],
        x: vec![],
    };
    for _ in 0..64 {
        let mut q: Vec<T> = (0..model.nq()).map(|_| T::from_f64(3.0 * next())).collect();
        model.normalize_configuration(&mut q);
        out.q.push(q);
        out.v
            .push((0..model.nv()).map(|_| T::from_f64(next())).collect());
        out.x
            .push((0..model.nv()).map(|_| T::from_f64(next())).collect());
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

/// A chain of `n` revolute bodies alternating z and y axes, realistic link inertias.
fn chain(n: usize) -> Model<f64> {
    let mut b = Model::<f64>::builder(format!("chain{n}"));
    for i in 0..n {
        let axis = if i % 2 == 0 {
            Vector3::z()
        } else {
            Vector3::y()
        };
        let inertia = SpatialInertia::from_com(
            1.0,
            Vector3::new(0.0, 0.0, 0.1),
            Matrix3::from_diagonal(&Vector3::new(4e-3, 4e-3, 1e-3)),
        );
        let placement = Transform::from_xyz_rpy([0.0, 0.0, 0.2], [0.0; 3]);
        b.add_body(
            i.checked_sub(1),
            format!("j{i}"),
            JointType::Revolute,
            axis,
            placement,
            format!("b{i}"),
            inertia,
        )
        .unwrap();
    }
    b.build().unwrap()
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
