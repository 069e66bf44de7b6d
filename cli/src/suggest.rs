//! "Did you mean …?": the names closest to a name that is not one of the model's (a link in `f_ext` or
//! `--frame`).

/// The longest name (in characters) compared: beyond it a typo is not the likely story, and the edit
/// distance's cost (the product of the lengths) stays small on a hostile input.
const MAX_COMPARED_CHARS: usize = 128;

/// The most names suggested.
const MAX_SUGGESTIONS: usize = 3;

/// Up to three of `candidates` close to `name`, closest first (ties in the candidates' order): equal but for
/// case, or within an edit distance of a quarter of the name's length (at least 1, at most 3).
pub fn close_names<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Vec<String> {
    let wanted: Vec<char> = name.chars().take(MAX_COMPARED_CHARS + 1).collect();
    if wanted.len() > MAX_COMPARED_CHARS {
        return Vec::new();
    }
    let lower: Vec<char> = wanted.iter().flat_map(|c| c.to_lowercase()).collect();
    let limit = (wanted.len() / 4).clamp(1, 3);
    let mut close: Vec<(usize, usize, &str)> = Vec::new();
    for (k, candidate) in candidates.enumerate() {
        let other: Vec<char> = candidate.chars().take(MAX_COMPARED_CHARS + 1).collect();
        if other.len() > MAX_COMPARED_CHARS || other.len().abs_diff(wanted.len()) > limit {
            continue;
        }
        let other_lower: Vec<char> = other.iter().flat_map(|c| c.to_lowercase()).collect();
        let distance = if other_lower == lower {
            0
        } else {
            edit_distance(&lower, &other_lower)
        };
        if distance <= limit {
            close.push((distance, k, candidate));
        }
    }
    close.sort_unstable_by_key(|&(d, k, _)| (d, k));
    close
        .into_iter()
        .take(MAX_SUGGESTIONS)
        .map(|(_, _, c)| c.to_string())
        .collect()
}

/// Levenshtein distance.
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut previous: Vec<usize> = (0..=b.len()).collect();
    let mut current = vec![0; b.len() + 1];
    for (i, ca) in a.iter().enumerate() {
        current[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitution = previous[j] + usize::from(ca != cb);
            current[j + 1] = substitution.min(previous[j + 1] + 1).min(current[j] + 1);
        }
        std::mem::swap(&mut previous, &mut current);
    }
    previous[b.len()]
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
        assert_eq!(
            close_names("lf_foot", links.into_iter()),
            ["LF_FOOT", "RF_FOOT", "LH_FOOT"]
        );
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
