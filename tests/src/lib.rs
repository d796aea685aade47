//! Helpers for Caravan's multi-process integration tests.

use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};

/// A unique group that removes its shared memory when dropped, so tests leave nothing behind.
pub struct TestGroup {
    pub name: String,
}

impl TestGroup {
    pub fn new(tag: &str) -> Self {
        Self {
            name: unique_group(tag),
        }
    }
}

impl Drop for TestGroup {
    fn drop(&mut self) {
        let _ = caravan::group::remove_resources(&self.name);
    }
}

/// A group name no other test (or concurrent test run) uses.
pub fn unique_group(tag: &str) -> String {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    format!("t-{tag}-{}-{n}", std::process::id())
}

/// Path of a binary built in this workspace's target directory, beside the test executable
/// (`target/<profile>/deps/<test>` → `target/<profile>/<name>`).
///
/// Cargo builds only the test package's own binaries for its tests, so the first call builds
/// every workspace binary (a no-op when they are fresh) so tests never run stale launchers.
pub fn workspace_bin(name: &str) -> std::path::PathBuf {
    static BUILD: std::sync::Once = std::sync::Once::new();
    let exe = std::env::current_exe().expect("test executable path");
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target layout");
    BUILD.call_once(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "--quiet", "--workspace", "--bins"]);
        if profile_dir.file_name().is_some_and(|n| n == "release") {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("cannot run cargo build");
        assert!(status.success(), "building the workspace binaries failed");
    });
    let path = profile_dir.join(name);
    assert!(
        path.exists(),
        "{} is not built; run the tests with `cargo nextest run --workspace`",
        path.display()
    );
    path
}

/// Command for the test node binary, set up as a node of `group`.
pub fn test_node(group: &str, name: &str, mode: &str, params: serde_json::Value) -> Command {
    let mut cmd = Command::new(workspace_bin("caravan-testnode"));
    cmd.arg(mode)
        .env("CARAVAN_GROUP", group)
        .env("CARAVAN_NODE", name)
        .env("CARAVAN_PARAMS", params.to_string())
        .stdin(Stdio::null());
    cmd
}

/// CPU time (user + system) a reaped child used, from wait4's rusage.
pub fn wait_with_cpu(child: &mut Child) -> (i32, std::time::Duration) {
    let mut status = 0;
    // SAFETY: rusage is plain data that wait4 fills in.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    // SAFETY: waits for our own child; status and usage are valid out-pointers.
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(r, pid, "wait4 failed");
    let tv = |t: libc::timeval| std::time::Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
    let code = if libc::WIFEXITED(status) {
        libc::WEXITSTATUS(status)
    } else {
        -1
    };
    (code, tv(usage.ru_utime) + tv(usage.ru_stime))
}

/// Sends SIGTERM to a child.
pub fn terminate(child: &Child) {
    // SAFETY: signalling our own child process.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
}
