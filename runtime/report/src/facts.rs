//! What the launcher knows about a run that the recording does not: `run.json`.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The launcher's record of a run, in `run.json`.
pub const FACTS_FILE: &str = "run.json";
/// The recorded topics, in MCAP with JSON messages.
pub const RECORDING_FILE: &str = "record.mcap";
/// The launch file after overrides, arguments, includes and templates.
pub const RESOLVED_LAUNCH_FILE: &str = "launch.toml";

/// Latency percentiles of one topic, µs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Latency {
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub max: f64,
}

/// How a process ended.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ProcessRecord {
    pub name: String,
    pub host: String,
    pub required: bool,
    pub restarts: u32,
    /// "exited 0", "exited 3", "killed by signal 9", "running", "never started"
    pub exit_status: String,
    pub success: bool,
    /// CPU time summed over all its runs (restarts included), s.
    #[serde(default)]
    pub cpu_s: f64,
    /// Largest peak resident set of its runs, MiB.
    #[serde(default)]
    pub max_rss_mib: f64,
    /// The container whose process ran this node (launch key `container`): its exit, CPU
    /// time and memory are the container's, shared by its members.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub container: Option<String>,
}

/// A virtual host of the group.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct HostFacts {
    /// How many times slower than this machine the host's CPU is; `None`: no CPU budget.
    pub cpu_slowdown: Option<f64>,
}

/// One `[[report]]` entry of the launch file: the plugin that computes report sections.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportEntry {
    /// The command line as written: a workspace binary, a program on PATH, or a path
    /// relative to `launch_dir`, with its arguments.
    pub exec: Vec<String>,
    /// The entry's `params` table.
    pub params: Value,
    /// The directory of the launch file that named the plugin (relative paths in `params`
    /// are relative to it).
    pub launch_dir: String,
    /// The plugin's time limit per run directory, s (its entry's `timeout`; ten minutes in
    /// the facts of runs made before the key existed).
    #[serde(default = "default_timeout_s")]
    pub timeout_s: f64,
}

fn default_timeout_s() -> f64 {
    600.0
}

/// How a node's resource use evolved during the run, from its running statuses (1 Hz).
/// "After warm-up" is from the first status after the first fifth of them.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct Trend {
    /// Statuses received.
    pub samples: usize,
    /// Resident memory after warm-up and at the last status, MiB.
    pub rss_mib_after_warmup: f64,
    pub rss_mib_end: f64,
    /// (end − after warm-up) / after warm-up, %.
    pub rss_growth_pct: f64,
    /// Deadline misses between warm-up and the last status.
    pub deadline_misses_after_warmup: u64,
}

impl Trend {
    /// The trend of statuses `(resident KiB, deadline misses so far)` in order; `None` for none.
    pub fn of(series: &[(u64, u64)]) -> Option<Self> {
        let (first, last) = (series.get(series.len() / 5)?, series.last()?);
        let mib = |kib: u64| kib as f64 / 1024.0;
        Some(Self {
            samples: series.len(),
            rss_mib_after_warmup: mib(first.0),
            rss_mib_end: mib(last.0),
            rss_growth_pct: if first.0 > 0 {
                (last.0 as f64 - first.0 as f64) / first.0 as f64 * 100.0
            } else {
                0.0
            },
            deadline_misses_after_warmup: last.1.saturating_sub(first.1),
        })
    }
}

/// What the recording holds of one topic.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct TopicCount {
    pub messages: u64,
    /// Messages missing from the file: gaps in each source's header `seq`.
    pub gaps: u64,
}

/// Counts one topic's messages, in file order, into a [`TopicCount`]: the recording's writer
/// as it writes, the report when it reads an older run's file back.
#[derive(Debug, Clone, Default)]
pub struct TopicCounter {
    count: TopicCount,
    /// The last `seq` of each source.
    last_seq: BTreeMap<u64, u64>,
}

impl TopicCounter {
    /// One message; `numbered` is its header's (source id, seq), if it has a header.
    pub fn add(&mut self, numbered: Option<(u64, u64)>) {
        self.count.messages += 1;
        if let Some((source, seq)) = numbered
            && let Some(last) = self.last_seq.insert(source, seq)
        {
            self.count.gaps += seq.saturating_sub(last + 1);
        }
    }

    pub fn count(&self) -> TopicCount {
        self.count
    }
}

/// The launcher's record of a run: who ran, how it ended, what the recorder measured.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunFacts {
    pub group: String,
    pub clock: String,
    pub seed: u64,
    pub launch_file: String,
    /// "completed"; "degraded" (completed, but a process was restarted on the way, so its
    /// state was lost); "interrupted" or "failed".
    pub outcome: String,
    pub failure: Option<String>,
    pub sim_time_s: f64,
    pub wall_time_s: f64,
    pub processes: Vec<ProcessRecord>,
    /// Each node's last `NodeStatus`, as JSON.
    pub node_status: BTreeMap<String, Value>,
    pub topic_latency: BTreeMap<String, Latency>,
    pub topic_types: BTreeMap<String, String>,
    /// Messages and gaps of every recorded topic (the Foxglove views left out), as the
    /// recording's writer counted them; `None`
    /// for runs from before it counted (the report then reads the recording back).
    #[serde(default)]
    pub topic_counts: Option<BTreeMap<String, TopicCount>>,
    /// The group's virtual hosts (none declared: empty).
    #[serde(default)]
    pub hosts: BTreeMap<String, HostFacts>,
    /// The report plugins, in launch-file order.
    #[serde(default)]
    pub reports: Vec<ReportEntry>,
    /// How each node's memory and deadline misses evolved over its once-a-second statuses.
    #[serde(default)]
    pub trends: BTreeMap<String, Trend>,
    /// Suspicious but legal things the launcher noticed (a process stepped by a topic on which
    /// nothing arrived), one sentence each.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Lockstep: what the scheduler did.
    #[serde(default)]
    pub schedule: Option<caravan_lockstep::ScheduleStats>,
    /// A lockstep group across machines, seen from a host other than its clock host: the
    /// host that kept simulated time and recorded the group (this host did neither).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clock_host: Option<String>,
}

impl RunFacts {
    /// Reads `run.json` of `run_dir`.
    pub fn load(run_dir: &Path) -> anyhow::Result<Self> {
        use anyhow::Context;
        let path = run_dir.join(FACTS_FILE);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("{} is not a Caravan run record", path.display()))
    }

    /// Writes `run.json` into `run_dir`.
    pub fn save(&self, run_dir: &Path) -> anyhow::Result<()> {
        use anyhow::Context;
        let path = run_dir.join(FACTS_FILE);
        std::fs::write(&path, serde_json::to_string_pretty(self)? + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    }

    /// Simulated seconds per wall-clock second (0 when no wall time passed).
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_time_s > 0.0 {
            self.sim_time_s / self.wall_time_s
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trend_starts_after_the_first_fifth() {
        // 10 statuses: memory settles at 2048 KiB from the third, then grows to 2150.
        let mut series: Vec<(u64, u64)> = (0..10).map(|i| (2048, i / 3)).collect();
        series[0].0 = 1024;
        series[9].0 = 2150;
        let t = Trend::of(&series).unwrap();
        assert_eq!(t.samples, 10);
        assert_eq!(t.rss_mib_after_warmup, 2.0);
        assert!((t.rss_growth_pct - 4.98).abs() < 0.01, "{t:?}");
        assert_eq!(t.deadline_misses_after_warmup, 3);
        assert_eq!(Trend::of(&[]), None);
    }
}
