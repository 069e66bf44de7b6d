// A function's name asks for it and takes no value: `minv = 3` says so instead of "unknown option".
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", minv = 3);
}
fn main() {}
