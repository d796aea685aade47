//! Caravan report plugins: turn a finished run into a section of its report.
//!
//! The generic report (`report.json`, `report.md`) says what every run has: nodes, topics,
//! links. What a scenario's run *means* (did the convoy keep its order? how far was the IMU
//! from the analytic value?) is computed by the scenario's own executable, a **report
//! plugin**, named in the launch file:
//!
//! ```toml
//! [[report]]
//! exec = "caravan-convoy-report"
//! params = { world = "worlds/lab.toml", urdf = "robots/convoy_bot.urdf" }
//! ```
//!
//! After the run, the launcher writes `run.json` ([`RunFacts`]) and `record.mcap`, then runs
//! each plugin with the run directory; the plugin reads both through this crate ([`Run`]),
//! writes one or more [`Section`]s (JSON for `report.json`, a Markdown fragment for
//! `report.md`) and any plots into the run directory, and the launcher merges the sections
//! into the report under their names. `caravan report RUN_DIR` reruns every plugin.
//!
//! A plugin is a small binary around a [`ReportPlugin`]:
//!
//! ```no_run
//! use caravan_report::{Inputs, ReportPlugin, Run, Section};
//! use serde::Deserialize;
//!
//! #[derive(Deserialize, caravan::schemars::JsonSchema)]
//! #[schemars(crate = "caravan::schemars")]
//! #[serde(deny_unknown_fields)]
//! struct Params {
//!     /// The topic whose messages are counted.
//!     topic: String,
//! }
//!
//! struct Count(Params);
//!
//! impl ReportPlugin for Count {
//!     type Params = Params;
//!     fn new(params: Params, _: &Inputs) -> Result<Self, String> {
//!         Ok(Count(params))
//!     }
//!     fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
//!         let n = run.messages()?.iter().filter(|m| m.topic == self.0.topic).count();
//!         Ok(vec![Section {
//!             name: "count".into(),
//!             json: serde_json::json!({ "messages": n }),
//!             markdown: format!("## Count\n\n{n} messages on {}.\n", self.0.topic),
//!         }])
//!     }
//! }
//!
//! fn main() -> std::process::ExitCode {
//!     caravan_report::plugin::main::<Count>("count-report")
//! }
//! ```
//!
//! The launcher also runs it once before the group starts (`--check`), so bad params are
//! reported with nothing started (exit code 2). The [`bench`] module holds what Caravan's
//! benchmarks share (the machine, percentiles, result tables).

pub mod bench;
mod facts;
pub mod format;
pub mod fuzz;
mod locate;
pub mod plot;
pub mod plugin;
mod recording;
mod section;
pub mod seeds;
pub mod stats;
pub mod wilson;

pub use facts::{
    FACTS_FILE, HostFacts, Latency, ProcessRecord, RECORDING_FILE, RESOLVED_LAUNCH_FILE,
    ReportEntry, RunFacts, TopicCount, TopicCounter, Trend,
};
pub use locate::{find_program, latest_run_dir};
pub use plugin::{Inputs, ReportPlugin, Run};
pub use recording::{RecordedMessage, as_u64, guarded, read_all};
pub use section::{RESERVED, SECTIONS_DIR, Section, written};
