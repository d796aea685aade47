//! Where a process's or report plugin's program is: a bare name beside the `caravan` binary
//! (the workspace's target directory) or on PATH, a name with '/' relative to the launch file
//! that wrote it.

use std::path::{Path, PathBuf};

/// Where a bare executable name is found: beside the `caravan` binary (the workspace's
/// target directory), then on PATH.
pub fn resolve_exec(name: &str) -> Option<PathBuf> {
    let beside = std::env::current_exe().ok()?.parent()?.join(name);
    if beside.is_file() {
        return Some(beside);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
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
