//! Every bad input of CONTRACT §1 gives an error naming the file, the element and the line; nothing
//! panics. Unusual-but-valid data loads with a warning. Fixtures: tests/data/bad/README.md.

mod common;

use common::repo_path;
use embedyn::{load, ModelOptions};

/// Loads and builds the f64 model, returning the error message.
fn error_of(file: &str, floating: bool) -> String {
    let path = repo_path(&format!("tests/data/bad/{file}"));
    let result = std::panic::catch_unwind(|| {
        load(&path).and_then(|l| {
            l.model::<f64>(&ModelOptions {
                floating,
                ..Default::default()
            })
            .map(|_| ())
        })
    })
    .unwrap_or_else(|_| panic!("{file}: loading panicked"));
    match result {
        Ok(()) => panic!("{file}: loaded, but it should have been rejected"),
        Err(e) => e.to_string(),
    }
}

fn assert_names(file: &str, msg: &str, needles: &[&str]) {
    assert!(
        msg.contains(file),
        "{file}: message does not name the file: {msg}"
    );
    for n in needles {
        assert!(
            msg.contains(n),
            "{file}: message does not mention `{n}`: {msg}"
        );
    }
}

macro_rules! bad {
    ($test:ident, $file:literal, [$($needle:literal),*]) => {
        #[test]
        fn $test() {
            let msg = error_of($file, false);
            assert_names($file, &msg, &[$($needle),*]);
        }
    };
}

bad!(malformed_xml, "malformed.urdf", [":17:", "malformed XML"]);
bad!(
    unknown_joint_type,
    "unknown_joint_type.urdf",
    [":33:", "joint \"joint2\"", "hinge"]
);
bad!(
    planar_joint,
    "planar_joint.urdf",
    [":33:", "joint \"joint2\"", "planar"]
);
bad!(
    missing_child_link,
    "missing_child_link.urdf",
    [":29:", "joint \"joint2\" <child>", "link2"]
);
bad!(
    missing_parent_link,
    "missing_parent_link.urdf",
    [":35:", "joint \"joint2\" <parent>", "lnk1"]
);
bad!(
    zero_axis,
    "zero_axis.urdf",
    [":37:", "joint \"joint2\" <axis>", "zero"]
);
bad!(
    negative_mass,
    "negative_mass.urdf",
    [":22:", "link \"link2\" <inertial> <mass>", "negative mass"]
);
bad!(
    nan_value,
    "nan_value.urdf",
    [":34:", "joint \"joint2\" <origin>", "not finite"]
);
bad!(
    infinite_value,
    "infinite_value.urdf",
    [
        ":23:",
        "link \"link2\" <inertial> <inertia>",
        "ixx",
        "not a finite number"
    ]
);
bad!(
    inertia_not_psd,
    "inertia_not_psd.urdf",
    [
        ":23:",
        "link \"link2\" <inertial> <inertia>",
        "not positive semi-definite"
    ]
);
bad!(cycle, "cycle.urdf", ["cycle"]);
bad!(
    two_roots,
    "two_roots.urdf",
    [":19:", "base", "orphan", "root"]
);
bad!(
    massless_leaf,
    "massless_leaf.urdf",
    [":27:", "joint \"joint2\"", "no inertia about its axis"]
);
bad!(
    duplicate_link,
    "duplicate_link.urdf",
    [":19:", "link \"link1\"", "already defined"]
);
bad!(
    duplicate_joint,
    "duplicate_joint.urdf",
    [":33:", "joint \"joint1\"", "already defined"]
);
bad!(
    two_parents,
    "two_parents.urdf",
    [":40:", "joint \"joint3\"", "link2", "joint2"]
);
bad!(
    missing_axis_value,
    "missing_axis_value.urdf",
    [":37:", "joint \"joint2\" <axis>", "three numbers"]
);
bad!(
    floating_not_root,
    "floating_not_root.urdf",
    [":33:", "joint \"joint2\"", "floating"]
);

#[test]
fn unreadable_file() {
    let msg = error_of("does_not_exist.urdf", false);
    assert_names("does_not_exist.urdf", &msg, &["cannot read"]);
}

