use embedyn::*;
#[path = "../tests/common/mod.rs"] mod common;
fn main() {
    let l = load("models/humanoid34.urdf".as_ref()).unwrap();
    let m = l.model::<f64>(&ModelOptions::default()).unwrap();
    let mut ws = Workspace::new(&m);
    let mut rng = common::Rng(7);
    for _ in 0..5 {
    let q = rng.configuration(&m);
    let mm = crba(&m, &mut ws, &q).unwrap().clone();
    let e = mm.clone().symmetric_eigen();
    let mut l = mm.clone();
    let p = linalg::cholesky_in_place(&mut l);
    println!("min eig {:e} pivot {:e}", e.eigenvalues.min(), p);
    }
}
