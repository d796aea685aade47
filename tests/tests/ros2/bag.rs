//! rosbag2 bags (`caravan export --ros2`, and `caravan launch --play BAG`) against an
//! independent implementation: a convoy's recording is exported, the bag is read with the
//! Python `rosbags` library (`tests/python/read_bag.py`, ROS 2 Jazzy's message definitions),
//! and every message is compared with the recording's, field by field; the bag played into a
//! group is recorded again as the messages it came from.

use caravan_tests::ros2::ros2_python;
use caravan_tests::{PINGPONG, Scenario, caravan, recording, run_convoy_with, workspace_root};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every message of the bag at `dir` as rosbags reads it, in log-time order:
/// `{"topic", "type", "log_time_ns", "data"}`.
fn read_with_rosbags(dir: &Path) -> Vec<Value> {
    let out = Command::new(ros2_python())
        .arg(workspace_root().join("tests/python/read_bag.py"))
        .arg(dir)
        .output()
        .expect("run read_bag.py");
    assert!(
        out.status.success(),
        "rosbags cannot read the bag: {}",
        stderr(&out)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// `caravan export --ros2 REC OUT`.
fn export(rec: &Path, out: &Path) -> Output {
    caravan(&[
        "export",
        "--ros2",
        rec.to_str().unwrap(),
        out.to_str().unwrap(),
    ])
}

/// The Caravan channels of a recording: topic → (type, its messages as JSON in file order).
fn caravan_channels(bytes: &[u8]) -> BTreeMap<String, (String, Vec<Value>)> {
    let mut out: BTreeMap<String, (String, Vec<Value>)> = BTreeMap::new();
    for (topic, summary) in recording::channels(bytes) {
        if summary.encoding == "json" && summary.schema.contains("::") && topic != "status" {
            out.insert(topic, (summary.schema, Vec::new()));
        }
    }
    for m in mcap::MessageStream::new(bytes).unwrap() {
        let m = m.unwrap();
        if let Some((_, messages)) = out.get_mut(&m.channel.topic) {
            messages.push(serde_json::from_slice(&m.data).unwrap());
        }
    }
    out
}

/// A number as read_bag.py prints it (non-finite ones as strings).
fn f(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "Infinity" => f64::INFINITY,
        Value::String(s) if s == "-Infinity" => f64::NEG_INFINITY,
        other => other
            .as_f64()
            .unwrap_or_else(|| panic!("not a number: {other}")),
    }
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(f).collect()
}

/// `ros[k]` is `c[k]` for each of the `keys` (numbers, or arrays of numbers).
fn assert_fields(ros: &Value, c: &Value, keys: &str, at: &str) {
    let numbers = |v: &Value| if v.is_array() { floats(v) } else { vec![f(v)] };
    for k in keys.split_whitespace() {
        assert_eq!(numbers(&ros[k]), numbers(&c[k]), "{at}: {k}");
    }
}

fn stamp_ns(header: &Value) -> u64 {
    header["stamp"]["sec"].as_u64().unwrap() * 1_000_000_000
        + header["stamp"]["nanosec"].as_u64().unwrap()
}

fn yaw(q: &Value) -> f64 {
    let (x, y, z, w) = (f(&q["x"]), f(&q["y"]), f(&q["z"]), f(&q["w"]));
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// A ROS pose is a Caravan Pose2D: x and y as they are, z = 0, a pure yaw of θ.
fn assert_planar(ros: &Value, p: &Value, at: &str) {
    let (position, q) = (&ros["position"], &ros["orientation"]);
    assert_eq!(
        (f(&position["x"]), f(&position["y"]), f(&position["z"])),
        (f(&p["x"]), f(&p["y"]), 0.0),
        "{at}"
    );
    assert_eq!((f(&q["x"]), f(&q["y"])), (0.0, 0.0), "{at}");
    let d = (yaw(q) - f(&p["theta"])).rem_euclid(std::f64::consts::TAU);
    assert!(
        d.min(std::f64::consts::TAU - d) < 1e-12,
        "{at}: yaw {q} for {p}"
    );
}

fn assert_vector(ros: &Value, v: &Value, at: &str) {
    for k in ["x", "y", "z"] {
        assert_eq!(f(&ros[k]), f(&v[k]), "{at}.{k}");
    }
}

fn assert_pose_3d(ros: &Value, p: &Value, at: &str) {
    assert_vector(&ros["position"], &p["position"], at);
    for k in ["x", "y", "z", "w"] {
        assert_eq!(
            f(&ros["orientation"][k]),
            f(&p["orientation"][k]),
            "{at}.{k}"
        );
    }
}

/// The robot frame `robot_<i>/<link>` of a per-robot topic.
fn robot_frame(topic: &str, link: &str) -> String {
    let i = topic.split('/').nth(1).unwrap();
    format!("robot_{i}/{link}")
}

/// One exported message `ros` (read by rosbags) against the recorded Caravan message `c` of
/// `caravan_type` on `topic`, field by field as docs/ros2.md maps them.
fn assert_exported(topic: &str, caravan_type: &str, c: &Value, ros: &Value) {
    let at = format!("{topic} at {}", c["header"]["stamp_ns"]);
    let stamp = c["header"]["stamp_ns"].as_u64().unwrap();
    assert_eq!(ros["log_time_ns"].as_u64(), Some(stamp), "{at}: log time");
    let d = &ros["data"];
    if let Some(header) = d.get("header") {
        assert_eq!(stamp_ns(header), stamp, "{at}: header stamp");
    }
    let frame = d["header"]["frame_id"].as_str().unwrap_or("");
    match caravan_type {
        "caravan::LaserScan" => {
            assert_eq!(ros["type"], "sensor_msgs/msg/LaserScan");
            assert_eq!(frame, robot_frame(topic, "base_link"), "{at}");
            let fields = "angle_min angle_max angle_increment time_increment scan_time \
                          range_min range_max ranges intensities";
            assert_fields(d, c, fields, &at);
        }
        "caravan::Pose2D" => {
            assert_eq!(ros["type"], "geometry_msgs/msg/PoseStamped");
            assert_eq!(frame, "map", "{at}");
            assert_planar(&d["pose"], c, &at);
        }
        "caravan::Twist" => {
            assert_eq!(ros["type"], "geometry_msgs/msg/Twist");
            assert_vector(&d["linear"], &c["linear"], &at);
            assert_vector(&d["angular"], &c["angular"], &at);
        }
        "caravan::Imu" => {
            assert_eq!(ros["type"], "sensor_msgs/msg/Imu");
            assert_eq!(frame, robot_frame(topic, "base_link"), "{at}");
            for k in ["x", "y", "z", "w"] {
                assert_eq!(f(&d["orientation"][k]), f(&c["orientation"][k]), "{at}");
            }
            assert_vector(&d["angular_velocity"], &c["angular_velocity"], &at);
            assert_vector(&d["linear_acceleration"], &c["linear_acceleration"], &at);
            let fields = "orientation_covariance angular_velocity_covariance \
                          linear_acceleration_covariance";
            assert_fields(d, c, fields, &at);
        }
        "caravan::Odometry" => {
            assert_eq!(ros["type"], "nav_msgs/msg/Odometry");
            let child = match topic.rsplit('/').next() {
                Some("odometry") => robot_frame(topic, "base_link"),
                Some("ground_truth") => robot_frame(topic, "base_link_true"),
                Some(leaf) => robot_frame(topic, leaf),
                None => unreachable!(),
            };
            assert_eq!(
                (frame, d["child_frame_id"].as_str()),
                ("map", Some(child.as_str()))
            );
            assert_pose_3d(&d["pose"]["pose"], &c["pose"], &at);
            assert_vector(&d["twist"]["twist"]["linear"], &c["twist"]["linear"], &at);
            assert_vector(&d["twist"]["twist"]["angular"], &c["twist"]["angular"], &at);
            assert_eq!(
                floats(&d["pose"]["covariance"]),
                floats(&c["pose_covariance"])
            );
            assert_eq!(
                floats(&d["twist"]["covariance"]),
                floats(&c["twist_covariance"])
            );
        }
        "caravan::OccupancyGrid" => {
            assert_eq!(ros["type"], "nav_msgs/msg/OccupancyGrid");
            let info = &d["info"];
            assert_eq!(
                (&info["width"], &info["height"]),
                (&c["width"], &c["height"])
            );
            assert_eq!(
                f(&info["resolution"]),
                f(&c["resolution"]) as f32 as f64,
                "{at}"
            );
            assert_planar(&info["origin"], &c["origin"], &at);
            assert_eq!(d["data"], c["data"], "{at}: cells");
        }
        "caravan::Path2D" => {
            assert_eq!(ros["type"], "nav_msgs/msg/Path");
            let (poses, expected) = (
                d["poses"].as_array().unwrap(),
                c["poses"].as_array().unwrap(),
            );
            assert_eq!(poses.len(), expected.len(), "{at}");
            for (p, e) in poses.iter().zip(expected) {
                assert_eq!(stamp_ns(&p["header"]), stamp, "{at}");
                assert_planar(&p["pose"], e, &at);
            }
        }
        "caravan::Wrench" => {
            assert_eq!(ros["type"], "geometry_msgs/msg/WrenchStamped");
            assert_vector(&d["wrench"]["force"], &c["force"], &at);
        }
        other => panic!("{at}: no check for {other}"),
    }
}

/// The types the exporter maps to a topic of their own, as docs/ros2.md lists them; a convoy
/// recording all its topics has messages of the first seven.
const EXPORTED: [&str; 9] = [
    "caravan::LaserScan",
    "caravan::Pose2D",
    "caravan::Twist",
    "caravan::Imu",
    "caravan::Odometry",
    "caravan::OccupancyGrid",
    "caravan::Path2D",
    "caravan::Wrench",
    "caravan::JointState",
];

/// The recording's own `tf` channel (Foxglove's FrameTransforms), as (stamp, child, parent,
/// translation, rotation) of every transform.
type Frame = (u64, String, String, [f64; 3], [f64; 4]);

fn recorded_frames(bytes: &[u8]) -> Vec<Frame> {
    use prost::Message;
    let mut out = Vec::new();
    for data in recording::messages(bytes, "tf") {
        let m = foxglove::messages::FrameTransforms::decode(data.as_slice()).unwrap();
        for t in m.transforms {
            let s = t.timestamp.unwrap();
            let (p, q) = (t.translation.unwrap(), t.rotation.unwrap());
            out.push((
                s.sec() as u64 * 1_000_000_000 + s.nsec() as u64,
                t.child_frame_id,
                t.parent_frame_id,
                [p.x, p.y, p.z],
                [q.x, q.y, q.z, q.w],
            ));
        }
    }
    out
}

fn bag_frames(messages: &[Value]) -> Vec<Frame> {
    let mut out = Vec::new();
    for m in messages.iter().filter(|m| m["topic"] == "/tf") {
        assert_eq!(m["type"], "tf2_msgs/msg/TFMessage");
        for t in m["data"]["transforms"].as_array().unwrap() {
            let (p, q) = (&t["transform"]["translation"], &t["transform"]["rotation"]);
            out.push((
                stamp_ns(&t["header"]),
                t["child_frame_id"].as_str().unwrap().to_string(),
                t["header"]["frame_id"].as_str().unwrap().to_string(),
                [f(&p["x"]), f(&p["y"]), f(&p["z"])],
                [f(&q["x"]), f(&q["y"]), f(&q["z"]), f(&q["w"])],
            ));
        }
    }
    out
}

#[test]
fn a_convoy_exports_to_a_bag_rosbags_reads_message_for_message() {
    let run = run_convoy_with("convoy.toml", "4s", &[r#"group.record=["**"]"#]);
    let rec = run.dir.join("record.mcap");
    let bag = run.dir.join("convoy_bag");
    let out = export(&rec, &bag);
    assert!(out.status.success(), "{}", stderr(&out));
    let summary = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(bag.join("metadata.yaml").is_file() && bag.join("convoy_bag_0.mcap").is_file());
    // Types without a ROS 2 counterpart are named on one line.
    let err = stderr(&out);
    let left_out = [
        "robot/0/wheel_setpoint (caravan::WheelSetpoint)",
        "scene (caravan::Scene)",
    ];
    assert!(
        err.lines().count() == 1 && left_out.iter().all(|t| err.contains(t)),
        "{err}"
    );

    let bytes = recording::read(&rec);
    let recorded = caravan_channels(&bytes);
    let messages = read_with_rosbags(&bag);
    let mut by_topic: BTreeMap<&str, Vec<&Value>> = BTreeMap::new();
    for m in &messages {
        by_topic
            .entry(m["topic"].as_str().unwrap())
            .or_default()
            .push(m);
    }
    let mut compared = BTreeMap::new();
    for (topic, (caravan_type, original)) in &recorded {
        if !EXPORTED.contains(&caravan_type.as_str()) {
            continue;
        }
        let ros_topic = format!("/{}", topic.replacen("robot/", "robot_", 1));
        let exported = by_topic
            .get(ros_topic.as_str())
            .cloned()
            .unwrap_or_default();
        assert_eq!(
            exported.len(),
            original.len(),
            "{topic} as {ros_topic}: the bag's messages"
        );
        assert!(summary.contains(&ros_topic), "{ros_topic}: {summary}");
        for (c, ros) in original.iter().zip(&exported) {
            assert_exported(topic, caravan_type, c, ros);
        }
        compared.insert(caravan_type.clone(), original.len());
    }
    // The convoy's types, each with messages, were compared.
    for t in &EXPORTED[..7] {
        assert!(
            compared.get(*t).is_some_and(|n| *n > 0),
            "{t}: {compared:?}"
        );
    }

    // /tf holds exactly the recording's frames: every pose, true pose (and link) transform.
    let mut expected = recorded_frames(&bytes);
    let mut got = bag_frames(&messages);
    assert!(expected.len() > 1000, "{} transforms", expected.len());
    let key = |f: &Frame| (f.0, f.1.clone());
    expected.sort_by_key(key);
    got.sort_by_key(key);
    let first = got.iter().zip(&expected).find(|(g, e)| g != e);
    assert!(
        got.len() == expected.len() && first.is_none(),
        "/tf: {first:?}"
    );
    // The bag's summary line counts what rosbags read.
    assert!(
        summary.contains(&format!("exported {} messages", messages.len())),
        "{summary}"
    );
}

/// A message's stamp and payload: a bag has no sequence numbers or sources.
fn payload(m: &Value) -> (u64, Value) {
    let mut m = m.clone();
    let stamp = m["header"]["stamp_ns"].as_u64().unwrap();
    m.as_object_mut().unwrap().remove("header");
    (stamp, m)
}

/// Whether `a` and `b` are the same JSON, a yaw (`theta`) within an ulp: it crosses as a
/// quaternion, which neighbouring angles may share (caravan_ros2::inverse::planar).
fn same(a: &Value, b: &Value, key: &str) -> bool {
    match (a, b) {
        (Value::Object(a), Value::Object(b)) => {
            a.len() == b.len()
                && a.iter()
                    .all(|(k, v)| b.get(k).is_some_and(|w| same(v, w, k)))
        }
        (Value::Array(a), Value::Array(b)) => {
            a.len() == b.len() && a.iter().zip(b).all(|(v, w)| same(v, w, key))
        }
        (Value::Number(x), Value::Number(y)) if key == "theta" => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || x.next_up() == y || x.next_down() == y
        }
        _ => a == b,
    }
}

#[test]
fn an_exported_bag_plays_into_a_group_as_the_recorded_messages() {
    let run = run_convoy_with("convoy.toml", "4s", &[]);
    let rec = run.dir.join("record.mcap");
    let bag = run.dir.join("bag");
    let out = export(&rec, &bag);
    assert!(out.status.success(), "{}", stderr(&out));
    // A group of pong alone (never stepped) records what the bag plays: in lockstep, each
    // message at its recorded stamp.
    let body = "clock = \"lockstep\"\nrecord = [\"robot/**\", \"map\"]\n\n[[process]]\n\
                name = \"pong\"\nexec = \"caravan-demo pong\"\non = \"demo/ping\"\n";
    let s = Scenario::new("bag-play", body);
    let out = s.run(&["--duration", "5s", "--play", bag.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let replayed = caravan_channels(&recording::read(
        &s.run_dirs().pop().unwrap().join("record.mcap"),
    ));
    let original = caravan_channels(&recording::read(&rec));
    let mut topics = 0;
    for (topic, (caravan_type, messages)) in &original {
        if !EXPORTED.contains(&caravan_type.as_str()) || messages.is_empty() {
            continue;
        }
        let (again_type, again) = replayed
            .get(topic)
            .unwrap_or_else(|| panic!("{topic} was not played"));
        assert_eq!(again_type, caravan_type, "{topic}");
        // The player makes a topic when its first message is due, and the recorder taps it
        // from the next advance: the first message reaches the group but not the recording.
        let want: Vec<(u64, Value)> = messages[1..].iter().map(payload).collect();
        let got: Vec<(u64, Value)> = again.iter().map(payload).collect();
        assert_eq!(got.len(), want.len(), "{topic}");
        for (g, w) in got.iter().zip(&want) {
            assert!(
                g.0 == w.0 && same(&g.1, &w.1, ""),
                "{topic}: {g:?} for {w:?}"
            );
        }
        // Sequence numbers count the bag's messages on the topic.
        let seqs: Vec<u64> = again
            .iter()
            .map(|m| m["header"]["seq"].as_u64().unwrap())
            .collect();
        assert_eq!(
            seqs,
            (2..=messages.len() as u64).collect::<Vec<_>>(),
            "{topic}"
        );
        topics += 1;
    }
    assert!(topics >= 10, "{topics} topics compared");
}

/// A two-second ping-pong recording exported: a small bag (`/demo/ping`, `/demo/pong`).
fn small_bag(s: &Scenario) -> PathBuf {
    let out = s.run(&["--duration", "2s"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let rec = s.run_dirs().pop().unwrap().join("record.mcap");
    let bag = s.dir.join("small");
    let out = export(&rec, &bag);
    assert!(out.status.success(), "{}", stderr(&out));
    bag
}

#[test]
fn bad_exports_and_bad_bags_are_refused_with_exit_2() {
    let source = Scenario::new("bag-bad-source", PINGPONG);
    let bag = small_bag(&source);
    let rec = source.run_dirs().pop().unwrap().join("record.mcap");
    let s = Scenario::new("bag-bad", PINGPONG);

    // OUT exists: refused, and left as it was.
    let existing = s.dir.join("existing");
    std::fs::create_dir_all(&existing).unwrap();
    let out = export(&rec, &existing);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("existing exists already"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read_dir(&existing).unwrap().count(), 0);
    // Not a recording: refused, nothing written.
    let nothing = s.dir.join("nothing");
    let out = export(&s.file, &nothing);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("is not an MCAP file"),
        "{}",
        stderr(&out)
    );
    assert!(!nothing.exists());

    let play = |what: &Path| {
        s.run(&[
            "--duration",
            "1s",
            "--only",
            "pong",
            "--play",
            what.to_str().unwrap(),
        ])
    };
    // A type Caravan does not map, in the bag's metadata.yaml.
    let unknown = s.dir.join("unknown");
    std::fs::create_dir_all(&unknown).unwrap();
    let mcap_name = "small_0.mcap";
    std::fs::copy(bag.join(mcap_name), unknown.join(mcap_name)).unwrap();
    let meta = std::fs::read_to_string(bag.join("metadata.yaml")).unwrap();
    assert!(meta.contains("geometry_msgs/msg/PoseStamped"), "{meta}");
    std::fs::write(
        unknown.join("metadata.yaml"),
        meta.replace(
            "geometry_msgs/msg/PoseStamped",
            "sensor_msgs/msg/PointCloud2",
        ),
    )
    .unwrap();
    let out = play(&unknown);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    for expected in [
        "unknown/metadata.yaml",
        "sensor_msgs/msg/PointCloud2",
        "topic /demo/",
    ] {
        assert!(
            stderr(&out).contains(expected),
            "{expected}: {}",
            stderr(&out)
        );
    }
    // The same in an MCAP file alone (its schema names the type).
    let file = s.dir.join("points.mcap");
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .create(std::io::BufWriter::new(
            std::fs::File::create(&file).unwrap(),
        ))
        .unwrap();
    let schema = w
        .add_schema("sensor_msgs/msg/PointCloud2", "ros2msg", b"int32 x\n")
        .unwrap();
    let channel = w
        .add_channel(schema, "/points", "cdr", &BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 1,
        log_time: 0,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, &[0, 1, 0, 0, 7, 0, 0, 0])
        .unwrap();
    w.finish().unwrap();
    let out = play(&file);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    for expected in ["points.mcap", "sensor_msgs/msg/PointCloud2", "/points"] {
        assert!(
            stderr(&out).contains(expected),
            "{expected}: {}",
            stderr(&out)
        );
    }
    // A truncated MCAP file.
    let whole = std::fs::read(bag.join(mcap_name)).unwrap();
    let cut = s.dir.join("cut.mcap");
    std::fs::write(&cut, &whole[..whole.len() * 2 / 3]).unwrap();
    let out = play(&cut);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("cut.mcap") && stderr(&out).contains("truncated"),
        "{}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    // A directory that is not a bag.
    let out = play(&s.dir.join("existing"));
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("without metadata.yaml"),
        "{}",
        stderr(&out)
    );
    assert!(s.run_dirs().is_empty(), "nothing started");
}
