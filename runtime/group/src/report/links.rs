//! The `links` section: what crossed each emulated network link, from the statistics every
//! receiving node leaves in `links/<node>.json` (see `caravan::network`), merged per ordered
//! host pair; and, for a group across machines, what the real network between two hosts took,
//! as each receiving launcher measured it (`network/<host>.json`).

use caravan::network::{LINK_STATS_DIR, LinkStats, NETWORK_STATS_DIR};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// `links[]`, or `None` when nothing crossed a link, emulated or real.
pub fn section(run_dir: &Path) -> Option<Value> {
    let mut all = Vec::new();
    for (dir, kind) in [(LINK_STATS_DIR, "emulated"), (NETWORK_STATS_DIR, "network")] {
        all.extend(merged(&run_dir.join(dir)).into_iter().map(|mut v| {
            v["kind"] = kind.into();
            v
        }));
    }
    (!all.is_empty()).then_some(Value::Array(all))
}

/// Every file's statistics in `dir`, merged per ordered host pair.
fn merged(dir: &Path) -> Vec<Value> {
    let mut merged: BTreeMap<(String, String), LinkStats> = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    for entry in entries.flatten() {
        let Ok(text) = std::fs::read_to_string(entry.path()) else {
            continue;
        };
        let Ok(stats) = serde_json::from_str::<Vec<LinkStats>>(&text) else {
            continue;
        };
        for s in stats {
            merged
                .entry((s.from.clone(), s.to.clone()))
                .or_insert_with(|| LinkStats {
                    from: s.from.clone(),
                    to: s.to.clone(),
                    ..Default::default()
                })
                .merge(&s);
        }
    }
    // Links nothing crossed (hosts that share no topic) say nothing.
    merged.retain(|_, s| s.delivered + s.dropped > 0);
    merged
        .values()
        .map(|s| {
            let q = |q: f64| s.latency_quantile_ms(q);
            json!({
                "from": s.from,
                "to": s.to,
                "delivered": s.delivered,
                "dropped": s.dropped,
                "loss_pct": 100.0 * s.dropped as f64 / (s.delivered + s.dropped).max(1) as f64,
                "latency_ms": {"p50": q(0.5), "p90": q(0.9), "p99": q(0.99), "max": q(1.0)},
            })
        })
        .collect()
}
