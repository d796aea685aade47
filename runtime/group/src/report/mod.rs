//! Run reports: `report.json` and `report.md`, computed from the run directory (the recording
//! and the launcher's `run.json`), so `caravan report RUN_DIR` can recompute them.
//!
//! The generic part is computed here; each `[[report]]` plugin of the launch file adds its
//! sections (see the `caravan-report` crate and `plugins.rs`).
//!
//! `report.json` layout (version 1; fields are only ever added):
//! - `version`: 1
//! - `group`: `{name, clock, seed, launch_file}`
//! - `run`: `{outcome ("completed" | "degraded" | "interrupted" | "failed"), failure (string
//!   or null; for "degraded", which processes were restarted),
//!   sim_time_s, wall_time_s, real_time_factor, warnings (sentences; suspicious but legal),
//!   schedule (lockstep, else null): {advances, steps, overlapped_steps, wake_ups, slot_reports, slot_grants,
//!   batched_steps}}`
//! - `nodes[]`: `{name, host, required, restarts, exit_status, period_ms (null when stepped by
//!   messages), steps, rate_hz, deadline_misses, jitter_p50_ms, jitter_p99_ms, jitter_max_ms,
//!   compute_mean_ms, compute_p99_ms, compute_max_ms (wall-clock time in the step),
//!   compute_cpu_mean_ms (the stepping thread's CPU time in the step, read at each of the
//!   first 64 steps and then at one in 8 at random, or at every step under a CPU slowdown in
//!   lockstep), messages_missed, cpu_s
//!   (CPU time of the process, all runs), max_rss_mib (peak resident memory), container (only
//!   for a node run in a container: its name; cpu_s and max_rss_mib are then the container's)}`
//! - `topics[]`: `{name, type, messages, gaps, latency_us: {p50, p90, p99, max}}`; latency is
//!   wall-clock time from send to the recorder's receipt.
//! - `links[]` (when messages crossed emulated network links): `{from, to, delivered, dropped,
//!   loss_pct, latency_ms: {p50, p90, p99, max}}` per ordered host pair, merged from the
//!   receiving nodes' `links/<node>.json`; latency is arrival − send in simulated time
//!   (lockstep) or wall time (realtime), in 0.1 ms bins. `nodes[].emulated_compute_mean_ms`
//!   is the mean step CPU time times the host's `cpu_slowdown` (null without one).
//! - one key per plugin section (e.g. `convoy`, `slam`), laid out as its plugin documents;
//! - `failed_sections[]` (only when a plugin failed): `{exec, message}`.
//!
//! Beside them, `nodes.svg` (compute time per step by node) and `topics.svg` (latency by topic)
//! chart the nodes' and topics' numbers; report.md shows them.

mod charts;
mod links;
mod markdown;
mod plugins;

use anyhow::Result;
use caravan_report::{RecordedMessage, RunFacts, TopicCount, TopicCounter};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// A written report and the plugins that failed to add their sections.
pub struct Written {
    pub report: Value,
    pub failures: Vec<String>,
}

/// Computes the report of `run_dir`, running every report plugin, and writes `report.json`
/// and `report.md` there; `quiet`: without saying that it waits for a slow plugin.
pub fn write(run_dir: &Path, quiet: bool) -> Result<Written> {
    let facts = RunFacts::load(run_dir)?;
    // The writer counted every topic's messages and gaps as it wrote them; only a run from
    // before it did is read back.
    let counts = match &facts.topic_counts {
        Some(counts) => counts.clone(),
        None => count(&caravan_report::read_all(
            &run_dir.join(caravan_report::RECORDING_FILE),
        )?),
    };
    let mut report = generic(&facts, &counts, run_dir);
    let mut markdown = markdown::render(&report);
    for chart in charts::write(run_dir, &report) {
        markdown.push_str(&format!("\n![{chart}]({chart})\n"));
    }
    let outcome = plugins::run_all(run_dir, &facts.reports, quiet);
    // Sections go into report.json as their plugins wrote them: reading their numbers back
    // and printing them again could change a last digit.
    let mut entries: BTreeMap<String, String> = match &report {
        Value::Object(map) => map
            .iter()
            .map(|(k, v)| Ok((k.clone(), serde_json::to_string_pretty(v)?)))
            .collect::<Result<_>>()?,
        _ => BTreeMap::new(),
    };
    for plugins::Written { section, text } in &outcome.sections {
        entries.insert(section.name.clone(), text.trim_end().to_string());
        report[&section.name] = section.json.clone();
        markdown.push('\n');
        markdown.push_str(&section.markdown);
    }
    if !outcome.failures.is_empty() {
        let failed: Value = outcome
            .failures
            .iter()
            .map(|(exec, message)| json!({"exec": exec, "message": message}))
            .collect();
        entries.insert(
            "failed_sections".into(),
            serde_json::to_string_pretty(&failed)?,
        );
        report["failed_sections"] = failed;
        markdown.push_str("\n## Failed report sections\n\n");
        for (exec, message) in &outcome.failures {
            markdown.push_str(&format!("- `{exec}`: {message}\n"));
        }
    }
    std::fs::write(run_dir.join("report.json"), object_text(&entries))?;
    std::fs::write(run_dir.join("report.md"), markdown)?;
    let failures = outcome
        .failures
        .into_iter()
        .map(|(exec, message)| format!("report plugin '{exec}' failed: {message}"))
        .collect();
    Ok(Written { report, failures })
}

