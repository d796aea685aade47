//! `caravan launch` and the inspection commands, with real process groups.

use caravan_tests::{PINGPONG, Scenario, caravan, node, ping_pong, recording, wait_until};
use std::path::Path;
use std::process::Output;

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn lockstep_group_runs_records_and_reports() {
    let s = Scenario::new("pingpong", PINGPONG);
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "completed");
    assert_eq!(report["run"]["sim_time_s"], 10.0);
    assert!(report["run"]["real_time_factor"].as_f64().unwrap() > 0.0);
    assert_eq!(node(&report, "ping")["steps"], 101); // 0 s … 10 s inclusive at 10 Hz
    assert_eq!(node(&report, "sum")["steps"], 201);
    assert_eq!(node(&report, "pong")["steps"], 100); // one tick after each ping but the last
    assert_eq!(node(&report, "pong")["exit_status"], "exited 0");
    // The charts of the nodes' compute times and the topics' latencies, shown in report.md.
    let dir = &s.run_dirs()[0];
    let markdown = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for chart in ["nodes.svg", "topics.svg"] {
        let svg = std::fs::read_to_string(dir.join(chart)).unwrap();
        assert!(
            svg.contains(">ping<") || svg.contains(">demo/ping<"),
            "{chart}: {svg}"
        );
        assert!(markdown.contains(&format!("]({chart})")), "{markdown}");
    }
    assert!(
        s.shm_entries().is_empty(),
        "left behind: {:?}",
        s.shm_entries()
    );

    // The recording, read back with the mcap crate, holds what was published.
    let bytes = std::fs::read(s.run_dirs()[0].join("record.mcap")).unwrap();
    let mut ping = Vec::new();
    let mut pong = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.message_encoding != "json" {
            continue; // a Foxglove view (protobuf), checked in foxglove.rs
        }
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        assert_eq!(m.log_time, v["header"]["stamp_ns"].as_u64().unwrap());
        assert!(
            v["header"].get("send_wall_ns").is_none(),
            "lockstep recordings carry no wall clock"
        );
        match m.channel.topic.as_str() {
            "demo/ping" => ping.push((m.log_time, v["x"].as_f64().unwrap())),
            "demo/pong" => pong.push((m.log_time, v["x"].as_f64().unwrap())),
            _ => {}
        }
    }
    assert_eq!(ping.len(), 101);
    for (i, (t, x)) in ping.iter().enumerate() {
        assert_eq!((*t, *x), (i as u64 * 100_000_000, i as f64));
    }
    assert_eq!(pong.len(), 100);
    for (i, (t, x)) in pong.iter().enumerate() {
        // Stepped by ping i one tick (1 ms) later, doubling it.
        assert_eq!(
            (*t, *x),
            (i as u64 * 100_000_000 + 1_000_000, 2.0 * i as f64)
        );
    }

    // An indexed reader finds every channel in the summary, with its schema and count.
    let channels = recording::channels(&bytes);
    let ping = &channels["demo/ping"];
    assert_eq!((ping.encoding.as_str(), ping.messages), ("json", 101));
    assert_eq!(channels["demo/pong"].messages, 100);
    // The run's seed, command line and version, and the launch file it ran.
    let meta = recording::run_metadata(&bytes);
    assert_eq!(meta["seed"], "3");
    assert_eq!(meta["caravan_version"], env!("CARGO_PKG_VERSION"));
    assert!(meta["arguments"].starts_with("launch "), "{meta:?}");
    assert!(
        !meta.contains_key("wall_clock_start_ns"),
        "no wall clock in a lockstep recording"
    );
    let launch = recording::attachment(&bytes, "launch.toml");
    assert_eq!(
        launch,
        std::fs::read(s.run_dirs()[0].join("launch.toml")).unwrap()
    );
}

/// Loads both cores for as long as it lives: determinism must not depend on timing.
struct CpuLoad(
    Vec<std::thread::JoinHandle<()>>,
    std::sync::Arc<std::sync::atomic::AtomicBool>,
);

