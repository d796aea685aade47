//! Seed specs, as `caravan sweep --seeds` and the scenarios' generators take them: seeds and
//! Rust ranges separated by commas (`1,2,3`, `1..=3`, `1..4`, `1..=3,10`), distinct, and at most
//! [`MAX_SEEDS`] of them.

use std::collections::BTreeSet;

/// The most seeds a spec gives: each is at least one run (or one world), so more is a typo,
/// and a range is never expanded past it.
pub const MAX_SEEDS: u64 = 100_000;

/// Parses a seed spec: comma-separated seeds or Rust ranges, e.g. `1,2,3`, `1..=3`, `1..4`,
/// `1..=3,10`.
pub fn parse(spec: &str) -> Result<Vec<u64>, String> {
    let num = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| format!("'{}' is not a seed (a whole number ≥ 0)", s.trim()))
    };
    let mut seeds: Vec<u64> = Vec::new();
    let room = |seeds: &Vec<u64>, a: u64, last: u64| {
        let wanted = (last - a)
            .saturating_add(1)
            .saturating_add(seeds.len() as u64);
        if wanted > MAX_SEEDS {
            Err(format!(
                "'{spec}' gives {wanted} seeds, more than the {MAX_SEEDS} one command takes"
            ))
        } else {
            Ok(())
        }
    };
    for part in spec.split(',') {
        if let Some((a, b)) = part.split_once("..=") {
            let (a, b) = (num(a)?, num(b)?);
            if a > b {
                return Err(format!("range {a}..={b} is empty"));
            }
            room(&seeds, a, b)?;
            seeds.extend(a..=b);
        } else if let Some((a, b)) = part.split_once("..") {
            let (a, b) = (num(a)?, num(b)?);
            if a >= b {
                return Err(format!("range {a}..{b} is empty"));
            }
            room(&seeds, a, b - 1)?;
            seeds.extend(a..b);
        } else {
            room(&seeds, 0, 0)?;
            seeds.push(num(part)?);
        }
    }
    check(&seeds)?;
    Ok(seeds)
}

/// Seeds must be distinct: each names its own run directory.
pub fn check(seeds: &[u64]) -> Result<(), String> {
    if seeds.is_empty() {
        return Err("no seeds".into());
    }
    if seeds.len() as u64 > MAX_SEEDS {
        return Err(format!(
            "{} seeds, more than the {MAX_SEEDS} one command takes",
            seeds.len()
        ));
    }
    let mut seen = BTreeSet::new();
    match seeds.iter().find(|s| !seen.insert(**s)) {
        Some(dup) => Err(format!("seed {dup} given twice")),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_specs_lists_and_ranges() {
        assert_eq!(parse("1,2,3").unwrap(), [1, 2, 3]);
        assert_eq!(parse("1..=3").unwrap(), [1, 2, 3]);
        assert_eq!(parse("1..4").unwrap(), [1, 2, 3]);
        assert_eq!(parse(" 7 ").unwrap(), [7]);
        assert_eq!(parse("1..=2,10").unwrap(), [1, 2, 10]);
        let huge = parse("0..9223372036854775807").unwrap_err();
        assert!(
            huge.contains("more than the 100000 one command takes"),
            "{huge}"
        );
        assert!(parse("0..=18446744073709551615").is_err());
        assert_eq!(parse("0..100000").unwrap().len(), 100_000);
        assert!(parse("3..3").unwrap_err().contains("empty"));
        assert!(parse("1,1").unwrap_err().contains("twice"));
        assert!(parse("x").unwrap_err().contains("'x'"));
        assert!(parse("").is_err());
        assert!(parse("-1").is_err());
    }
}