pub use plugins::check;

/// A JSON object, pretty-printed, from its members' pretty-printed values.
fn object_text(entries: &BTreeMap<String, String>) -> String {
    let members: Vec<String> = entries
        .iter()
        .map(|(key, value)| {
            // Pretty JSON has no raw newline inside strings, so indenting lines is safe.
            format!(
                "  {}: {}",
                Value::from(key.as_str()),
                value.replace('\n', "\n  ")
            )
        })
        .collect();
    format!("{{\n{}\n}}\n", members.join(",\n"))
}

/// The part of the report every run has.
fn generic(facts: &RunFacts, counts: &BTreeMap<String, TopicCount>, run_dir: &Path) -> Value {
    let mut report = json!({
        "version": 1,
        "group": {"name": facts.group, "clock": facts.clock, "seed": facts.seed, "launch_file": facts.launch_file},
        "run": {
            "outcome": facts.outcome,
            "failure": facts.failure,
            "sim_time_s": facts.sim_time_s,
            "wall_time_s": facts.wall_time_s,
            "real_time_factor": facts.real_time_factor(),
            "warnings": facts.warnings,
            "schedule": facts.schedule,
            "clock_host": facts.clock_host,
        },
        "nodes": nodes(facts),
        "topics": topics(facts, counts),
    });
    if let Some(section) = links::section(run_dir) {
        report["links"] = section;
    }
    report
}

fn ms(ns: &Value) -> Value {
    ns.as_u64().map_or(Value::Null, |n| json!(n as f64 / 1e6))
}

/// What a node's step took on its emulated host, ms: its CPU time times the host's slowdown
/// (`None` without one). Runs recorded before CPU time was measured: wall-clock time, as
/// their stamps were.
fn emulated_compute_ms(status: &Value, slowdown: Option<f64>) -> Option<f64> {
    let cpu = status["compute_cpu_mean_ns"].as_u64();
    Some(cpu.or(status["compute_mean_ns"].as_u64())? as f64 * slowdown? / 1e6)
}

fn nodes(facts: &RunFacts) -> Vec<Value> {
    facts
        .processes
        .iter()
        .map(|p| {
            let s = facts.node_status.get(&p.name).cloned().unwrap_or(Value::Null);
            let period = s["period_ns"].as_u64().filter(|&p| p > 0);
            let steps = s["steps"].as_u64();
            let slowdown = facts.hosts.get(&p.host).and_then(|h| h.cpu_slowdown);
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
                "compute_cpu_mean_ms": ms(&s["compute_cpu_mean_ns"]),
                "emulated_compute_mean_ms": emulated_compute_ms(&s, slowdown),
                "messages_missed": s["messages_missed"],
                "cpu_s": p.cpu_s,
                "max_rss_mib": p.max_rss_mib,
                "container": p.container,
                "trend": facts.trends.get(&p.name),
            })
        })
        .collect()
}

/// Each topic's messages and gaps (in each source's `seq`), from the recording's messages.
fn count(messages: &[RecordedMessage]) -> BTreeMap<String, TopicCount> {
    let mut counters: BTreeMap<&str, TopicCounter> = BTreeMap::new();
    for m in messages {
        let numbered = m.header_u64("source_id").zip(m.header_u64("seq"));
        counters.entry(&m.topic).or_default().add(numbered);
    }
    counters
        .into_iter()
        .map(|(topic, c)| (topic.to_string(), c.count()))
        .collect()
}

fn topics(facts: &RunFacts, counts: &BTreeMap<String, TopicCount>) -> Vec<Value> {
    counts
        .iter()
        .map(|(name, c)| {
            json!({
                "name": name,
                "type": facts.topic_types.get(name),
                "messages": c.messages,
                "gaps": c.gaps,
                "latency_us": facts.topic_latency.get(name),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::emulated_compute_ms;
    use serde_json::json;

    #[test]
    fn emulated_compute_scales_cpu_time_or_an_older_runs_wall_time() {
        let now = json!({ "compute_mean_ns": 9_000_000, "compute_cpu_mean_ns": 2_000_000 });
        assert_eq!(emulated_compute_ms(&now, Some(10.0)), Some(20.0));
        assert_eq!(emulated_compute_ms(&now, None), None);
        let older = json!({ "compute_mean_ns": 3_000_000 });
        assert_eq!(emulated_compute_ms(&older, Some(10.0)), Some(30.0));
        assert_eq!(emulated_compute_ms(&json!(null), Some(10.0)), None);
    }
}
