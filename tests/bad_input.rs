//! Every bad input of docs/model-format.md gives an error naming the file, the element and the line; nothing
//! panics. Unusual-but-valid data loads with a warning. Fixtures: tests/data/bad/README.md.

use crate::common;

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
    limit_reversed,
    "limit_reversed.urdf",
    [
        ":38:",
        "joint \"joint2\" <limit>",
        "`lower` (1) is above `upper` (-1)"
    ]
);
bad!(
    limit_infinite,
    "limit_infinite.urdf",
    [
        ":38:",
        "joint \"joint2\" <limit>",
        "`upper=\"inf\"` is not a finite number"
    ]
);
bad!(
    limit_nan_effort,
    "limit_nan_effort.urdf",
    [
        ":38:",
        "joint \"joint2\" <limit>",
        "`effort=\"nan\"` is not a finite number"
    ]
);
bad!(
    limit_negative_velocity,
    "limit_negative_velocity.urdf",
    [
        ":38:",
        "joint \"joint2\" <limit>",
        "`velocity` is -5e0; it must be ≥ 0"
    ]
);
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

/// `--floating` names the root's joint `root_joint`; a file that already has a joint of that name is an
/// error (joints are matched to coordinates by name; it once gave two joints called `root_joint`).
#[test]
fn floating_option_on_a_file_with_a_joint_named_root_joint() {
    let text = r#"<robot name="r">
  <link name="base"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="root_joint" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/></joint>
</robot>"#;
    let loaded = embedyn::codegen::parse_urdf(text, "r.urdf".as_ref()).unwrap();
    assert_eq!(
        loaded.model::<f64>(&ModelOptions::default()).unwrap().nv(),
        1
    );
    let err = loaded
        .model::<f64>(&ModelOptions {
            floating: true,
            ..Default::default()
        })
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("r.urdf:4") && err.contains("already has a joint of that name"),
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

/// Armature is read from `<dynamics armature>` and from transmissions' rotor inertias times their
/// ratio squared (Drake's gear ratio, else `<mechanicalReduction>`, else 1), without a warning.
#[test]
fn armature_is_read_from_dynamics_and_transmissions() {
    let loaded = load(&repo_path("tests/data/armature.urdf")).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let model = loaded.model::<f64>(&ModelOptions::default()).unwrap();
    let armature: Vec<(&str, f64)> = model
        .joints
        .iter()
        .map(|j| (j.name.as_str(), j.armature))
        .collect();
    let expected = [("j1", 100.0 * 2e-4), ("j2", 0.5 + 9.0 * 1e-4), ("j3", 0.1)];
    for ((name, got), (want_name, want)) in armature.iter().zip(expected) {
        assert_eq!(*name, want_name);
        assert!(
            (got - want).abs() <= 1e-15 * want,
            "{name}: {got} vs {want}"
        );
    }
}

/// A negative armature or rotor inertia, a ratio that is not a number, and a rotor on a joint the model
/// lacks are errors at their lines.
#[test]
fn bad_armature_is_an_error_at_its_line() {
    let head = r#"<robot name="r" xmlns:drake="http://drake.mit.edu"><link name="base"/><link name="l"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j" type="revolute"><parent link="base"/><child link="l"/>"#;
    let cases = [
        (r#"<dynamics armature="-1"/></joint>"#, "`armature` is -1e0; it must be ≥ 0"),
        (
            "</joint>\n<transmission name=\"t\"><joint name=\"j\"/><actuator name=\"m\"><drake:rotor_inertia value=\"1e-4\"/><mechanicalReduction>fifty</mechanicalReduction></actuator></transmission>",
            "<mechanicalReduction> holds \"fifty\"",
        ),
        (
            "</joint>\n<transmission name=\"t\"><joint name=\"k\"/><actuator name=\"m\"><drake:rotor_inertia value=\"1e-4\"/></actuator></transmission>",
            "joint \"k\", which the model does not have",
        ),
    ];
    for (tail, message) in cases {
        let text = format!("{head}{tail}</robot>");
        let e = embedyn::codegen::parse_urdf(&text, "r.urdf".as_ref())
            .unwrap_err()
            .to_string();
        assert!(e.contains(message) && e.contains("r.urdf:"), "{e}");
    }
}

/// A rotor on a joint the reader left out for a problem of its own adds no second error (as for mimic
/// targets): the joint's problem is the one reported.
#[test]
fn a_transmission_on_a_joint_left_out_is_no_further_problem() {
    let text = r#"<robot name="r" xmlns:drake="http://drake.mit.edu"><link name="base"/><link name="l"/>
<joint name="j" type="hinge"><parent link="base"/><child link="l"/></joint>
<transmission name="t"><joint name="j"/><actuator name="m"><drake:rotor_inertia value="1e-4"/></actuator></transmission></robot>"#;
    let e = embedyn::codegen::parse_urdf(text, "r.urdf".as_ref()).unwrap_err();
    assert!(e.also.is_empty(), "{e}");
    assert!(
        e.to_string().contains("unknown joint type \"hinge\""),
        "{e}"
    );
}

/// One warning at several elements is reported once, at the first, naming the others (talos_reduced
/// printed twelve identical `<mimic>` lines).
#[test]
fn repeated_warnings_fold_into_one() {
    let mut text = String::from(r#"<robot name="r"><link name="base"/>"#);
    for k in 0..8 {
        text += &format!(
            r#"<link name="l{k}"/><joint name="g{k}" type="fixed"><parent link="base"/><child link="l{k}"/><mimic joint="j"/></joint>"#
        );
    }
    text += r#"<link name="m"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
<joint name="j" type="revolute"><parent link="base"/><child link="m"/></joint></robot>"#;
    let loaded = embedyn::codegen::parse_urdf(&text, "r.urdf".as_ref()).unwrap();
    let w: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("joint \"g0\"")
            && w[0].contains("nothing to drive")
            && w[0].contains("(the same for joint \"g1\", joint \"g2\", joint \"g3\", joint \"g4\", joint \"g5\" and 2 more)"),
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

/// The bundled models' joints carry `<dynamics damping friction>`, which embedyn ignores: one warning
/// each, naming the joints; nothing else.
#[test]
fn bundled_models_load_with_only_the_damping_warning() {
    for (m, line, joints) in [
        ("models/arm7.urdf", 44, "5 joint(s) (\"joint1\", \"joint2\", \"joint3\", \"joint4\", \"joint6\")"),
        ("models/humanoid34.urdf", 69, "9 joint(s) (\"l_hip_pitch\", \"l_knee\", \"r_hip_pitch\", \"r_knee\", \"waist_pitch\" and 4 more)"),
        ("models/quadruped.urdf", 55, "12 joint(s)"),
    ] {
        let w: Vec<String> = load(&repo_path(m))
            .unwrap()
            .warnings
            .iter()
            .map(|w| w.to_string())
            .collect();
        assert_eq!(w.len(), 1, "{m}: {w:?}");
        assert!(
            w[0].contains("<dynamics damping/friction> of ") && w[0].contains(joints),
            "{m}: {w:?}"
        );
        assert!(w[0].contains(&format!("{m}:{line}: joint ")), "{m}: {w:?}");
    }
}

/// A tensor that is not positive semi-definite loads with a warning (public files carry them and
/// Pinocchio loads them; docs/model-format.md); the dynamics fail later, with the joint named, only where an
/// articulated inertia is then not positive.
#[test]
fn inertia_not_psd_loads_with_a_warning() {
    let w = warnings_of("inertia_not_psd.urdf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("inertia_not_psd.urdf:23: link \"link2\" <inertial> <inertia>")
            && w[0].contains("not positive semi-definite")
            && w[0].contains("smallest eigenvalue -4.000e0"),
        "{w:?}"
    );
}

/// Off by rounding at the scale of the link's inertia about its frame (icub's head: zeros and 2.4e-35 for
/// a 1.3 kg link 11 cm from its frame), an inertia loads without a word.
#[test]
fn inertia_off_by_rounding_loads_without_a_warning() {
    let w = warnings_of("inertia_rounding.urdf");
    assert!(w.is_empty(), "{w:?}");
}

/// `<dynamics damping friction>` are ignored with one warning per file that names the joints (zeros,
/// which change nothing, pass silently).
#[test]
fn joint_damping_and_friction_are_ignored_with_one_warning() {
    let w = warnings_of("joint_damping.urdf");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("joint_damping.urdf:15: joint \"j1\" <dynamics>")
            && w[0].contains(
                "of 7 joint(s) (\"j1\", \"j2\", \"j3\", \"j4\", \"j5\" and 2 more) ignored"
            )
            && !w[0].contains("\"j0\""),
        "{w:?}"
    );
}

/// 20,000 nested elements used to overflow the XML parser's stack (an abort); the nesting is checked
/// before parsing, with the line where the limit is passed. Run on a thread with a small stack.
#[test]
fn deeply_nested_elements_are_refused_before_parsing() {
    let depth = 20_000;
    let text = format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"deep\">\n  <link name=\"base\"/>\n{}{}</robot>\n",
        "<a>\n".repeat(depth),
        "</a>".repeat(depth)
    );
    let err = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || {
            embedyn::codegen::parse_urdf(&text, "deep.urdf".as_ref())
                .map(|_| ())
                .unwrap_err()
                .to_string()
        })
        .unwrap()
        .join()
        .unwrap();
    // The robot element is at depth 1, so the 256th <a> (line 4 + 255) is element 257.
    assert!(
        err.starts_with("deep.urdf:259: XML: elements are nested more than 256 deep"),
        "{err}"
    );
}

