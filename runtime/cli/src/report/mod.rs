//! Run reports: `report.json` and `report.md`, computed from the run directory (the recording
//! and the launcher's `run.json`), so `caravan report RUN_DIR` can recompute them.
//!
//! `report.json` layout (version 1; fields are only ever added):
//! - `version`: 1
//! - `group`: `{name, clock, seed, launch_file}`
//! - `run`: `{outcome ("completed" | "interrupted" | "failed"), failure (string or null),
//!   sim_time_s, wall_time_s, real_time_factor}`
//! - `nodes[]`: `{name, host, required, restarts, exit_status, period_ms (null when stepped by
//!   messages), steps, rate_hz, deadline_misses, jitter_p50_ms, jitter_p99_ms, jitter_max_ms,
//!   compute_mean_ms, compute_p99_ms, compute_max_ms, messages_missed, cpu_s (CPU time of the
//!   process, all runs), max_rss_mib (peak resident memory)}`
//! - `topics[]`: `{name, type, messages, gaps, latency_us: {p50, p90, p99, max}}`; latency is
//!   wall-clock time from send to the recorder's receipt.
//!
//! - `convoy` (when the recording holds `robot/<i>/pose_true` of two or more robots and
//!   `goal`): `{robots, goals_total, goals_reached, goal_times_s[], min_gap_m, collisions,
//!   order_kept, followers[]: {robot, cross_track_to_predecessor_m, cross_track_to_leader_m}
//!   (each {mean, p95, max}), plot}`; definitions in `report/convoy.rs`. The plot is
//!   `trajectories.svg` in the run directory.
//!
//! - `slam` (when the run left a map or recorded `robot/0/pose`): `{pose_error_m: {mean, max,
//!   samples}, map_scale_error_pct[], surveys[]: {name, true_m, map_m, error_pct}, plot}`;
//!   definitions in `report/slam.rs`. The plot is `map.svg`.
//!
//! - `links[]` (when messages crossed emulated network links): `{from, to, delivered, dropped,
//!   loss_pct, latency_ms: {p50, p90, p99, max}}` per ordered host pair, merged from the
//!   receiving nodes' `links/<node>.json`; latency is arrival − send in simulated time
//!   (lockstep) or wall time (realtime), in 0.1 ms bins. `nodes[].emulated_compute_mean_ms`
//!   is the mean step compute time times the host's `cpu_slowdown` (null without one).

mod convoy;
mod links;
mod markdown;
mod slam;
mod svg;

use crate::record::reader::read_all;
use crate::run::supervisor::ProcessRecord;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// Latency percentiles of one topic, µs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Latency {
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub max: f64,
}

/// What the launcher knows that the recording does not: written to `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunFacts {
    pub group: String,
    pub clock: String,
    pub seed: u64,
    pub launch_file: String,
    pub outcome: String,
    pub failure: Option<String>,
    pub sim_time_s: f64,
    pub wall_time_s: f64,
    pub processes: Vec<ProcessRecord>,
    /// Each node's last `NodeStatus`, as JSON.
    pub node_status: BTreeMap<String, Value>,
    pub topic_latency: BTreeMap<String, Latency>,
    pub topic_types: BTreeMap<String, String>,
}

pub const FACTS_FILE: &str = "run.json";
pub const RECORDING_FILE: &str = "record.mcap";

/// Computes the report of `run_dir` and writes `report.json` and `report.md` there.
pub fn write(run_dir: &Path) -> Result<Value> {
    let report = compute(run_dir)?;
    std::fs::write(
        run_dir.join("report.json"),
        serde_json::to_string_pretty(&report)? + "\n",
    )?;
    std::fs::write(run_dir.join("report.md"), markdown::render(&report))?;
    Ok(report)
}

