//! Lane modules (issue 13, `lanes = N`): each lane function evaluates N states at once, and lane `k` of
//! its result must be bit-identical to the scalar generated function's result for state `k` (the lanes
//! change the layout, never the arithmetic). Checked on the floating ANYmal B (`aba`, `rnea`, `crba`: the
//! free flyer's quaternion, sines and cosines through the batch), on a four-bar (run-time pivoting by
//! `select_gt`, the returned singularity measure) and on the Z1 in f32 with 8 lanes.

use crate::common::{load_model, Rng, UNWRITTEN};
use embedyn::codegen_support::{F32x8, F64x4};
use embedyn::random::SplitMix64;
use embedyn::{random_configuration_within_limits, Model};

mod anymal {
    embedyn::robot!(
        "tests/data/pinocchio/anymal_b.urdf",
        floating,
        f64_only,
        only(aba, rnea, crba),
        lanes = 4
    );
}
mod four_bar {
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(aba),
        lanes = 4
    );
}
mod z1 {
    embedyn::robot!("models/peers/z1.urdf", f32_only, only(aba, com), lanes = 8);
}

/// Generated lane code compiles in a module without the implicit prelude (attacker's trial: the batch
/// wrappers named `core::array::from_fn` without the leading `::`).
#[no_implicit_prelude]
mod without_prelude {
    ::embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(aba),
        lanes = 2
    );
}

#[test]
fn lane_code_builds_without_the_implicit_prelude() {
    // The module's existence is the check; its lane batch also agrees with its scalar function.
    let q = [0.0f64; without_prelude::NQ];
    let v = [0.0f64; without_prelude::NV];
    let u = [1.0f64; without_prelude::NV];
    let (mut batch, mut measure) = ([[0.0f64; without_prelude::NV]; 1], [0.0]);
    assert!(without_prelude::f64x2::aba_batch(
        &[q],
        &[v],
        &[u],
        &mut batch,
        &mut measure
    ));
    let mut scalar = [0.0f64; without_prelude::NV];
    let scalar_measure = without_prelude::f64::aba(&q, &v, &u, &mut scalar);
    assert_eq!(batch[0].map(f64::to_bits), scalar.map(f64::to_bits));
    assert_eq!(measure[0].to_bits(), scalar_measure.to_bits());
}

/// Lane `k` of `x` for each entry.
fn lane<const N: usize>(x: &[F64x4; N], k: usize) -> [f64; N] {
    std::array::from_fn(|i| x[i].to_array()[k])
}

/// `states[k][i]` packed as entry `i`, lane `k` (the first four states).
fn pack<const N: usize>(states: &[[f64; N]]) -> [F64x4; N] {
    std::array::from_fn(|i| F64x4::new(std::array::from_fn(|k| states[k][i])))
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

type AnymalStates = (
    Vec<[f64; anymal::NQ]>,
    Vec<[f64; anymal::NV]>,
    Vec<[f64; anymal::NV]>,
);

/// `n` random states of the floating ANYmal B: `(q, v, tau)`, joints within their limits.
fn anymal_states(n: usize, seed: u64) -> AnymalStates {
    let model: Model<f64> = load_model("tests/data/pinocchio/anymal_b.urdf", true);
    let mut rng = SplitMix64::new(seed);
    let mut noise = Rng::new(seed + 1);
    let mut q = vec![[0.0; anymal::NQ]; n];
    let mut v = vec![[0.0; anymal::NV]; n];
    let mut u = vec![[0.0; anymal::NV]; n];
    for k in 0..n {
        random_configuration_within_limits(&model, &mut rng, &mut q[k]).unwrap();
        v[k].copy_from_slice(&noise.vec(anymal::NV, -2.0, 2.0));
        u[k].copy_from_slice(&noise.vec(anymal::NV, -20.0, 20.0));
    }
    (q, v, u)
}

type FourBarStates = (
    Vec<[f64; four_bar::NQ]>,
    Vec<[f64; four_bar::NV]>,
    Vec<[f64; four_bar::NV]>,
);

/// `n` states of the four-bar on its constraint manifold, the crank from −1 rad in steps of `step`.
fn four_bar_states(n: usize, step: f64, noise: &mut Rng) -> FourBarStates {
    let model: Model<f64> = load_model("models/loops/four_bar_internal.urdf", false);
    let mut ws = embedyn::Workspace::new(&model);
    let (mut q, mut v, mut u) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        let mut state = model.neutral_configuration();
        state[0] = -1.0 + step * k as f64;
        embedyn::constraints::complete_configuration(&model, &mut ws, &mut state).unwrap();
        let mut vel = noise.vec(four_bar::NV, -1.0, 1.0);
        embedyn::constraints::complete_velocity(&model, &mut ws, &state, &mut vel).unwrap();
        q.push(<[f64; four_bar::NQ]>::try_from(state).unwrap());
        v.push(<[f64; four_bar::NV]>::try_from(vel).unwrap());
        u.push(<[f64; four_bar::NV]>::try_from(noise.vec(four_bar::NV, -1.0, 1.0)).unwrap());
    }
    (q, v, u)
}

