//! "Did you mean …?" for misspelt keys, hosts and process names.

/// The candidate closest to `word`, if it is close enough to be a plausible typo.
///
/// Edit distance catches transpositions and dropped letters (`rat` → `rate`); Jaro-Winkler
/// catches longer words with a shared prefix (`restart_backof` → `restart_backoff`). A word
/// that is far from every candidate gets no suggestion rather than a misleading one.
pub fn nearest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let lower = word.to_lowercase();
    // Short words tolerate fewer edits: "on" must not suggest "name".
    let max_edits = match word.chars().count() {
        0..=3 => 1,
        4..=7 => 2,
        _ => 3,
    };
    candidates
        .into_iter()
        .filter(|c| *c != word)
        .filter_map(|c| {
            let edits = strsim::damerau_levenshtein(&lower, &c.to_lowercase());
            let similarity = strsim::jaro_winkler(&lower, &c.to_lowercase());
            let close = edits <= max_edits || (similarity >= 0.9 && word.len() > 3);
            close.then_some((edits, c))
        })
        .min_by_key(|(edits, _)| *edits)
        .map(|(_, c)| c)
}

/// `"; did you mean 'x'?"`, or an empty string when nothing is close.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    nearest(word, candidates)
        .map(|c| format!("; did you mean '{c}'?"))
        .unwrap_or_default()
}

/// A hint for an unknown word: the nearest candidate, or else the full list when it is short
/// enough to read.
pub fn hint(word: &str, candidates: &[&str]) -> String {
    let near = did_you_mean(word, candidates.iter().copied());
    if !near.is_empty() || candidates.is_empty() {
        return near;
    }
    if candidates.len() <= 16 {
        format!("; expected one of: {}", candidates.join(", "))
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEYS: &[&str] = &[
        "name",
        "exec",
        "args",
        "rate",
        "on",
        "restart",
        "restart_backoff",
    ];

    #[test]
    fn launch_suggest_close_words() {
        assert_eq!(nearest("rat", KEYS.iter().copied()), Some("rate"));
        assert_eq!(nearest("exce", KEYS.iter().copied()), Some("exec"));
        assert_eq!(nearest("Rate", KEYS.iter().copied()), Some("rate"));
        assert_eq!(
            nearest("restart_backof", KEYS.iter().copied()),
            Some("restart_backoff")
        );
    }

    #[test]
    fn launch_suggest_nothing_for_far_words() {
        assert_eq!(nearest("colour", KEYS.iter().copied()), None);
        assert_eq!(nearest("xyz", KEYS.iter().copied()), None);
        assert_eq!(did_you_mean("xyz", KEYS.iter().copied()), "");
        assert!(hint("xyz", KEYS).contains("expected one of: name, exec"));
    }
}
