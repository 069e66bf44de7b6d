// `lock(joint = value)` takes a number literal: a constant is a compile error saying so.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", lock(joint1 = core::f64::consts::PI));
}
fn main() {}
