//! Writes the URDF of an `N`-body revolute chain to stdout (the model of the generation-scale table in
//! BENCHMARKS.md): `cargo run -p embedyn-codegen --example chain_urdf -- 1000 > chain1000.urdf`.

#[path = "../tests/support/chain_urdf.rs"]
mod chain_urdf;

fn main() {
    let arg = std::env::args().nth(1).unwrap_or_default();
    let Ok(n) = arg.parse::<usize>() else {
        eprintln!("usage: chain_urdf N (the number of moving bodies, e.g. 1000)");
        std::process::exit(2);
    };
    print!("{}", chain_urdf::chain_urdf(n));
}
