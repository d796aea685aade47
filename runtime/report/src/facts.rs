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
    /// The group's virtual hosts (none declared: empty).
    #[serde(default)]
    pub hosts: BTreeMap<String, HostFacts>,
    /// The report plugins, in launch-file order.
    #[serde(default)]
    pub reports: Vec<ReportEntry>,
    /// Suspicious but legal things the launcher noticed (a process stepped by a topic on which
    /// nothing arrived), one sentence each.
    #[serde(default)]
    pub warnings: Vec<String>,
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
