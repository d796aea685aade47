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
    assert_live_measures_agree_with_the_report(&run);
    // The shipped layout shows what the recording holds.
    let layout = caravan_tests::workspace_root().join("launch/convoy/foxglove-layout.json");
    let mut topics = Vec::new();
    layout_topics(
        &serde_json::from_str(&std::fs::read_to_string(layout).unwrap()).unwrap(),
        &mut topics,
    );
    for topic in topics {
        let shown = if verdict["channels"][format!("foxglove/{topic}")].is_object() {
            format!("foxglove/{topic}")
        } else {
            topic
        };
        assert!(
            messages(&verdict, &shown) > 0,
            "the layout shows {shown}, which has no messages"
        );
    }
}

/// The monitor's gaps (10 Hz, live) agree with the report's (every physics stamp, after
/// the run): its smallest is the report's, or a little larger for sampling less often.
fn assert_live_measures_agree_with_the_report(run: &caravan_tests::ConvoyRun) {
    let recorded = caravan_report::read_all(&run.dir.join("record.mcap")).unwrap();
    let metrics: Vec<&Value> = recorded
        .iter()
        .filter(|m| m.topic == "convoy/metrics")
        .map(|m| &m.json)
        .collect();
    assert!(metrics.len() >= 100, "{} metrics messages", metrics.len());
    let value = |m: &Value, name: &str| {
        m["values"]
            .as_array()
            .unwrap()
            .iter()
            .find(|v| v["name"] == name)
            .and_then(|v| v["value"].as_f64())
            .unwrap_or_else(|| panic!("no {name} in {m}"))
    };
    for m in &metrics {
        assert_eq!(m["values"].as_array().unwrap().len(), 9, "{m}");
        for i in 1..5 {
            assert!(
                value(m, &format!("gap_{i}_m")) >= value(m, "min_gap_m"),
                "{m}"
            );
            assert!(value(m, &format!("cross_track_{i}_m")) < 0.5, "{m}");
        }
    }
    let live_min = metrics
        .iter()
        .map(|m| value(m, "min_gap_m"))
        .fold(f64::INFINITY, f64::min);
    let report_min = run.report["convoy"]["min_gap_m"].as_f64().unwrap();
    assert!(
        live_min >= report_min - 1e-9 && live_min <= report_min + 0.02,
        "live {live_min} m, report {report_min} m"
    );
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
        assert_eq!(out.status.code(), Some(2), "{err}");
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
            "foxglove/scene",
            "status",
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

/// The topics a shipped layout names: its 3D panels' Foxglove channels (as their raw topics)
/// and the quoted topics of its plot paths.
fn layout_topics(layout: &Value, out: &mut Vec<String>) {
    match layout {
        Value::Object(map) => {
            if map.get("panelType").and_then(Value::as_str) == Some("ThreeDee") {
                for topic in map["config"]["topics"]
                    .as_object()
                    .into_iter()
                    .flatten()
                    .map(|(k, _)| k)
                {
                    out.push(topic.trim_start_matches("foxglove/").to_string());
                }
            }
            if let Some(path) = map.get("value").and_then(Value::as_str)
                && let Some(rest) = path.strip_prefix('"')
                && let Some((topic, _)) = rest.split_once('"')
            {
                out.push(topic.to_string());
            }
            map.values().for_each(|v| layout_topics(v, out));
        }
        Value::Array(items) => items.iter().for_each(|v| layout_topics(v, out)),
        _ => {}
    }
}

/// Every shipped layout is the generator's output (`python/layouts/make_layouts.py`, with the
/// Foxglove SDK's layout classes), and names only topics its scenario's launch files record.
#[test]
fn shipped_layouts_are_generated_and_name_recorded_topics() {
    let root = caravan_tests::workspace_root();
    let out = std::env::temp_dir().join(format!("caravan-layouts-{}", std::process::id()));
    let made = std::process::Command::new(root.join("python/caravan-python"))
        .args([
            "--venv",
            "layouts",
            "--requirements",
            "layouts/requirements.txt",
        ])
        .arg(root.join("python/layouts/make_layouts.py"))
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    for (scenario, file) in [
        ("convoy", "convoy/foxglove-layout.json"),
        ("tracked", "tracked/foxglove-layout.json"),
        ("imu", "imu/foxglove-layout.json"),
        ("contact", "contact/foxglove-layout.json"),
        ("uav", "uav/foxglove-layout.json"),
        ("", "pingpong.foxglove-layout.json"),
    ] {
        let shipped = std::fs::read_to_string(root.join("launch").join(file)).unwrap();
        let generated = std::fs::read_to_string(out.join(file)).unwrap();
        assert_eq!(
            shipped, generated,
            "launch/{file} is not the generator's output"
        );
        let mut topics = Vec::new();
        layout_topics(&serde_json::from_str(&shipped).unwrap(), &mut topics);
        assert!(!topics.is_empty(), "{file}");
        // The record patterns of the scenario's launch files.
        let dir = root.join("launch").join(scenario);
        let files: Vec<std::path::PathBuf> = if scenario.is_empty() {
            vec![root.join("launch/pingpong.toml")]
        } else {
            std::fs::read_dir(&dir)
                .unwrap()
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "toml"))
                .collect()
        };
        let patterns: Vec<String> = files
            .iter()
            .filter_map(|f| {
                let doc: toml::Table = std::fs::read_to_string(f).unwrap().parse().ok()?;
                Some(
                    doc.get("group")?
                        .get("record")?
                        .as_array()?
                        .iter()
                        .filter_map(|p| p.as_str().map(str::to_string))
                        .collect::<Vec<_>>(),
                )
            })
            .flatten()
            .collect();
        for topic in &topics {
            assert!(
                patterns
                    .iter()
                    .any(|p| caravan::pattern::glob_match(p, topic)),
                "{file} shows '{topic}', which no launch file of its scenario records ({patterns:?})"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}
