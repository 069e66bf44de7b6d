//! The build.rs route of embedyn: `build.rs` writes the generated module, `include!` brings it in, and a
//! program that calls one of its functions builds without a warning (denied here, so that the route stays
//! clean: once 19 dead-code warnings).
#![deny(warnings)]

mod arm7 {
    include!(concat!(env!("OUT_DIR"), "/arm7.rs"));
}

fn main() {
    let q = [0.1; arm7::NQ];
    let v = [0.0; arm7::NV];
    let tau = [0.0; arm7::NV];
    let mut qdd = [0.0; arm7::NV];
    arm7::f64::aba(&q, &v, &tau, &mut qdd);
    println!("qdd under gravity at q = 0.1: {qdd:?}");
}
