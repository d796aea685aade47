//! `caravan-script`: scripted commands from a launch file, in real groups with the physics:
//! a joint target at a time, a wrench held over an interval, a trigger on a joint's position,
//! lockstep reruns byte for byte; and every bad command refused before anything starts, with
//! its file, line and key.

use caravan_tests::{Scenario, assert_refused, recording, workspace_root};
use serde_json::Value;

const MS: u64 = 1_000_000;

/// `launch/imu/<path>`, absolute, for a launch file written elsewhere.
fn imu(path: &str) -> String {
    workspace_root()
        .join("launch/imu")
        .join(path)
        .display()
        .to_string()
}

/// The IMU scenario's two-link arm (shoulder and elbow about z) bolted to the world, its
/// joints under position PIDs, and a script that sets the shoulder's target to 0.5 rad at
/// 1 s and, once the shoulder passes 0.25 rad, the elbow's to 0.3 rad.
fn arm() -> String {
    format!(
        r#"clock = "lockstep"
duration = "2.5s"
tick = "1ms"
record = ["robot/0/joint_states", "robot/0/joint_command"]

[[process]]
name = "physics"
exec = "caravan-physics"
rate = "100Hz"
params = {{ world = "{world}", substeps = 10, robots = [
  {{ urdf = "{urdf}", base = "fixed", poses = [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]],
     actuators = [{{ type = "position", joints = ["*"], kp = 20.0, ki = 0.0, kd = 6.0 }}] }},
] }}

[[process]]
name = "script"
exec = "caravan-script"
rate = "100Hz"

[[process.params.command]]
at_s = 1.0
topic = "robot/0/joint_command"
message = {{ joints = [{{ name = "shoulder", position = 0.5, effort = "nan" }}] }}

[[process.params.command]]
when = {{ topic = "robot/0/joint_states", field = "joints[shoulder].position", above = 0.25 }}
topic = "robot/0/joint_command"
message = {{ joints = [{{ name = "elbow", position = 0.3 }}] }}
"#,
        world = imu("worlds/empty.toml"),
        urdf = imu("robots/arm.urdf"),
    )
}

/// Runs `s` and returns its recording's bytes.
fn run(s: &Scenario) -> Vec<u8> {
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = s.run_dirs().pop().expect("a run directory");
    recording::read(&dir.join("record.mcap"))
}

/// The recorded messages of `topic` as (stamp, JSON).
fn messages(bytes: &[u8], topic: &str) -> Vec<(u64, Value)> {
    recording::messages(bytes, topic)
        .iter()
        .map(|m| {
            let v: Value = serde_json::from_slice(m).unwrap();
            (v["header"]["stamp_ns"].as_u64().unwrap(), v)
        })
        .collect()
}

/// The position of joint `name` in a `JointState`.
fn position(js: &Value, name: &str) -> f64 {
    js["joints"]
        .as_array()
        .unwrap()
        .iter()
        .find(|j| j["name"] == name)
        .unwrap()["position"]
        .as_f64()
        .unwrap()
}

#[test]
fn a_scripted_joint_target_moves_the_joint_only_after_its_time() {
    let s = Scenario::new("script-joint", &arm());
    let bytes = run(&s);
    let commands = messages(&bytes, "robot/0/joint_command");
    // Published at exactly 1 s; the effort given as "nan" is NaN (null in the recording).
    let (stamp, first) = &commands[0];
    assert_eq!(*stamp, 1000 * MS, "{commands:?}");
    let joint = &first["joints"][0];
    assert_eq!(
        (
            &joint["name"],
            &joint["position"],
            &joint["velocity"],
            &joint["effort"]
        ),
        (&"shoulder".into(), &0.5.into(), &0.0.into(), &Value::Null),
        "{first}"
    );
    let states = messages(&bytes, "robot/0/joint_states");
    assert!(states.len() >= 250, "{}", states.len());
    for (t, js) in &states {
        let q = position(js, "shoulder");
        if *t <= 1000 * MS {
            // The physics step at 1 s ran before the command was visible (one tick later).
            assert_eq!(q, 0.0, "at {t} ns");
        } else if *t >= 2000 * MS {
            assert!((q - 0.5).abs() < 0.01, "at {t} ns: {q}");
        }
    }
    let after = states.iter().find(|(t, _)| *t == 1010 * MS).unwrap();
    assert!(position(&after.1, "shoulder") > 0.0, "{}", after.1);
}

