//! Helpers for Caravan's multi-process integration tests.

pub mod hosts;
pub mod node;
pub mod recording;
pub mod ros2;
pub mod slurm;
pub mod sweep;

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
///
/// Under nextest every test is a process of its own; one build per run is enough (sources do
/// not change during a run). The first test of a run (`NEXTEST_RUN_ID`) to get here builds,
/// under a file lock, and leaves a marker; the others only wait for the lock. Before, every
/// test ran `cargo build` and queued on cargo's lock: a 2 s host test waited up to 170 s
/// while anything else built, and ran into its time limit.
pub fn workspace_bin(name: &str) -> std::path::PathBuf {
    static BUILD: std::sync::Once = std::sync::Once::new();
    let exe = std::env::current_exe().expect("test executable path");
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target layout");
    BUILD.call_once(|| build_once_per_run(profile_dir));
    let path = profile_dir.join(name);
    assert!(
        path.exists(),
        "{} is not built; run the tests with `cargo nextest run --workspace`",
        path.display()
    );
    path
}

/// Builds the workspace's binaries, once per nextest run (see [`workspace_bin`]).
fn build_once_per_run(profile_dir: &std::path::Path) {
    use std::os::fd::AsRawFd;
    let Ok(run) = std::env::var("NEXTEST_RUN_ID") else {
        return build_binaries(profile_dir);
    };
    let lock = std::fs::File::create(profile_dir.join(".caravan-bins.lock"))
        .expect("create the binaries' build lock");
    // SAFETY: flock(2) on a file this function holds open; released when it is dropped.
    unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_EX) };
    let marker = profile_dir.join(".caravan-bins.run");
    if std::fs::read_to_string(&marker).is_ok_and(|built| built == run) {
        return;
    }
    build_binaries(profile_dir);
    std::fs::write(&marker, &run).expect("write the binaries' build marker");
}

fn build_binaries(profile_dir: &std::path::Path) {
    {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "--quiet", "--workspace", "--bins"]);
        if profile_dir.file_name().is_some_and(|n| n == "release") {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("cannot run cargo build");
        assert!(status.success(), "building the workspace binaries failed");
    }
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

/// The workspace's root directory (the parent of `tests/`).
pub fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ lies inside the workspace")
        .to_path_buf()
}

/// A finished scenario run: its report and run directory (removed when dropped).
pub struct ScenarioRun {
    /// `report.json`, parsed.
    pub report: serde_json::Value,
    /// The run directory.
    pub dir: std::path::PathBuf,
    runs: std::path::PathBuf,
}

impl Drop for ScenarioRun {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.runs);
    }
}

