//! The generic report's charts: `nodes.svg` (each node's compute time per step, mean, p99
//! and max) and `topics.svg` (each recorded topic's send-to-recorder latency, p50, p90, p99
//! and max), drawn from report.json's numbers.

use caravan_report::plot::{BarRow, bars_svg};
use serde_json::Value;
use std::path::Path;

pub const NODES_FILE: &str = "nodes.svg";
pub const TOPICS_FILE: &str = "topics.svg";

/// Rows of `items` (`name` plus the numbers at `keys` of `field`, or of the item itself).
fn rows(items: &Value, field: Option<&str>, keys: &[&str]) -> Vec<BarRow> {
    items
        .as_array()
        .into_iter()
        .flatten()
        .map(|item| {
            let source = field.map_or(item, |f| &item[f]);
            BarRow {
                label: item["name"].as_str().unwrap_or("?").to_string(),
                values: keys
                    .iter()
                    .map(|k| source[*k].as_f64().unwrap_or(f64::NAN))
                    .collect(),
            }
        })
        .filter(|r| r.values.iter().any(|v| v.is_finite()))
        .collect()
}

/// Writes the charts that have data; returns the files written, for report.md to show.
pub fn write(run_dir: &Path, report: &Value) -> Vec<&'static str> {
    let mut written = Vec::new();
    let nodes = rows(
        &report["nodes"],
        None,
        &["compute_mean_ms", "compute_p99_ms", "compute_max_ms"],
    );
    if !nodes.is_empty()
        && bars_svg(
            &run_dir.join(NODES_FILE),
            "Compute time per step, by node",
            "ms",
            &["mean", "p99", "max"],
            &nodes,
        )
        .is_ok()
    {
        written.push(NODES_FILE);
    }
    let topics = rows(
        &report["topics"],
        Some("latency_us"),
        &["p50", "p90", "p99", "max"],
    );
    if !topics.is_empty()
        && bars_svg(
            &run_dir.join(TOPICS_FILE),
            "Latency from send to the recorder, by topic (wall clock)",
            "µs",
            &["p50", "p90", "p99", "max"],
            &topics,
        )
        .is_ok()
    {
        written.push(TOPICS_FILE);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn charts_are_written_for_nodes_and_topics_with_numbers() {
        let dir = std::env::temp_dir().join(format!("caravan-charts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let report = json!({
            "nodes": [
                {"name": "physics", "compute_mean_ms": 0.3, "compute_p99_ms": 0.5, "compute_max_ms": 2.0},
                {"name": "python-agent", "compute_mean_ms": null},
            ],
            "topics": [{"name": "map", "latency_us": null}],
        });
        assert_eq!(write(&dir, &report), [NODES_FILE]);
        let svg = std::fs::read_to_string(dir.join(NODES_FILE)).unwrap();
        assert!(
            svg.contains(">physics<") && !svg.contains("python-agent"),
            "{svg}"
        );
        assert!(!dir.join(TOPICS_FILE).exists());
        let _ = std::fs::remove_dir_all(dir);
    }
}
