//! The convoy's benchmarks, each a real `caravan launch` of convoy groups:
//! - `scale`: a leader and N followers in lockstep and realtime (real-time factor, CPU per
//!   simulated second, jitter, latency);
//! - `pipeline`: a realtime convoy's latency from a laser scan to the wheel set-point it
//!   caused, per hop.

pub mod pipeline;
pub mod scale;

use anyhow::{Result, anyhow};
use std::path::PathBuf;

/// The `caravan` launcher: beside this program (the workspace's target directory), else on
/// PATH.
pub fn caravan() -> Result<PathBuf> {
    caravan_report::find_program("caravan")
        .ok_or_else(|| anyhow!("cannot find the caravan launcher beside this program or on PATH"))
}
