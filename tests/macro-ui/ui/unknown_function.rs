mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", only(aba, forward_dynamics));
}
fn main() {}
