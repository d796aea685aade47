//! Initial joint states (`initial_positions`, `initial_velocities`) in a real group, their
//! refusals, and a sensor frame given by a fixed URDF link with its own `rpy`.

use super::{f, messages};
use caravan_tests::{Scenario, workspace_root};
use serde_json::Value;

/// A 1 kg bob 1 m below a pivot 1.5 m up, swinging on revolute joint `swing` about y (limits
/// ±1 rad, 5 rad/s), and a link fixed to the pivot by `mount`.
const SWING: &str = r#"<robot name="swing">
  <link name="pivot"/>
  <link name="tag"/>
  <link name="bob">
    <inertial><origin xyz="0 0 -1.0"/><mass value="1.0"/>
      <inertia ixx="0.00004" iyy="0.00004" izz="0.00004" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 -1.0"/><geometry><sphere radius="0.01"/></geometry></collision>
  </link>
  <joint name="mount" type="fixed"><parent link="pivot"/><child link="tag"/></joint>
  <joint name="swing" type="revolute"><parent link="pivot"/><child link="bob"/>
    <origin xyz="0 0 1.5"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="100" velocity="5"/></joint>
</robot>"#;

/// A physics-only group in lockstep with `robots` (TOML) in the empty world, `swing.urdf`
/// beside the launch file.
fn scenario(tag: &str, params: &str) -> Scenario {
    let world = workspace_root().join("processes/physics/tests/robots/empty.toml");
    let body = format!(
        "clock = \"lockstep\"\nduration = \"1.5s\"\nrecord = [\"robot/**\"]\n\n[[process]]\n\
         name = \"physics\"\nexec = \"caravan-physics\"\nrate = \"100Hz\"\n\
         [process.params]\nworld = \"{}\"\n{params}\n",
        world.display()
    );
    let s = Scenario::new(tag, &body);
    std::fs::write(s.dir.join("swing.urdf"), SWING).unwrap();
    s
}

/// Joint `swing`'s (time s, position, velocity) of robot `i` in run directory `dir`.
fn swing(s: &Scenario, i: usize) -> Vec<(f64, f64, f64)> {
    messages(s, &format!("robot/{i}/joint_states"))
        .iter()
        .map(|(t, m): &(u64, Value)| {
            let j = &m["joints"][0];
            (*t as f64 * 1e-9, f(&j["position"]), f(&j["velocity"]))
        })
        .collect()
}

/// Every recorded message of a run: topic, log time, payload.
fn recording(dir: &std::path::Path) -> Vec<(String, u64, Vec<u8>)> {
    let bytes = std::fs::read(dir.join("record.mcap")).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .map(|m| (m.channel.topic.clone(), m.log_time, m.data.to_vec()))
        .collect()
}

#[test]
fn pendulums_start_at_their_initial_joint_state() {
    // Robots 0, 2, 4 on multibody joints (the fixed base's default), 1 and 3 on impulse
    // joints; 4 is held by a position loop; each in its own plane.
    let s = scenario(
        "physics-initial-joints",
        r#"robots = [
  { urdf = "swing.urdf", base = "fixed", poses = [[2.0, 0.4, 0.0]], initial_positions = { swing = 0.5 } },
  { urdf = "swing.urdf", base = "fixed", poses = [[2.0, 1.1, 0.0]], joints = "impulse", initial_positions = { swing = 0.5 } },
  { urdf = "swing.urdf", base = "fixed", poses = [[2.0, 1.8, 0.0]], initial_velocities = { swing = 1.0 } },
  { urdf = "swing.urdf", base = "fixed", poses = [[2.0, 2.5, 0.0]], joints = "impulse", initial_velocities = { swing = 1.0 } },
  { urdf = "swing.urdf", base = "fixed", poses = [[2.0, 3.2, 0.0]], initial_positions = { swing = 0.5 },
    actuators = [{ type = "position", joints = ["swing"], kp = 400.0, ki = 1000.0, kd = 20.0 }] },
]"#,
    );
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let g: f64 = 9.81;
    // I about the pivot: the bob's 1 kg at 1 m and its own 4e-5 kg·m².
    let inertia = 1.0 + 4e-5;
    for i in [0, 1] {
        let q = swing(&s, i);
        // The first reading, at t = 0 before any step: the initial position (f32 bodies).
        assert!(
            q[0].0 == 0.0 && (q[0].1 - 0.5).abs() < 1e-6,
            "robot {i}: {:?}",
            q[0]
        );
        // Undamped, it swings through 0 to its first turning point at −0.5 rad, less what
        // the integrator loses: energy is conserved to O(dt) (3e-6 rad on multibody, 6e-5 on
        // impulse joints, seen), and the 100 Hz samples catch the minimum to within
        // α·(5 ms)²/2 = 6e-5 rad (α = g·sin 0.5/L).
        let low = q.iter().map(|r| r.1).fold(f64::INFINITY, f64::min);
        assert!((low + 0.5).abs() < 2e-4, "robot {i}: turns at {low} rad");
    }
    for i in [2, 3] {
        let q = swing(&s, i);
        assert_eq!((q[0].1, q[0].2), (0.0, 1.0), "robot {i}");
        // ½·I·ω² = m·g·L·(1 − cos q_max); within the integrator's loss and the sampling's
        // α·(5 ms)²/2 = 4e-5 rad, as above.
        let q_max = (1.0 - 0.5 * inertia * 1.0 / g).acos();
        let high = q.iter().map(|r| r.1).fold(f64::NEG_INFINITY, f64::max);
        assert!(
            (high - q_max).abs() < 2e-3,
            "robot {i}: turns at {high}, not {q_max}"
        );
    }
    // The position loop holds the initial position rather than pulling to 0.
    let held = swing(&s, 4);
    let worst = held.iter().map(|r| (r.1 - 0.5).abs()).fold(0.0, f64::max);
    assert!(worst < 0.05, "the held joint strays {worst} rad from 0.5");
    assert!(
        (held.last().unwrap().1 - 0.5).abs() < 5e-3,
        "{:?}",
        held.last()
    );

    // Lockstep: a second run records the same messages, bit for bit.
    let again = s.run(&[]);
    assert!(again.status.success());
    let dirs = s.run_dirs();
    assert_eq!(dirs.len(), 2);
    assert_eq!(recording(&dirs[0]), recording(&dirs[1]));
}

