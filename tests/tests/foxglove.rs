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
