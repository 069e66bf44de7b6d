mod robot {
    embedyn::robot!("bad/loop_missing_link.urdf");
}
fn main() {}
