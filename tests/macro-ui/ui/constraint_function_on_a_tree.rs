mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", only(aba, complete));
}
fn main() {}
