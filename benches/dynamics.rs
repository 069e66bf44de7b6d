//! Interpreted-solver benchmarks: ABA, RNEA, CRBA and the Eq. 6 inverse on bundled and public robots,
//! f64 and f32, and ABA on chains of 10, 100 and 1000 bodies (cost must grow linearly); generated code
//! (`gen_*`: aba, rnea, gravity, nle, crba) on the same robots.
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
    let mut rng = Rng::new(42);
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

/// Models with loops and couplings: (name, path). The rotor chains measure how embedding scales against
/// the Lagrange-multiplier (KKT) baseline; GRBDA's files compare with GRBDA's published timings.
pub const LOOP_MODELS: [(&str, &str); 9] = [
    ("rotor_chain_10", "models/loops/rotor_chain_10.urdf"),
    ("rotor_chain_50", "models/loops/rotor_chain_50.urdf"),
    ("rotor_chain_200", "models/loops/rotor_chain_200.urdf"),
    ("four_bar", "tests/data/grbda/four_bar.urdf"),
    ("six_bar", "tests/data/grbda/six_bar.urdf"),
    (
        "revolute_rotor_chain",
        "tests/data/grbda/revolute_rotor_chain.urdf",
    ),
    ("mini_cheetah", "tests/data/grbda/mini_cheetah.urdf"),
    ("mit_humanoid", "tests/data/grbda/mit_humanoid.urdf"),
    ("jvrc1_humanoid", "tests/data/grbda/jvrc1_humanoid.urdf"),
];

/// 16 consistent states of a loop model: independent coordinates within ±0.3 of zero, completed.
fn loop_states(model: &Model<f64>) -> States<f64> {
    use embedyn::constraints::{complete_configuration, complete_velocity};
    let mut ws = Workspace::new(model);
    let mut rng = Rng::new(7);
    let mut out = States {
        q: vec![],
        v: vec![],
        x: vec![],
    };
    while out.q.len() < 16 {
        let mut q = model.neutral_configuration();
        for j in 0..model.joints.len() {
            if model.is_independent(j) && model.joints[j].nq() == 1 {
                q[model.joints[j].q_index] = rng.uniform(-0.3, 0.3);
            }
        }
        if complete_configuration(model, &mut ws, &mut q).map_or(true, |r| r > 1e-12) {
            continue;
        }
        let mut v = rng.vec(model.nv(), -1.0, 1.0);
        complete_velocity(model, &mut ws, &q, &mut v).unwrap();
        out.q.push(q);
        out.v.push(v);
        out.x.push(rng.vec(model.nv(), -1.0, 1.0));
    }
    out
}

fn bench_loops(c: &mut Criterion) {
    for (name, path) in LOOP_MODELS {
        let model = load_model::<f64>(path, false);
        let st = loop_states(&model);
        let mut ws = Workspace::new(&model);
        let mut k = 0usize;
        c.bench_function(&format!("embedded_aba/{name}"), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                black_box(aba(&model, &mut ws, &st.q[k], &st.v[k], &st.x[k]).unwrap()[0])
            })
        });
        c.bench_function(&format!("kkt_aba/{name}"), |b| {
            b.iter(|| {
                k = (k + 1) & 15;
                black_box(
                    embedyn::kkt_forward_dynamics(&model, &mut ws, &st.q[k], &st.v[k], &st.x[k])
                        .unwrap()[0],
                )
            })
        });
    }
}

/// The same models through `embedyn::robot!` (generated straight-line code), with `gravity` and `nle`
/// beside the default functions (timed next to `rnea`: issue 10's target is gravity ≤ 0.4× rnea).
macro_rules! generated_models {
    ($($name:ident: $path:literal $(, $opt:ident)?;)*) => {
        $(mod $name { embedyn::robot!($path, gravity, nle $(, $opt)?); })*

        fn bench_generated(c: &mut Criterion) {
            $({
                const NQ: usize = $name::NQ;
                const NV: usize = $name::NV;
                let floating = stringify!($($opt)?) == "floating";
                let model = load_model::<f64>($path, floating);
                let st = states(&model);
                let q: Vec<[f64; NQ]> = st.q.iter().map(|x| x.as_slice().try_into().unwrap()).collect();
                let v: Vec<[f64; NV]> = st.v.iter().map(|x| x.as_slice().try_into().unwrap()).collect();
                let x: Vec<[f64; NV]> = st.x.iter().map(|x| x.as_slice().try_into().unwrap()).collect();
                let name = bench_name(stringify!($name));
                let mut out = [0.0; NV];
                let mut mat = [[0.0; NV]; NV];
                let mut k = 0usize;
                c.bench_function(&format!("gen_aba/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f64::aba(black_box(&q[k]), &v[k], &x[k], &mut out);
                    black_box(out[0])
                }));
                c.bench_function(&format!("gen_rnea/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f64::rnea(black_box(&q[k]), &v[k], &x[k], &mut out);
                    black_box(out[0])
                }));
                c.bench_function(&format!("gen_gravity/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f64::gravity(black_box(&q[k]), &mut out);
                    black_box(out[0])
                }));
                c.bench_function(&format!("gen_nle/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f64::nle(black_box(&q[k]), &v[k], &mut out);
                    black_box(out[0])
                }));
                c.bench_function(&format!("gen_crba/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f64::crba(black_box(&q[k]), &mut mat);
                    black_box(mat[0][0])
                }));
                let (q32, v32, x32): (Vec<[f32; NQ]>, Vec<[f32; NV]>, Vec<[f32; NV]>) = (
                    q.iter().map(|a| a.map(|e| e as f32)).collect(),
                    v.iter().map(|a| a.map(|e| e as f32)).collect(),
                    x.iter().map(|a| a.map(|e| e as f32)).collect(),
                );
                let mut out32 = [0.0f32; NV];
                c.bench_function(&format!("gen_aba_f32/{name}"), |b| b.iter(|| {
                    k = (k + 1) & 63;
                    $name::f32::aba(black_box(&q32[k]), &v32[k], &x32[k], &mut out32);
                    black_box(out32[0])
                }));
            })*
        }
    };
}

/// Module names are identifiers; benchmark names follow MODELS.
fn bench_name(module: &str) -> &str {
    match module {
        "solo12_free" => "solo12_floating",
        "anymal_b_free" => "anymal_b_floating",
        other => other,
    }
}

generated_models! {
    ur5: "tests/data/pinocchio/ur5.urdf";
    z1: "models/peers/z1.urdf";
    arm7: "models/arm7.urdf";
    panda: "tests/data/pinocchio/panda.urdf";
    anymal_b: "models/peers/anymal_b.urdf";
    anymal_b_free: "models/peers/anymal_b.urdf", floating;
    solo12_free: "tests/data/pinocchio/solo12.urdf", floating;
    quadruped: "models/quadruped.urdf";
    humanoid34: "models/humanoid34.urdf";
}

fn all(c: &mut Criterion) {
    bench_generated(c);
    bench_algorithms::<f64>(c, "");
    bench_algorithms::<f32>(c, "_f32");
    bench_scaling(c);
    bench_loops(c);
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
    targets = all
}
criterion_main!(benches);