/// Each state's `qdd` from a batch equals the scalar `aba`'s, bit for bit.
fn assert_anymal_aba_per_state(states: &AnymalStates, qdd: &[[f64; anymal::NV]]) {
    let (q, v, u) = states;
    for k in 0..q.len() {
        let mut expected = [0.0; anymal::NV];
        anymal::f64::aba(&q[k], &v[k], &u[k], &mut expected);
        assert_eq!(bits(&qdd[k]), bits(&expected), "aba, state {k}");
    }
}

/// Each four-bar state's `qdd` and measure from a batch equal the scalar `aba`'s, bit for bit.
fn assert_four_bar_aba_per_state(
    states: &FourBarStates,
    qdd: &[[f64; four_bar::NV]],
    measure: &[f64],
) {
    let (q, v, u) = states;
    for k in 0..q.len() {
        let mut expected = [0.0; four_bar::NV];
        let c = four_bar::f64::aba(&q[k], &v[k], &u[k], &mut expected);
        assert_eq!(bits(&qdd[k]), bits(&expected), "four-bar, state {k}");
        assert_eq!(
            measure[k].to_bits(),
            c.to_bits(),
            "four-bar measure, state {k}"
        );
    }
}

#[test]
fn lane_functions_equal_the_scalar_ones_bit_for_bit_on_a_floating_quadruped() {
    const NQ: usize = anymal::NQ;
    const NV: usize = anymal::NV;
    let model: Model<f64> = load_model("tests/data/pinocchio/anymal_b.urdf", true);
    let mut rng = SplitMix64::new(7);
    let mut noise = Rng::new(8);
    for _ in 0..3 {
        let mut q = [[0.0; NQ]; 4];
        let mut v = [[0.0; NV]; 4];
        let mut u = [[0.0; NV]; 4];
        for k in 0..4 {
            random_configuration_within_limits(&model, &mut rng, &mut q[k]).unwrap();
            v[k].copy_from_slice(&noise.vec(NV, -2.0, 2.0));
            u[k].copy_from_slice(&noise.vec(NV, -20.0, 20.0));
        }
        let (ql, vl, ul) = (pack(&q), pack(&v), pack(&u));
        let mut qdd = [F64x4::splat(0.0); NV];
        anymal::f64x4::aba(&ql, &vl, &ul, &mut qdd);
        let mut tau = [F64x4::splat(0.0); NV];
        anymal::f64x4::rnea(&ql, &vl, &ul, &mut tau);
        let mut m = [[F64x4::splat(0.0); NV]; NV];
        anymal::f64x4::crba(&ql, &mut m);
        for k in 0..4 {
            let mut expected = [0.0; NV];
            anymal::f64::aba(&q[k], &v[k], &u[k], &mut expected);
            assert_eq!(bits(&lane(&qdd, k)), bits(&expected), "aba, lane {k}");
            anymal::f64::rnea(&q[k], &v[k], &u[k], &mut expected);
            assert_eq!(bits(&lane(&tau, k)), bits(&expected), "rnea, lane {k}");
            let mut mass = [[UNWRITTEN; NV]; NV];
            anymal::f64::crba(&q[k], &mut mass);
            for r in 0..NV {
                assert_eq!(
                    bits(&lane(&m[r], k)),
                    bits(&mass[r]),
                    "crba row {r}, lane {k}"
                );
            }
        }
        // The lanes are different states (a test of one state copied four times could not fail).
        assert_ne!(
            qdd[0].to_array()[0].to_bits(),
            qdd[0].to_array()[1].to_bits()
        );
    }
}

