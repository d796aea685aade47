//! Where a process's or report plugin's program is: a bare name beside the `caravan` binary
//! (the workspace's target directory) or on PATH, a name with '/' relative to the launch file
//! that wrote it.

use std::path::{Path, PathBuf};

/// Where a bare executable name is found: beside the `caravan` binary (the workspace's
/// target directory), then on PATH.
pub fn resolve_exec(name: &str) -> Option<PathBuf> {
    caravan_report::find_program(name)
}

/// The program of a command line whose first word is `first`, written in a launch file in
/// `launch_dir`.
pub fn program(first: &str, launch_dir: &Path) -> PathBuf {
    if first.contains('/') {
        launch_dir.join(first)
    } else {
        resolve_exec(first).unwrap_or_else(|| PathBuf::from(first))
    }
}
