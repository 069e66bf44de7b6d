// `lock(joint = value)` names joints of the model: an unknown one is a compile error naming it.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", lock(elbow = 0.3));
}
fn main() {}
