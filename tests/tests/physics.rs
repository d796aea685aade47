//! The physics process's per-robot topics in a real group: an arm on a fixed base follows
//! joint commands and reports joint efforts that answer an applied wrench as Jᵀ·F, a box
//! resting on the floor reports contacts carrying its weight, and a kinematic box flies at
//! its commanded velocity. Commands come from `caravan-testnode arm-commands`.

#[path = "physics/initial.rs"]
mod initial;

use caravan_tests::{Scenario, workspace_root};
use serde_json::Value;

/// The group: physics at 100 Hz (5 substeps), the commander at 10 Hz and an IMU on the arm's
/// link `imu_link`, in lockstep. The
/// position loops' gains suit each joint's inertia: an explicit damping term kd·dt/I above 2
/// would make a light hand oscillate.
fn launch(imu_link: &str) -> String {
    let robots = workspace_root().join("processes/physics/tests/robots");
    let r = |f: &str| robots.join(f).display().to_string();
    format!(
        r#"clock = "lockstep"
duration = "5s"
record = ["robot/**"]

[[process]]
name = "physics"
exec = "caravan-physics"
rate = "100Hz"
[process.params]
world = "{world}"
robots = [
  {{ urdf = "{arm}", base = "fixed", poses = [[1.0, 1.0, 0.0]], link_states = true,
     actuators = [
       {{ type = "position", joints = ["upper_joint"], kp = 400.0, ki = 1000.0, kd = 20.0 }},
       {{ type = "position", joints = ["fore_joint"], kp = 200.0, ki = 500.0, kd = 10.0 }},
       {{ type = "position", joints = ["hand_joint"], kp = 20.0, ki = 50.0, kd = 0.5 }},
     ] }},
  {{ urdf = "{box_}", poses = [[3.0, 3.0, 0.0]], contacts = true }},
  {{ urdf = "{box_}", base = "kinematic", poses = [[3.0, 1.0, 1.5, 0.0, 0.0, 0.0]],
     ground_truth = true }},
  {{ urdf = "{mass}", base = "fixed", poses = [[1.0, 3.0, 1.0, 0.0, 0.0, 0.0]],
     force_torque = ["sensor_joint"], link_states = true }},
]

[[process]]
name = "commander"
exec = "caravan-testnode arm-commands"
rate = "10Hz"

[[process]]
name = "hand-imu"
exec = "caravan-sensor"
rate = "100Hz"
params = {{ robot = 0, count = 1, world = "{world}", urdf = "{arm}", link = "{imu_link}",
           imu_offset = [0.3, 0.0, 0.0] }}

# The force-sensor accelerometer on robot 3's hanging 1 kg mass, told the mass is 2 kg: it
# reads half the specific force, which the finite difference would not.
[[process]]
name = "mass-imu"
exec = "caravan-sensor"
rate = "100Hz"
params = {{ robot = 3, count = 4, world = "{world}", urdf = "{mass}", link = "mass",
           imu_accelerometer = "force_sensor", imu_force_joint = "sensor_joint",
           imu_test_mass_kg = 2.0 }}
"#,
        world = r("empty.toml"),
        arm = r("arm3.urdf"),
        box_ = r("box.urdf"),
        mass = r("test_mass.urdf"),
    )
}

/// Runs the group with `extra` arguments; it must complete.
fn run_ok(s: &Scenario, extra: &[&str]) {
    let out = s.run(extra);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
}

/// Recorded messages of `topic`: (log time ns, JSON).
fn messages(s: &Scenario, topic: &str) -> Vec<(u64, Value)> {
    let bytes = std::fs::read(s.run_dirs()[0].join("record.mcap")).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == topic)
        .map(|m| (m.log_time, serde_json::from_slice(&m.data).unwrap()))
        .collect()
}

