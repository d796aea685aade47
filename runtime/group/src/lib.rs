//! Running a group: start its processes, drive the lockstep schedule or the realtime
//! recorder, supervise them until the group ends, and write the run's facts and report; play a
//! recording into a group, re-simulate a node, look into a running group, and clean up after
//! one. Callable from Rust: [`launch::start`] runs a loaded launch file in this process.
//!
//! ```no_run
//! use caravan_group::launch::{RunOptions, start};
//! # fn main() -> anyhow::Result<()> {
//! let lf = caravan_group::launch::load_file("launch/pingpong.toml".as_ref(), &[])?;
//! let launched = start(lf, &RunOptions::new("runs"))?;
//! assert_eq!(launched.code, 0);
//! # Ok(())
//! # }
//! ```

pub mod bad_input;
mod bag;
pub mod clean;
pub mod graph;
pub mod info;
pub mod inject;
pub mod launch;
pub mod play;
mod recording;
pub mod report;
pub mod resim;
pub mod run;
pub mod signals;
pub mod watch;
