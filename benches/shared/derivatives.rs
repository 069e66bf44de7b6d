//! `bench_robot!`, shared by benches/derivatives.rs and benches/derivatives_large.rs: a robot's
//! generated `aba`, `aba_derivatives` and `rnea_derivatives` over 64 random states (criterion ids
//! `gen_<function>/<name>`, read by bench/derivatives_table.py). The caller has `load_model`, `Rng`,
//! `black_box` in scope and a module `$robot` made by `robot!` with those three functions.

macro_rules! bench_robot {
    ($c:expr, $robot:ident, $name:literal, $path:literal, $floating:expr) => {{
        const NQ: usize = $robot::NQ;
        const NV: usize = $robot::NV;
        let model = load_model::<f64>($path, $floating);
        let mut rng = Rng::new(7);
        let (q, v, u) = rng.states::<_, NQ, NV>(&model, 64);
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
        // The two derivative functions share one signature: (q, v, u) in, the value and three matrices out.
        type Derivatives = fn(
            &[f64; NQ],
            &[f64; NV],
            &[f64; NV],
            &mut [f64; NV],
            &mut [[f64; NV]; NV],
            &mut [[f64; NV]; NV],
            &mut [[f64; NV]; NV],
        );
        let functions: [(&str, Derivatives); 2] = [
            ("aba_derivatives", $robot::f64::aba_derivatives),
            ("rnea_derivatives", $robot::f64::rnea_derivatives),
        ];
        for (function, f) in functions {
            $c.bench_function(&format!("gen_{function}/{}", $name), |bench| {
                bench.iter(|| {
                    k = (k + 1) & 63;
                    f(black_box(&q[k]), &v[k], &u[k], &mut out, &mut a, &mut b, &mut m);
                    black_box(a[0][0] + b[0][0] + m[0][0])
                })
            });
        }
    }};
}
