//! The `links` section: what crossed each emulated network link, from the statistics every
//! receiving node leaves in `links/<node>.json` (see `caravan::network`), merged per ordered
//! host pair.

use caravan::network::{LINK_STATS_DIR, LinkStats};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// `links[]`, or `None` when no node received anything over a link.
pub fn section(run_dir: &Path) -> Option<Value> {
    let mut merged: BTreeMap<(String, String), LinkStats> = BTreeMap::new();
    for entry in std::fs::read_dir(run_dir.join(LINK_STATS_DIR))
        .ok()?
        .flatten()
    {
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
    if merged.is_empty() {
        return None;
    }
    Some(
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
            .collect(),
    )
}