#[test]
fn lane_functions_pivot_lane_by_lane_on_a_loop() {
    const NQ: usize = four_bar::NQ;
    const NV: usize = four_bar::NV;
    let model: Model<f64> = load_model("models/loops/four_bar_internal.urdf", false);
    let mut ws = embedyn::Workspace::new(&model);
    let mut noise = Rng::new(3);
    let mut q = [[0.0; NQ]; 4];
    let mut v = [[0.0; NV]; 4];
    let mut u = [[0.0; NV]; 4];
    for k in 0..4 {
        // Crank angles far apart, so that the lanes pivot differently.
        let mut state = model.neutral_configuration();
        state[0] = -1.2 + 0.8 * k as f64;
        embedyn::constraints::complete_configuration(&model, &mut ws, &mut state).unwrap();
        q[k].copy_from_slice(&state);
        let mut vel = noise.vec(NV, -1.0, 1.0);
        embedyn::constraints::complete_velocity(&model, &mut ws, &state, &mut vel).unwrap();
        v[k].copy_from_slice(&vel);
        u[k].copy_from_slice(&noise.vec(NV, -1.0, 1.0));
    }
    let mut qdd = [F64x4::splat(0.0); NV];
    let condition = four_bar::f64x4::aba(&pack(&q), &pack(&v), &pack(&u), &mut qdd);
    for k in 0..4 {
        let mut expected = [0.0; NV];
        let c = four_bar::f64::aba(&q[k], &v[k], &u[k], &mut expected);
        assert_eq!(bits(&lane(&qdd, k)), bits(&expected), "lane {k}");
        assert_eq!(
            condition.to_array()[k].to_bits(),
            c.to_bits(),
            "measure, lane {k}"
        );
        assert!(condition.to_array()[k] < four_bar::f64x4::SINGULARITY_THRESHOLD);
    }
}

#[test]
fn f32_lane_functions_equal_the_scalar_ones() {
    const N: usize = z1::NV;
    let mut noise = Rng::new(11);
    let draw = |noise: &mut Rng, scale: f64| -> [[f32; N]; 8] {
        std::array::from_fn(|_| std::array::from_fn(|_| noise.uniform(-scale, scale) as f32))
    };
    let (q, v, u) = (
        draw(&mut noise, 2.5),
        draw(&mut noise, 2.0),
        draw(&mut noise, 5.0),
    );
    let pack8 = |states: &[[f32; N]; 8]| -> [F32x8; N] {
        std::array::from_fn(|i| F32x8::new(std::array::from_fn(|k| states[k][i])))
    };
    let mut qdd = [F32x8::splat(0.0); N];
    z1::f32x8::aba(&pack8(&q), &pack8(&v), &pack8(&u), &mut qdd);
    for k in 0..8 {
        let mut expected = [0.0f32; N];
        z1::f32::aba(&q[k], &v[k], &u[k], &mut expected);
        let got: [f32; N] = std::array::from_fn(|i| qdd[i].to_array()[k]);
        assert!(
            got.iter()
                .zip(&expected)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "lane {k}: {got:?} vs {expected:?}"
        );
    }
    // `com`'s first output is named `com` too: its `_batch` form must still reach the function (an
    // attacker's trial found it shadowed, and the crate did not compile).
    let (mut c, mut vc, mut jc) = ([[0.0f32; 3]; 8], [[0.0f32; 3]; 8], [[[0.0f32; N]; 3]; 8]);
    assert!(z1::f32x8::com_batch(&q, &v, &mut c, &mut vc, &mut jc));
    for k in 0..8 {
        let (mut c1, mut vc1, mut jc1) = ([0.0f32; 3], [0.0f32; 3], [[0.0f32; N]; 3]);
        z1::f32::com(&q[k], &v[k], &mut c1, &mut vc1, &mut jc1);
        let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same(&c[k], &c1) && same(&vc[k], &vc1), "com, state {k}");
        assert!((0..3).all(|r| same(&jc[k][r], &jc1[r])), "J_com, state {k}");
    }
}