/// The last message of `topic` at or before `t_s`.
fn at(msgs: &[(u64, Value)], t_s: f64) -> &Value {
    &msgs
        .iter()
        .rev()
        .find(|(t, _)| *t as f64 <= t_s * 1e9)
        .expect("a message before the time")
        .1
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn joints_links_contacts_wrenches_and_kinematic_bases_on_topics() {
    let s = Scenario::new("physics-topics", &launch("hand"));
    run_ok(&s, &[]);

    // Joint states: by name, in URDF order, at the commanded positions.
    let states = messages(&s, "robot/0/joint_states");
    assert!(states.len() >= 490, "{} joint states", states.len());
    let before = &at(&states, 2.95)["joints"];
    let names: Vec<&str> = before
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["upper_joint", "fore_joint", "hand_joint"]);
    for (k, target) in [0.2, -0.2, 0.0].iter().enumerate() {
        let q = f(&before[k]["position"]);
        assert!(
            (q - target).abs() < 0.01,
            "joint {k} at {q}, target {target}"
        );
    }

    // A 10 N downward force 0.3 m along the hand: each joint's effort changes by the
    // force times the point's horizontal distance from the joint (Jᵀ·F), opposing it.
    let during = &at(&states, 3.95)["joints"];
    let after = &at(&states, 4.95)["joints"];
    let q: Vec<f64> = (0..3).map(|k| f(&during[k]["position"])).collect();
    let (c1, c12, c123) = (q[0].cos(), (q[0] + q[1]).cos(), (q[0] + q[1] + q[2]).cos());
    let reach = [
        0.5 * c1 + 0.4 * c12 + 0.3 * c123,
        0.4 * c12 + 0.3 * c123,
        0.3 * c123,
    ];
    for k in 0..3 {
        let delta = f(&during[k]["effort"]) - f(&before[k]["effort"]);
        let expected = -10.0 * reach[k];
        assert!(
            (delta - expected).abs() < 0.02 * expected.abs(),
            "joint {k}: effort changed by {delta}, Jᵀ·F gives {expected}"
        );
        // The wrench ended after 1 s: the effort is back to holding the arm.
        let back = f(&after[k]["effort"]) - f(&before[k]["effort"]);
        assert!(back.abs() < 0.02 * expected.abs(), "joint {k}: {back}");
    }

    // Link states: the hand joint sits 0.9 m out along the arm from the upper joint.
    let links = messages(&s, "robot/0/link_states");
    let hand = at(&links, 2.95)["links"]
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["name"] == "hand")
        .unwrap()
        .clone();
    let x = f(&hand["pose"]["position"]["x"]);
    let expected_x = 1.0 + 0.5 * q[0].cos() + 0.4 * (q[0] + q[1]).cos();
    assert!(
        (x - expected_x).abs() < 0.01,
        "hand at x = {x}, expected {expected_x}"
    );

    // Contacts: the resting box's normal forces carry its weight, 5 kg × 9.81 m/s².
    let contacts = messages(&s, "robot/1/contacts");
    let resting = at(&contacts, 4.95)["contacts"].as_array().unwrap().clone();
    assert!(!resting.is_empty());
    let total: f64 = resting.iter().map(|c| f(&c["normal_force"])).sum();
    assert!(
        (total - 49.05).abs() < 0.02 * 49.05,
        "normal forces sum to {total} N"
    );
    for c in &resting {
        assert_eq!(
            (c["link"].as_str(), c["other_robot"].as_i64()),
            (Some("body"), Some(-1))
        );
        assert!(f(&c["normal"]["z"]) > 0.99, "{c}");
    }
    // Robots without the option publish no contacts; the arm publishes no wheel state.
    assert!(messages(&s, "robot/0/contacts").is_empty());
    assert!(messages(&s, "robot/0/wheel_state").is_empty());

    // The kinematic box flies at 0.5 m/s along x and does not fall; at 2 s `set_pose` puts
    // it back to (3, 2, 1) m, from where it flies on.
    let twist = messages(&s, "robot/2/twist_true");
    let v = &at(&twist, 4.95)["linear"];
    assert!((f(&v["x"]) - 0.5).abs() < 1e-6, "{v}");
    assert!(f(&v["z"]).abs() < 1e-9, "{v}");
    let pose = messages(&s, "robot/2/pose_true");
    let moved = f(&at(&pose, 1.9)["x"]) - f(&at(&pose, 1.0)["x"]);
    assert!((moved - 0.5 * 0.9).abs() < 0.02, "moved {moved} m");
    assert!((f(&at(&pose, 1.9)["y"]) - 1.0).abs() < 1e-9);
    let truth = messages(&s, "robot/2/ground_truth");
    let after = &at(&truth, 4.95)["pose"]["position"];
    assert!(
        (f(&after["y"]) - 2.0).abs() < 1e-9 && (f(&after["z"]) - 1.0).abs() < 1e-9,
        "{after}"
    );
    let moved = f(&at(&pose, 4.95)["x"]) - f(&at(&pose, 2.5)["x"]);
    assert!((moved - 0.5 * 2.45).abs() < 0.02, "moved {moved} m");
    assert!(
        (f(&at(&pose, 2.2)["x"]) - 3.1).abs() < 0.06,
        "{}",
        at(&pose, 2.2)
    );

    // The force–torque sensor carries the hanging 1 kg test mass: its weight in the sensor's
    // frame, turned 0.5 rad about x.
    let ft = messages(&s, "robot/3/force_torque");
    let reading = &at(&ft, 4.95)["sensors"][0];
    assert_eq!(reading["joint"], "sensor_joint");
    let (fy, fz) = (f(&reading["force"]["y"]), f(&reading["force"]["z"]));
    assert!(
        (fy - 9.81 * 0.5f64.sin()).abs() < 1e-3 && (fz - 9.81 * 0.5f64.cos()).abs() < 1e-3,
        "{reading}"
    );
    // The force-sensor accelerometer on that mass reads F / 2 kg.
    let imu = messages(&s, "robot/3/imu");
    let a = &at(&imu, 4.95)["linear_acceleration"];
    assert!(
        (f(&a["y"]) - fy / 2.0).abs() < 1e-6 && (f(&a["z"]) - fz / 2.0).abs() < 1e-6,
        "{a}"
    );
}