#[test]
fn a_trigger_fires_once_at_the_first_step_after_the_field_crosses() {
    let s = Scenario::new("script-trigger", &arm());
    let bytes = run(&s);
    let commands = messages(&bytes, "robot/0/joint_command");
    assert_eq!(commands.len(), 2, "fired once: {commands:?}");
    let (fired, elbow) = &commands[1];
    assert_eq!(elbow["joints"][0]["name"], "elbow", "{elbow}");
    assert_eq!(elbow["joints"][0]["position"], 0.3, "{elbow}");
    // The script steps every 10 ms and sees a message one tick (1 ms) after its stamp: the
    // first step that could see a joint state above 0.25 rad.
    let states = messages(&bytes, "robot/0/joint_states");
    let crossed = states
        .iter()
        .find(|(_, js)| position(js, "shoulder") > 0.25)
        .map(|(t, _)| *t)
        .expect("the shoulder passes 0.25 rad");
    let expected = (crossed + MS).div_ceil(10 * MS) * 10 * MS;
    assert_eq!(*fired, expected, "crossed at {crossed} ns");
    assert!(*fired > 1000 * MS);
    // The elbow then moves toward its target.
    let (_, last) = states.last().unwrap();
    assert!(position(last, "elbow") > 0.2, "{last}");
}

#[test]
fn lockstep_runs_of_a_script_record_the_same_bytes() {
    let s = Scenario::new("script-same", &arm());
    let a = run(&s);
    let b = run(&s);
    assert!(a.len() > 10_000, "{}", a.len());
    assert!(a == b, "the recordings differ");
    assert_eq!(messages(&a, "robot/0/joint_command").len(), 2);
}

#[test]
fn a_held_wrench_accelerates_a_free_cube_only_in_its_interval() {
    // No gravity: the 5 kg cube floats still until pushed along x with 5 N, in its own frame
    // through its origin (no torque), from 1 s until 1.5 s: 1 m/s² for 0.5 s.
    let body = format!(
        r#"clock = "lockstep"
duration = "2s"
tick = "1ms"
record = ["robot/0/ground_truth", "robot/0/wrench"]

[[process]]
name = "physics"
exec = "caravan-physics"
rate = "100Hz"
params = {{ world = "{world}", substeps = 10, gravity = 0.0, robots = [
  {{ urdf = "{urdf}", poses = [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]], ground_truth = true }},
] }}

[[process]]
name = "script"
exec = "caravan-script"
rate = "100Hz"

[[process.params.command]]
from_s = 1.0
until_s = 1.5
topic = "robot/0/wrench"
message = {{ link = "cube", frame = 1, force = {{ x = 5.0 }}, duration_s = 0.01 }}
"#,
        world = imu("worlds/empty.toml"),
        urdf = imu("robots/cube.urdf"),
    );
    let s = Scenario::new("script-wrench", &body);
    let bytes = run(&s);
    let wrenches = messages(&bytes, "robot/0/wrench");
    let stamps: Vec<u64> = wrenches.iter().map(|w| w.0).collect();
    let expected: Vec<u64> = (100..150).map(|k| k * 10 * MS).collect();
    assert_eq!(stamps, expected, "every step from 1 s until before 1.5 s");
    let truth = messages(&bytes, "robot/0/ground_truth");
    assert!(truth.len() >= 200);
    let speed = |v: &Value| v["twist"]["linear"]["x"].as_f64().unwrap();
    for (t, v) in &truth {
        let x = speed(v);
        if *t <= 1000 * MS {
            assert_eq!(x, 0.0, "still before the push, at {t} ns");
        } else if *t < 1500 * MS {
            // 1 m/s² from the step after 1 s.
            let pushed = (*t - 1000 * MS) as f64 * 1e-9;
            assert!(
                (x - pushed).abs() < 1e-3,
                "at {t} ns: {x} m/s, not {pushed}"
            );
        } else {
            assert!((x - 0.5).abs() < 1e-3, "coasting at {t} ns: {x} m/s");
        }
    }
    // After the interval the cube coasts: nothing pushes it any more.
    let coasting: Vec<f64> = truth
        .iter()
        .filter(|(t, _)| *t >= 1500 * MS)
        .map(|(_, v)| speed(v))
        .collect();
    assert!(coasting.len() > 40);
    assert!(coasting.iter().all(|x| *x == coasting[0]), "{coasting:?}");
}

