mod z1 {
    embedyn::robot!("models/peers/z1.urdf");
}
mod anymal {
    embedyn::robot!("models/peers/anymal_b.urdf");
}
use std::hint::black_box;
fn time(f: &mut dyn FnMut()) -> f64 {
    let mut v = Vec::new();
    for _ in 0..51 {
        let t = std::time::Instant::now();
        for _ in 0..2000 {
            f();
        }
        v.push(t.elapsed().as_nanos() as f64 / 2000.0);
    }
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[25]
}
fn main() {
    let mut qs = Vec::new();
    for k in 0..64 {
        qs.push([0.1 * k as f64; 12]);
    }
    let mut i = 0;
    let mut out = [0.0; 7];
    let ta = time(&mut || {
        i = (i + 1) & 63;
        let q: [f64; 7] = qs[i][..7].try_into().unwrap();
        z1::f64::aba(black_box(&q), &q, &q, &mut out);
        black_box(&out);
    });
    let tr = time(&mut || {
        i = (i + 1) & 63;
        let q: [f64; 7] = qs[i][..7].try_into().unwrap();
        z1::f64::rnea(black_box(&q), &q, &q, &mut out);
        black_box(&out);
    });
    let mut m = [[0.0; 7]; 7];
    let tc = time(&mut || {
        i = (i + 1) & 63;
        let q: [f64; 7] = qs[i][..7].try_into().unwrap();
        z1::f64::crba(black_box(&q), &mut m);
        black_box(&m);
    });
    println!("z1 generated f64: aba {ta:.0} rnea {tr:.0} crba {tc:.0}");
    let mut out = [0.0; 12];
    let ta = time(&mut || {
        i = (i + 1) & 63;
        let q = qs[i];
        anymal::f64::aba(black_box(&q), &q, &q, &mut out);
        black_box(&out);
    });
    let tr = time(&mut || {
        i = (i + 1) & 63;
        let q = qs[i];
        anymal::f64::rnea(black_box(&q), &q, &q, &mut out);
        black_box(&out);
    });
    let mut m = [[0.0; 12]; 12];
    let tc = time(&mut || {
        i = (i + 1) & 63;
        let q = qs[i];
        anymal::f64::crba(black_box(&q), &mut m);
        black_box(&m);
    });
    println!("anymal_b generated f64: aba {ta:.0} rnea {tr:.0} crba {tc:.0}");
}