/// 200,000 attributes on one element (a 2.3 MB file) took the XML parser a minute (its duplicate check
/// is quadratic in an element's attributes; attacker's trial): more than 1,000 are refused before
/// parsing, with the element's line.
#[test]
fn an_element_with_too_many_attributes_is_refused_before_parsing() {
    let attributes: String = (0..200_000).map(|k| format!(" a{k}=\"1\"")).collect();
    let text = format!(
        "<robot name=\"r\">\n  <link name=\"base\"/>\n  <link name=\"arm\"/>\n  <joint name=\"j\" type=\"revolute\">\n    <parent link=\"base\"/><child link=\"arm\"/>\n    <axis xyz=\"0 0 1\"{attributes}/>\n  </joint>\n</robot>\n"
    );
    let err = embedyn::codegen::parse_urdf(&text, "many.urdf".as_ref())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("many.urdf:6: XML: an element has more than 1000 attributes"),
        "{err}"
    );
    // Up to the limit, a model loads (the extra attributes are ignored, as unknown ones are).
    let attributes: String = (0..998).map(|k| format!(" a{k}=\"1\"")).collect();
    let text = text.replace(
        &text[text.find(" a0=").unwrap()..text.find("/>\n  </joint>").unwrap()],
        &attributes,
    );
    let loaded = embedyn::codegen::parse_urdf(&text, "many.urdf".as_ref());
    assert!(loaded.is_ok(), "{:?}", loaded.err().map(|e| e.to_string()));
}

