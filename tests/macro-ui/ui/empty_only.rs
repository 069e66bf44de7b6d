// `only()` with no function would generate nothing at all.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", only());
}
fn main() {}
