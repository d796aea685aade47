//! What the launcher writes to `run.json` about a finished group: from the launch file, the
//! supervisor's records and the recorder's statistics.

use super::driver::DriverOutcome;
use super::events::Ending;
use caravan_launch::model::LaunchFile;
use caravan_report::{HostFacts, Latency, ProcessRecord, RunFacts};

/// The facts of a run that ended as `ending` after `wall_time_s`.
pub fn collect(
    lf: &LaunchFile,
    ending: Ending,
    processes: Vec<ProcessRecord>,
    driven: DriverOutcome,
    wall_time_s: f64,
) -> RunFacts {
    let lockstep = lf.group.clock == caravan::ClockMode::Lockstep;
    let recording = driven.recording;
    let sim_time_s = if lockstep {
        driven.sim_time_ns as f64 / 1e9
    } else {
        wall_time_s
    };
    let topic_counts = recording
        .topics
        .iter()
        .map(|(name, s)| (name.clone(), s.counted.count()))
        .collect();
    let topic_latency = recording
        .topics
        .iter()
        .map(|(name, s)| {
            let q = |q: f64| s.latency.value_at_quantile(q) as f64 / 1e3;
            (
                name.clone(),
                Latency {
                    p50: q(0.5),
                    p90: q(0.9),
                    p99: q(0.99),
                    max: s.latency.max() as f64 / 1e3,
                },
            )
        })
        .collect();
    let topic_types = recording
        .topics
        .iter()
        .map(|(n, s)| (n.clone(), s.type_name.clone()))
        .collect();
    let (outcome, failure) = degrade(ending, &processes);
    let warnings = never_triggered(lf, &recording.node_status);
    RunFacts {
        group: lf.group.name.clone(),
        clock: lf.group.clock.to_string(),
        seed: lf.group.seed,
        launch_file: lf.path.display().to_string(),
        outcome,
        failure,
        sim_time_s,
        wall_time_s,
        processes,
        node_status: recording.node_status,
        topic_latency,
        topic_types,
        topic_counts: Some(topic_counts),
        hosts: lf
            .hosts
            .iter()
            .map(|(name, h)| {
                let facts = HostFacts {
                    cpu_slowdown: h.cpu_slowdown,
                };
                (name.clone(), facts)
            })
            .collect(),
        reports: Vec::new(),
        warnings,
        schedule: driven.schedule,
        clock_host: None,
        trends: recording
            .status_series
            .iter()
            .filter_map(|(n, s)| Some((n.clone(), caravan_report::Trend::of(s)?)))
            .collect(),
    }
}

/// Processes stepped by a topic (`on`) that never stepped: nothing published it (or a cycle of
/// triggers waits on itself). Legal, so a warning rather than an error.
fn never_triggered(
    lf: &LaunchFile,
    status: &std::collections::BTreeMap<String, serde_json::Value>,
) -> Vec<String> {
    lf.processes
        .iter()
        .filter_map(|p| {
            let topic = p.on.as_ref()?;
            let steps = status.get(&p.name).and_then(|s| s["steps"].as_u64());
            (steps.unwrap_or(0) == 0).then(|| {
                format!(
                    "process '{}' is stepped by messages on '{topic}' and never stepped: no message arrived (does a process publish '{topic}'?)",
                    p.name
                )
            })
        })
        .collect()
}

/// A run that completed though a process was restarted is "degraded": the restarted process
/// lost what it held (physics its bodies' state, an agent its history), so the run is not the
/// one its launch file and seed describe. `failure` then says which restarted.
fn degrade(ending: Ending, processes: &[ProcessRecord]) -> (String, Option<String>) {
    let restarted: Vec<String> = processes
        .iter()
        .filter(|p| p.restarts > 0)
        .map(|p| format!("'{}' ({}×)", p.name, p.restarts))
        .collect();
    if ending.outcome != "completed" || restarted.is_empty() {
        return (ending.outcome.to_string(), ending.failure);
    }
    let why = format!(
        "restarted during the run, losing their state: {}",
        restarted.join(", ")
    );
    ("degraded".to_string(), Some(why))
}