/// Line numbers come from an index built once: a 20,000-link chain (15 MB) loads in time linear in its
/// size (before, every element's line rescanned the file: 61 s here), and the line of an element near the
/// end is exact.
#[test]
fn a_large_file_loads_with_exact_lines() {
    let n = 20_000;
    let mut text =
        String::from("<?xml version=\"1.0\"?>\n<robot name=\"chain\">\n<link name=\"l0\"/>\n");
    for i in 1..=n {
        text += &format!(
            "<link name=\"l{i}\">\n  <inertial>\n    <mass value=\"1\"/>\n    <inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/>\n  </inertial>\n  <visual><geometry><box size=\"0.1 0.1 0.1\"/></geometry></visual>\n</link>\n<joint name=\"j{i}\" type=\"revolute\">\n  <parent link=\"l{}\"/><child link=\"l{i}\"/>\n  <origin xyz=\"0 0 0.1\"/><axis xyz=\"0 1 0\"/>\n</joint>\n",
            i - 1
        );
    }
    // One more joint whose child already has a parent: an error at its line, the file's last but one.
    text += "<joint name=\"extra\" type=\"fixed\"><parent link=\"l0\"/><child link=\"l7\"/></joint>\n</robot>\n";
    let last_line = 3 + 11 * n + 1;
    let err = embedyn::codegen::parse_urdf(&text, "chain.urdf".as_ref())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(&format!("chain.urdf:{last_line}: joint \"extra\"")),
        "{err}"
    );
}

/// GRBDA's own URDF+ files load unchanged (docs/model-format.md), with the groups and independent coordinates
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

