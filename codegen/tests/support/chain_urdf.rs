//! A serial chain of `n` revolute bodies as URDF text, for measuring how generation scales with the
//! number of bodies (`cargo run --example chain_urdf`) and for the scale tests. Shared by both through
//! `#[path]`, so the measured model and the tested model are the same file format and numbers.
//!
//! Axes alternate z, y, x (so no two neighbours fold into one rotation), every joint origin has an
//! offset in all three coordinates, and every link a different mass, an offset centre of mass and a full
//! inertia tensor with products of inertia: nothing folds beyond what a real arm's numbers fold.

use std::fmt::Write;

/// The URDF of the chain `chain{n}`: links `link0` (the fixed base) … `link{n}`, joints `joint1` …
/// `joint{n}`.
pub fn chain_urdf(n: usize) -> String {
    let mut s = String::new();
    writeln!(s, "<?xml version=\"1.0\"?>").unwrap();
    writeln!(s, "<robot name=\"chain{n}\">").unwrap();
    writeln!(s, "  <link name=\"link0\"/>").unwrap();
    for i in 1..=n {
        // Deterministic variation in [0, 1) per body, so that no two bodies carry the same numbers.
        let t = ((i * 37) % 101) as f64 / 101.0;
        let mass = 0.5 + 1.5 * t;
        let (ixx, iyy, izz) = (
            mass * (4.0e-3 + 1.0e-3 * t),
            mass * (3.5e-3 + 0.5e-3 * t),
            mass * (1.0e-3 + 0.2e-3 * t),
        );
        // Products well inside the positive-definite region (< 10 % of the smallest moment).
        let (ixy, ixz, iyz) = (1.0e-5 * (1.0 + t), -2.0e-5 * t, 0.5e-5);
        writeln!(s, "  <link name=\"link{i}\">").unwrap();
        writeln!(s, "    <inertial>").unwrap();
        writeln!(
            s,
            "      <origin xyz=\"{:.4} {:.4} {:.4}\" rpy=\"0 0 0\"/>",
            0.01 * t,
            -0.005,
            0.08 + 0.02 * t
        )
        .unwrap();
        writeln!(s, "      <mass value=\"{mass:.6}\"/>").unwrap();
        writeln!(
            s,
            "      <inertia ixx=\"{ixx:.6e}\" ixy=\"{ixy:.6e}\" ixz=\"{ixz:.6e}\" iyy=\"{iyy:.6e}\" iyz=\"{iyz:.6e}\" izz=\"{izz:.6e}\"/>"
        )
        .unwrap();
        writeln!(s, "    </inertial>").unwrap();
        writeln!(s, "  </link>").unwrap();
        let axis = ["0 0 1", "0 1 0", "1 0 0"][(i - 1) % 3];
        writeln!(s, "  <joint name=\"joint{i}\" type=\"revolute\">").unwrap();
        writeln!(s, "    <parent link=\"link{}\"/>", i - 1).unwrap();
        writeln!(s, "    <child link=\"link{i}\"/>").unwrap();
        writeln!(
            s,
            "    <origin xyz=\"{:.4} {:.4} {:.4}\" rpy=\"0 0 0\"/>",
            0.02,
            -0.01 * t,
            0.15 + 0.05 * t
        )
        .unwrap();
        writeln!(s, "    <axis xyz=\"{axis}\"/>").unwrap();
        writeln!(
            s,
            "    <limit lower=\"-3.14\" upper=\"3.14\" effort=\"100\" velocity=\"10\"/>"
        )
        .unwrap();
        writeln!(s, "  </joint>").unwrap();
    }
    writeln!(s, "</robot>").unwrap();
    s
}
