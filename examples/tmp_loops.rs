use embedyn::constraints::*;
use embedyn::*;
#[path = "../tests/common/mod.rs"]
mod common;
fn main() {
    for f in std::env::args().skip(1) {
        let l = match load(f.as_ref()) {
            Ok(l) => l,
            Err(e) => {
                println!("{e}");
                continue;
            }
        };
        let m = match l.model::<f64>(&ModelOptions::default()) {
            Ok(m) => m,
            Err(e) => {
                println!("{e}");
                continue;
            }
        };
        println!(
            "{}: nv {} indep {} groups {}",
            m.name,
            m.nv(),
            m.independent_nv(),
            m.groups.len()
        );
        for g in &m.groups {
            println!(
                "  bodies {:?} rows {:?} dep {:?} chosen {} cond {:.2e}",
                g.bodies, g.rows, g.dependent, g.chosen, g.condition_at_load
            );
        }
        let mut ws = Workspace::new(&m);
        let mut rng = common::Rng(3);
        let mut q = rng.configuration(&m);
        for j in 0..m.joints.len() {
            if !m.is_independent(j) {
                q[m.joints[j].q_index] = 0.0;
            }
        }
        let r = complete_configuration(&m, &mut ws, &mut q);
        let mut v = rng.vec(m.nv(), -1.0, 1.0);
        complete_velocity(&m, &mut ws, &q, &mut v).unwrap();
        println!(
            "  completion {:?}, violation {:?}",
            r,
            constraint_violation(&m, &mut ws, &q, &v)
        );
        let tau = rng.vec(m.nv(), -1.0, 1.0);
        let a = aba(&m, &mut ws, &q, &v, &tau).map(|x| x.to_vec());
        let k = kkt_forward_dynamics(&m, &mut ws, &q, &v, &tau);
        match (a, k) {
            (Ok(a), Ok(k)) => println!("  aba vs kkt {:.2e}", relative_error(&a, &k)),
            (a, k) => println!("  {:?} {:?}", a.err(), k.err()),
        }
    }
}
