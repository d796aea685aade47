//! The passability table: a sweep's crossings pooled per running-gear variant and terrain
//! kind (over the terrain seeds), with Wilson 95 % intervals, beside the reference's table.

use caravan_report::wilson::wilson95;
use serde_json::Value;
use std::collections::BTreeMap;

/// The reference's passability, % passed: (variant, [random, horizontal, diagonal]).
pub const REFERENCE: [(&str, [u32; 3]); 4] = [
    ("v1", [0, 0, 0]),
    ("v3", [15, 10, 0]),
    ("v2", [100, 100, 50]),
    ("v4", [100, 100, 40]),
];

/// The terrain kinds, each with the column of [`REFERENCE`] it is set beside: the random
/// RSE is two kinds here (a field of holes, and hills on holes; docs/tracked.md), then the
/// barriers.
pub const TERRAINS: [(&str, usize); 4] = [
    ("random", 0),
    ("hills", 0),
    ("horizontal", 1),
    ("diagonal", 2),
];

/// Crossings of one variant on one terrain kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    pub passed: usize,
    pub stuck: usize,
    pub flipped: usize,
    /// Runs whose base left the world's floor plan (in practice: veered off the terrain).
    pub off_world: usize,
    /// Runs without a `tracked` section (the group failed).
    pub failed: usize,
    /// Stuck runs high-centred, the chassis bearing over a third of the contact force
    /// ([`crate::resting`]); `None` when no run recorded its contacts.
    pub high_centred: Option<usize>,
}

impl Tally {
    pub fn runs(&self) -> usize {
        self.passed + self.stuck + self.flipped + self.off_world + self.failed
    }
}

/// Pools a sweep's `summary.json` by (`args.variant`, `args.terrain`).
pub fn pool(summary: &Value) -> Result<BTreeMap<(String, String), Tally>, String> {
    let cells = summary["cells"]
        .as_array()
        .ok_or("summary.json: no 'cells' list")?;
    let mut out: BTreeMap<(String, String), Tally> = BTreeMap::new();
    for cell in cells {
        let value = |axis: &str| {
            cell["values"][axis]
                .as_str()
                .map(str::to_owned)
                .ok_or_else(|| format!("cell {}: no '{axis}' axis", cell["id"]))
        };
        let tally = out
            .entry((value("args.variant")?, value("args.terrain")?))
            .or_default();
        let count = |flag: &str| cell["flags"][flag]["successes"].as_u64().unwrap_or(0) as usize;
        let runs = cell["runs"].as_array().map_or(0, Vec::len);
        let (p, s, f, o) = (
            count("tracked.passed"),
            count("tracked.stuck"),
            count("tracked.flipped"),
            count("tracked.off_world"),
        );
        tally.passed += p;
        tally.stuck += s;
        tally.flipped += f;
        tally.off_world += o;
        tally.failed += runs.saturating_sub(p + s + f + o);
        if let Some(k) = cell["flags"]["tracked.high_centred"]["successes"].as_u64() {
            *tally.high_centred.get_or_insert(0) += k as usize;
        }
    }
    Ok(out)
}

/// `k/n (lo–hi %)`, or `–` without runs.
fn rate(k: usize, n: usize) -> String {
    if n == 0 {
        return "–".into();
    }
    let (lo, hi) = wilson95(k, n);
    format!(
        "{:.0} % ({k}/{n}; {:.0}–{:.0} %)",
        100.0 * k as f64 / n as f64,
        100.0 * lo,
        100.0 * hi
    )
}

