//! "Did you mean …?": the names closest to a name that is not one of the model's (a link in `f_ext` or
//! `--frame`).

/// The names of `candidates` closest to `name` (at most three; the generator's rule, so that the command
/// line and `robot!` suggest the same names).
pub fn close_names<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Vec<String> {
    embedyn_codegen::names::closest(name, candidates)
        .into_iter()
        .map(String::from)
        .collect()
}

/// ", did you mean `a`, `b` or `c`?" for the suggestions (shortened, as names are in messages), or nothing.
pub fn did_you_mean(suggestions: &[String]) -> String {
    let shown: Vec<String> = suggestions
        .iter()
        .map(|s| format!("`{}`", embedyn_codegen::shortened(s)))
        .collect();
    match shown.split_last() {
        None => String::new(),
        Some((last, [])) => format!("; did you mean {last}?"),
        Some((last, rest)) => format!("; did you mean {} or {last}?", rest.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_names_are_found_closest_first() {
        let links = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "base", "trunk"];
        assert_eq!(close_names("lf_foot", links.into_iter()), ["LF_FOOT"]);
        assert_eq!(close_names("LF_FOT", links.into_iter()), ["LF_FOOT"]);
        assert_eq!(close_names("bse", links.into_iter()), ["base"]);
        assert!(close_names("gripper", links.into_iter()).is_empty());
        assert!(close_names(&"x".repeat(1000), links.into_iter()).is_empty());
        assert_eq!(did_you_mean(&[]), "");
        assert_eq!(
            did_you_mean(&["a".into(), "b".into()]),
            "; did you mean `a` or `b`?"
        );
    }
}
