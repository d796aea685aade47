//! Foxglove's own readers, run with Node (`tests/node/`): the MCAP reader and protobuf parser
//! the Foxglove app uses and the official JSON schemas of its messages. The packages are
//! installed into `tests/node/node_modules` on first use, pinned by `package-lock.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn node_dir() -> PathBuf {
    crate::workspace_root().join("tests/node")
}

/// Installs the pinned packages once, whichever test asks first (a file lock keeps parallel
/// tests from installing twice).
fn ensure_installed() {
    let dir = node_dir();
    let lock = std::fs::File::create(dir.join(".install.lock")).expect("create the install lock");
    // SAFETY: flock on a file descriptor this function owns; released when `lock` drops.
    let locked = unsafe { libc::flock(std::os::fd::AsRawFd::as_raw_fd(&lock), libc::LOCK_EX) };
    assert_eq!(locked, 0, "cannot lock {}", dir.display());
    // The lock file as installed: a changed lock installs again.
    let stamp = dir.join("node_modules/.caravan-installed-lock.json");
    let wanted =
        std::fs::read(dir.join("package-lock.json")).expect("tests/node/package-lock.json");
    if std::fs::read(&stamp).is_ok_and(|installed| installed == wanted) {
        return;
    }
    let out = Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund"])
        .current_dir(&dir)
        .output()
        .expect("npm is needed for the Foxglove reader tests (Node 20 with npm)");
    assert!(
        out.status.success(),
        "npm ci in {} failed: {}",
        dir.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::write(&stamp, wanted).expect("write the install stamp");
}

/// Reads a live group the way the Foxglove app does (`check-live.mjs`, the
/// `@foxglove/ws-protocol` client): connects to `url` (retrying until it listens), subscribes
/// to every channel, and returns when each of `topics` delivered a message or `seconds` passed.
/// The verdict is `{server, channels: {topic: {schema, encoding, messages}}, errors: [...]}`.
pub fn check_live(url: &str, seconds: u32, topics: &[&str]) -> serde_json::Value {
    verdict(
        "check-live.mjs",
        &[url, &seconds.to_string(), &topics.join(",")],
    )
}

/// Runs one of the checking scripts with `args` and parses the JSON line it prints; panics,
/// with its output, if it printed none.
fn verdict<S: AsRef<std::ffi::OsStr>>(script: &str, args: &[S]) -> serde_json::Value {
    ensure_installed();
    let out = Command::new("node")
        .arg(node_dir().join(script))
        .args(args)
        .output()
        .expect("run node");
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.trim()).unwrap_or_else(|_| {
        panic!(
            "{script} gave no verdict: {stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// A TCP port on loopback that was free a moment ago, for a server under test.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("bind a free port")
        .port()
}

/// Reads `mcap` as Foxglove does (`check-recording.mjs`): returns its JSON verdict
/// `{channels: {topic: {schema, encoding, messages}}, errors: [...]}`; panics if Node cannot
/// read the file at all.
pub fn check_recording(mcap: &Path) -> serde_json::Value {
    verdict("check-recording.mjs", &[mcap])
}