impl CpuLoad {
    fn start() -> Self {
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let threads = (0..2)
            .map(|_| {
                let stop = stop.clone();
                std::thread::spawn(move || {
                    let mut x = 0u64;
                    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                        x = std::hint::black_box(
                            x.wrapping_mul(6364136223846793005).wrapping_add(1),
                        );
                    }
                })
            })
            .collect();
        Self(threads, stop)
    }
}

impl Drop for CpuLoad {
    fn drop(&mut self) {
        self.1.store(true, std::sync::atomic::Ordering::Relaxed);
        for t in self.0.drain(..) {
            let _ = t.join();
        }
    }
}

#[test]
fn lockstep_reruns_are_byte_identical_under_cpu_load() {
    let s = Scenario::new("determinism", PINGPONG);
    let quiet = s.run(&["--duration", "5s"]);
    assert!(quiet.status.success(), "{}", stderr(&quiet));
    let loaded = {
        let _load = CpuLoad::start();
        s.run(&["--duration", "5s"])
    };
    assert!(loaded.status.success(), "{}", stderr(&loaded));
    let dirs = s.run_dirs();
    assert_eq!(dirs.len(), 2);
    let a = std::fs::read(dirs[0].join("record.mcap")).unwrap();
    let b = std::fs::read(dirs[1].join("record.mcap")).unwrap();
    assert!(a.len() > 1000);
    assert!(a == b, "recordings differ");
    // Identical with their summary index, which Foxglove uses to open a file without reading
    // all of it.
    assert!(recording::channels(&a).contains_key("demo/pong"));
}

#[test]
fn a_group_run_in_process_records_the_bytes_caravan_launch_records() {
    let s = Scenario::new("in-process", PINGPONG);
    let launched = s.run(&["--duration", "3s"]);
    assert!(launched.status.success(), "{}", stderr(&launched));
    // The workspace's programs, as the command finds them beside itself.
    let bin_dir = caravan_tests::workspace_bin("caravan-demo")
        .parent()
        .unwrap()
        .to_path_buf();
    let path = std::env::join_paths(
        std::iter::once(bin_dir).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap())),
    )
    .unwrap();
    // SAFETY: nextest runs each test in a process of its own, and no other thread of this one
    // reads the environment yet.
    unsafe { std::env::set_var("PATH", path) };
    let lf = caravan_group::launch::load_file(&s.file, &["group.duration=3s".into()]).unwrap();
    let mut options = caravan_group::launch::RunOptions::new(s.dir.join("runs"));
    options.quiet = true;
    // The recording keeps the command line it was made by; say it was the command's.
    let (file, runs) = (
        s.file.display().to_string(),
        s.dir.join("runs").display().to_string(),
    );
    let command = [
        "launch",
        &file,
        "--runs-dir",
        &runs,
        "--quiet",
        "--duration",
        "3s",
    ];
    options.arguments = command.map(String::from).to_vec();
    let run = caravan_group::launch::start(lf, &options).unwrap();
    assert_eq!(run.code, 0);
    let dir = run.dir.expect("a run directory");
    let dirs = s.run_dirs();
    assert_eq!(dirs.len(), 2);
    let by_command = std::fs::read(
        dirs.iter()
            .find(|d| **d != dir)
            .unwrap()
            .join("record.mcap"),
    );
    let in_process = std::fs::read(dir.join("record.mcap")).unwrap();
    assert!(recording::channels(&in_process).contains_key("demo/pong"));
    assert!(by_command.unwrap() == in_process, "recordings differ");
    assert!(dir.join("report.json").is_file());
}

/// A realtime group of a healthy node and one that exits with status 3 after two steps;
/// `policy` is appended to the crashing process's table.
fn crash_scenario(duration: &str, policy: &str) -> String {
    format!(
        "clock = \"realtime\"\nduration = \"{duration}\"\n\n[[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n\n\
         [[process]]\nname = \"crashy\"\nexec = \"caravan-demo crash\"\nparams = {{ steps = 2 }}\n{policy}"
    )
}

