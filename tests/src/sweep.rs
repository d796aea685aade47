//! Sweeps for the tests: a temporary output folder, `caravan sweep`, and summaries compared
//! without their wall-clock fields.

use crate::{unique_group, workspace_bin, workspace_root};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A temporary directory removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("caravan-{}", unique_group(tag)));
        std::fs::create_dir_all(&dir).unwrap();
        Self(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

pub fn sweep(args: &[&str], out: &Path) -> Output {
    Command::new(workspace_bin("caravan"))
        .arg("sweep")
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap()
}

/// Parts of a metric's key that measure the machine rather than the simulation: latencies,
/// CPU and compute times, memory, wall time, real-time factor, and how the launcher's
/// schedule overlapped steps. Everything else of a lockstep run is the same on every rerun.
pub const WALL_CLOCK: &[&str] = &[
    "latency",
    "cpu",
    "rss",
    "compute_",
    "wall_time",
    "real_time_factor",
    "overlapped",
    "trend",
];

/// A summary less what differs between reruns of a lockstep sweep: wall-clock metrics and the
/// run directories (their names hold the launcher's pid and the time).
pub fn comparable(summary: &Value) -> Value {
    let mut s = summary.clone();
    for cell in s["cells"].as_array_mut().expect("cells") {
        let metrics = cell["metrics"].as_object_mut().expect("metrics");
        metrics.retain(|key, _| !WALL_CLOCK.iter().any(|w| key.contains(w)));
        for run in cell["runs"].as_array_mut().expect("runs") {
            run.as_object_mut().expect("a run").remove("dir");
        }
    }
    s
}

pub fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// The arguments of a lockstep pingpong sweep over `gains` and `seeds`, 2 s a run, 2 at once.
pub fn lockstep_pingpong(gains: &str, seeds: &str) -> Vec<String> {
    let launch = workspace_root().join("launch/pingpong.toml");
    [
        launch.to_str().unwrap(),
        "--grid",
        &format!("process.pong.params.gain={gains}"),
        "--seeds",
        seeds,
        "--duration",
        "2s",
        "--set",
        "group.clock=\"lockstep\"",
        "--jobs",
        "2",
        "--quiet",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}