/// The `_batch` form: any number of states (here 7: a full chunk of four and a padded one of three), each
/// state's result bit-identical to the scalar function's, the measure per state on a loop model, and
/// slices of different lengths refused (false, nothing written).
#[test]
fn batch_functions_equal_the_scalar_ones_for_any_number_of_states() {
    const NV: usize = anymal::NV;
    let n = 7;
    let states = anymal_states(n, 21);
    let (q, v, u) = &states;
    let mut noise = Rng::new(22);
    let mut qdd = vec![[f64::NAN; NV]; n];
    assert!(anymal::f64x4::aba_batch(q, v, u, &mut qdd));
    assert_anymal_aba_per_state(&states, &qdd);
    let mut m = vec![[[f64::NAN; NV]; NV]; n];
    assert!(anymal::f64x4::crba_batch(q, &mut m));
    for k in 0..n {
        let mut mass = [[UNWRITTEN; NV]; NV];
        anymal::f64::crba(&q[k], &mut mass);
        for r in 0..NV {
            assert_eq!(bits(&m[k][r]), bits(&mass[r]), "crba row {r}, state {k}");
        }
    }
    // Different lengths: refused, nothing written.
    let mut short = vec![[f64::NAN; NV]; n - 1];
    assert!(!anymal::f64x4::aba_batch(q, v, u, &mut short));
    assert!(short.iter().flatten().all(|x| x.is_nan()));
    // No states: nothing to do.
    assert!(anymal::f64x4::aba_batch(&[], &[], &[], &mut []));

    // A loop model: the measure per state.
    let loops = four_bar_states(5, 0.5, &mut noise);
    let (q, v, u) = &loops;
    let mut qdd = vec![[0.0; four_bar::NV]; 5];
    let mut measure = vec![0.0; 5];
    assert!(four_bar::f64x4::aba_batch(q, v, u, &mut qdd, &mut measure));
    assert_four_bar_aba_per_state(&loops, &qdd, &measure);
}

/// Threads over a batch: `embedyn::parallel::par_batch` cuts every slice at the same states and runs the
/// pieces' `_batch` calls on rayon's pool; each of 203 states (pieces of 16 and a last one of 11, padded
/// inside its lane chunk) is bit-identical to the scalar call, the loop model's measures included.
#[test]
fn threads_over_a_batch_equal_the_scalar_calls() {
    const NV: usize = anymal::NV;
    let n = 203;
    let states = anymal_states(n, 31);
    let (q, v, u) = &states;
    let mut noise = Rng::new(32);
    let mut qdd = vec![[f64::NAN; NV]; n];
    let ok = embedyn::parallel::par_batch(
        (&q[..], &v[..], &u[..], &mut qdd[..]),
        16,
        |(q, v, u, qdd)| {
            assert!(q.len() <= 16);
            assert!(anymal::f64x4::aba_batch(q, v, u, qdd));
        },
    );
    assert!(ok);
    assert_anymal_aba_per_state(&states, &qdd);
    // Slices of different lengths: refused before any thread starts, nothing written.
    let mut short = vec![[f64::NAN; NV]; n - 1];
    let ok = embedyn::parallel::par_batch((&q[..], &v[..], &u[..], &mut short[..]), 16, |_| {
        panic!("called on mismatched slices")
    });
    assert!(!ok);
    assert!(short.iter().flatten().all(|x| x.is_nan()));

    // A loop model: the measure slice is cut with the others.
    let loops = four_bar_states(37, 0.05, &mut noise);
    let (q, v, u) = &loops;
    let mut qdd = vec![[0.0; four_bar::NV]; 37];
    let mut measure = vec![0.0; 37];
    let slices = (&q[..], &v[..], &u[..], &mut qdd[..], &mut measure[..]);
    assert!(embedyn::parallel::par_batch(
        slices,
        8,
        |(q, v, u, qdd, measure)| {
            assert!(four_bar::f64x4::aba_batch(q, v, u, qdd, measure));
        }
    ));
    assert_four_bar_aba_per_state(&loops, &qdd, &measure);
}

