//! Model strings (robot, link, joint and file names) are data, never code (docs/model-format.md, "Names are data").
//!
//! Everything generated from a name goes through this module: the one sanitizer that derives Rust
//! identifiers and crate names, and the escaping of names shown in doc comments and Markdown. (TOML goes
//! through the `toml` serializer and Rust string literals through `quote`, which escape for themselves.)

use sha2::{Digest, Sha256};

/// Identifiers longer than this are shortened (and made distinct by the hash suffix): a crate name
/// becomes a folder name in the cache, and file systems limit those to 255 bytes.
const MAX_IDENTIFIER: usize = 48;

/// Hex digits of the suffix that keeps sanitized names distinct.
const SUFFIX_DIGITS: usize = 8;

/// Words Rust reserves (strict, reserved and edition-dependent keywords); the sanitizer never returns
/// one (lowercase only: its results are lowercase).
const KEYWORDS: &[&str] = &[
    "abstract", "as", "async", "await", "become", "box", "break", "const", "continue", "crate",
    "do", "dyn", "else", "enum", "extern", "false", "final", "fn", "for", "gen", "if", "impl",
    "in", "let", "loop", "macro", "match", "mod", "move", "mut", "override", "priv", "pub", "ref",
    "return", "self", "static", "struct", "super", "trait", "true", "try", "type", "typeof",
    "union", "unsafe", "unsized", "use", "virtual", "where", "while", "yield",
];

/// The sanitizer: a snake_case Rust identifier derived from `name`, starting with `prefix` where the
/// name does not start with a letter.
///
/// The result is lowercase ASCII letters, digits and single underscores, never a keyword, never empty,
/// never starting with a digit or an underscore, at most about 48 characters (`MAX_IDENTIFIER`). A name that
/// is already such an identifier (up to ASCII case) is kept as it is; any other name is transliterated
/// (every other character becomes `_`) and gets `_` and 8 hex digits of the SHA-256 of the original name,
/// so that names which sanitize alike (`a-b`, `a.b`, `a b`) still give distinct identifiers. Results of
/// the two kinds cannot meet: a kept name never ends in `_` and 8 hex digits (such names are suffixed
/// too). Names that differ only in ASCII case give the same identifier (cargo's registry also treats
/// crate names case-insensitively).
pub fn identifier(name: &str, prefix: &str) -> String {
    let mut base = String::with_capacity(name.len());
    for c in name.chars() {
        let c = if c.is_ascii_alphanumeric() {
            c.to_ascii_lowercase()
        } else {
            '_'
        };
        // Single underscores, none leading: rustc's snake_case lint warns on `__` inside a name.
        if c == '_' && (base.is_empty() || base.ends_with('_')) {
            continue;
        }
        base.push(c);
    }
    while base.ends_with('_') {
        base.pop();
    }
    let kept_as_is = base == name.to_ascii_lowercase()
        && !KEYWORDS.contains(&base.as_str())
        && !ends_in_suffix(&base)
        && base.len() <= MAX_IDENTIFIER
        && base.starts_with(|c: char| c.is_ascii_alphabetic());
    if kept_as_is {
        return base;
    }
    base.truncate(MAX_IDENTIFIER);
    while base.ends_with('_') {
        base.pop();
    }
    if !base.starts_with(|c: char| c.is_ascii_alphabetic()) {
        base = if base.is_empty() {
            prefix.to_string()
        } else {
            format!("{prefix}_{base}")
        };
    }
    let digest = Sha256::digest(name.as_bytes());
    let hex: String = digest
        .iter()
        .flat_map(|b| [b >> 4, b & 0xf])
        .take(SUFFIX_DIGITS)
        .map(|d| char::from_digit(u32::from(d), 16).unwrap_or('0'))
        .collect();
    format!("{base}_{hex}")
}

/// Whether `s` ends in `_` and [`SUFFIX_DIGITS`] lowercase hex digits (the shape of the suffix).
fn ends_in_suffix(s: &str) -> bool {
    let b = s.as_bytes();
    b.len() > SUFFIX_DIGITS
        && b[b.len() - SUFFIX_DIGITS - 1] == b'_'
        && b[b.len() - SUFFIX_DIGITS..]
            .iter()
            .all(|c| c.is_ascii_digit() || (b'a'..=b'f').contains(c))
}

/// Constant names for a list of model names (joint or link names, in the model's order): each name's
/// [`identifier`] in SCREAMING_SNAKE_CASE (`lf_foot` → `LF_FOOT`, `肩 joint ✓` → `JOINT_…_3A9F…`, with
/// `prefix` where the name does not start with a letter). Names that give the same constant (they differ
/// only in ASCII case: `Knee` and `knee`) are told apart deterministically: the first keeps it, each later
/// one gets the smallest `_2`, `_3`, … that no other name of the list takes.
pub fn constants(names: &[&str], prefix: &str) -> Vec<String> {
    let bases: Vec<String> = names
        .iter()
        .map(|n| identifier(n, prefix).to_ascii_uppercase())
        .collect();
    let all: std::collections::HashSet<&str> = bases.iter().map(String::as_str).collect();
    let mut taken = std::collections::HashSet::new();
    let mut out = Vec::with_capacity(names.len());
    for base in &bases {
        let mut name = base.clone();
        let mut n = 2;
        while !taken.insert(name.clone()) {
            loop {
                name = format!("{base}_{n}");
                n += 1;
                if !all.contains(name.as_str()) {
                    break;
                }
            }
        }
        out.push(name);
    }
    out
}