pub fn compute(run_dir: &Path) -> Result<Value> {
    let facts_path = run_dir.join(FACTS_FILE);
    let facts: RunFacts = serde_json::from_str(
        &std::fs::read_to_string(&facts_path)
            .with_context(|| format!("cannot read {}", facts_path.display()))?,
    )
    .with_context(|| format!("{} is not a Caravan run record", facts_path.display()))?;
    let messages = read_all(&run_dir.join(RECORDING_FILE))?;
    let rtf = if facts.wall_time_s > 0.0 {
        facts.sim_time_s / facts.wall_time_s
    } else {
        0.0
    };
    let launch_dir = Path::new(&facts.launch_file)
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let scene = convoy::Scene::from_run(run_dir, &launch_dir);
    let mut report = json!({
        "version": 1,
        "group": {"name": facts.group, "clock": facts.clock, "seed": facts.seed, "launch_file": facts.launch_file},
        "run": {
            "outcome": facts.outcome,
            "failure": facts.failure,
            "sim_time_s": facts.sim_time_s,
            "wall_time_s": facts.wall_time_s,
            "real_time_factor": rtf,
        },
        "nodes": nodes(&facts, &links::slowdowns(run_dir)),
        "topics": topics(&facts, &messages),
    });
    if let Some(section) = convoy::section(&messages, &scene, run_dir) {
        report["convoy"] = section;
    }
    if let Some(section) = links::section(run_dir) {
        report["links"] = section;
    }
    if let Some(section) = slam::section(&messages, scene.world.as_ref(), run_dir) {
        report["slam"] = section;
    }
    Ok(report)
}

fn ms(ns: &Value) -> Value {
    ns.as_u64().map_or(Value::Null, |n| json!(n as f64 / 1e6))
}

fn nodes(facts: &RunFacts, slowdowns: &BTreeMap<String, f64>) -> Vec<Value> {
    facts
        .processes
        .iter()
        .map(|p| {
            let s = facts.node_status.get(&p.name).cloned().unwrap_or(Value::Null);
            let period = s["period_ns"].as_u64().filter(|&p| p > 0);
            let steps = s["steps"].as_u64();
            json!({
                "name": p.name,
                "host": p.host,
                "required": p.required,
                "restarts": p.restarts,
                "exit_status": p.exit_status,
                "period_ms": period.map(|p| p as f64 / 1e6),
                "steps": steps,
                "rate_hz": steps.filter(|_| facts.sim_time_s > 0.0).map(|n| n as f64 / facts.sim_time_s),
                "deadline_misses": s["deadline_misses"],
                "jitter_p50_ms": ms(&s["jitter_p50_ns"]),
                "jitter_p99_ms": ms(&s["jitter_p99_ns"]),
                "jitter_max_ms": ms(&s["jitter_max_ns"]),
                "compute_mean_ms": ms(&s["compute_mean_ns"]),
                "compute_p99_ms": ms(&s["compute_p99_ns"]),
                "compute_max_ms": ms(&s["compute_max_ns"]),
                // What the step took on its emulated host (compute × the host's slowdown).
                "emulated_compute_mean_ms": slowdowns
                    .get(&p.host)
                    .and_then(|f| Some(s["compute_mean_ns"].as_u64()? as f64 * f / 1e6)),
                "messages_missed": s["messages_missed"],
                "cpu_s": p.cpu_s,
                "max_rss_mib": p.max_rss_mib,
            })
        })
        .collect()
}

fn topics(facts: &RunFacts, messages: &[crate::record::reader::RecordedMessage]) -> Vec<Value> {
    // (count, gaps, last seq per source)
    let mut per_topic: BTreeMap<&str, (u64, u64, BTreeMap<u64, u64>)> = BTreeMap::new();
    for m in messages {
        let entry = per_topic.entry(&m.topic).or_default();
        entry.0 += 1;
        let header = &m.json["header"];
        if let (Some(src), Some(seq)) = (header["source_id"].as_u64(), header["seq"].as_u64())
            && let Some(last) = entry.2.insert(src, seq)
        {
            entry.1 += seq.saturating_sub(last + 1);
        }
    }
    per_topic
        .into_iter()
        .map(|(name, (count, gaps, _))| {
            json!({
                "name": name,
                "type": facts.topic_types.get(name),
                "messages": count,
                "gaps": gaps,
                "latency_us": facts.topic_latency.get(name),
            })
        })
        .collect()
}
