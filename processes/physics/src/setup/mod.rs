//! From params to a running simulation, with every input checked, in three steps:
//! [`check()`] the params, the world file and each robot description against its kind's spec;
//! [`place()`] each robot at its start pose on the world's floor; [`build()`] the bodies, which
//! tells whether a robot starts inside an obstacle or another robot. Errors are one
//! paragraph naming the file or key.

mod build;
pub mod check;
mod place;

pub use build::build;
pub use check::{Checked, Kind, check};
pub use place::{Start, place};

use crate::params::Params;
use crate::simulation::Simulation;
use std::fmt;
use std::path::Path;

/// Bad input; the message is meant for the author of the launch file.
#[derive(Debug, Clone, PartialEq)]
pub struct SetupError(pub String);

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SetupError {}

/// Loads the world and the robots named in `params` (paths relative to `launch_dir`) and
/// builds the simulation with physics step `dt_ns`: [`check()`], [`place()`], [`build()`].
pub fn load(params: &Params, launch_dir: &Path, dt_ns: u64) -> Result<Simulation, SetupError> {
    let checked = check(params, launch_dir)?;
    let starts = checked.place()?;
    build(&checked, &starts, params.sim_config(dt_ns))
}

/// The directory of the crate's test robots and their `empty.toml` world.
#[cfg(test)]
fn test_robots() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots")
}

/// `robots` in `empty.toml` of [`test_robots`], checked.
#[cfg(test)]
fn checked(robots: serde_json::Value) -> Result<Checked, SetupError> {
    let params = serde_json::json!({ "world": "empty.toml", "robots": robots });
    let params: Params = caravan::parse_params("physics", &params).unwrap();
    check(&params, &test_robots())
}
