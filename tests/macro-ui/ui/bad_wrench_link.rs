// `wrenches(link, …)` names links of the model: an unknown one is a compile error naming it and the
// closest link names.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", wrenches(link_2, lnk1));
}
fn main() {}