// --- Bad commands: exit 2 before anything starts, naming the file, line and key. ---

/// A script-only group with one command of `lines`.
fn script(lines: &str) -> Scenario {
    let body = format!(
        r#"clock = "lockstep"
duration = "1s"

[[process]]
name = "script"
exec = "caravan-script"
rate = "100Hz"

[[process.params.command]]
{lines}
"#
    );
    Scenario::new("script-bad", &body)
}

/// Runs `lines` and checks it is refused at the line holding `at`, with each of `expected`.
fn refused(lines: &str, at: &str, expected: &[&str]) {
    let s = script(lines);
    let text = std::fs::read_to_string(&s.file).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains(at))
        .expect("the marked line")
        + 1;
    let out = s.run(&[]);
    let place = format!("launch.toml:{line}:");
    let mut all = vec![place.as_str()];
    all.extend(expected);
    assert_refused(&s, &out, &all);
}

#[test]
fn an_unknown_message_type_is_refused() {
    refused(
        "at_s = 1.0\ntopic = \"my/topic\"\ntype = \"caravan::Nope\"",
        "type =",
        &[
            "key 'command[0].type'",
            "unknown message type 'caravan::Nope'",
        ],
    );
}

#[test]
fn a_type_other_than_a_well_known_topics_is_refused() {
    refused(
        "at_s = 1.0\ntopic = \"robot/0/cmd_vel\"\ntype = \"caravan::Pose2D\"",
        "type =",
        &["key 'command[0].type'", "carries caravan::Twist"],
    );
}

#[test]
fn a_message_field_the_type_does_not_have_is_refused() {
    refused(
        "at_s = 1.0\ntopic = \"robot/0/cmd_vel\"\nmessage = { linear = { w = 1.0 } }",
        "message =",
        &["key 'command[0].message.linear.w'", "has no field 'w'"],
    );
}

#[test]
fn a_message_field_of_the_wrong_type_is_refused() {
    refused(
        "at_s = 1.0\ntopic = \"robot/0/joint_command\"\n\
         message = { joints = [{ name = \"a\", position = \"far\" }] }",
        "message =",
        &[
            "key 'command[0].message.joints[0].position'",
            "expected f64",
        ],
    );
}

#[test]
fn a_negative_time_is_refused() {
    refused(
        "at_s = -1.0\ntopic = \"robot/0/cmd_vel\"",
        "at_s",
        &["key 'command[0].at_s'", "0 or more"],
    );
}

#[test]
fn a_non_finite_time_is_refused() {
    // The launcher itself refuses TOML's nan and inf in params (JSON has neither).
    refused(
        "from_s = nan\ntopic = \"robot/0/cmd_vel\"",
        "from_s",
        &["from_s", "cannot be passed as a parameter"],
    );
}

#[test]
fn an_end_not_after_the_start_is_refused() {
    refused(
        "from_s = 2.0\nuntil_s = 2.0\ntopic = \"robot/0/cmd_vel\"",
        "until_s",
        &["key 'command[0].until_s'", "must be after from_s"],
    );
}

#[test]
fn a_trigger_field_the_topics_type_does_not_have_is_refused() {
    refused(
        "when = { topic = \"robot/0/ground_truth\", field = \"pose.position.q\", above = 1.0 }\n\
         topic = \"robot/0/cmd_vel\"",
        "when =",
        &[
            "key 'command[0].when.field'",
            "caravan::Odometry",
            "has no field 'q'",
        ],
    );
}

#[test]
fn an_invalid_topic_name_is_refused() {
    refused(
        "at_s = 1.0\ntopic = \"robot//cmd vel\"",
        "topic =",
        &["key 'command[0].topic'", "is not a topic name"],
    );
}

#[test]
fn two_ways_of_saying_when_are_refused() {
    refused(
        "at_s = 1.0\nfrom_s = 2.0\ntopic = \"robot/0/cmd_vel\"",
        "[[process.params.command]]",
        &["key 'command[0]'", "exactly one of at_s"],
    );
}
