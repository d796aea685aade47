//! Python report plugins (`caravan.report`) and the Python recording reader
//! (`caravan.recording`) against the Rust side: the launcher takes a Python plugin's sections
//! as it takes a Rust plugin's, the plugin's numbers are those Rust reads from the same
//! `record.mcap`, and Python reads every message Rust reads, with the same values.

use caravan_schemas::{
    FixedString, JointState, JointValue, LaserScan, NodeStatus, OccupancyGrid, Path2D, Pose2D,
};
use caravan_tests::{
    Scenario, TestGroup, ping_pong, python_env, recording, workspace_bin, workspace_root,
};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The example launch file: the pingpong demo with the Python plugin as its `[[report]]`.
const EXAMPLE: &str = "python/examples/travelled_distance/pingpong.toml";

/// A run of [`EXAMPLE`] under a unique group name; its runs directory is removed when dropped.
struct ExampleRun {
    out: Output,
    runs: PathBuf,
    _group: TestGroup,
}

impl ExampleRun {
    fn launch(extra: &[&str]) -> Self {
        python_env();
        let group = TestGroup::new("py-report");
        let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
        let out = Command::new(workspace_bin("caravan"))
            .arg("launch")
            .arg(workspace_root().join(EXAMPLE))
            .arg("--runs-dir")
            .arg(&runs)
            .args(["--quiet", "--duration", "5s", "--set"])
            .arg(format!("group.name={}", group.name))
            .args(extra)
            .output()
            .unwrap();
        Self {
            out,
            runs,
            _group: group,
        }
    }

    /// The run directory; panics with the launcher's output unless the run succeeded.
    fn dir(&self) -> PathBuf {
        assert!(self.out.status.success(), "{}", text(&self.out));
        let mut dirs = std::fs::read_dir(&self.runs).unwrap().flatten();
        dirs.next().expect("a run directory").path()
    }
}

impl Drop for ExampleRun {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.runs);
    }
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// tests/python/read_recording.py on `file` (only `topics` when given).
fn python_read(file: &Path, topics: &[&str]) -> Output {
    let root = workspace_root();
    Command::new(python_env())
        .arg(root.join("tests/python/read_recording.py"))
        .arg(file)
        .args(topics)
        .env("PYTHONPATH", root.join("python"))
        .output()
        .unwrap()
}

/// What read_recording.py printed: its topics line, its metadata line, then the messages.
fn python_lines(out: &Output) -> (Value, Value, Vec<Value>) {
    assert!(out.status.success(), "{}", text(out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let mut lines = stdout
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap());
    let topics = lines.next().unwrap()["topics"].clone();
    let meta = lines.next().unwrap();
    (topics, meta, lines.collect())
}

/// Two JSON values alike, numbers equal as f64 or as f32 (Python widens a Rust `f32` field to
/// a double: 0.1f32 reads back as 0.10000000149011612).
fn alike(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || x as f32 == y as f32
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| alike(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| alike(v, w)))
        }
        _ => a == b,
    }
}

/// Python's messages are Rust's, in the same order: topic, log time, header and the message
/// (the recorded JSON without its header).
fn assert_same_messages(file: &Path, python: &[Value]) {
    let bytes = recording::read(file);
    let rust = caravan_report::read_all(file).unwrap();
    let caravan_topics: std::collections::BTreeSet<&str> =
        rust.iter().map(|m| m.topic.as_str()).collect();
    let log_times: Vec<u64> = recording::all_messages(&bytes)
        .into_iter()
        .filter(|(_, topic, _, _)| caravan_topics.contains(topic.as_str()))
        .map(|(_, _, log_time, _)| log_time)
        .collect();
    assert_eq!(
        python.len(),
        rust.len(),
        "Python and Rust read different counts"
    );
    assert!(!rust.is_empty());
    for ((py, rust), log_time) in python.iter().zip(&rust).zip(&log_times) {
        assert_eq!(py["topic"], rust.topic.as_str());
        assert_eq!(py["log_time_ns"], *log_time, "{py}");
        for key in ["seq", "stamp_ns", "source_id"] {
            assert_eq!(
                py["header"][key].as_u64(),
                rust.header_u64(key),
                "{key}: {py}"
            );
        }
        let mut message = rust.json.clone();
        message.as_object_mut().unwrap().remove("header");
        assert!(alike(&py["message"], &message), "{py}\nagainst {message}");
    }
}

