//! Topic patterns: `*` matches one path segment, `**` any number of segments.

pub fn matches(pattern: &str, topic: &str) -> bool {
    let p: Vec<&str> = pattern.split('/').collect();
    let t: Vec<&str> = topic.split('/').collect();
    match_segments(&p, &t)
}

fn match_segments(p: &[&str], t: &[&str]) -> bool {
    match (p.first(), t.first()) {
        (None, None) => true,
        (Some(&"**"), _) => match_segments(&p[1..], t) || (!t.is_empty() && match_segments(p, &t[1..])),
        (Some(ps), Some(ts)) => segment_matches(ps, ts) && match_segments(&p[1..], &t[1..]),
        _ => false,
    }
}

/// `*` inside a segment matches any run of characters within it (`scan*`, `*_true`).
fn segment_matches(pattern: &str, text: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == text,
        Some((head, tail)) => {
            text.starts_with(head)
                && (0..=text.len() - head.len())
                    .any(|i| text.is_char_boundary(head.len() + i) && segment_matches(tail, &text[head.len() + i..]))
        }
    }
}

pub fn matches_any(patterns: &[String], topic: &str) -> bool {
    patterns.iter().any(|p| matches(p, topic))
}

#[cfg(test)]
mod tests {
    use super::matches;

    #[test]
    fn segment_and_deep_wildcards() {
        assert!(matches("robot/*/pose_true", "robot/3/pose_true"));
        assert!(!matches("robot/*/pose_true", "robot/3/odometry"));
        assert!(!matches("robot/*", "robot/3/scan"));
        assert!(matches("robot/**", "robot/3/scan"));
        assert!(matches("**", "map"));
        assert!(matches("demo/*", "demo/ping"));
        assert!(matches("robot/*/pose*", "robot/1/pose_true"));
        assert!(matches("map", "map") && !matches("map", "maps"));
    }
}
