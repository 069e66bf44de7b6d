// An option that sets one value is given once: a second `lanes = …` would otherwise silently win over
// the first. The error points at the repetition.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", lanes = 4, only(aba), lanes = 2);
}
fn main() {}