/// Length of the polyline through the (x, y) of `topic`'s messages, as Rust reads them.
fn rust_distance(file: &Path, topic: &str) -> (usize, f64) {
    let messages = caravan_report::read_all(file).unwrap();
    let xy: Vec<(f64, f64)> = (messages.iter())
        .filter(|m| m.topic == topic)
        .map(|m| (m.f64("x"), m.f64("y")))
        .collect();
    let distance = (xy.windows(2))
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .sum();
    (xy.len(), distance)
}

#[test]
fn a_python_report_plugin_scores_the_run_from_its_recording() {
    let run = ExampleRun::launch(&[]);
    let dir = run.dir();
    let report = read_json(&dir.join("report.json"));
    assert!(report.get("failed_sections").is_none(), "{report}");
    let section = &report["distance"];
    let file = dir.join("record.mcap");
    let mut total = 0.0;
    for topic in ["demo/noise", "demo/ping", "demo/pong", "demo/sum"] {
        let row = &section["topics"][topic];
        let (messages, distance) = rust_distance(&file, topic);
        assert_eq!(row["messages"], messages, "{topic}: {row}");
        let python = row["distance_m"].as_f64().unwrap();
        assert!(
            (python - distance).abs() <= 1e-9 * distance.max(1.0),
            "{topic}: {row}"
        );
        total += distance;
    }
    // ping counts its steps 0, 1, … 50 in x over 5 s at 10 Hz: 50 m along x.
    let ping = &section["topics"]["demo/ping"];
    assert_eq!(ping["messages"], 51, "{ping}");
    assert_eq!(ping["distance_m"], 50.0, "{ping}");
    assert_eq!(ping["displacement_m"], 50.0, "{ping}");
    assert_eq!(ping["duration_s"], 5.0, "{ping}");
    let python_total = section["total_distance_m"].as_f64().unwrap();
    assert!((python_total - total).abs() <= 1e-9 * total, "{section}");

    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("## Travelled distance\n"), "{md}");
    assert!(md.contains("| `demo/ping` | 51 | 50.000 |"), "{md}");
    assert!(md.contains("![paths](distance.svg)"), "{md}");
    let svg = std::fs::read_to_string(dir.join("distance.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("demo/noise"),
        "{svg}"
    );

    // `caravan report` reruns the Python plugin: the same section after the files are gone.
    std::fs::remove_file(dir.join("report.json")).unwrap();
    std::fs::remove_dir_all(dir.join("sections")).unwrap();
    let again = Command::new(workspace_bin("caravan"))
        .arg("report")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(again.status.success(), "{}", text(&again));
    assert_eq!(read_json(&dir.join("report.json"))["distance"], *section);
}

/// A Python plugin's bad param stops the launch with exit code 2 before anything starts,
/// named by the plugin, as a Rust plugin's does.
#[test]
fn bad_params_of_a_python_plugin_start_nothing() {
    for (set, expected) in [
        (
            "report.0.params.section=nodes",
            "section name 'nodes' is the generic report's own",
        ),
        (
            "report.0.params.topic=x",
            "unknown key 'topic'; this report does not take it",
        ),
        (
            "report.0.params.topics=3",
            "key 'topics': expected a list, got 3",
        ),
    ] {
        let run = ExampleRun::launch(&["--set", set]);
        assert_eq!(run.out.status.code(), Some(2), "{}", text(&run.out));
        let err = String::from_utf8_lossy(&run.out.stderr);
        assert!(
            err.contains("params of report 'travelled-distance-report'") && err.contains(expected),
            "{set}: {err}"
        );
        assert!(!run.runs.exists(), "{set}: a run directory was created");
    }
}

#[test]
fn python_reads_every_message_rust_reads() {
    let run = ExampleRun::launch(&[]);
    let dir = run.dir();
    let file = dir.join("record.mcap");
    let (topics, meta, messages) = python_lines(&python_read(&file, &[]));
    assert_same_messages(&file, &messages);
    assert!(messages.iter().all(|m| m["class"] == "Pose2D"));

    // The topics and counts of the summary, the run's metadata and launch file.
    let bytes = recording::read(&file);
    let summary = recording::channels(&bytes);
    let json_channels: Vec<_> = (summary.iter())
        .filter(|(_, c)| c.encoding == "json")
        .map(|(topic, c)| {
            json!({"name": topic, "type": c.schema, "count": c.messages,
                                 "encoding": "json"})
        })
        .collect();
    assert_eq!(topics, Value::from(json_channels));
    let metadata: serde_json::Map<String, Value> = (recording::run_metadata(&bytes).into_iter())
        .map(|(k, v)| (k, v.into()))
        .collect();
    assert_eq!(meta["metadata"]["run"], Value::from(metadata));
    let launch = String::from_utf8(recording::attachment(&bytes, "launch.toml")).unwrap();
    assert_eq!(meta["launch_file"], launch.as_str());

    // One topic only, and the same messages of it.
    let (_, _, pings) = python_lines(&python_read(&file, &["demo/ping"]));
    assert_eq!(pings.len(), 51);
    assert!(pings.iter().all(|m| m["topic"] == "demo/ping"));
    assert_eq!(pings[7]["message"]["x"], 7.0);

    // A file cut short, or not MCAP at all, is an error naming it (and Rust refuses it too).
    let cut = run.runs.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    assert!(caravan_report::read_all(&cut).is_err());
    let out = python_read(&cut, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("{} is cut short", cut.display())),
        "{err}"
    );
    let not_mcap = dir.join("run.json");
    let out = python_read(&not_mcap, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("{} is not an MCAP file", not_mcap.display())),
        "{err}"
    );
}

