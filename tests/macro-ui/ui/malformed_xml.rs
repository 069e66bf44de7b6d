mod robot {
    embedyn::robot!("bad/malformed.urdf");
}
fn main() {}