/// The AVX twins of the 256-bit lane modules (`f64x4`, `f32x8`: one AVX instruction per lane value where the
/// CPU has AVX, codegen/src/dispatch.rs) give the bits of their baseline copies and of the scalar functions:
/// every lane function here run with both twins allowed (AVX-512 where the CPU has it), with the AVX-512
/// twins forbidden (`use_avx512`) and with all forbidden (`use_avx`), the floating ANYmal B's
/// `aba`, `rnea`, `crba` and `aba_batch` (whose baseline copy goes state by state through the paired scalar
/// function, its twin through the lanes), the four-bar's pivoting `aba` with its measure, and the Z1's `aba` in
/// eight f32 lanes. (On a CPU without AVX all three runs take the baseline copy, and without AVX-512 the first two
/// take the AVX twin; the CI machines have AVX, and the test says what ran.)
#[test]
fn lane_twins_give_the_bits_of_the_baseline_copies() {
    use embedyn::codegen_support::dispatch::{avx, avx512, use_avx, use_avx512};
    const NV: usize = anymal::NV;
    let n = 9;
    let states = anymal_states(n, 31);
    let (q, v, u) = &states;
    let packed = |k: usize| (pack(&q[k..]), pack(&v[k..]), pack(&u[k..]));
    let mut noise = Rng::new(32);
    let loops = four_bar_states(4, 0.6, &mut noise);
    let z1_states: [[[f32; z1::NV]; 8]; 3] = std::array::from_fn(|_| {
        std::array::from_fn(|_| std::array::from_fn(|_| noise.uniform(-2.5, 2.5) as f32))
    });
    let pack8 = |states: &[[f32; z1::NV]; 8]| -> [F32x8; z1::NV] {
        std::array::from_fn(|i| F32x8::new(std::array::from_fn(|k| states[k][i])))
    };
    // Every result of one run, as bits.
    let run = || {
        let mut out: Vec<u64> = Vec::new();
        for k in [0, 5] {
            let (ql, vl, ul) = packed(k);
            let mut qdd = [F64x4::splat(0.0); NV];
            anymal::f64x4::aba(&ql, &vl, &ul, &mut qdd);
            let mut tau = [F64x4::splat(0.0); NV];
            anymal::f64x4::rnea(&ql, &vl, &ul, &mut tau);
            let mut m = [[F64x4::splat(0.0); NV]; NV];
            anymal::f64x4::crba(&ql, &mut m);
            for j in 0..4 {
                out.extend(bits(&lane(&qdd, j)));
                out.extend(bits(&lane(&tau, j)));
                m.iter().for_each(|row| out.extend(bits(&lane(row, j))));
            }
        }
        let mut qdd = vec![[0.0; NV]; n];
        assert!(anymal::f64x4::aba_batch(q, v, u, &mut qdd));
        assert_anymal_aba_per_state(&states, &qdd);
        qdd.iter().for_each(|x| out.extend(bits(x)));
        let (lq, lv, lu) = &loops;
        let mut qdd = [F64x4::splat(0.0); four_bar::NV];
        let measure = four_bar::f64x4::aba(&pack(lq), &pack(lv), &pack(lu), &mut qdd);
        out.extend(measure.to_array().map(f64::to_bits));
        for j in 0..4 {
            out.extend(bits(&lane(&qdd, j)));
        }
        for s in &z1_states {
            let mut qdd = [F32x8::splat(0.0); z1::NV];
            z1::f32x8::aba(&pack8(s), &pack8(s), &pack8(s), &mut qdd);
            for (j, state) in s.iter().enumerate() {
                let mut expected = [0.0f32; z1::NV];
                z1::f32::aba(state, state, state, &mut expected);
                let got: [f32; z1::NV] = std::array::from_fn(|i| qdd[i].to_array()[j]);
                assert_eq!(
                    got.map(f32::to_bits),
                    expected.map(f32::to_bits),
                    "f32x8, lane {j}"
                );
                out.extend(got.map(|x| u64::from(x.to_bits())));
            }
        }
        out
    };
    use_avx(true);
    let with_avx512 = run();
    use_avx512(false);
    let with_avx = run();
    use_avx512(true);
    use_avx(false);
    let baseline = run();
    use_avx(true);
    for (twins, name) in [(&with_avx512, "AVX-512"), (&with_avx, "AVX")] {
        assert_eq!(twins.len(), baseline.len());
        let differing = twins.iter().zip(&baseline).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing,
            0,
            "{name} twins: {differing} of {} results differ",
            baseline.len()
        );
    }
    // The lane results are those of the scalar functions too (the lanes of the first pack).
    let (ql, vl, ul) = packed(0);
    let mut qdd = [F64x4::splat(0.0); NV];
    anymal::f64x4::aba(&ql, &vl, &ul, &mut qdd);
    for j in 0..4 {
        let mut expected = [0.0; NV];
        anymal::f64::aba(&q[j], &v[j], &u[j], &mut expected);
        assert_eq!(bits(&lane(&qdd, j)), bits(&expected), "aba, lane {j}");
    }
    eprintln!(
        "lane twins: {} (this CPU {} AVX, {} AVX-512 F and VL)",
        if avx() {
            "compared with the baseline copies"
        } else {
            "not run"
        },
        if avx() { "has" } else { "lacks" },
        if avx512() { "has" } else { "lacks" }
    );
}
