mod robot {
    embedyn::robot!("bad/planar_joint.urdf");
}
fn main() {}
