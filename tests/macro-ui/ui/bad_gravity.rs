// `gravity = [x, y, z]` takes three numbers (m/s²): two are a compile error at the brackets.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", gravity = [0.0, -9.81]);
}
fn main() {}
