//! Name patterns, as launch files use them for topics (`record`) and hosts (`links`): `*`
//! matches within one `/`-separated segment, `**` matches anything.

/// Checks one topic's name (not a pattern): segments of letters, digits, '_', '-' and '.'
/// between single slashes, as iceoryx2 takes service names. The launcher's `on` and
/// `caravan-script`'s topics are checked with it.
pub fn check_topic_name(topic: &str) -> Result<(), String> {
    let segment_ok = |seg: &str| {
        !seg.is_empty()
            && seg
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
    };
    if topic.split('/').all(segment_ok) {
        Ok(())
    } else {
        Err(format!(
            "'{topic}' is not a topic name (segments of letters, digits, '_', '-' and '.' \
             between single '/')"
        ))
    }
}

/// Matches topic or host names against a pattern: `*` matches within one `/`-separated
/// segment, `**` matches anything (and `a/**/b` also matches `a/b`).
pub fn glob_match(pattern: &str, text: &str) -> bool {
    glob(pattern.as_bytes(), text.as_bytes())
}

// Plain backtracking: patterns and names are short, so the worst case does not matter.
fn glob(p: &[u8], t: &[u8]) -> bool {
    match p {
        [] => t.is_empty(),
        [b'*', b'*', rest @ ..] => {
            if let [b'/', after @ ..] = rest
                && glob(after, t)
            {
                return true;
            }
            (0..=t.len()).any(|i| glob(rest, &t[i..]))
        }
        [b'*', rest @ ..] => (0..=t.len())
            .take_while(|&i| i == 0 || t[i - 1] != b'/')
            .any(|i| glob(rest, &t[i..])),
        [c, rest @ ..] => t.first() == Some(c) && glob(rest, &t[1..]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn launch_glob_star_stays_in_segment() {
        assert!(glob_match("robot/*/pose_true", "robot/3/pose_true"));
        assert!(!glob_match("robot/*/pose_true", "robot/3/x/pose_true"));
        assert!(glob_match("map", "map"));
        assert!(!glob_match("map", "maps"));
        assert!(glob_match("rpi-*", "rpi-0"));
        assert!(!glob_match("rpi-*", "remote-pc"));
    }

    #[test]
    fn launch_glob_double_star_crosses_segments() {
        assert!(glob_match("robot/**", "robot/3/x/pose"));
        assert!(glob_match("robot/**/pose", "robot/pose"));
        assert!(glob_match("robot/**/pose", "robot/1/2/pose"));
        assert!(glob_match("**", "anything/at/all"));
        assert!(!glob_match("robot/**/pose", "robot/1/posex"));
    }
}