bad!(
    duplicate_coupling_name,
    "duplicate_coupling_name.urdf",
    [
        ":12:",
        "coupling \"gear\"",
        "coupling \"gear\" at line 11",
        "own name"
    ]
);
bad!(
    coupling_named_like_loop,
    "coupling_named_like_loop.urdf",
    [":14:", "coupling \"drive\"", "loop \"drive\" at line 11"]
);
bad!(
    coupling_named_like_mimic,
    "coupling_named_like_mimic.urdf",
    [
        ":10:",
        "coupling \"finger2\"",
        "the <mimic> of joint \"finger2\" at line 8"
    ]
);
bad!(
    coupling_without_name,
    "coupling_without_name.urdf",
    [":11:", "<coupling>", "missing attribute `name`"]
);
bad!(
    inertia_overflow,
    "inertia_overflow.urdf",
    [
        ":6:",
        "link \"link2\" <inertial>",
        "overflows f64",
        "mass 1e308"
    ]
);
bad!(
    inertia_overflow_far,
    "inertia_overflow_far.urdf",
    [
        ":6:",
        "link \"link2\" <inertial>",
        "centre of mass 1e200 m from the frame"
    ]
);
bad!(
    inertia_overflow_merged,
    "inertia_overflow_merged.urdf",
    [
        ":7:",
        "link \"link2\" <inertial>",
        "fixed to (link \"link1\") overflows f64"
    ]
);
bad!(
    inertia_overflow_combined,
    "inertia_overflow_combined.urdf",
    [
        ":7:",
        "link \"link2\"",
        "joint `joint1`",
        "overflow",
        "largest is body `link2`'s"
    ]
);

/// A `<mimic>` whose multiplier is near the largest f64 loads without a panic (an attacker's trial: the
/// grouping's Newton steps from its start configurations overflowed the coordinates to ±inf and the
/// forward kinematics after them refused with a panic, `sizes match`). The mimic is a constraint like
/// any other: three independent coordinates of four.
#[test]
fn a_mimic_multiplier_near_the_largest_f64_loads() {
    let link = |name: &str| {
        format!(
            r#"<link name="{name}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"#
        )
    };
    let joint = |name: &str, parent: &str, child: &str, extra: &str| {
        format!(
            r#"<joint name="{name}" type="revolute"><origin xyz="0.2 0.01 0" rpy="0.1 0.2 0.3"/><parent link="{parent}"/><child link="{child}"/><axis xyz="0 1 0"/>{extra}</joint>"#
        )
    };
    let text = format!(
        r#"<robot name="m"><link name="base"/>{}{}{}{}{}{}{}{}</robot>"#,
        link("l1"),
        link("l2"),
        link("l3"),
        link("l4"),
        joint("d", "base", "l1", ""),
        joint("e", "l1", "l2", ""),
        joint("f", "l2", "l3", r#"<mimic joint="d" multiplier="1e308"/>"#),
        joint("g", "l3", "l4", ""),
    );
    let model = std::panic::catch_unwind(|| {
        embedyn::codegen::parse_urdf(&text, std::path::Path::new("m.urdf"))
            .and_then(|l| l.model::<f64>(&ModelOptions::default()))
    })
    .expect("loading panicked")
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((model.nv(), model.independent_nv()), (4, 3));
}

/// A `<mimic>` offset too large for f32 is reported with the sign the file wrote (an attacker's trial:
/// `offset="1e39"` was reported as −1e39, the constraint's own constant).
#[test]
fn a_mimic_offset_too_large_for_f32_is_reported_as_written() {
    let link = |name: &str| {
        format!(
            r#"<link name="{name}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"#
        )
    };
    let text = format!(
        r#"<robot name="m"><link name="base"/>{}{}<joint name="d" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/></joint><joint name="f" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/><mimic joint="d" offset="1e39"/></joint></robot>"#,
        link("l1"),
        link("l2"),
    );
    let loaded = embedyn::codegen::parse_urdf(&text, std::path::Path::new("m.urdf")).unwrap();
    assert!(loaded.model::<f64>(&ModelOptions::default()).is_ok());
    let e = loaded
        .model::<f32>(&ModelOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("offset 1e39") && e.contains("too large for f32"),
        "{e}"
    );
}