/// Runs `launch/<scenario>/<file>` with `extra` arguments for `caravan launch`, under a
/// unique group name, into a temporary runs directory; panics with the launcher's output
/// unless the run completes.
pub fn run_scenario(scenario: &str, file: &str, extra: &[&str]) -> ScenarioRun {
    let group = TestGroup::new(scenario);
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(workspace_root().join("launch").join(scenario).join(file))
        .args(["--runs-dir".as_ref(), runs.as_os_str()])
        .args(["--quiet", "--set"])
        .arg(format!("group.name={}", group.name))
        .args(extra)
        .output()
        .unwrap();
    let dir = std::fs::read_dir(&runs)
        .ok()
        .and_then(|mut d| d.next())
        .map(|e| e.unwrap().path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = dir.expect("a run directory");
    let report = std::fs::read_to_string(dir.join("report.json")).unwrap();
    ScenarioRun {
        report: serde_json::from_str(&report).unwrap(),
        dir,
        runs,
    }
}

/// Runs `launch/<file>` for `duration` with `--set set`, under a unique group name, into a
/// runs directory removed afterwards; returns the exit code (-1 if killed) and stderr. For
/// tests of bad input.
pub fn launch_with_set(file: &str, duration: &str, set: &str) -> (i32, String) {
    launch_with_sets(file, duration, &[set])
}

/// [`launch_with_set`] with several `--set`s, applied in order.
pub fn launch_with_sets(file: &str, duration: &str, sets: &[&str]) -> (i32, String) {
    let group = TestGroup::new("bad");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(workspace_root().join("launch").join(file))
        .args(["--quiet", "--duration", duration])
        .args(sets.iter().flat_map(|s| ["--set", s]))
        .arg("--set")
        .arg(format!("group.name={}", group.name))
        .arg("--runs-dir")
        .arg(&runs)
        .output()
        .expect("run caravan launch");
    let _ = std::fs::remove_dir_all(&runs);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The interpreter of `<workspace>/.venv`, the environment Python agents run in. The first
/// call has `python/caravan-python --setup` create it (with the iceoryx2, mcap and zstandard
/// packages from the package registry), the same set-up a launch file's Python agent gets on first use; it is
/// safe when several test processes call it at once.
pub fn python_env() -> std::path::PathBuf {
    let root = workspace_root();
    let out = Command::new(root.join("python/caravan-python"))
        .arg("--setup")
        .stdin(Stdio::null())
        .output()
        .expect("cannot run python/caravan-python");
    assert!(
        out.status.success(),
        "python/caravan-python --setup failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    root.join(".venv/bin/python")
}

/// A finished lockstep convoy run; its run directory is removed when this is dropped.
pub struct ConvoyRun {
    /// The run directory (logs, report, recording).
    pub dir: std::path::PathBuf,
    pub report: serde_json::Value,
    runs: std::path::PathBuf,
    _group: TestGroup,
}

impl Drop for ConvoyRun {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.runs);
    }
}

/// Runs `launch/convoy/<file>` for 70 simulated seconds (the leader reaches D after about 47 s and
/// the followers line up behind it) under a unique group name; panics if the launch fails.
pub fn run_convoy(file: &str) -> ConvoyRun {
    run_convoy_with(file, "70s", &[])
}

/// Runs `launch/convoy/<file>` for `duration` of simulated time with extra `--set` overrides.
pub fn run_convoy_with(file: &str, duration: &str, sets: &[&str]) -> ConvoyRun {
    let group = TestGroup::new("convoy");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let mut cmd = Command::new(workspace_bin("caravan"));
    cmd.arg("launch")
        .arg(workspace_root().join("launch/convoy").join(file));
    for set in sets {
        cmd.args(["--set", set]);
    }
    let out = cmd
        .args([
            "--quiet",
            "--duration",
            duration,
            "--set",
            &format!("group.name={}", group.name),
        ])
        .arg("--runs-dir")
        .arg(&runs)
        .env_remove("CARAVAN_PYTHON")
        .output()
        .expect("run caravan launch");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = std::fs::read_dir(&runs)
        .unwrap()
        .flatten()
        .next()
        .unwrap()
        .path();
    let report =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    ConvoyRun {
        dir,
        report,
        runs,
        _group: group,
    }
}

/// The convoy succeeded: every goal reached, gaps kept, no collision, order kept.
pub fn assert_convoy_succeeded(c: &serde_json::Value) {
    assert_eq!(c["robots"], 5, "{c}");
    assert_eq!(c["goals_total"], 4, "{c}");
    assert_eq!(c["goals_reached"], 4, "{c}");
    assert!(c["min_gap_m"].as_f64().unwrap() >= 0.15, "{c}");
    assert_eq!(c["collisions"], 0, "{c}");
    assert_eq!(c["order_kept"], true, "{c}");
    assert_eq!(c["followers"].as_array().unwrap().len(), 4, "{c}");
}

/// A launch file written for one test, run under a unique group name, with its runs in a
/// temporary directory removed afterwards.
pub struct Scenario {
    pub group: TestGroup,
    pub dir: std::path::PathBuf,
    pub file: std::path::PathBuf,
}

impl Scenario {
    /// `body` is the launch file after its `[group]` header line and name.
    pub fn new(tag: &str, body: &str) -> Self {
        let group = TestGroup::new(tag);
        let dir = std::env::temp_dir().join(format!("caravan-{}", group.name));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("launch.toml");
        std::fs::write(&file, format!("[group]\nname = \"{}\"\n{body}", group.name)).unwrap();
        Self { group, dir, file }
    }

    pub fn command(&self, extra: &[&str]) -> std::process::Command {
        let mut cmd = std::process::Command::new(workspace_bin("caravan"));
        cmd.arg("launch")
            .arg(&self.file)
            .arg("--runs-dir")
            .arg(self.dir.join("runs"))
            .arg("--quiet")
            .args(extra);
        cmd
    }

    pub fn run(&self, extra: &[&str]) -> std::process::Output {
        self.command(extra).output().unwrap()
    }

    /// Starts the group in realtime for ten minutes and returns once `nodes` of its processes
    /// have joined (the launcher not counted).
    pub fn start_realtime(&self, nodes: usize) -> Child {
        let child = self
            .command(&["--clock", "realtime", "--duration", "10min"])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        wait_until("the group's nodes run", || {
            let out = caravan(&["node", "list", "--group", &self.group.name]);
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .filter(|l| !l.starts_with("(launcher)"))
                .count()
                >= nodes
        });
        child
    }

    pub fn run_dirs(&self) -> Vec<std::path::PathBuf> {
        let mut dirs: Vec<std::path::PathBuf> = std::fs::read_dir(self.dir.join("runs"))
            .map(|rd| rd.flatten().map(|e| e.path()).collect())
            .unwrap_or_default();
        dirs.sort();
        dirs
    }

    pub fn report(&self) -> serde_json::Value {
        let dir = self.run_dirs().pop().expect("a run directory");
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
    }

    pub fn shm_entries(&self) -> Vec<String> {
        let prefix = caravan::group::prefix(&self.group.name);
        std::fs::read_dir("/dev/shm")
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with(&prefix))
            .collect()
    }
}

