//! Mutation fuzzing of the loaders (launch files, world files, robot descriptions): a valid
//! file, edited a few times at random, the way a hurried user or a broken editor would, with
//! the values that break parsers (0, −1, 1e308, NaN, huge integers, empty and long strings).
//! Seeded, so a failing input is reproduced from its seed; the fuzz tests draw the seeds with
//! proptest, and `PROPTEST_CASES` sets how many.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Numbers and values that exercise limits and type checks.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-300",
    "nan",
    "inf",
    "NaN",
    "18446744073709551616",
    "9223372036854775807",
    "\"\"",
    "\"x\"",
    "[]",
    "{}",
    "true",
    "[1e308, 1e308]",
];

/// Strings that exercise names, paths and durations.
const STRINGS: &[&str] = &[
    "",
    "../../../../etc/passwd",
    "nohost",
    "1e9Hz",
    "1e-30Hz",
    "-5s",
    "2777777777777778h",
    "robot/*/**",
    "é\u{0}",
];

const BYTES: &[char] = &[
    '"', '[', ']', '{', '}', '=', '<', '>', '/', '\n', ',', '.', '-', '\0',
];

/// `text` after 1 to 4 random edits chosen by `seed`.
pub fn mutate(text: &str, seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut text = text.to_string();
    for _ in 0..rng.random_range(1..=4) {
        text = edit(&text, &mut rng);
    }
    text
}

fn edit(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() {
        return "x".into();
    }
    let n = lines.len();
    let at = rng.random_range(0..n);
    match rng.random_range(0..7) {
        0 => replace_token(
            text,
            rng,
            |c| c.is_ascii_digit() || c == '.' || c == '-',
            VALUES,
        ),
        1 => replace_quoted(text, rng),
        2 => {
            lines.remove(at);
            lines.join("\n")
        }
        3 => {
            lines.insert(at, lines[at]);
            lines.join("\n")
        }
        4 => {
            lines.swap(at, rng.random_range(0..n));
            lines.join("\n")
        }
        5 => {
            let mut s = text.to_string();
            let i = boundary(text, rng.random_range(0..=text.len()));
            s.insert(i, BYTES[rng.random_range(0..BYTES.len())]);
            s
        }
        _ => text[..boundary(text, rng.random_range(0..=text.len()))].to_string(),
    }
}

/// The nearest char boundary at or before `i`.
fn boundary(text: &str, mut i: usize) -> usize {
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Replaces a random run of chars matching `is_token` with one of `values`.
fn replace_token(
    text: &str,
    rng: &mut ChaCha8Rng,
    is_token: impl Fn(char) -> bool,
    values: &[&str],
) -> String {
    let starts: Vec<usize> = text
        .char_indices()
        .filter(|&(i, c)| is_token(c) && !text[..i].ends_with(&is_token))
        .map(|(i, _)| i)
        .collect();
    if starts.is_empty() {
        return text.to_string();
    }
    let start = starts[rng.random_range(0..starts.len())];
    let len = text[start..]
        .find(|c: char| !is_token(c))
        .unwrap_or(text.len() - start);
    let value = values[rng.random_range(0..values.len())];
    format!("{}{value}{}", &text[..start], &text[start + len..])
}

/// Replaces the contents of a random double-quoted string.
fn replace_quoted(text: &str, rng: &mut ChaCha8Rng) -> String {
    let quotes: Vec<usize> = text.match_indices('"').map(|(i, _)| i).collect();
    if quotes.len() < 2 {
        return text.to_string();
    }
    let k = rng.random_range(0..quotes.len() / 2) * 2;
    let (open, close) = (quotes[k], quotes[k + 1]);
    let long = "x".repeat(10_000);
    let value = match rng.random_range(0..=STRINGS.len()) {
        i if i == STRINGS.len() => long.as_str(),
        i => STRINGS[i],
    };
    format!("{}{value}{}", &text[..=open], &text[close..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutations_are_seeded_and_change_the_text() {
        let text = "[world]\nname = \"lab\"\nsize = [7.0, 5.0]\n";
        assert_eq!(mutate(text, 7), mutate(text, 7));
        let changed = (0..100).filter(|&s| mutate(text, s) != text).count();
        assert!(changed > 90, "{changed}");
    }
}