#[test]
fn an_imu_on_a_link_reads_gravity_in_the_link_frame() {
    let s = Scenario::new("physics-imu", &launch("hand"));
    run_ok(&s, &["--duration", "3s"]);
    // The arm holds still from about 2 s with the hand level (joint angles summing to 0):
    // the IMU, 0.3 m out on the hand, reads +g along the hand's z axis and no rotation.
    let imu = messages(&s, "robot/0/imu");
    assert!(imu.len() >= 290, "{} readings", imu.len());
    let r = at(&imu, 2.95);
    let a = &r["linear_acceleration"];
    let (ax, ay, az) = (f(&a["x"]), f(&a["y"]), f(&a["z"]));
    let norm = (ax * ax + ay * ay + az * az).sqrt();
    assert!((norm - 9.81).abs() < 0.01, "|f| = {norm}: {r}");
    assert!(az > 9.8 && ax.abs() < 0.01 && ay.abs() < 0.01, "{r}");
    let w = &r["angular_velocity"];
    assert!(
        f(&w["x"]).abs() + f(&w["y"]).abs() + f(&w["z"]).abs() < 0.01,
        "{r}"
    );
}

/// A sensor on a link whose states physics does not publish says so instead of staying
/// silent.
#[test]
fn a_sensor_without_link_states_says_so() {
    let body = launch("hand").replacen("link_states = true", "link_states = false", 1);
    let s = Scenario::new("physics-silent", &body);
    let out = s.run(&["--duration", "2s"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(messages(&s, "robot/0/imu").is_empty());
    let log = std::fs::read_to_string(s.run_dirs()[0].join("logs/hand-imu.log")).unwrap();
    assert!(
        log.contains("no state of link 'hand' on robot/0/link_states after 1 s")
            && log.contains("link_states = true"),
        "{log}"
    );
}

/// A sensor on a link its robot does not have exits 2 naming the key, the file and the links
/// there are, before it joins any group.
#[test]
fn a_sensor_on_a_missing_link_exits_2_naming_it() {
    let robots = workspace_root().join("processes/physics/tests/robots");
    let params = serde_json::json!({
        "robot": 0, "count": 1,
        "world": robots.join("empty.toml"), "urdf": robots.join("arm3.urdf"), "link": "claw",
    });
    let group = caravan_tests::TestGroup::new("sensor-claw");
    let out = std::process::Command::new(caravan_tests::workspace_bin("caravan-sensor"))
        .env("CARAVAN_GROUP", &group.name)
        .env("CARAVAN_NODE", "hand-imu")
        .env("CARAVAN_PARAMS", params.to_string())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("key 'link' = \"claw\"")
            && err.contains("arm3.urdf has no link named 'claw'")
            && err.contains("links: post, upper, fore, hand"),
        "{err}"
    );
}

/// A physics process without its world, or without its robots, is refused before anything
/// starts, naming the key at the process's params in the launch file: neither has a default.
#[test]
fn a_physics_process_without_world_or_robots_is_refused() {
    let robots = workspace_root().join("processes/physics/tests/robots");
    let world = robots.join("empty.toml").display().to_string();
    let urdf = robots.join("box.urdf").display().to_string();
    for (tag, params, says) in [
        (
            "physics-noworld",
            format!("{{ urdf = \"{urdf}\", count = 1 }}"),
            "key 'world': missing",
        ),
        (
            "physics-norobots",
            format!("{{ world = \"{world}\" }}"),
            "key 'robots': missing",
        ),
    ] {
        let body = format!(
            "clock = \"lockstep\"\nduration = \"1s\"\n\n[[process]]\nname = \"physics\"\n\
             exec = \"caravan-physics\"\nparams = {params}\n"
        );
        let s = caravan_tests::Scenario::new(tag, &body);
        let out = s.run(&[]);
        let line = std::fs::read_to_string(&s.file)
            .unwrap()
            .lines()
            .position(|l| l.starts_with("params = "))
            .unwrap()
            + 1;
        let at = format!("launch.toml:{line}");
        caravan_tests::assert_refused(&s, &out, &[&at, "process 'physics'", says]);
    }
}