/// The names of `candidates` closest to `name`, at most three (for "did you mean"): those at the
/// smallest edit distance (in characters, ignoring ASCII case) found, if it is at most a third of the
/// name's length (at least 1); ties in the candidates' order.
///
/// Names longer than 128 characters are not compared (a typo is not the likely story there, and the edit
/// distance's cost, the product of the lengths, stays small on a hostile input).
pub fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Vec<&'a str> {
    const MAX_COMPARED_CHARS: usize = 128;
    let lower = |s: &str| -> Vec<char> {
        s.chars()
            .take(MAX_COMPARED_CHARS + 1)
            .map(|c| c.to_ascii_lowercase())
            .collect()
    };
    let target = lower(name);
    if target.len() > MAX_COMPARED_CHARS {
        return Vec::new();
    }
    let limit = (target.len() / 3).max(1);
    let mut close: Vec<(usize, usize, &str)> = candidates
        .into_iter()
        .enumerate()
        .map(|(i, c)| (lower(c), i, c))
        .filter(|(other, _, _)| {
            other.len() <= MAX_COMPARED_CHARS && other.len().abs_diff(target.len()) <= limit
        })
        .map(|(other, i, c)| (edit_distance(&target, &other), i, c))
        .filter(|&(d, _, _)| d <= limit)
        .collect();
    close.sort_unstable();
    let nearest = close.first().map_or(0, |&(d, _, _)| d);
    close
        .into_iter()
        .take_while(|&(d, _, _)| d == nearest)
        .take(3)
        .map(|(_, _, c)| c)
        .collect()
}

/// Levenshtein distance between two strings of characters.
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// The crate name of a robot's generated code: its [`identifier`] followed by `_dynamics` (a valid
/// package name, library name and Rust path segment, in snake_case).
pub fn crate_name(robot: &str) -> String {
    format!("{}_dynamics", identifier(robot, "robot"))
}

/// Why `name` cannot be a generated crate's package name (`embedyn generate --name`), if it cannot, as a
/// message naming it: it must be an ASCII letter and then letters, digits, `_` or `-` (at most 64), and its
/// library name (`-` as `_`) a Rust identifier that is not a keyword nor the name of a crate every Rust
/// program knows (`core`, `std`, `alloc`, `proc_macro`, `test`), since the user's code names the crate by it.
pub fn check_crate_name(name: &str) -> Result<(), String> {
    crate_name_problem(name).map_or(Ok(()), |problem| {
        Err(format!(
            "{}: {problem} (a crate name: an ASCII letter, then letters, digits, `_` or `-`)",
            code_span(name)
        ))
    })
}

/// What is wrong with `name` as a crate name (see [`check_crate_name`]).
fn crate_name_problem(name: &str) -> Option<String> {
    let mut chars = name.chars();
    if !chars.next().is_some_and(|c| c.is_ascii_alphabetic()) {
        return Some("must start with an ASCII letter".into());
    }
    if let Some(c) = chars.find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '-')) {
        return Some(format!(
            "{} is not a letter, digit, `_` or `-` of ASCII",
            fenced(&shown(&c.to_string()))
        ));
    }
    if name.len() > 64 {
        return Some(format!("is {} characters long (at most 64)", name.len()));
    }
    let library = name.replace('-', "_");
    if ["core", "std", "alloc", "proc_macro", "test"].contains(&library.as_str())
        || syn::parse_str::<syn::Ident>(&library).is_err()
    {
        return Some(format!(
            "`{library}` is a Rust keyword or a built-in crate's name"
        ));
    }
    None
}

/// A name as a reader should see it in generated docs and Markdown: control characters, quotes and
/// backslashes shown as Rust escapes (`\n`, `\"`, `\u{7}`), so nothing in it can end a comment line or
/// look like another name; every other character (letters of any script) as it is.
pub fn shown(name: &str) -> String {
    name.escape_debug().to_string()
}

/// A Markdown code span of a name ([`shown`]); safe in doc comments and README text.
pub fn code_span(name: &str) -> String {
    fenced(&shown(name))
}

