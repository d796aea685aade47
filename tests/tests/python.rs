//! Python agents: the generated ctypes module has the Rust layouts, and a Python follower
//! completes the lockstep convoy. Each test sets up `<workspace>/.venv` itself (python3 -m venv,
//! pip install iceoryx2) on first use.

use caravan_schemas::{lockstep, topics};
use caravan_tests::{
    assert_convoy_succeeded, python_env, run_convoy, workspace_bin, workspace_root,
};
use std::io::Write;
use std::process::{Command, Output, Stdio};

/// `caravan schemas --layout`, parsed.
fn rust_layout() -> serde_json::Value {
    let out = Command::new(workspace_bin("caravan"))
        .args(["schemas", "--layout"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// More facts from Rust for the checker: the registry, hashes, topic names, constants.
fn rust_facts() -> serde_json::Value {
    serde_json::json!({
        "registry": caravan_schemas::message_type_names(),
        "hashes": {
            "follower-2": lockstep::name_hash("follower-2"),
            "robot/1/pose_true": lockstep::name_hash("robot/1/pose_true"),
            "": lockstep::name_hash(""),
            "ünïcode": lockstep::name_hash("ünïcode"),
        },
        "topics": {
            "pose_true": [1, topics::pose_true(1).name()],
            "wheel_setpoint": [3, topics::wheel_setpoint(3).name()],
            "scan": [0, topics::scan(0).name()],
            "odometry": [12, topics::odometry(12).name()],
            "path": [2, topics::path(2).name()],
        },
        "constants": {
            "SCAN_MAX_BEAMS": caravan_schemas::SCAN_MAX_BEAMS,
            "MAP_MAX_CELLS": caravan_schemas::MAP_MAX_CELLS,
            "PATH_MAX_POSES": caravan_schemas::PATH_MAX_POSES,
            "STATUS": topics::status().name(),
            "GOAL": topics::goal().name(),
            "MAX_TOPICS": lockstep::MAX_TOPICS,
            "HELLO": lockstep::HELLO,
            "DONE": lockstep::DONE,
        },
        "grant_service": ["follower-2", lockstep::grant_service("follower-2")],
    })
}

/// Every catalog type's descriptor, by type name, as a process registers one (the structs
/// that messages only hold are described inside them).
fn catalog_descriptors() -> serde_json::Value {
    let all: serde_json::Map<String, serde_json::Value> = caravan_schemas::catalog::layouts()
        .iter()
        .filter_map(|l| {
            let d = caravan_schemas::catalog::descriptor(l.type_name)?;
            Some((l.type_name.to_string(), d.to_json()))
        })
        .collect();
    all.into()
}

/// Runs tests/python/check_layout.py on `layout` with the workspace's `caravan` package.
fn check_layout(layout: &serde_json::Value, facts: &serde_json::Value) -> Output {
    let root = workspace_root();
    let mut child = Command::new(python_env())
        .arg(root.join("tests/python/check_layout.py"))
        .arg(facts.to_string())
        .env("PYTHONPATH", root.join("python"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(layout.to_string().as_bytes())
        .unwrap();
    child.wait_with_output().unwrap()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn python_schemas_have_the_rust_layouts() {
    let layout = rust_layout();
    let out = check_layout(&layout, &rust_facts());
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("types match"), "{}", text(&out));

    // The checker catches a mismatch: move one field, rename one type.
    let mut moved = layout.clone();
    let scan = moved
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|l| l["name"] == "LaserScan")
        .unwrap();
    scan["fields"][8]["offset"] = 36.into();
    let out = check_layout(&moved, &serde_json::json!({}));
    assert!(!out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("LaserScan: offset of ranges is 32 in Python, 36 in Rust"),
        "{}",
        text(&out)
    );
    let mut renamed = layout;
    renamed[0]["type_name"] = "caravan::Headr".into();
    let out = check_layout(&renamed, &serde_json::json!({}));
    assert!(!out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("caravan::Headr"), "{}", text(&out));
}

/// A class built at run time from a type's descriptor (`caravan.types.message_class`) has the
/// layout the generator gives the type's class, and reads bytes into the same `to_dict()`.
#[test]
fn python_classes_built_from_descriptors_have_the_generated_layouts() {
    let layout = rust_layout();
    let descriptors = catalog_descriptors();
    let out = check_layout(&layout, &serde_json::json!({"descriptors": descriptors}));
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("types match"), "{}", text(&out));

    // The checker catches a layout ctypes can follow but the generated class lacks (theta 8
    // bytes on), and the builder refuses one ctypes cannot (w between two f64 slots).
    let mut tampered = descriptors;
    let pose = &mut tampered["caravan::Pose2D"]["layouts"][0];
    pose["size"] = 32.into();
    pose["fields"][2]["offset"] = 24.into();
    let quaternion = &mut tampered["caravan::Quaternion"]["layouts"][0];
    quaternion["size"] = 40.into();
    quaternion["fields"][3]["offset"] = 28.into();
    let out = check_layout(&layout, &serde_json::json!({"descriptors": tampered}));
    assert!(!out.status.success(), "{}", text(&out));
    for expected in [
        "caravan::Pose2D: ctypes.sizeof is 32 from its descriptor, 24 in schemas.py",
        "caravan::Pose2D: offset of theta is 24 from its descriptor, 16 in schemas.py",
        "message type 'caravan::Quaternion': Quaternion.w: offset 28 cannot be expressed with ctypes",
    ] {
        assert!(text(&out).contains(expected), "{expected}:\n{}", text(&out));
    }
}

/// Python registers and looks up message types outside the catalog in the files Rust uses:
/// each reads what the other registered, a second layout under one name is refused on either
/// side, and Python's `to_dict()` of such a type is Rust's JSON view of its bytes.
#[test]
fn python_registers_and_looks_up_message_types_as_rust_does() {
    use caravan_schemas::descriptor::Descriptor;
    let group = caravan_tests::TestGroup::new("py-types");
    let config = caravan::group::config(&group.name).unwrap();
    // The group's directory, which its first iceoryx2 node would create.
    std::fs::create_dir_all(config.global.root_path().to_string()).unwrap();
    let vector3 = caravan_schemas::catalog::descriptor("caravan::Vector3")
        .unwrap()
        .to_json();
    let gadget = serde_json::json!({
        "layouts": [vector3["layouts"][0], {
            "name": "Gadget", "type_name": "test::Gadget", "size": 64, "align": 8,
            "fields": [
                {"name": "name_len", "offset": 0, "size": 4, "type": "u32"},
                {"name": "name", "offset": 4, "size": 8, "type": "u8", "len": 8,
                 "count": ["name_len"], "text": true},
                {"name": "position", "offset": 16, "size": 24, "type": "Vector3"},
                {"name": "values", "offset": 40, "size": 16, "type": "i32", "len": 4,
                 "count": ["n"]},
                {"name": "n", "offset": 56, "size": 1, "type": "u8"},
            ],
        }],
        "default": {"name": "gizmo"},
    });
    let gadget = Descriptor::from_json(&gadget).unwrap();
    caravan::types::register(&config, &gadget).unwrap();

    let root = workspace_root();
    let out = Command::new(python_env())
        .arg(root.join("tests/python/check_types.py"))
        .arg(&group.name)
        .arg(gadget.to_json().to_string())
        .env("PYTHONPATH", root.join("python"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("types: registration and lookup as in Rust"),
        "{}",
        text(&out)
    );

    // The gadget Python wrote reads in Rust as Python showed it.
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let view = stdout
        .lines()
        .find_map(|l| l.strip_prefix("view "))
        .unwrap();
    let mut stream = serde_json::Deserializer::from_str(view).into_iter::<serde_json::Value>();
    let bytes: Vec<u8> = serde_json::from_value(stream.next().unwrap().unwrap()).unwrap();
    let python_view = stream.next().unwrap().unwrap();
    assert_eq!(gadget.view(&bytes).unwrap(), python_view);

    // Rust reads the type Python registered, and refuses another layout under its name.
    let widget = caravan::types::lookup(&config, "test::Widget").unwrap();
    let names: Vec<&str> = widget
        .layout()
        .fields
        .iter()
        .map(|f| f.name.as_str())
        .collect();
    assert_eq!(names, ["a", "b_len", "b"]);
    assert_eq!(widget.layout().fields[2].count, ["b_len"]);
    assert_eq!(widget.layout().size, 40);
    let mut other = widget.to_json();
    other["layouts"][0]["fields"][0]["type"] = "i32".into();
    let refused =
        caravan::types::register(&config, &Descriptor::from_json(&other).unwrap()).unwrap_err();
    assert!(
        refused
            .to_string()
            .contains("'test::Widget' is declared with two layouts"),
        "{refused}"
    );
}

#[test]
fn python_follower_completes_the_lockstep_convoy() {
    python_env();
    let run = run_convoy("convoy-python.toml");
    let report = &run.report;
    assert_convoy_succeeded(&report["convoy"]);
    // follower-2 really was the Python agent, and it reported its steps like a Rust node.
    let log = std::fs::read_to_string(run.dir.join("logs/follower-2.log")).unwrap_or_default();
    let launched = std::fs::read_to_string(run.dir.join("launch.toml")).unwrap();
    assert!(
        launched.contains("examples/python/follower.py"),
        "{launched}"
    );
    let node = report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == "follower-2")
        .unwrap();
    assert_eq!(node["exit_status"], "exited 0", "{node}\n{log}");
    assert!(node["steps"].as_u64().unwrap() >= 1400, "{node}\n{log}");
    assert_eq!(node["period_ms"], 50.0, "{node}");
    // The Rust nodes report into their slots of the shared page; the Python node, which has
    // none, in samples: every one of its steps is among the rest (a grant of several
    // periods, `batched_steps`, is reported once).
    let s = &report["run"]["schedule"];
    let count = |key: &str| s[key].as_u64().unwrap();
    let python = node["steps"].as_u64().unwrap();
    assert_eq!(
        count("slot_reports") + python + count("batched_steps"),
        count("steps"),
        "{s}"
    );
}

/// A Python node on a host with links or a CPU budget says that it does not emulate them,
/// rather than let a run look emulated.
#[test]
fn python_node_warns_that_it_does_not_emulate_links() {
    let root = workspace_root();
    let network = serde_json::json!({
        "seed": 1,
        "hosts": {"n": "rpi-1"},
        "cpu_slowdown": {},
        "links": [{"from": "pc", "to": "rpi-1"}],
    });
    let probe = |host: &str| {
        Command::new(python_env())
            .args(["-c", "from caravan import node; node.Identity.from_env()"])
            .env("PYTHONPATH", root.join("python"))
            .env("CARAVAN_GROUP", "g")
            .env("CARAVAN_NODE", "n")
            .env("CARAVAN_HOST", host)
            .env("CARAVAN_NETWORK", network.to_string())
            .output()
            .unwrap()
    };
    let linked = probe("rpi-1");
    assert!(linked.status.success(), "{}", text(&linked));
    assert!(
        String::from_utf8_lossy(&linked.stderr)
            .contains("network links of host 'rpi-1' are not emulated"),
        "{}",
        text(&linked)
    );
    let alone = probe("pc");
    assert!(alone.stderr.is_empty(), "{}", text(&alone));
}

/// A Python agent with bad params exits 2 naming the key, as Rust nodes do, before it joins
/// any group.
#[test]
fn python_agent_with_bad_params_exits_2() {
    let root = workspace_root();
    // Run outside a launcher, whose clean-up would otherwise remove what the nodes made.
    let group = caravan_tests::TestGroup::new("py-bad");
    let run = |params: serde_json::Value| {
        Command::new(python_env())
            .arg(root.join("examples/python/follower.py"))
            .env("PYTHONPATH", root.join("python"))
            .env("CARAVAN_GROUP", &group.name)
            .env("CARAVAN_NODE", "follower-2")
            .env("CARAVAN_PARAMS", params.to_string())
            .env("CARAVAN_LAUNCH_DIR", root.join("launch/convoy"))
            .output()
            .unwrap()
    };
    let typo = run(
        serde_json::json!({"robot": 2, "urdf": "robots/convoy_bot.urdf", "follower": {"k9": 1.0}}),
    );
    assert_eq!(typo.status.code(), Some(2), "{}", text(&typo));
    assert!(text(&typo).contains("'follower.k9'"), "{}", text(&typo));
    let no_urdf = run(serde_json::json!({"robot": 2}));
    assert_eq!(no_urdf.status.code(), Some(2), "{}", text(&no_urdf));
    assert!(text(&no_urdf).contains("key 'urdf'"), "{}", text(&no_urdf));
    // A robot the world's [[start]] poses do not name (the convoy's lab has five).
    let robot_9 = run(
        serde_json::json!({"robot": 9, "urdf": "robots/convoy_bot.urdf",
                                         "world": "worlds/lab.toml"}),
    );
    assert_eq!(robot_9.status.code(), Some(2), "{}", text(&robot_9));
    assert!(
        text(&robot_9).contains("key 'robot': world file worlds/lab.toml lists 5"),
        "{}",
        text(&robot_9)
    );
    let bad_urdf = run(serde_json::json!({"robot": 2, "urdf": "robots/missing.urdf"}));
    assert_eq!(bad_urdf.status.code(), Some(2), "{}", text(&bad_urdf));
    assert!(
        text(&bad_urdf).contains("missing.urdf"),
        "{}",
        text(&bad_urdf)
    );
}

/// A Python message's `to_dict()` is the JSON view Rust writes into recordings, and `print`
/// shows it readably.
#[test]
fn python_messages_print_the_recordings_json_view() {
    use caravan_schemas::{LaserScan, NodeStatus, OccupancyGrid, Path2D, Pose2D};
    let script = r#"
import json
from caravan.schemas import *
pose = Pose2D(1.0, 2.0, 0.5)
scan = LaserScan(); scan.angle_max = 1.5; scan.beam_count = 3; scan.ranges[0] = 1.5; scan.ranges[2] = 4.0
status = NodeStatus(); set_fixed_str(status, "node", "ping"); status.steps = 5
path = Path2D(); set_fixed_vec(path, "poses", [Pose2D(1.0, 2.0, 0.0), Pose2D(3.0, 4.0, 1.0)])
grid = OccupancyGrid(); grid.resolution = 0.05; grid.width = 2; grid.height = 2; grid.data[3] = 100
for m in (pose, scan, status, path, grid):
    print(json.dumps(m.to_dict()))
print(repr(pose))
"#;
    let out = Command::new(python_env())
        .args(["-c", script])
        .current_dir(workspace_root().join("python"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let lines: Vec<&str> = stdout.lines().collect();
    let pose = Pose2D {
        x: 1.0,
        y: 2.0,
        theta: 0.5,
    };
    let mut scan = caravan_schemas::boxed_placement_new::<LaserScan>();
    scan.angle_max = 1.5;
    scan.beam_count = 3;
    scan.ranges[0] = 1.5;
    scan.ranges[2] = 4.0;
    let mut status = caravan_schemas::placement_new::<NodeStatus>();
    status.node = caravan_schemas::FixedString::new("ping");
    status.steps = 5;
    let mut path = caravan_schemas::boxed_placement_new::<Path2D>();
    path.poses
        .push(Pose2D {
            x: 1.0,
            y: 2.0,
            theta: 0.0,
        })
        .unwrap();
    path.poses
        .push(Pose2D {
            x: 3.0,
            y: 4.0,
            theta: 1.0,
        })
        .unwrap();
    let mut grid = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
    grid.resolution = 0.05;
    grid.width = 2;
    grid.height = 2;
    grid.data[3] = 100;
    let rust = [
        serde_json::to_value(pose).unwrap(),
        serde_json::to_value(scan.as_ref()).unwrap(),
        serde_json::to_value(status).unwrap(),
        serde_json::to_value(path.as_ref()).unwrap(),
        serde_json::to_value(grid.as_ref()).unwrap(),
    ];
    for (py, rust) in lines.iter().zip(&rust) {
        let py: serde_json::Value = serde_json::from_str(py).unwrap();
        assert_eq!(&py, rust);
    }
    assert_eq!(lines[5], "Pose2D(x=1.0, y=2.0, theta=0.5)");
}

/// `python/` is an installable package: pip builds it from its pyproject and installs the
/// `caravan` package with the generated message module.
#[test]
fn python_package_installs_with_pip() {
    let dir = std::env::temp_dir().join(format!("caravan-pip-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // Built from a copy: setuptools writes build/ and egg-info/ beside the sources.
    let source = dir.join("source");
    std::fs::create_dir_all(source.join("caravan")).unwrap();
    let python = workspace_root().join("python");
    std::fs::copy(python.join("pyproject.toml"), source.join("pyproject.toml")).unwrap();
    for file in std::fs::read_dir(python.join("caravan")).unwrap().flatten() {
        if file.path().extension().is_some_and(|e| e == "py") {
            std::fs::copy(file.path(), source.join("caravan").join(file.file_name())).unwrap();
        }
    }
    let target = dir.join("installed");
    let out = Command::new(python_env())
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "--no-deps",
            "--target",
        ])
        .arg(&target)
        .arg(&source)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    assert!(target.join("caravan/schemas.py").is_file());
    assert!(target.join("caravan/node.py").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[path = "python/recording.rs"]
mod recording_and_report;

#[path = "python/plugin.rs"]
mod plugin_protocol;

#[path = "python/outside.rs"]
mod outside;
