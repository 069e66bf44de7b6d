// Generated code that rustc is estimated to need more memory for than allowed is a compile error that
// names the estimate and what shrinks it (here a limit of 100 MB against a 24-body chain's functions).
mod chain {
    embedyn::robot!("scale/chain24.urdf", max_compile_memory = 100);
}

fn main() {}