impl Drop for Scenario {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// A demo group after its `[group]` name: 10 s of lockstep, `ping` at 10 Hz, `pong` on each
/// ping (gain 2), `sum` at 20 Hz and `noise` at 7 Hz, recording `demo/*`.
pub const PINGPONG: &str = r#"clock = "lockstep"
duration = "10s"
seed = 3
record = ["demo/*"]

[[process]]
name = "ping"
exec = "caravan-demo ping"
rate = "10Hz"

[[process]]
name = "pong"
exec = "caravan-demo pong"
on = "demo/ping"
params = { gain = 2.0 }

[[process]]
name = "sum"
exec = "caravan-demo sum"
rate = "20Hz"

[[process]]
name = "noise"
exec = "caravan-demo noise"
rate = "7Hz"
"#;

/// [`PINGPONG`] with only its `ping` and `pong` processes.
pub fn ping_pong() -> &'static str {
    let end = PINGPONG
        .find("\n[[process]]\nname = \"sum\"")
        .expect("PINGPONG has a sum process");
    &PINGPONG[..end + 1]
}

/// [`ping_pong`] under the realtime clock, for `duration` of wall time.
pub fn realtime_ping_pong(duration: &str) -> String {
    let body = ping_pong()
        .strip_prefix("clock = \"lockstep\"\nduration = \"10s\"\n")
        .expect("PINGPONG starts with its clock and duration");
    format!("clock = \"realtime\"\nduration = \"{duration}\"\n{body}")
}

/// Polls `cond` every 100 ms until it holds; panics naming `what` after 30 s. Polling with
/// sleeps is fine in a test helper: nothing asserts how long it takes.
pub fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    for _ in 0..300 {
        if cond() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    panic!("timed out waiting until {what}");
}

/// Runs the `caravan` command with `args`.
/// The row of node `name` in a run report's `nodes`; panics naming it if there is none.
pub fn node<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == name)
        .unwrap_or_else(|| panic!("no node '{name}' in {report}"))
}

pub fn caravan(args: &[&str]) -> std::process::Output {
    Command::new(workspace_bin("caravan"))
        .args(args)
        .output()
        .expect("run caravan")
}

/// Checks `out` is bad input: exit 2, every `expected` text in its message, no panic, and no
/// run directory or shared memory of the group made.
pub fn assert_refused(s: &Scenario, out: &std::process::Output, expected: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expected {
        assert!(err.contains(e), "expected '{e}' in: {err}");
    }
    assert!(s.run_dirs().is_empty(), "a run directory was made: {err}");
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// Whether process `pid` is alive (a zombie has exited; only its parent's wait is missing).
pub fn alive(pid: i32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        !stat
            .rsplit(')')
            .next()
            .unwrap_or("")
            .trim_start()
            .starts_with('Z')
    })
}

/// The children of `pid`, whichever of its threads started them (from /proc).
pub fn children(pid: u32) -> Vec<i32> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task"))
        .into_iter()
        .flatten();
    tasks
        .flatten()
        .flat_map(|t| {
            let list = std::fs::read_to_string(t.path().join("children")).unwrap_or_default();
            list.split_whitespace()
                .filter_map(|p| p.parse().ok())
                .collect::<Vec<i32>>()
        })
        .collect()
}