/// Writes a recording as the recorder does (library `caravan`, zstd chunks, JSON messages with
/// a header), with a message of each shape the schema classes have: f32 arrays counted by a
/// field, a grid counted by two, strings, vectors of structs holding strings, NaN; a type
/// Python has no class for, and a channel in an encoding it cannot read.
fn write_shapes(file: &Path) -> Vec<(&'static str, &'static str, Value)> {
    let mut scan = caravan_schemas::boxed_placement_new::<LaserScan>();
    scan.angle_max = 1.5;
    scan.angle_increment = 0.1;
    scan.beam_count = 3;
    scan.ranges[..3].copy_from_slice(&[0.1, 2.5, 30.0]);
    scan.intensities[1] = 0.3;
    let mut grid = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
    grid.resolution = 0.05;
    grid.width = 3;
    grid.height = 2;
    grid.origin = Pose2D {
        x: -1.0,
        y: 2.0,
        theta: 0.25,
    };
    grid.data[..6].copy_from_slice(&[0, 100, -1, 50, 0, 100]);
    let mut status = caravan_schemas::placement_new::<NodeStatus>();
    status.node = FixedString::new("ping ü");
    status.steps = 12;
    let mut path = caravan_schemas::boxed_placement_new::<Path2D>();
    for i in 0..3 {
        let pose = Pose2D {
            x: f64::from(i),
            y: 0.5,
            theta: 0.0,
        };
        path.poses.push(pose).unwrap();
    }
    let mut joints = caravan_schemas::boxed_placement_new::<JointState>();
    for (name, position) in [("hinge", 0.5), ("slider", -0.25)] {
        let joint = JointValue {
            name: FixedString::new(name),
            position,
            velocity: 1.0,
            effort: 0.0,
        };
        joints.joints.push(joint).unwrap();
    }
    let nan = Pose2D {
        x: 1.0,
        y: f64::NAN,
        theta: 0.0,
    };
    let shapes: Vec<(&str, &str, Value)> = vec![
        (
            "scan",
            "caravan::LaserScan",
            serde_json::to_value(scan.as_ref()).unwrap(),
        ),
        (
            "map",
            "caravan::OccupancyGrid",
            serde_json::to_value(grid.as_ref()).unwrap(),
        ),
        (
            "status",
            "caravan::NodeStatus",
            serde_json::to_value(status).unwrap(),
        ),
        (
            "path",
            "caravan::Path2D",
            serde_json::to_value(path.as_ref()).unwrap(),
        ),
        (
            "joints",
            "caravan::JointState",
            serde_json::to_value(joints.as_ref()).unwrap(),
        ),
        ("nan", "caravan::Pose2D", serde_json::to_value(nan).unwrap()),
        ("gadget", "test::Gadget", json!({"size": 3, "label": "g"})),
    ];
    let mut out = std::io::Cursor::new(Vec::new());
    let mut w = mcap::WriteOptions::new()
        .library("caravan")
        .create(&mut out)
        .unwrap();
    let mut written = Vec::new();
    for (seq, (topic, type_name, view)) in shapes.into_iter().enumerate() {
        let schema = w.add_schema(type_name, "jsonschema", b"{}").unwrap();
        let channel = w
            .add_channel(schema, topic, "json", &Default::default())
            .unwrap();
        let stamp = 1_000_000 * seq as u64;
        let mut recorded = view.clone();
        recorded["header"] = json!({"seq": seq + 1, "stamp_ns": stamp,
                                    "source_id": "18446744073709551557"});
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: seq as u32,
            log_time: stamp,
            publish_time: stamp,
        };
        let data = serde_json::to_vec(&recorded).unwrap();
        w.write_to_known_channel(&header, &data).unwrap();
        written.push((topic, type_name, view));
    }
    // A binary encoding a later recorder might write.
    let schema = w
        .add_schema("caravan::Pose2D", "ros2msg", b"float64 x")
        .unwrap();
    let channel = w
        .add_channel(schema, "cdr_pose", "cdr", &Default::default())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 0,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, &[0, 1, 0, 0]).unwrap();
    w.finish().unwrap();
    drop(w);
    std::fs::write(file, out.into_inner()).unwrap();
    written
}

