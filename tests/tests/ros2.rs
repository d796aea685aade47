//! The ROS 2 bridge (`caravan-ros2`) against an independent DDS implementation: a Cyclone DDS
//! probe (`tests/python/ros2_probe.py`) subscribes to the convoy's topics by their ROS 2 names
//! and publishes `cmd_vel` into the running group, in a private network of the test's own.

#[path = "ros2/bag.rs"]
mod bag;

use caravan_tests::recording;
use caravan_tests::ros2::{companion_lines, domain, in_private_network, probe};
use caravan_tests::{
    Scenario, TestGroup, assert_refused, launch_with_set, workspace_bin, workspace_root,
};
use serde_json::Value;
use std::collections::BTreeMap;

/// ROS 2 topic → (Caravan topic, ROS type, QoS) of launch/convoy/convoy-ros2.toml's entries.
const BRIDGED: &[(&str, &str, &str)] = &[
    ("/robot_0/scan", "robot/0/scan", "sensor_msgs/msg/LaserScan"),
    (
        "/map",
        "map",
        "nav_msgs/msg/OccupancyGrid:reliable,transient_local",
    ),
    ("/robot_0/path", "robot/0/path", "nav_msgs/msg/Path"),
    (
        "/robot_0/cmd_vel",
        "robot/0/cmd_vel",
        "geometry_msgs/msg/Twist",
    ),
    (
        "/robot_0/pose",
        "robot/0/pose",
        "geometry_msgs/msg/PoseStamped",
    ),
    (
        "/robot_3/pose",
        "robot/3/pose",
        "geometry_msgs/msg/PoseStamped",
    ),
    (
        "/robot_4/pose_true",
        "robot/4/pose_true",
        "geometry_msgs/msg/PoseStamped",
    ),
];

fn stamp_ns(header: &Value) -> u64 {
    header["stamp"]["sec"].as_u64().unwrap() * 1_000_000_000
        + header["stamp"]["nanosec"].as_u64().unwrap()
}

fn f(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "Infinity" => f64::INFINITY,
        Value::String(s) if s == "-Infinity" => f64::NEG_INFINITY,
        Value::String(s) if s == "NaN" => f64::NAN,
        other => other
            .as_f64()
            .unwrap_or_else(|| panic!("not a number: {other}")),
    }
}

