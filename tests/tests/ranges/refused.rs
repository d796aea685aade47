//! A shipped launch file launched with one `--set` that puts a param out of its physical
//! range must be bad input refused before anything starts: exit 2, a message naming the key,
//! no panic, no run directory (so no recording) and no shared memory of the group.

use caravan_tests::{TestGroup, workspace_bin, workspace_root};
use std::process::Command;

/// Launches `launch/<file>` with `--set set` into a runs directory of its own and checks the
/// launch was refused before the start, naming `key`; returns what it said.
pub fn assert_refused_before_start(file: &str, set: &str, key: &str) -> String {
    let group = TestGroup::new("range");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(workspace_root().join("launch").join(file))
        // Short, so that a value let through does not run the whole scenario.
        .args(["--quiet", "--duration", "1s", "--set", set, "--set"])
        .arg(format!("group.name={}", group.name))
        .arg("--runs-dir")
        .arg(&runs)
        .output()
        .expect("run caravan launch");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let run_dirs = std::fs::read_dir(&runs).map_or(0, |d| d.count());
    let _ = std::fs::remove_dir_all(&runs);
    let prefix = caravan::group::prefix(&group.name);
    let shm: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&prefix))
        .collect();
    assert_eq!(out.status.code(), Some(2), "{set}: {err}");
    assert!(!err.contains("panicked"), "{set}: {err}");
    assert!(
        err.contains(&format!("key '{key}'")),
        "{set}: expected key '{key}' in: {err}"
    );
    assert_eq!(run_dirs, 0, "{set}: a run directory was made: {err}");
    assert!(shm.is_empty(), "{set}: {shm:?}");
    err
}
