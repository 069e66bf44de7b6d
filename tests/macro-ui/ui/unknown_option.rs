mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", fast);
}
fn main() {}