#[test]
fn optional_process_is_restarted_per_policy() {
    let s = Scenario::new(
        "restart",
        &crash_scenario(
            "6s",
            "restart = \"on-failure\"\nrestart_backoff = \"100ms\"\nmax_restarts = 2\nrequired = false\n",
        ),
    );
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(node(&report, "crashy")["restarts"], 2);
    assert_eq!(node(&report, "crashy")["exit_status"], "exited 3");
    assert_eq!(node(&report, "ping")["exit_status"], "exited 0");
    // It lost its state twice: the run is not the one the launch file describes.
    assert_eq!(report["run"]["outcome"], "degraded");
    let why = report["run"]["failure"].as_str().unwrap();
    assert!(why.contains("'crashy' (2×)"), "{why}");
}

#[test]
fn failed_required_process_fails_the_group() {
    let s = Scenario::new("required", &crash_scenario("20s", ""));
    let out = s.run(&[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("required process 'crashy' exited 3"),
        "{}",
        stderr(&out)
    );
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "failed");
    // Its peer was stopped cleanly, not killed.
    assert_eq!(node(&report, "ping")["exit_status"], "exited 0");
    assert!(s.shm_entries().is_empty());
}

#[test]
fn sigterm_stops_the_group_cleanly() {
    let s = Scenario::new("sigterm", PINGPONG);
    let child = s.start_realtime(4);
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "interrupted");
    for n in report["nodes"].as_array().unwrap() {
        // Each process handled SIGTERM within the grace period instead of being killed.
        assert_eq!(n["exit_status"], "exited 0", "{n}");
    }
    assert!(s.shm_entries().is_empty());
}

#[test]
fn kill_9_of_a_member_or_the_launcher_leaves_no_shared_memory() {
    // A member: the launcher notices, stops the group and cleans up.
    let s = Scenario::new("kill-member", PINGPONG);
    let child = s.start_realtime(4);
    let nodes = caravan(&["node", "list", "--group", &s.group.name]);
    let pong_pid: i32 = String::from_utf8_lossy(&nodes.stdout)
        .lines()
        .find(|l| l.starts_with("pong"))
        .and_then(|l| l.split_whitespace().last())
        .and_then(|p| p.parse().ok())
        .expect("pong's pid");
    // SAFETY: killing a process of the group under test.
    unsafe { libc::kill(pong_pid, libc::SIGKILL) };
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());

    // The launcher: its processes get SIGTERM from the kernel; `caravan clean` sweeps the rest.
    let s = Scenario::new("kill-launcher", PINGPONG);
    let mut child = s.start_realtime(4);
    child.kill().unwrap();
    child.wait().unwrap();
    wait_until("the group's processes are gone", || {
        let out = caravan(&["node", "list", "--group", &s.group.name]);
        String::from_utf8_lossy(&out.stdout).trim().is_empty()
    });
    assert!(
        caravan(&["clean", "--group", &s.group.name])
            .status
            .success()
    );
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// Runs `caravan launch` on a bad launch file and checks it failed as bad input, named where,
/// and started nothing.
fn assert_bad_input(s: &Scenario, extra: &[&str], expected: &[&str]) {
    let out = s.run(extra);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for e in expected {
        assert!(err.contains(e), "expected '{e}' in: {err}");
    }
    assert!(s.run_dirs().is_empty(), "a run directory was created");
    assert!(s.shm_entries().is_empty());
}

fn file_line(s: &Scenario, line: usize) -> String {
    format!("{}:{line}", s.file.display())
}

const ONE_PROCESS: &str =
    "clock = \"lockstep\"\n\n[[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n";

