// `rotors = exact` or `rotors = reflected`: anything else is a compile error at the choice.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", rotors = approximate);
}
fn main() {}