/// The Markdown table: per variant and terrain, Caravan's pass rate with its interval and
/// flips, runs stuck (and of them high-centred, when the sweep recorded contacts) and runs
/// off the world, and the reference's pass rate.
pub fn table(tallies: &BTreeMap<(String, String), Tally>) -> String {
    let bellies = tallies.values().any(|t| t.high_centred.is_some());
    let (belly_head, belly_rule) = if bellies {
        (" of them high-centred |", "---|")
    } else {
        ("", "")
    };
    let mut out = format!(
        "| variant | terrain | passed (95 % Wilson) | flipped | stuck |{belly_head} off the world | reference passed |\n\
         |---|---|---|---|---|{belly_rule}---|---:|\n"
    );
    // A kind no run of the sweep drove on is left out.
    let kinds: Vec<_> = TERRAINS
        .iter()
        .filter(|(kind, _)| tallies.keys().any(|(_, t)| t == kind))
        .collect();
    for (variant, reference) in REFERENCE {
        for &&(terrain, column) in &kinds {
            let refp = reference[column];
            let t = tallies
                .get(&(variant.to_string(), terrain.to_string()))
                .copied()
                .unwrap_or_default();
            let n = t.runs();
            let of = |k: usize| {
                if n == 0 {
                    "–".into()
                } else {
                    format!("{k}/{n}")
                }
            };
            let belly = match (bellies, t.high_centred) {
                (false, _) => String::new(),
                (true, Some(k)) if t.stuck > 0 => format!(" {k}/{} |", t.stuck),
                (true, _) => " – |".into(),
            };
            out.push_str(&format!(
                "| {variant} | {terrain} | {} | {} | {} |{belly} {} | {refp} % |\n",
                rate(t.passed, n),
                of(t.flipped),
                of(t.stuck),
                of(t.off_world),
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn cell(variant: &str, terrain: &str, seed: u32, outcome: &str) -> Value {
        let flag = |name: &str| json!({"successes": usize::from(outcome == name), "n": 1});
        json!({
            "id": format!("{variant},{terrain},{seed}"),
            "values": {"args.variant": variant, "args.terrain": terrain, "args.terrain_seed": seed},
            "runs": [{"seed": 1}],
            "flags": if outcome == "error" { json!({}) } else { json!({
                "tracked.passed": flag("passed"),
                "tracked.stuck": flag("stuck"),
                "tracked.flipped": flag("flipped"),
                "tracked.off_world": flag("off_world"),
            })},
        })
    }

    #[test]
    fn crossings_pool_over_terrain_seeds_per_variant_and_terrain() {
        let summary = json!({"cells": [
            cell("v4", "random", 1, "passed"),
            cell("v4", "random", 2, "passed"),
            cell("v4", "random", 3, "flipped"),
            cell("v4", "diagonal", 1, "stuck"),
            cell("v4", "diagonal", 2, "off_world"),
            cell("v1", "random", 1, "error"),
            cell("v2", "hills", 1, "passed"),
        ]});
        let t = pool(&summary).unwrap();
        let v4 = t[&("v4".into(), "random".into())];
        assert_eq!((v4.passed, v4.flipped, v4.runs()), (2, 1, 3));
        let diagonal = t[&("v4".into(), "diagonal".into())];
        assert_eq!(
            (diagonal.stuck, diagonal.off_world, diagonal.runs()),
            (1, 1, 2)
        );
        assert_eq!(t[&("v1".into(), "random".into())].failed, 1);
        let md = table(&t);
        assert!(
            md.contains("| v4 | random | 67 % (2/3; 21–94 %) | 1/3 | 0/3 | 0/3 | 100 % |"),
            "{md}"
        );
        assert!(
            md.contains("| v2 | random | – | – | – | – | 100 % |"),
            "{md}"
        );
        // Hills stand beside the reference's random RSE; a kind nobody drove is left out.
        assert!(
            md.contains("| v2 | hills | 100 % (1/1; 21–100 %) | 0/1 | 0/1 | 0/1 | 100 % |"),
            "{md}"
        );
        assert!(!md.contains("horizontal"), "{md}");
    }

    #[test]
    fn stuck_runs_high_centred_get_a_column_when_contacts_were_recorded() {
        let stuck = |seed: u32, belly: bool| {
            let mut c = cell("v4", "hills", seed, "stuck");
            c["flags"]["tracked.high_centred"] = json!({"successes": usize::from(belly), "n": 1});
            c
        };
        let summary = json!({"cells": [
            stuck(1, true),
            stuck(2, false),
            stuck(3, true),
            cell("v4", "hills", 4, "passed"),
            cell("v1", "hills", 1, "stuck"),
        ]});
        let t = pool(&summary).unwrap();
        assert_eq!(t[&("v4".into(), "hills".into())].high_centred, Some(2));
        let md = table(&t);
        assert!(md.contains("| stuck | of them high-centred |"), "{md}");
        assert!(
            md.contains("| v4 | hills | 25 % (1/4; 5–70 %) | 0/4 | 3/4 | 2/3 | 0/4 | 100 % |"),
            "{md}"
        );
        // A cell whose runs recorded no contacts says so.
        assert!(
            md.contains("| v1 | hills | 0 % (0/1; 0–79 %) | 0/1 | 1/1 | – | 0/1 | 0 % |"),
            "{md}"
        );
    }

    /// The held-out table of docs/tracked.md is the tool's output on the shipped per-run
    /// outcomes (docs/tracked/passability-held-out-runs.csv, one row per run of the sweep).
    #[test]
    fn the_shipped_held_out_table_is_the_shipped_runs_pooled() {
        let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/tracked");
        let runs = std::fs::read_to_string(docs.join("passability-held-out-runs.csv")).unwrap();
        let mut cells = Vec::new();
        for line in runs.lines().skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            let seed: u32 = f[2].parse().unwrap();
            let mut c = cell(f[0], f[1], seed, f[3]);
            if !f[4].is_empty() {
                let belly = usize::from(f[4] == "true");
                c["flags"]["tracked.high_centred"] = json!({"successes": belly, "n": 1});
            }
            cells.push(c);
        }
        assert_eq!(cells.len(), 320);
        let md = table(&pool(&json!({ "cells": cells })).unwrap());
        let shipped = std::fs::read_to_string(docs.join("passability-held-out.md")).unwrap();
        assert_eq!(md.trim(), shipped.trim());
    }

    #[test]
    fn a_summary_without_the_axes_is_an_error() {
        let e = pool(&json!({"cells": [{"id": "all", "values": {}}]})).unwrap_err();
        assert!(e.contains("args.variant"), "{e}");
        assert!(pool(&json!({})).is_err());
    }
}
