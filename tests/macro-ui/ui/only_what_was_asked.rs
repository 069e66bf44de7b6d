// `only(aba)` generates `aba` and nothing else: asking for `rnea` is a compile error.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", f64_only, only(aba));
}
fn main() {
    let mut out = [0.0; robot::NV];
    robot::f64::aba(&[0.1; robot::NQ], &[0.0; robot::NV], &[0.0; robot::NV], &mut out);
    robot::f64::rnea(&[0.1; robot::NQ], &[0.0; robot::NV], &[0.0; robot::NV], &mut out);
}