#[test]
fn typo_in_a_key_is_named_with_a_suggestion() {
    let s = Scenario::new("bad-key", &format!("{ONE_PROCESS}rat = \"10Hz\"\n"));
    assert_bad_input(&s, &[], &[&file_line(&s, 8), "rat", "rate"]);
}

#[test]
fn wrong_type_is_named() {
    let s = Scenario::new("bad-type", "seed = \"seven\"\n");
    assert_bad_input(&s, &[], &[&file_line(&s, 3), "seed"]);
}

#[test]
fn unknown_executable_is_rejected() {
    let s = Scenario::new(
        "bad-exec",
        "[[process]]\nname = \"x\"\nexec = \"no-such-program-here\"\n",
    );
    assert_bad_input(&s, &[], &[&file_line(&s, 5), "no-such-program-here"]);
}

#[test]
fn duplicate_process_names_are_rejected() {
    let s = Scenario::new(
        "bad-dup",
        &format!("{ONE_PROCESS}\n[[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n"),
    );
    assert_bad_input(&s, &[], &[&file_line(&s, 10), "ping"]);
}

#[test]
fn bad_duration_is_rejected() {
    let s = Scenario::new("bad-duration", "duration = \"ten seconds\"\n");
    assert_bad_input(&s, &[], &[&file_line(&s, 3), "duration"]);
}

#[test]
fn bad_rate_is_rejected() {
    let s = Scenario::new("bad-rate", &format!("{ONE_PROCESS}rate = \"fast\"\n"));
    assert_bad_input(&s, &[], &[&file_line(&s, 8), "rate"]);
}

#[test]
fn missing_launch_file_is_reported() {
    let s = Scenario::new("missing", "");
    std::fs::remove_file(&s.file).unwrap();
    assert_bad_input(&s, &[], &[&s.file.display().to_string()]);
}

#[test]
fn set_of_a_path_that_does_not_exist_is_rejected() {
    let s = Scenario::new("bad-set", ONE_PROCESS);
    assert_bad_input(&s, &["--set", "process.pnig.rate=5Hz"], &["pnig", "ping"]);
}

#[test]
fn unknown_host_is_rejected() {
    let s = Scenario::new(
        "bad-host",
        &format!("\n[hosts.rpi-0]\n{ONE_PROCESS}host = \"rpi-9\"\n"),
    );
    assert_bad_input(&s, &[], &["host", "rpi-9"]);
}

#[test]
fn rate_and_on_together_are_rejected() {
    let s = Scenario::new(
        "bad-trigger",
        &format!("{ONE_PROCESS}rate = \"10Hz\"\non = \"demo/x\"\n"),
    );
    assert_bad_input(&s, &[], &["rate", "on"]);
}

