// The names of tests/data/hostile_names.urdf as the file means them (XML entities resolved), written
// independently of the loader. Included by tests/hostile_names.rs (the macro route) and
// cli/tests/edges.rs (the command line's routes), so both check the same list.

pub const JOINTS: [&str; 12] = [
    "q\"uote",
    "back\\slash",
    "new\nline\rbuild = \"evil.rs\"",
    "*/ compile_error!(\"boom\") /*",
    "fn",
    "self",
    "Self",
    "crate",
    "肩 joint ✓",
    "a-b",
    "a.b",
    "a b",
];
pub const FRAMES: [&str; 13] = [
    "l\\1",
    "</robot>",
    "r#type",
    "_",
    "ロボット",
    "tab\tbed",
    "back`tick|pipe",
    "super",
    "1st",
    "x-y",
    "x.y",
    "x y",
    "merged \"*/\"",
];
