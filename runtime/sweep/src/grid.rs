//! Axes, their Cartesian product (cells), cell ids and seed specs.

use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// One value of an axis: how it is named, and the `--set`s it applies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisValue {
    pub label: String,
    pub sets: Vec<String>,
    /// Where a sweep file wrote the value (`sweep.toml:7`), so that a problem with it names
    /// the line; `None` for `--grid` values. Not in shard manifests: only the check before
    /// the start reports it.
    #[serde(skip)]
    pub origin: Option<String>,
}

/// An axis: over one `--set` key (`key` is `Some`), or named, with bundles of sets as values.
/// Shards' manifests hold them as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// The key (plain axis) or the name (named axis): the axis' column in the summary.
    pub label: String,
    pub key: Option<String>,
    pub values: Vec<AxisValue>,
}

impl Axis {
    /// A plain axis over `key`; each value is set as written.
    pub fn plain(key: &str, values: Vec<String>) -> Self {
        Self {
            label: key.to_string(),
            key: Some(key.to_string()),
            values: values
                .into_iter()
                .map(|v| AxisValue {
                    sets: vec![format!("{key}={v}")],
                    label: v,
                    origin: None,
                })
                .collect(),
        }
    }
}

/// One combination of axis values.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// File-name-safe and readable, e.g. `gain=3,localisation=ideal` (see [`cell_ids`]).
    pub id: String,
    /// (axis label, value label), in axis order.
    pub values: Vec<(String, String)>,
    /// The overrides of the cell, in axis order.
    pub sets: Vec<String>,
}

/// Parses `--grid KEY=V1,V2,…`. Commas inside brackets or quotes do not split, so
/// `--grid 'process.x.params.v=[1,2],[3,4]'` has two values.
pub fn parse_grid(text: &str) -> Result<Axis, String> {
    let (key, values) = text
        .split_once('=')
        .ok_or_else(|| format!("--grid {text}: expected KEY=V1,V2,…"))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(format!("--grid {text}: empty key"));
    }
    let values: Vec<String> = split_top_level(values)
        .into_iter()
        .map(|v| v.trim().to_string())
        .collect();
    if values.iter().any(String::is_empty) {
        return Err(format!("--grid {text}: empty value"));
    }
    let mut seen = BTreeSet::new();
    if let Some(dup) = values.iter().find(|v| !seen.insert(v.as_str())) {
        return Err(format!("--grid {text}: value '{dup}' given twice"));
    }
    Ok(Axis::plain(key, values))
}

fn split_top_level(text: &str) -> Vec<&str> {
    let (mut depth, mut quote, mut start) = (0i32, None, 0);
    let mut parts = Vec::new();
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// Adds `axis` to `axes`, replacing an axis with the same label (a command-line `--grid`
/// overrides a sweep file's axis over the same key).
pub fn merge_axis(axes: &mut Vec<Axis>, axis: Axis) {
    match axes.iter_mut().find(|a| a.label == axis.label) {
        Some(old) => *old = axis,
        None => axes.push(axis),
    }
}

/// The Cartesian product of `axes`, the first axis varying slowest. No axes: one cell.
pub fn expand(axes: &[Axis]) -> Vec<Cell> {
    let mut combos: Vec<Vec<usize>> = vec![Vec::new()];
    for axis in axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                (0..axis.values.len()).map(move |i| {
                    let mut c = c.clone();
                    c.push(i);
                    c
                })
            })
            .collect();
    }
    let ids = cell_ids(axes, &combos);
    combos
        .into_iter()
        .zip(ids)
        .map(|(combo, id)| {
            let picked = axes.iter().zip(&combo).map(|(a, &i)| (a, &a.values[i]));
            Cell {
                id,
                values: picked
                    .clone()
                    .map(|(a, v)| (a.label.clone(), v.label.clone()))
                    .collect(),
                sets: picked.flat_map(|(_, v)| v.sets.iter().cloned()).collect(),
            }
        })
        .collect()
}

/// Longest cell id kept whole; longer ones are cut and get a hash of the whole.
const MAX_ID: usize = 100;

