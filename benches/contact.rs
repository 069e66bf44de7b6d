//! Contacts, frames and momentum on the floating ANYmal B (issue 11's targets), generated code:
//! `aba` and `aba_ext` with wrenches on the four feet, one foot's `frame_lf_foot` (pose, Jacobian and
//! `J̇ v` in local_world_aligned), `com` (com, vcom, J_com), `centroidal` (A_g, h_g) and `centroidal_bias` (Ȧ_g v).
//!
//! `cargo bench --bench contact`; `bench/contact.sh` runs it with Pinocchio's `computeFrameJacobian` +
//! `getFrameClassicalAcceleration`, `jacobianCenterOfMass`, `ccrba`, `dccrba` and `aba` with `fext` in one go and
//! writes the table in BENCHMARKS.md. Every call cycles through 64 pre-generated random states.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{load_model, Rng};

mod anymal {
    embedyn::robot!(
        "models/peers/anymal_b.urdf",
        floating,
        f64_only,
        only(aba, aba_ext, frame, com, centroidal, centroidal_bias),
        wrenches(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT),
        frames(LF_FOOT)
    );
}
use anymal::{NQ, NV};

fn all(c: &mut Criterion) {
    let model = load_model::<f64>("models/peers/anymal_b.urdf", true);
    let mut rng = Rng::new(42);
    let (q, v, tau) = rng.states::<_, NQ, NV>(&model, 64);
    let f_ext: Vec<[[f64; 6]; 4]> = (0..64)
        .map(|_| {
            let mut w = [[0.0; 6]; 4];
            for row in &mut w {
                *row = rng.vec(6, -20.0, 20.0).try_into().unwrap();
            }
            w
        })
        .collect();
    let mut k = 0usize;
    let mut qdd = [0.0; NV];
    let mut pose = [0.0; 12];
    let mut jacobian = [[0.0; NV]; 6];
    let mut bias = [0.0; 6];
    c.bench_function("gen_aba/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::aba(black_box(&q[k]), &v[k], &tau[k], &mut qdd);
            black_box(qdd[0])
        })
    });
    c.bench_function("gen_aba_ext4/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::aba_ext(black_box(&q[k]), &v[k], &tau[k], &f_ext[k], &mut qdd);
            black_box(qdd[0])
        })
    });
    c.bench_function("gen_frame_jacobian_bias/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::frame_lf_foot(
                black_box(&q[k]),
                &v[k],
                &mut pose,
                &mut jacobian,
                &mut bias,
            );
            black_box(jacobian[0][0] + bias[0])
        })
    });
    let (mut com, mut vcom, mut j_com) = ([0.0; 3], [0.0; 3], [[0.0; NV]; 3]);
    c.bench_function("gen_com/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::com(black_box(&q[k]), &v[k], &mut com, &mut vcom, &mut j_com);
            black_box(j_com[0][0])
        })
    });
    let (mut h_g, mut a_g, mut dh_g) = ([0.0; 6], [[0.0; NV]; 6], [0.0; 6]);
    c.bench_function("gen_centroidal/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::centroidal(black_box(&q[k]), &v[k], &mut h_g, &mut a_g);
            black_box(a_g[0][0] + h_g[0])
        })
    });
    c.bench_function("gen_centroidal_bias/anymal_b_floating", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            anymal::f64::centroidal_bias(black_box(&q[k]), &v[k], &mut dh_g);
            black_box(dh_g[0])
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
    targets = all
}
criterion_main!(benches);