fn yaw(q: &Value) -> f64 {
    let (x, y, z, w) = (f(&q["x"]), f(&q["y"]), f(&q["z"]), f(&q["w"]));
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

fn same(a: f64, b: f64, what: &str) {
    assert!(
        a == b || (a - b).abs() <= 1e-9 * b.abs().max(1.0),
        "{what}: {a} ≠ {b}"
    );
}

/// Checks a ROS 2 pose against a recorded Pose2D.
fn same_pose(pose: &Value, rec: &Value, what: &str) {
    same(f(&pose["position"]["x"]), f(&rec["x"]), what);
    same(f(&pose["position"]["y"]), f(&rec["y"]), what);
    same(yaw(&pose["orientation"]), f(&rec["theta"]), what);
}

/// Compares one received ROS 2 message with the recorded Caravan message of the same stamp.
fn check(ros_topic: &str, data: &Value, rec: &Value) {
    match ros_topic {
        "/robot_0/scan" => {
            assert_eq!(data["header"]["frame_id"], "robot_0/base_link");
            let n = rec["ranges"].as_array().unwrap().len();
            let ranges = data["ranges"].as_array().unwrap();
            assert_eq!(ranges.len(), n, "beams");
            for (k, r) in ranges.iter().enumerate() {
                // float32 on both sides: exactly equal (infinities included).
                assert_eq!(f(r) as f32, f(&rec["ranges"][k]) as f32, "beam {k}");
            }
            for key in ["angle_min", "angle_max", "angle_increment", "range_max"] {
                assert_eq!(f(&data[key]) as f32, f(&rec[key]) as f32, "{key}");
            }
        }
        "/map" => {
            let info = &data["info"];
            assert_eq!(info["width"], rec["width"]);
            assert_eq!(info["height"], rec["height"]);
            assert_eq!(f(&info["resolution"]) as f32, f(&rec["resolution"]) as f32);
            same_pose(&info["origin"], &rec["origin"], "map origin");
            let cells = rec["width"].as_u64().unwrap() * rec["height"].as_u64().unwrap();
            let recorded: Vec<&Value> = rec["data"]
                .as_array()
                .unwrap()
                .iter()
                .take(cells as usize)
                .collect();
            let sent: Vec<&Value> = data["data"].as_array().unwrap().iter().collect();
            assert_eq!(sent, recorded, "map cells");
        }
        "/robot_0/path" => {
            let poses = data["poses"].as_array().unwrap();
            let recorded = rec["poses"].as_array().unwrap();
            assert_eq!(poses.len(), recorded.len(), "path length");
            for (p, r) in poses.iter().zip(recorded) {
                same_pose(&p["pose"], r, "path pose");
            }
        }
        "/robot_0/cmd_vel" => {
            for part in ["linear", "angular"] {
                for axis in ["x", "y", "z"] {
                    same(f(&data[part][axis]), f(&rec[part][axis]), "cmd_vel");
                }
            }
        }
        _ => {
            assert_eq!(data["header"]["frame_id"], "map");
            same_pose(&data["pose"], rec, ros_topic);
        }
    }
}

/// The recorded messages of `topic` by stamp.
fn recorded(bytes: &[u8], topic: &str) -> BTreeMap<u64, Value> {
    recording::messages(bytes, topic)
        .iter()
        .map(|m| {
            let v: Value = serde_json::from_slice(m).unwrap();
            (v["header"]["stamp_ns"].as_u64().unwrap(), v)
        })
        .collect()
}

#[test]
fn the_convoy_reaches_a_cyclone_dds_subscriber_as_recorded_and_its_cmd_vel_drives_a_robot() {
    bridge_the_convoy("lockstep", "12s");
}

#[test]
fn in_realtime_too_the_convoy_reaches_cyclone_dds_and_its_cmd_vel_drives_a_robot() {
    bridge_the_convoy("realtime", "10s");
}

/// Runs convoy-ros2.toml for `duration` with `clock`, a Cyclone DDS probe listening to every
/// bridged topic and another publishing `/robot_4/cmd_vel`, and checks what crossed.
fn bridge_the_convoy(clock: &str, duration: &str) {
    let group = TestGroup::new("ros2");
    let dir = std::env::temp_dir().join(format!("caravan-{}", group.name));
    std::fs::create_dir_all(&dir).unwrap();
    let domain = domain().to_string();
    let mut listen: Vec<String> = vec![
        "--domain".into(),
        domain.clone(),
        "--duration".into(),
        "120".into(),
    ];
    for (ros, _, ty) in BRIDGED {
        listen.extend(["--listen".into(), format!("{ros}={ty}")]);
    }
    listen.extend(["--listen".into(), "/tf=tf2_msgs/msg/TFMessage".into()]);
    listen.extend(["--listen".into(), "/clock=rosgraph_msgs/msg/Clock".into()]);
    // The probe ends when the group has: the launcher below is the namespace's last process.
    let listen: Vec<&str> = listen.iter().map(String::as_str).collect();
    let drive = [
        "--domain",
        &domain,
        "--publish",
        "/robot_4/cmd_vel=geometry_msgs/msg/Twist",
        "--json",
        r#"{"linear": {"x": 0.3}}"#,
        "--rate",
        "20",
        "--duration",
        "120",
    ];
    let runs = dir.join("runs");
    let launcher: Vec<String> = [
        workspace_bin("caravan").display().to_string(),
        "launch".into(),
        workspace_root()
            .join("launch/convoy/convoy-ros2.toml")
            .display()
            .to_string(),
        "--quiet".into(),
        "--duration".into(),
        duration.into(),
        "--clock".into(),
        clock.into(),
        "--set".into(),
        format!("group.name={}", group.name),
        "--set".into(),
        format!("process.ros2.params.domain={domain}"),
        "--runs-dir".into(),
        runs.display().to_string(),
    ]
    .into();
    let out = in_private_network(&dir, &[probe(&listen), probe(&drive)], &launcher);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let run = std::fs::read_dir(&runs)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let bytes = recording::read(&run.join("record.mcap"));
    let received = companion_lines(&dir, 0);
    let probe_err = || std::fs::read_to_string(dir.join("companion-0.err")).unwrap_or_default();

    // Every bridged topic arrived, and every message is the recorded one of its stamp. A
    // realtime recorder may drop a message on a loaded machine (lockstep's never does), so in
    // realtime a message the recording lacks is skipped (under load it may lack most), as long
    // as some of all are there to compare.
    let lockstep = clock == "lockstep";
    let mut matched_all = 0;
    for (ros, caravan, _) in BRIDGED {
        let mut matched = 0;
        let rec = recorded(&bytes, caravan);
        let got: Vec<&Value> = received.iter().filter(|m| m["topic"] == *ros).collect();
        // The map, the plan and the planner's commands come now and then; a realtime run on a
        // loaded machine may publish them before the probe has matched, so there only the
        // topics published at every step must arrive.
        let steady = ros.contains("pose") || ros.contains("scan");
        assert!(
            !got.is_empty() || !(lockstep || steady),
            "nothing on {ros}; probe: {}",
            probe_err()
        );
        for m in &got {
            let stamp = match *ros {
                // Twist has no header: match it by value among the recorded commands.
                "/robot_0/cmd_vel" => {
                    let same = rec.iter().find(|(_, r)| {
                        r["linear"]["x"] == m["data"]["linear"]["x"]
                            && r["angular"]["z"] == m["data"]["angular"]["z"]
                    });
                    match same {
                        Some((stamp, _)) => *stamp,
                        None => u64::MAX,
                    }
                }
                _ => stamp_ns(&m["data"]["header"]),
            };
            let Some(r) = rec.get(&stamp) else {
                assert!(
                    clock == "realtime",
                    "{ros}: no recorded message at {stamp} ns"
                );
                continue;
            };
            check(ros, &m["data"], r);
            matched += 1;
        }
        matched_all += matched;
    }
    assert!(matched_all > 0, "no received message was in the recording");

    // /tf: each transform is the recorded pose of its frame at its stamp.
    let frames = [
        ("robot_0/base_link", "robot/0/pose"),
        ("robot_3/base_link", "robot/3/pose"),
        ("robot_4/base_link_true", "robot/4/pose_true"),
    ];
    let tf: Vec<&Value> = received.iter().filter(|m| m["topic"] == "/tf").collect();
    for (frame, topic) in frames {
        let rec = recorded(&bytes, topic);
        let mut seen = 0;
        for t in tf
            .iter()
            .flat_map(|m| m["data"]["transforms"].as_array().unwrap())
        {
            if t["child_frame_id"] != frame {
                continue;
            }
            assert_eq!(t["header"]["frame_id"], "map");
            seen += 1;
            let Some(r) = rec.get(&stamp_ns(&t["header"])) else {
                assert!(
                    clock == "realtime",
                    "{frame}: no recorded pose at its stamp"
                );
                continue;
            };
            let tr = &t["transform"];
            let pose =
                serde_json::json!({ "position": tr["translation"], "orientation": tr["rotation"] });
            same_pose(&pose, r, frame);
        }
        assert!(seen > 0, "no transform of {frame} on /tf");
    }

    // /clock advances with the group's time (in lockstep in the bridge's 10 ms steps).
    let clock: Vec<u64> = received
        .iter()
        .filter(|m| m["topic"] == "/clock")
        .map(|m| stamp_ns(&serde_json::json!({ "stamp": m["data"]["clock"] })))
        .collect();
    assert!(clock.len() >= 10, "{} /clock samples", clock.len());
    assert!(clock.windows(2).all(|w| w[0] < w[1]), "/clock went back");
    assert!(
        !lockstep || clock.iter().all(|t| t % 10_000_000 == 0),
        "/clock off the 10 ms steps"
    );
    assert!(
        *clock.last().unwrap() >= 8_000_000_000,
        "/clock ended at {:?}",
        clock.last()
    );

    // Follower 4 drives only what arrives on /robot_4/cmd_vel (0.3 m/s): without the probe's
    // commands it would stand still. A realtime run on a loaded machine loses some steps, so
    // there only the motion counts.
    let poses = recorded(&bytes, "robot/4/pose_true");
    let (first, last) = (
        poses.values().next().unwrap(),
        poses.values().last().unwrap(),
    );
    let moved = (f(&last["x"]) - f(&first["x"])).hypot(f(&last["y"]) - f(&first["y"]));
    assert!(
        moved > if lockstep { 1.0 } else { 0.2 },
        "robot 4 moved {moved} m; probe: {}",
        std::fs::read_to_string(dir.join("companion-1.err")).unwrap_or_default()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_bridge_entries_stop_the_launch_naming_file_line_and_key() {
    let cases = [
        (
            r#"{ caravan = "robot/0/scan", type = "sensor_msgs/msg/PointCloud2" }"#,
            "topics[1].type",
            "unknown ROS 2 type 'sensor_msgs/msg/PointCloud2'",
        ),
        (
            r#"{ caravan = "robot/0/scan", type = "sensor_msgs/msg/Imu" }"#,
            "topics[1].type",
            "'robot/0/scan' is a caravan::LaserScan",
        ),
        (
            r#"{ caravan = "map", qos = { reliability = "sometimes" } }"#,
            "topics[1].qos.reliability",
            "best_effort",
        ),
        (
            r#"{ caravan = "robot/0/scan", ros = "/robot/0/scan" }"#,
            "topics[1].ros",
            "not a valid ROS 2 topic name",
        ),
        (
            r#"{ caravan = "robot/0/cmd_vel", direction = "in" }"#,
            "topics[1].ros",
            "crosses both ways",
        ),
    ];
    for (entry, key, words) in cases {
        let body = format!(
            "clock = \"lockstep\"\nduration = \"1s\"\n\n[[process]]\nname = \"bridge\"\nexec = \"caravan-ros2\"\n\
             params = {{ topics = [{{ caravan = \"robot/0/cmd_vel\" }}, {entry}] }}\n"
        );
        let s = Scenario::new("ros2-bad", &body);
        let out = s.run(&[]);
        // The params sit on line 9 of the file (after the [group] header and name).
        let at = format!("{}:9", s.file.display());
        assert_refused(
            &s,
            &out,
            &[&at, "process 'bridge'", &format!("key '{key}'"), words],
        );
    }
    // A --set is named instead of a line.
    let (code, err) = launch_with_set(
        "convoy/convoy-ros2.toml",
        "1s",
        "process.ros2.params.topics.0.type=sensor_msgs/msg/Imu",
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--set process.ros2.params.topics.0.type=")
            && err.contains("key 'topics[0].type'"),
        "{err}"
    );
}