/// Cell ids: `short=value` per axis joined by `,`, where `short` is a plain axis' last key
/// segment (the whole key if two axes share it) or a named axis' name; characters other than
/// `[A-Za-z0-9._=+-]` become `_`. Ids depend only on the axis values, not on their positions,
/// so adding a value to an axis keeps the ids (and the finished runs) of existing cells. Ids
/// that collide after cleaning get `-2`, `-3`…; no axes gives the single id `all`.
fn cell_ids(axes: &[Axis], combos: &[Vec<usize>]) -> Vec<String> {
    let last = |a: &Axis| match &a.key {
        Some(k) => k.rsplit('.').next().unwrap_or(k).to_string(),
        None => a.label.clone(),
    };
    let shorts: Vec<String> = axes
        .iter()
        .map(|a| {
            let short = last(a);
            let shared = axes.iter().filter(|b| last(b) == short).count() > 1;
            if shared { a.label.clone() } else { short }
        })
        .collect();
    let mut seen = BTreeSet::new();
    combos
        .iter()
        .map(|combo| {
            let raw = if axes.is_empty() {
                "all".to_string()
            } else {
                let parts: Vec<String> = axes
                    .iter()
                    .zip(combo)
                    .zip(&shorts)
                    .map(|((a, &i), s)| format!("{s}={}", a.values[i].label))
                    .collect();
                parts.join(",")
            };
            let mut id = clean(&raw);
            if id.len() > MAX_ID {
                id = format!("{}-{:08x}", &id[..MAX_ID - 9], fnv(raw.as_bytes()) as u32);
            }
            let base = id.clone();
            let mut n = 2;
            while !seen.insert(id.clone()) {
                id = format!("{base}-{n}");
                n += 1;
            }
            id
        })
        .collect()
}

fn clean(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._=+-,".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// FNV-1a: a stable hash (std's is randomised per process, and ids and sweep fingerprints
/// must survive restarts).
pub fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100000001b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_arguments() {
        let a = parse_grid("process.pong.params.gain=1, 3").unwrap();
        assert_eq!(a.label, "process.pong.params.gain");
        assert_eq!(a.values[1].label, "3");
        assert_eq!(a.values[1].sets, ["process.pong.params.gain=3"]);
        let b = parse_grid("process.x.params.v=[1,2],[3,4],\"a,b\"").unwrap();
        let labels: Vec<_> = b.values.iter().map(|v| v.label.as_str()).collect();
        assert_eq!(labels, ["[1,2]", "[3,4]", "\"a,b\""]);
        assert!(parse_grid("gain").is_err());
        assert!(parse_grid("=1,2").is_err());
        assert!(parse_grid("a.b=1,,2").is_err());
        assert!(parse_grid("a.b=1,1").unwrap_err().contains("twice"));
    }

    #[test]
    fn the_product_varies_the_last_axis_fastest() {
        let axes = vec![
            Axis::plain(
                "args.localisation",
                vec!["estimated".into(), "ideal".into()],
            ),
            Axis {
                label: "network".into(),
                key: None,
                values: vec![
                    AxisValue {
                        label: "no-delay".into(),
                        sets: vec![],
                        origin: None,
                    },
                    AxisValue {
                        label: "bad-wlan".into(),
                        sets: vec![
                            "args.wlan_latency=50ms".into(),
                            "args.wlan_loss=0.05".into(),
                        ],
                        origin: None,
                    },
                ],
            },
        ];
        let cells = expand(&axes);
        let ids: Vec<_> = cells.iter().map(|c| c.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "localisation=estimated,network=no-delay",
                "localisation=estimated,network=bad-wlan",
                "localisation=ideal,network=no-delay",
                "localisation=ideal,network=bad-wlan",
            ]
        );
        assert_eq!(
            cells[3].sets,
            [
                "args.localisation=ideal",
                "args.wlan_latency=50ms",
                "args.wlan_loss=0.05"
            ]
        );
        assert_eq!(
            cells[3].values,
            [
                ("args.localisation".to_string(), "ideal".to_string()),
                ("network".to_string(), "bad-wlan".to_string())
            ]
        );
    }

    #[test]
    fn cell_ids_are_readable_unique_and_bounded() {
        assert_eq!(expand(&[])[0].id, "all");
        // Two axes ending in the same segment keep their whole keys.
        let cells = expand(&[
            Axis::plain("process.ping.rate", vec!["10Hz".into()]),
            Axis::plain("process.sum.rate", vec!["5 Hz".into()]),
        ]);
        assert_eq!(cells[0].id, "process.ping.rate=10Hz,process.sum.rate=5_Hz");
        // Values that clean to the same text stay apart.
        let cells = expand(&[Axis::plain("a.x", vec!["1 s".into(), "1/s".into()])]);
        assert_eq!(cells[0].id, "x=1_s");
        assert_eq!(cells[1].id, "x=1_s-2");
        let long = "v".repeat(300);
        let cells = expand(&[Axis::plain("a.x", vec![long])]);
        assert!(cells[0].id.len() <= MAX_ID, "{}", cells[0].id);
        let merged = &mut vec![Axis::plain("a.x", vec!["1".into()])];
        merge_axis(merged, Axis::plain("a.x", vec!["2".into(), "3".into()]));
        assert_eq!(merged.len(), 1);
        assert_eq!(merged[0].values.len(), 2);
    }
}