#[test]
fn bad_initial_joint_states_exit_2_naming_the_key() {
    let entry = |keys: &str| {
        format!(
            "robots = [\n  {{ urdf = \"swing.urdf\", base = \"fixed\", poses = [[2.0, 2.0, 0.0]],\n    {keys} }},\n]"
        )
    };
    let cases = [
        (
            "swnig",
            entry("initial_positions = { swnig = 0.5 }"),
            vec![
                "key 'robots[0].initial_positions.swnig'",
                "no joint named 'swnig'",
                "did you mean 'swing'",
            ],
        ),
        (
            "fixed",
            entry("initial_positions = { mount = 0.1 }"),
            vec!["key 'robots[0].initial_positions.mount'", "is fixed"],
        ),
        (
            "limits",
            entry("initial_positions = { swing = 1.5 }"),
            vec![
                "key 'robots[0].initial_positions.swing'",
                "outside joint 'swing''s limits [-1, 1] rad",
            ],
        ),
        (
            "nan",
            entry("initial_positions = { swing = nan }"),
            vec!["initial_positions.swing", "NaN cannot be passed"],
        ),
        (
            "inf",
            entry("initial_velocities = { swing = inf }"),
            vec!["initial_velocities.swing", "inf cannot be passed"],
        ),
        (
            "fast",
            entry("initial_velocities = { swing = 6.0 }"),
            vec![
                "key 'robots[0].initial_velocities.swing'",
                "velocity limit 5 rad/s",
            ],
        ),
        (
            "convoy",
            "urdf = \"swing.urdf\"\ncount = 1\ninitial_positions = { swing = 0.5 }".into(),
            vec!["key 'initial_positions'", "convoy's wheeled robot"],
        ),
    ];
    for (tag, params, says) in cases {
        let s = scenario(&format!("physics-initial-{tag}"), &params);
        let out = s.run(&[]);
        let mut says = says;
        says.push("launch.toml:");
        caravan_tests::assert_refused(&s, &out, &says);
    }
}

/// An IMU frame is a link's: a fixed child link `imu_link` turned by its joint's `rpy` (a
/// ROS robot's sensor frame) is reported by link_states with its own frame, so an IMU on it
/// reads gravity along that frame's axes.
#[test]
fn an_imu_on_a_turned_fixed_link_reads_in_that_links_axes() {
    let (roll, pitch, yaw) = (0.3, -0.2, 0.5);
    let urdf = format!(
        r#"<robot name="mount">
  <link name="base"/>
  <link name="imu_link"/>
  <joint name="imu_joint" type="fixed"><parent link="base"/><child link="imu_link"/>
    <origin xyz="0.1 0 0.2" rpy="{roll} {pitch} {yaw}"/></joint>
</robot>"#
    );
    let world = workspace_root().join("processes/physics/tests/robots/empty.toml");
    let body = format!(
        r#"clock = "lockstep"
duration = "0.5s"
record = ["robot/**"]

[[process]]
name = "physics"
exec = "caravan-physics"
rate = "100Hz"
params = {{ world = "{w}", precision = "f64", robots = [
  {{ urdf = "mount.urdf", base = "fixed", poses = [[2.0, 2.0, 0.0]], link_states = true }}] }}

[[process]]
name = "imu"
exec = "caravan-sensor"
rate = "100Hz"
params = {{ robot = 0, count = 1, world = "{w}", urdf = "mount.urdf", link = "imu_link" }}
"#,
        w = world.display()
    );
    let s = Scenario::new("physics-imu-frame", &body);
    std::fs::write(s.dir.join("mount.urdf"), urdf).unwrap();
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let imu = messages(&s, "robot/0/imu");
    assert!(imu.len() >= 40, "{} readings", imu.len());
    // URDF rpy: R = Rz(yaw)·Ry(pitch)·Rx(roll), sensor → base; at rest the specific force
    // is Rᵀ·(0, 0, g), g times R's last row.
    let g: f64 = 9.81;
    let expected = [
        -g * f64::sin(pitch),
        g * f64::cos(pitch) * f64::sin(roll),
        g * f64::cos(pitch) * f64::cos(roll),
    ];
    for (_, m) in &imu {
        let a = &m["linear_acceleration"];
        let got = [f(&a["x"]), f(&a["y"]), f(&a["z"])];
        let error = (0..3)
            .map(|k| (got[k] - expected[k]).abs())
            .fold(0.0, f64::max);
        assert!(error < 1e-9, "{got:?} vs {expected:?}");
        let w = &m["angular_velocity"];
        assert!(
            f(&w["x"]).abs() + f(&w["y"]).abs() + f(&w["z"]).abs() < 1e-12,
            "{m}"
        );
    }
}
