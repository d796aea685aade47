//! Recordings read the way the Foxglove app reads them: its MCAP reader, its protobuf schema
//! parser and the official JSON schemas of its messages, run with Node (`tests/node/`).

use caravan_tests::{Scenario, node, realtime_ping_pong, run_convoy_with};
use serde_json::Value;

fn assert_no_errors(verdict: &Value) {
    let errors = verdict["errors"].as_array().expect("a verdict");
    assert!(errors.is_empty(), "{:#}", verdict["errors"]);
}

fn messages(verdict: &Value, topic: &str) -> u64 {
    verdict["channels"][topic]["messages"]
        .as_u64()
        .unwrap_or_else(|| panic!("no channel {topic}: {}", verdict["channels"]))
}

#[test]
fn a_convoy_recording_opens_in_foxglove_with_valid_scene_messages() {
    let run = run_convoy_with("convoy.toml", "12s", &[]);
    let verdict = node::check_recording(&run.dir.join("record.mcap"));
    assert_no_errors(&verdict);
    for (topic, schema) in [
        ("tf", "foxglove.FrameTransforms"),
        ("foxglove/robot/0/scan", "foxglove.LaserScan"),
        ("foxglove/map", "foxglove.Grid"),
        ("foxglove/robot/0/path", "foxglove.PosesInFrame"),
        ("foxglove/robot/4/pose", "foxglove.PoseInFrame"),
        ("robot/0/scan", "caravan::LaserScan"),
        ("map", "caravan::OccupancyGrid"),
        ("foxglove/scene", "foxglove.SceneUpdate"),
        ("scene", "caravan::Scene"),
    ] {
        assert_eq!(verdict["channels"][topic]["schema"], schema, "{topic}");
        assert!(messages(&verdict, topic) > 0, "{topic} has no messages");
    }
    // Recorded from the start, though nothing collided.
    assert_eq!(messages(&verdict, "collisions"), 0);
}

#[test]
fn a_realtime_recording_opens_in_foxglove() {
    let s = Scenario::new("foxglove-rt", &realtime_ping_pong("2s"));
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let verdict = node::check_recording(&s.run_dirs()[0].join("record.mcap"));
    assert_no_errors(&verdict);
    assert!(messages(&verdict, "demo/ping") > 5);
}

#[test]
fn info_on_a_file_that_is_not_a_recording_names_it_and_fails() {
    let dir = std::env::temp_dir().join(format!("caravan-info-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = dir.join("notes.mcap");
    std::fs::write(&text, "not a recording").unwrap();
    for (path, expected) in [
        (text.clone(), "is not an MCAP file"),
        (dir.join("missing.mcap"), "cannot read"),
    ] {
        let out = caravan_tests::caravan(&["info", path.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(
            err.contains(expected) && err.contains(path.to_str().unwrap()),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The convoy served live with `--foxglove PORT` in `clock`; a Foxglove WebSocket client
/// subscribes to everything and must get the laser scan (raw and Foxglove) and the transforms,
/// each message valid against its schema. Then the group stops cleanly.
fn live_convoy_reaches_a_foxglove_client(clock: &str) {
    let group = caravan_tests::TestGroup::new(&format!("live-{clock}"));
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let port = node::free_port();
    let launcher = std::process::Command::new(caravan_tests::workspace_bin("caravan"))
        .arg("launch")
        .arg(caravan_tests::workspace_root().join("launch/convoy/convoy.toml"))
        .args([
            "--quiet",
            "--clock",
            clock,
            "--duration",
            "10min",
            "--foxglove",
        ])
        .arg(port.to_string())
        .args(["--set", &format!("group.name={}", group.name)])
        .arg("--runs-dir")
        .arg(&runs)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let verdict = node::check_live(
        &format!("ws://127.0.0.1:{port}"),
        120,
        &[
            "tf",
            "foxglove/robot/0/scan",
            "robot/0/scan",
            "foxglove/robot/1/pose",
        ],
    );
    // SAFETY: signalling our own child.
    unsafe { libc::kill(launcher.id() as i32, libc::SIGINT) };
    let out = launcher.wait_with_output().unwrap();
    assert_no_errors(&verdict);
    assert_eq!(
        verdict["server"]["capabilities"],
        serde_json::json!(["time"])
    );
    assert_eq!(
        verdict["channels"]["tf"]["schema"],
        "foxglove.FrameTransforms"
    );
    assert_eq!(verdict["channels"]["robot/0/scan"]["encoding"], "json");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let prefix = caravan::group::prefix(&group.name);
    let left: Vec<_> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_live_realtime_convoy_reaches_a_foxglove_websocket_client() {
    live_convoy_reaches_a_foxglove_client("realtime");
}

#[test]
fn a_live_lockstep_convoy_reaches_a_foxglove_websocket_client() {
    live_convoy_reaches_a_foxglove_client("lockstep");
}

#[test]
fn a_taken_foxglove_port_is_bad_input_and_starts_nothing() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let s = Scenario::new("live-taken", &realtime_ping_pong("2s"));
    let out = s.run(&["--foxglove", &port]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "--foxglove {port}: cannot serve on 127.0.0.1:{port}"
        )),
        "{err}"
    );
    assert!(s.run_dirs().is_empty(), "no run directory is made");
}
