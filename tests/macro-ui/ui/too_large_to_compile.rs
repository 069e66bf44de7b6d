// Generated code that rustc is estimated to need more memory for than allowed is a compile error that
// names the estimate and what shrinks it (here a limit of 60 MB against the 269 MB predicted for a 24-body
// chain's functions: more than `PREDICTION_SLACK` = 4 times the limit, so refused before tracing).
mod chain {
    embedyn::robot!("scale/chain24.urdf", max_compile_memory = 60);
}

fn main() {}
