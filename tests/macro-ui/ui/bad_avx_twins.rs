// `avx_twins` takes a value, one of three names: a bare key and a string point at themselves and list them.
mod bare {
    embedyn::robot!("grbda/double_pendulum.urdf", f64_only, avx_twins);
}
mod quoted {
    embedyn::robot!("grbda/double_pendulum.urdf", avx_twins = "none");
}
mod unknown {
    embedyn::robot!("grbda/double_pendulum.urdf", avx_twins = some);
}
fn main() {}
