//! Derivatives of the dynamics on the larger robots of issue 12's report: the floating TALOS reduced
//! (nv = 38; `aba`, `aba_derivatives`, `rnea_derivatives`, beside Pinocchio's analytical derivatives in
//! bench/derivatives.sh) and three of GRBDA's URDF+ robots, where no peer has derivatives of the
//! constrained dynamics: the floating Mini Cheetah (12 geared rotors: couplings), the MIT humanoid's leg
//! (5 couplings) and the six-bar linkage (a closed loop). For those, `aba_derivatives_independent` (the
//! derivatives along the constraint manifold) against the same model's `aba`.
//!
//! Its generated code is large (TALOS' `aba_derivatives` alone is 7 MB of source): behind the
//! `large-benches` feature, so that `cargo clippy --all-targets` and the test builds leave it out.
//! `cargo bench --features large-benches --bench derivatives_large`; bench/derivatives.sh runs it.

use criterion::{criterion_group, criterion_main, Criterion};
use embedyn::constraints::{complete_configuration, complete_velocity};
use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{load_model, Rng};

#[path = "shared/derivatives.rs"]
#[macro_use]
mod derivatives_macro;

mod talos {
    embedyn::robot!(
        "tests/data/erd/talos_reduced.urdf",
        floating,
        f64_only,
        only(aba, aba_derivatives, rnea_derivatives)
    );
}
mod mini_cheetah {
    embedyn::robot!(
        "tests/data/grbda/mini_cheetah.urdf",
        f64_only,
        only(aba, aba_derivatives_independent)
    );
}
mod mit_leg {
    embedyn::robot!(
        "tests/data/grbda/mit_humanoid_leg.urdf",
        f64_only,
        only(aba, aba_derivatives_independent)
    );
}
mod six_bar {
    embedyn::robot!(
        "tests/data/grbda/six_bar.urdf",
        f64_only,
        only(aba, aba_derivatives_independent)
    );
}

/// `aba` and `aba_derivatives_independent` of a model with constraints, at 64 states on the manifold
/// (random joint angles completed by the interpreted solver's position and velocity completion).
macro_rules! bench_constrained {
    ($c:expr, $robot:ident, $name:literal, $path:literal) => {{
        const NQ: usize = $robot::NQ;
        const NV: usize = $robot::NV;
        const NI: usize = $robot::NI;
        let model = load_model::<f64>($path, false);
        let mut ws = embedyn::Workspace::new(&model);
        let mut rng = Rng::new(11);
        let (mut q, mut v, mut u) = (Vec::new(), Vec::new(), Vec::new());
        while q.len() < 64 {
            let mut state = rng.configuration(&model);
            if complete_configuration(&model, &mut ws, &mut state).is_err() {
                continue;
            }
            let mut vel = rng.vec(NV, -1.0, 1.0);
            if complete_velocity(&model, &mut ws, &state, &mut vel).is_err() {
                continue;
            }
            q.push(<[f64; NQ]>::try_from(state).unwrap());
            v.push(<[f64; NV]>::try_from(vel).unwrap());
            u.push(<[f64; NV]>::try_from(rng.vec(NV, -1.0, 1.0)).unwrap());
        }
        let mut k = 0usize;
        let mut out = [0.0; NV];
        let mut qdd_i = [0.0; NI];
        let (mut dq, mut dv) = ([[0.0; NI]; NI], [[0.0; NI]; NI]);
        let mut dtau = [[0.0; NV]; NI];
        $c.bench_function(concat!("gen_aba/", $name), |bench| {
            bench.iter(|| {
                k = (k + 1) & 63;
                black_box($robot::f64::aba(black_box(&q[k]), &v[k], &u[k], &mut out));
                black_box(out[0])
            })
        });
        $c.bench_function(
            concat!("gen_aba_derivatives_independent/", $name),
            |bench| {
                bench.iter(|| {
                    k = (k + 1) & 63;
                    black_box($robot::f64::aba_derivatives_independent(
                        black_box(&q[k]),
                        &v[k],
                        &u[k],
                        &mut qdd_i,
                        &mut dq,
                        &mut dv,
                        &mut dtau,
                    ));
                    black_box(dq[0][0] + dv[0][0] + dtau[0][0])
                })
            },
        );
    }};
}

fn all(c: &mut Criterion) {
    bench_robot!(
        c,
        talos,
        "talos_reduced_floating",
        "tests/data/erd/talos_reduced.urdf",
        true
    );
    bench_constrained!(
        c,
        mini_cheetah,
        "mini_cheetah",
        "tests/data/grbda/mini_cheetah.urdf"
    );
    bench_constrained!(
        c,
        mit_leg,
        "mit_humanoid_leg",
        "tests/data/grbda/mit_humanoid_leg.urdf"
    );
    bench_constrained!(c, six_bar, "six_bar", "tests/data/grbda/six_bar.urdf");
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
    targets = all
}
criterion_main!(benches);
