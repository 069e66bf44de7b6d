// `f64_only` and `f32_only` together would generate no scalar module at all.
mod robot {
    embedyn::robot!("grbda/double_pendulum.urdf", f64_only, f32_only);
}
fn main() {}