#[test]
fn python_decodes_every_shape_and_names_an_encoding_it_cannot_read() {
    let dir = std::env::temp_dir().join(format!("caravan-py-shapes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("record.mcap");
    let written = write_shapes(&file);
    let topics: Vec<&str> = written.iter().map(|(t, _, _)| *t).collect();
    let (_, _, messages) = python_lines(&python_read(&file, &topics));
    assert_same_messages(&file, &messages);
    for (m, (topic, type_name, view)) in messages.iter().zip(&written) {
        assert_eq!(m["topic"], *topic);
        assert_eq!(m["type"], *type_name);
        assert!(alike(&m["message"], view), "{m}\nagainst {view}");
        // A type the schema classes have is decoded into its class, another stays a dict.
        let class = type_name.strip_prefix("caravan::");
        assert_eq!(m["class"].as_str(), class, "{m}");
        assert_eq!(m["header"]["source_id"], 18446744073709551557u64, "{m}");
    }
    assert_eq!(messages[5]["message"]["y"], Value::Null, "NaN reads as NaN");
    assert_eq!(messages[2]["message"]["node"], "ping ü");

    // The channel in an encoding Python cannot decode is named, asked for or read with all.
    for asked in [&["cdr_pose"][..], &[]] {
        let out = python_read(&file, asked);
        assert_eq!(out.status.code(), Some(2), "{}", text(&out));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("UnsupportedEncoding")
                && err.contains(&file.display().to_string())
                && err.contains(
                    "topic 'cdr_pose' (caravan::Pose2D) is in the unsupported encoding 'cdr'"
                ),
            "{err}"
        );
    }

    // An MCAP file another program wrote is not taken for a recording.
    let other = dir.join("other.mcap");
    let mut w = mcap::WriteOptions::new()
        .library("someone-else")
        .create(std::io::BufWriter::new(
            std::fs::File::create(&other).unwrap(),
        ))
        .unwrap();
    w.finish().unwrap();
    drop(w);
    let out = python_read(&other, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("is an MCAP file but not a Caravan recording"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The Python plugin docs/scenarios.md shows beside the Rust one
/// (tests/src/bin/caravan-count-report.rs) runs under the launcher and writes, on the same run,
/// the section the Rust one writes: the protocol and the page's example both hold.
#[test]
fn the_documented_python_plugin_writes_what_the_rust_one_writes() {
    let docs = std::fs::read_to_string(workspace_root().join("docs/scenarios.md")).unwrap();
    let opening = "```python\nfrom caravan import report";
    let start = docs
        .find(opening)
        .expect("a Python plugin in docs/scenarios.md")
        + 10;
    let end = start + docs[start..].find("```").unwrap();
    let launcher = workspace_root().join("python/caravan-python");
    let params = r#"{ topic = "demo/ping", field = "x" }"#;
    let body = format!(
        "{}\n[[report]]\nexec = \"{} count.py\"\nparams = {params}\n",
        ping_pong(),
        launcher.display()
    );
    python_env();
    let s = Scenario::new("py-count", &body);
    std::fs::write(s.dir.join("count.py"), &docs[start..end]).unwrap();
    let out = s.run(&["--duration", "5s"]);
    assert!(out.status.success(), "{}", text(&out));
    let report = s.report();
    // ping steps at 0, 0.1, …, 5.0 s and publishes its step index as x.
    let expected = json!({"topic": "demo/ping", "messages": 51, "sum": 1275.0});
    assert_eq!(report["count"], expected, "{report}");

    let dir = s.run_dirs().pop().unwrap();
    let read = |ext: &str| std::fs::read_to_string(dir.join(format!("sections/count.{ext}")));
    let (python_json, python_md) = (read("json").unwrap(), read("md").unwrap());
    std::fs::remove_dir_all(dir.join("sections")).unwrap();
    let rust = Command::new(workspace_bin("caravan-count-report"))
        .arg(&dir)
        .env("CARAVAN_PARAMS", r#"{"topic": "demo/ping", "field": "x"}"#)
        .output()
        .unwrap();
    assert!(rust.status.success(), "{}", text(&rust));
    let parse = |t: &str| serde_json::from_str::<Value>(t).unwrap();
    assert_eq!(parse(&python_json), parse(&read("json").unwrap()));
    assert_eq!(python_md, read("md").unwrap());
}
