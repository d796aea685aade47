//! Finding things a run leaves and a tool needs: the newest run directory the launcher
//! created, and a Caravan program.

use std::path::{Path, PathBuf};

/// The newest run directory in `runs` (the launcher names them `<group>-<UTC time>[-n]`, so
/// the last in name order is the latest), if there is one.
pub fn latest_run_dir(runs: &Path) -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(runs)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    dirs.pop()
}

/// A program by bare name: beside the running executable (the workspace's target directory
/// holds every Caravan binary), then on PATH.
pub fn find_program(name: &str) -> Option<PathBuf> {
    let beside = std::env::current_exe().ok()?.with_file_name(name);
    if beside.is_file() {
        return Some(beside);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
}