/// `text` as a Markdown code span as it is (escape it first where it may hold control characters): a
/// backtick inside cannot end the span early.
pub fn fenced(text: &str) -> String {
    // The fence is one backtick longer than the longest run of backticks inside.
    let mut longest = 0;
    let mut run = 0;
    for c in text.chars() {
        run = if c == '`' { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    let fence = "`".repeat(longest + 1);
    // A space keeps a backtick at either end from joining the fence (Markdown strips one space each side).
    let pad = if text.starts_with('`') || text.ends_with('`') || text.is_empty() {
        " "
    } else {
        ""
    };
    format!("{fence}{pad}{text}{pad}{fence}")
}

/// A name in a Markdown table cell: a [`code_span`] with its pipes escaped (GitHub tables split cells on
/// `|` even inside code spans).
pub fn table_cell(name: &str) -> String {
    code_span(name).replace('|', "\\|")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A backtick inside a name cannot end its code span early (attacker trial, issue 12: an unknown
    /// `f_ext` link named with a backtick broke the error's span).
    #[test]
    fn fenced_spans_hold_backticks() {
        assert_eq!(fenced("foot"), "`foot`");
        assert_eq!(fenced("a`b"), "``a`b``");
        assert_eq!(fenced("`x"), "`` `x ``");
        assert_eq!(code_span("a`b"), fenced("a`b"));
    }

    /// What rustc accepts as a crate name without a warning: ASCII, snake_case, not a keyword.
    fn is_clean_identifier(s: &str) -> bool {
        s.starts_with(|c: char| c.is_ascii_lowercase())
            && s.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && !s.contains("__")
            && !s.ends_with('_')
            && !KEYWORDS.contains(&s)
    }

    #[test]
    fn clean_names_are_kept() {
        for (name, id) in [("arm7", "arm7"), ("UR5", "ur5"), ("left_leg", "left_leg")] {
            assert_eq!(identifier(name, "robot"), id);
        }
        assert_eq!(crate_name("arm7"), "arm7_dynamics");
    }

    #[test]
    fn hostile_names_give_valid_distinct_identifiers() {
        let names = [
            "x\"\nbuild = \"evil.rs\"\n#",
            "a\\b",
            "*/ compile_error!(\"boom\") /*",
            "fn",
            "self",
            "Self",
            "crate",
            "_",
            "",
            "2dof",
            "robot_2dof",
            "ロボット",
            "ロボ",
            "a-b",
            "a.b",
            "a b",
            "a_b",
            "a__b",
            "_a_b_",
            "x_0123abcd",
            &"long".repeat(100),
            &"long".repeat(101),
        ];
        let ids: Vec<String> = names.iter().map(|n| identifier(n, "robot")).collect();
        for (n, id) in names.iter().zip(&ids) {
            assert!(is_clean_identifier(id), "{n:?} -> {id:?}");
            assert!(id.len() <= MAX_IDENTIFIER + 1 + SUFFIX_DIGITS + 6, "{id}");
            assert!(syn::parse_str::<syn::Ident>(id).is_ok(), "{id}");
            assert!(is_clean_identifier(&crate_name(n)));
        }
        for i in 0..ids.len() {
            for k in 0..i {
                assert_ne!(ids[i], ids[k], "{:?} and {:?}", names[i], names[k]);
            }
        }
        // Deterministic.
        assert_eq!(identifier("a.b", "robot"), identifier("a.b", "robot"));
    }

    #[test]
    fn constants_are_screaming_snake_case_and_distinct() {
        let names = [
            "lf_foot",
            "Knee",
            "knee",
            "knee_2",
            "KNEE",
            "fn",
            "Self",
            "self",
            "肩 joint ✓",
            "1st",
            "a-b",
            "a.b",
        ];
        let c = constants(&names, "joint");
        assert_eq!(&c[..5], ["LF_FOOT", "KNEE", "KNEE_3", "KNEE_2", "KNEE_4"]);
        for id in &c {
            assert!(
                id.starts_with(|c: char| c.is_ascii_uppercase())
                    && id
                        .chars()
                        .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
                    && !id.contains("__")
                    && !id.ends_with('_'),
                "{id}"
            );
            assert!(syn::parse_str::<syn::Ident>(id).is_ok(), "{id}");
        }
        for i in 0..c.len() {
            for k in 0..i {
                assert_ne!(c[i], c[k]);
            }
        }
        assert!(c[9].starts_with("JOINT_1ST_"), "{}", c[9]);
        assert_eq!(constants(&names, "joint"), c);
    }

    #[test]
    fn close_names_are_suggested_closest_first() {
        let links = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "base", "trunk"];
        assert_eq!(closest("lf_foot", links), ["LF_FOOT"]);
        assert_eq!(closest("LF_FOT", links), ["LF_FOOT"]);
        assert_eq!(closest("XF_FOOT", links), ["LF_FOOT", "RF_FOOT"]);
        assert_eq!(closest("trunc", links), ["trunk"]);
        assert_eq!(closest("bse", links), ["base"]);
        assert!(closest("elbow", links).is_empty());
        assert!(closest("", links).is_empty());
        assert!(closest(&"x".repeat(100_000), links).is_empty());
    }

    #[test]
    fn shown_names_cannot_break_a_comment_line() {
        for name in ["a\nb", "a\rb", "*/", "`x`", "a|b", "\u{7}", "a\\nb"] {
            let s = code_span(name);
            assert!(
                !s.contains('\n') && !s.contains('\r') && !s.contains('\u{7}'),
                "{s}"
            );
        }
        assert_ne!(shown("a\nb"), shown("a\\nb"));
        assert_eq!(code_span("`x`"), "`` `x` ``");
        assert_eq!(table_cell("a|b"), "`a\\|b`");
        assert_eq!(code_span("ロボット"), "`ロボット`");
    }
}
