//! Benchmarks run briefly and write their files. They assert nothing about time.

use caravan_tests::recording::{all_messages, assert_same_messages, read};
use caravan_tests::{children, wait_until, workspace_bin};
use std::collections::BTreeSet;
use std::process::Command;

const TRANSPORTS: [&str; 11] = [
    "caravan-event",
    "caravan-spin",
    "caravan-poll",
    "caravan-bridged",
    "iceoryx2-event",
    "iceoryx2-poll",
    "uds",
    "tcp",
    "udp",
    "zenoh",
    "zenoh-shm",
];

#[test]
fn bench_transport_quick_writes_csv_and_plot() {
    let out = std::env::temp_dir().join(format!("caravan-bench-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let child = Command::new(workspace_bin("caravan"))
        .args(["bench", "transport", "--quick", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot run caravan bench transport");
    let pid = child.id();
    let run = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "bench failed\nstdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );

    let csv = std::fs::read_to_string(out.join("transport.csv")).expect("transport.csv");
    let comments: Vec<&str> = csv.lines().filter(|l| l.starts_with('#')).collect();
    assert!(comments.iter().any(|l| l.starts_with("# cpu: ")), "{csv}");
    assert!(
        comments.iter().any(|l| l.starts_with("# kernel: ")),
        "{csv}"
    );
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("CSV header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (transport, bytes, p50, status, cpu) = (
        col("transport"),
        col("payload_bytes"),
        col("p50_ns"),
        col("status"),
        col("cpu_ns_per_message"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let sizes: BTreeSet<u64> = rows.iter().map(|r| r[bytes].parse().unwrap()).collect();
    assert!(sizes.contains(&16) && sizes.len() >= 2, "sizes {sizes:?}");
    for t in TRANSPORTS {
        for &size in &sizes {
            let row = rows
                .iter()
                .find(|r| r[transport] == t && r[bytes] == size.to_string())
                .unwrap_or_else(|| panic!("no row for {t} at {size} B\n{csv}"));
            // Only UDP may be unable to carry a payload (its socket buffer).
            if row[status] == "ok" || t != "udp" {
                assert_eq!(row[status], "ok", "{row:?}");
                assert!(row[p50].parse::<u64>().unwrap() > 0, "{row:?}");
                // Both sides run for every message, so each costs some CPU.
                assert!(row[cpu].parse::<f64>().unwrap() > 0.0, "{row:?}");
            } else {
                assert!(row[status].starts_with("unsupported"), "{row:?}");
            }
        }
    }
    assert_eq!(rows.len(), TRANSPORTS.len() * sizes.len(), "{csv}");

    let svg = std::fs::read_to_string(out.join("transport.svg")).expect("transport.svg");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for t in TRANSPORTS {
        assert!(svg.contains(t), "the plot's legend lacks {t}");
    }
    assert!(stdout.contains("kernel"), "{stdout}");
    // Every pair's shared memory is gone, both "hosts'" of the bridged one too.
    let left: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|name| name.starts_with(&format!("cvn_bt-{pid}-")))
        .collect();
    assert!(left.is_empty(), "left in /dev/shm: {left:?}");
    let _ = std::fs::remove_dir_all(&out);
}

/// A relays' process held off the CPU for longer than the launcher's 1 s lease (as on a loaded
/// machine) used to close the hosts' link and lose the message in flight, and the bench then
/// waited on its echo for good. The measurement must ride the stall out.
#[test]
fn bench_transport_bridged_rides_out_a_stalled_relay() {
    let out = std::env::temp_dir().join(format!("caravan-bench-stall-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let mut bench = Command::new(workspace_bin("caravan"))
        .args(["bench", "transport", "--transports", "caravan-bridged"])
        .args(["--sizes", "16", "--rounds", "5000", "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot run caravan bench transport");
    let command_line =
        |pid: i32| std::fs::read_to_string(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let (mut relays, mut pong) = (None, false);
    wait_until("the relays and the echoing side run", || {
        for pid in children(bench.id()) {
            let line = command_line(pid);
            relays = relays.or(line.contains("transport-relays").then_some(pid));
            pong |= line.contains("transport-pong");
        }
        relays.is_some() && pong
    });
    let relays = relays.expect("the relays' process");
    // Round trips are under way once the echoing side runs.
    std::thread::sleep(std::time::Duration::from_millis(500));
    // SAFETY: signalling a process this test's bench started.
    unsafe { libc::kill(relays, libc::SIGSTOP) };
    std::thread::sleep(std::time::Duration::from_secs(2));
    unsafe { libc::kill(relays, libc::SIGCONT) };
    assert!(
        bench.try_wait().unwrap().is_none(),
        "the bench ended before the stall was over: give it more rounds"
    );
    let run = bench.wait_with_output().unwrap();
    assert!(
        run.status.success(),
        "bench failed\nstdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = out.join("transport.csv");
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!(rows[0][csv_column(&csv, "status")], "ok", "{rows:?}");
    let _ = std::fs::remove_dir_all(&out);
}

/// Runs `caravan bench ARGS` (transport, wrapper) or, for the convoy's own benches (scale,
/// pipeline), `caravan-convoy-bench ARGS`.
fn run_bench(args: &[&str], out: &std::path::Path) -> String {
    let _ = std::fs::remove_dir_all(out);
    let mut cmd = match args[0] {
        "scale" | "pipeline" => Command::new(workspace_bin("caravan-convoy-bench")),
        _ => {
            let mut cmd = Command::new(workspace_bin("caravan"));
            cmd.arg("bench");
            cmd
        }
    };
    let run = cmd
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("cannot run caravan bench");
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(
        run.status.success(),
        "bench {args:?} failed\nstdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    stdout
}

/// The data rows of a bench CSV (comment lines and the header left out), split at commas.
fn csv_rows(path: &std::path::Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(text.lines().any(|l| l.starts_with("# cpu: ")), "{text}");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Where column `name` stands in a bench CSV's header.
fn csv_column(path: &std::path::Path, name: &str) -> usize {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header = text
        .lines()
        .find(|l| !l.starts_with('#'))
        .expect("a header");
    header
        .split(',')
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header}"))
}

#[test]
fn bench_transport_streams_with_several_messages_in_flight() {
    let out = std::env::temp_dir().join(format!("caravan-bench-window-{}", std::process::id()));
    let args = [
        "transport",
        "--quick",
        "--transports",
        "caravan-event,caravan-bridged,zenoh",
        "--sizes",
        "16,65536",
        "--in-flight",
        "8",
    ];
    run_bench(&args, &out);
    let csv = out.join("transport.csv");
    let [status, in_flight, throughput] =
        ["status", "in_flight", "throughput_bytes_per_s"].map(|name| csv_column(&csv, name));
    let rows = csv_rows(&csv);
    assert_eq!(rows.len(), 6, "{rows:?}");
    for row in &rows {
        assert_eq!(row[status], "ok", "{row:?}");
        assert_eq!(row[in_flight], "8", "{row:?}");
        let throughput: f64 = row[throughput].parse().unwrap();
        assert!(throughput > 0.0, "{row:?}");
    }
    let _ = std::fs::remove_dir_all(&out);
    // Transports that cannot stream are refused, before anything runs.
    let run = Command::new(workspace_bin("caravan"))
        .args([
            "bench",
            "transport",
            "--transports",
            "uds",
            "--in-flight",
            "4",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert_ne!(run.status.code(), Some(0), "{err}");
    assert!(
        err.contains("--in-flight 4") && err.contains("uds"),
        "{err}"
    );
    assert!(!out.join("transport.csv").exists());
}

#[test]
fn bench_scale_runs_each_clock_and_writes_its_table() {
    let out = std::env::temp_dir().join(format!("caravan-bench-scale-{}", std::process::id()));
    run_bench(&["scale", "--followers", "1,2", "--seconds", "2"], &out);
    let rows = csv_rows(&out.join("scale.csv"));
    let runs: BTreeSet<(String, String)> =
        rows.iter().map(|r| (r[0].clone(), r[1].clone())).collect();
    let expected: BTreeSet<(String, String)> = ["lockstep", "realtime"]
        .iter()
        .flat_map(|c| ["1", "2"].map(|n| (c.to_string(), n.to_string())))
        .collect();
    assert_eq!(runs, expected);
    for r in &rows {
        // Simulated time ran and every process was measured (physics, leader, followers).
        assert!(r[3].parse::<f64>().unwrap() > 1.0, "{r:?}");
        let followers: usize = r[1].parse().unwrap();
        assert_eq!(r[2].parse::<usize>().unwrap(), followers + 2, "{r:?}");
    }
    assert!(out.join("scale.md").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

/// `--team-states`: the agents read every robot's pose from the physics' one message per
/// step (`robots/state_true`, agent key `states_topic`) instead of each robot's `pose_true`.
/// They read the same poses, so the robots drive the same: the recorded set-points match.
/// And they read only that topic: the team run's file with a topic nobody publishes named
/// instead leaves every robot without a pose, and without a set-point.
#[test]
fn bench_scale_with_team_states_drives_as_with_each_robots_topic() {
    let mut unpublished = Vec::new();
    let mut setpoints = |team: bool| {
        let out =
            std::env::temp_dir().join(format!("caravan-bench-team-{team}-{}", std::process::id()));
        let mut args = vec!["scale", "--followers", "2", "--seconds", "3"];
        args.extend(["--clocks", "lockstep"]);
        if team {
            args.push("--team-states");
        }
        run_bench(&args, &out);
        let runs = out.join("scale-runs");
        let group = std::fs::read_dir(&runs).unwrap().next().unwrap().unwrap();
        let run = std::fs::read_dir(group.path().join("runs"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap();
        let launch = std::fs::read_to_string(group.path().join("launch.toml")).unwrap();
        assert_eq!(launch.contains("states_topic"), team, "{launch}");
        let messages = all_messages(&read(&run.path().join("record.mcap")));
        if team {
            let file = group.path().join("nobody.toml");
            let text = launch.replace("robots/state_true", "robots/nobody");
            std::fs::write(&file, text).unwrap();
            let runs = out.join("nobody-runs");
            let args = ["launch", file.to_str().unwrap(), "--quiet", "--runs-dir"];
            let ran = caravan_tests::caravan(&[&args[..], &[runs.to_str().unwrap()]].concat());
            assert!(ran.status.success(), "{ran:?}");
            let run = std::fs::read_dir(&runs).unwrap().next().unwrap().unwrap();
            unpublished = all_messages(&read(&run.path().join("record.mcap")));
        }
        let _ = std::fs::remove_dir_all(&out);
        messages
    };
    let (each, team) = (setpoints(false), setpoints(true));
    // The followers moved: some set-point is not zero.
    let moving = |m: &(u16, String, u64, Vec<u8>)| {
        let value: serde_json::Value = serde_json::from_slice(&m.3).unwrap();
        m.1 == "robot/2/wheel_setpoint" && value["left_rad_s"].as_f64().unwrap() != 0.0
    };
    assert!(each.iter().any(moving), "{each:?}");
    assert_same_messages(&each, &team);
    assert!(
        unpublished.iter().all(|m| !m.1.ends_with("wheel_setpoint")),
        "{unpublished:?}"
    );
}

#[test]
fn bench_pipeline_measures_every_hop_of_a_realtime_convoy() {
    let out = std::env::temp_dir().join(format!("caravan-bench-pipe-{}", std::process::id()));
    let launch = caravan_tests::workspace_root().join("launch/convoy/convoy.toml");
    run_bench(
        &[
            "pipeline",
            "--seconds",
            "6",
            "--launch",
            launch.to_str().unwrap(),
        ],
        &out,
    );
    let rows = csv_rows(&out.join("pipeline.csv"));
    let hops: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
    assert_eq!(
        hops,
        [
            "scan → pose",
            "pose → cmd_vel",
            "cmd_vel → wheel_setpoint",
            "scan → wheel_setpoint (total)"
        ]
    );
    for r in &rows {
        assert!(r[1].parse::<u64>().unwrap() > 0, "no samples: {r:?}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