#[test]
fn floating_option_on_a_file_with_a_floating_joint() {
    let path = repo_path("models/quadruped.urdf");
    let err = load(&path)
        .unwrap()
        .model::<f64>(&ModelOptions {
            floating: true,
            ..Default::default()
        })
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("quadruped.urdf") && err.contains("already has a floating joint"),
        "{err}"
    );
}

fn warnings_of(file: &str) -> Vec<String> {
    let loaded =
        load(&repo_path(&format!("tests/data/bad/{file}"))).unwrap_or_else(|e| panic!("{e}"));
    loaded
        .model::<f64>(&ModelOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    loaded.warnings.iter().map(|w| w.to_string()).collect()
}

#[test]
fn triangle_inequality_violation_loads_with_a_warning() {
    let w = warnings_of("triangle_violation.urdf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("link \"link2\"")
            && w[0].contains("triangle inequality")
            && w[0].contains(":23:"),
        "{w:?}"
    );
}

#[test]
fn massless_rotor_loads_with_a_warning() {
    let w = warnings_of("massless_rotor.urdf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("link \"link2\"") && w[0].contains("massless"),
        "{w:?}"
    );
}

#[test]
fn bundled_models_load_without_warnings() {
    for m in [
        "models/arm7.urdf",
        "models/humanoid34.urdf",
        "models/quadruped.urdf",
    ] {
        let loaded = load(&repo_path(m)).unwrap();
        assert!(loaded.warnings.is_empty(), "{m}: {:?}", loaded.warnings);
    }
}

/// GRBDA's own URDF+ files load unchanged (CONTRACT §1), with the groups and independent coordinates
/// their authors declared; `independent` on joints outside any loop or coupling is ignored.
#[test]
fn grbda_files_load_unchanged() {
    // (file, nv, independent nv, groups)
    let expectations = [
        ("double_pendulum.urdf", 2, 2, 0),
        ("four_bar.urdf", 3, 1, 1),
        ("planar_leg_linkage.urdf", 4, 2, 1),
        ("six_bar.urdf", 5, 3, 1),
        ("revolute_rotor_chain.urdf", 6, 3, 3),
        ("mit_humanoid_leg.urdf", 10, 5, 4),
        ("mit_humanoid.urdf", 42, 24, 16),
        ("mini_cheetah.urdf", 30, 18, 12),
        ("jvrc1_humanoid.urdf", 63, 38, 25),
        ("tello_legs.urdf", 20, 20, 0),
        ("tello_humanoid.urdf", 42, 42, 0),
    ];
    for (file, nv, independent_nv, groups) in expectations {
        let path = repo_path(&format!("tests/data/grbda/{file}"));
        let model = load(&path)
            .and_then(|l| l.model::<f64>(&ModelOptions::default()))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (model.nv(), model.independent_nv(), model.groups.len()),
            (nv, independent_nv, groups),
            "{file}"
        );
    }
}

bad!(
    loop_missing_link,
    "loop_missing_link.urdf",
    [
        ":60:",
        "loop \"loop1\" <successor>",
        "link9",
        "does not exist"
    ]
);
bad!(
    loop_never_meets,
    "loop_never_meets.urdf",
    [":56:", "loop \"loop1\"", "never meet"]
);
bad!(
    loop_dependent_mismatch,
    "loop_dependent_mismatch.urdf",
    [
        ":56:",
        "loop \"loop1\"",
        "1 joint(s) are declared dependent",
        "remove 2"
    ]
);
bad!(
    coupling_missing_link,
    "coupling_missing_link.urdf",
    [":9:", "coupling \"gear1\" <predecessor>", "lnk1"]
);
bad!(
    mimic_missing_joint,
    "mimic_missing_joint.urdf",
    [":9:", "joint \"finger2\" <mimic>", "finger_1"]
);

#[test]
fn mimic_on_a_fixed_joint_is_ignored_with_a_warning() {
    let w = warnings_of("mimic_on_fixed.urdf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("joint \"finger_fixed\"") && w[0].contains("ignored") && w[0].contains(":8:"),
        "{w:?}"
    );
}
