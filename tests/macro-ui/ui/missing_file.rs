mod robot {
    embedyn::robot!("bad/no_such_model.urdf");
}
fn main() {}