#[test]
fn report_is_recomputed_from_the_run_directory() {
    let s = Scenario::new("report", PINGPONG);
    assert!(s.run(&["--duration", "2s"]).status.success());
    let dir = s.run_dirs().pop().unwrap();
    let before = s.report();
    std::fs::remove_file(dir.join("report.json")).unwrap();
    let out = caravan(&["report", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(s.report(), before);
    assert!(Path::new(&dir.join("report.md")).exists());
}

/// A group of a healthy node and one that hangs in its step after `count` steps, with a 1–2 s
/// step timeout: the launcher kills the hung one, names it, and the group goes on.
fn assert_hang_is_handled(tag: &str, clock: &str, duration: &str, count: u32) -> serde_json::Value {
    let s = Scenario::new(
        tag,
        &format!(
            "clock = \"{clock}\"\nduration = \"{duration}\"\nstep_timeout = \"2s\"\n\n\
             [[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n\n\
             [[process]]\nname = \"stuck\"\nexec = \"caravan-testnode hang\"\n\
             params = {{ count = {count} }}\nrequired = false\n"
        ),
    );
    let out = s.run(&[]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("process 'stuck' has not finished a step") && err.contains("hung"),
        "{err}"
    );
    let report = s.report();
    assert_eq!(node(&report, "stuck")["exit_status"], "killed by signal 9");
    assert_eq!(node(&report, "ping")["exit_status"], "exited 0");
    assert_eq!(report["run"]["outcome"], "completed");
    report
}

#[test]
fn hung_lockstep_process_is_killed_and_named() {
    let report = assert_hang_is_handled("hang", "lockstep", "5s", 3);
    // Simulated time went on without it.
    assert_eq!(node(&report, "ping")["steps"], 51);
}

#[test]
fn hung_realtime_process_is_killed_and_named() {
    assert_hang_is_handled("hang-rt", "realtime", "8s", 15);
}

#[test]
fn mismatched_message_type_is_reported_and_tolerated_when_optional() {
    let s = Scenario::new(
        "mismatch",
        r#"clock = "realtime"
duration = "3s"

[[process]]
name = "ping"
exec = "caravan-demo ping"

[[process]]
name = "impostor"
exec = "caravan-testnode wrong-type"
params = { topic = "demo/ping", count = 700 }
required = false
"#,
    );
    let out = s.run(&[]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("process 'impostor' exited 1")
            && err.contains("'demo/ping'")
            && err.contains("caravan::WheelSetpoint")
            && err.contains("different message type"),
        "{err}"
    );
    assert_eq!(node(&s.report(), "ping")["exit_status"], "exited 0");
}

/// Included by the tests below (ping and pong); line numbers refer to it.
fn base() -> String {
    format!("[group]\nname = \"base\"\n{}", ping_pong())
}

/// A file that includes `base()` (changing it with `set`) and adds three templated processes.
const INCLUDING: &str = r#"duration = "2s"

[[include]]
file = "base.toml"
set = ["process.ping.rate=20Hz"]

[[process]]
name = "noise-{i}"
for = "i in 0..3"
exec = "caravan-demo noise"
rate = "7Hz"
"#;

#[test]
fn a_process_that_ends_the_group_completes_the_run_early() {
    // 20 steps at 10 Hz: the counter exits at 1.9 s of a 100 s run, and takes the group with it.
    let s = Scenario::new(
        "ends",
        r#"clock = "lockstep"
duration = "100s"

[[process]]
name = "counter"
exec = "caravan-testnode steps"
rate = "10Hz"
ends_group = true
params = { count = 20 }

[[process]]
name = "idle"
exec = "caravan-testnode idle"
rate = "10Hz"
"#,
    );
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("ended the group"), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "completed");
    let t = report["run"]["sim_time_s"].as_f64().unwrap();
    assert!((1.9..=2.0).contains(&t), "{t}");
    assert_eq!(node(&report, "counter")["steps"], 20);
}

#[test]
fn included_files_and_templates_run_as_one_group() {
    let s = Scenario::new("include", INCLUDING);
    std::fs::write(s.dir.join("base.toml"), base()).unwrap();
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "completed");
    assert_eq!(report["run"]["sim_time_s"], 2.0);
    let mut names: Vec<&str> = report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["name"].as_str().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["noise-0", "noise-1", "noise-2", "ping", "pong"]);
    // The include's `set` reached the included process: 20 Hz for 2 s, both ends included.
    assert_eq!(node(&report, "ping")["steps"], 41);
    for n in ["noise-0", "noise-1", "noise-2", "pong"] {
        assert_eq!(node(&report, n)["exit_status"], "exited 0", "{n}");
    }
}

#[test]
fn error_in_an_included_file_names_that_file_and_line() {
    let s = Scenario::new("include-bad", INCLUDING);
    let file = s.dir.join("base.toml");
    let bad = base().replace("gain = 2.0 }", "gain = 2.0 }\nrestart = \"sometimes\"");
    std::fs::write(&file, bad).unwrap();
    assert_bad_input(
        &s,
        &[],
        &[
            &format!("{}:18: process 'pong', key 'restart'", file.display()),
            "'sometimes' is not a restart policy",
        ],
    );
}

#[path = "launch/counts.rs"]
mod counts;
