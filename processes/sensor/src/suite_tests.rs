use super::*;
use caravan_schemas::{ForceTorque, LinkState, Name, Pose3D, Quaternion, Vector3, placement_new};
use caravan_world::world::parse_world;
use serde_json::{Value, json};

const SEED: u64 = 42;
/// The node's step, ns (100 Hz).
const DT_NS: u64 = 10_000_000;

/// A 4 × 3 m room with walls 0.1 m thick on its outline and a 0.4 m box at (3, 1).
const ROOM: &str = r#"
[world]
name = "room"
size = [4.0, 3.0]
[[wall]]
from = [0.0, 0.0]
to = [4.0, 0.0]
thickness = 0.1
[[wall]]
from = [4.0, 0.0]
to = [4.0, 3.0]
thickness = 0.1
[[wall]]
from = [4.0, 3.0]
to = [0.0, 3.0]
thickness = 0.1
[[wall]]
from = [0.0, 3.0]
to = [0.0, 0.0]
thickness = 0.1
[[box]]
center = [3.0, 1.0]
size = [0.4, 0.4]
"#;

fn world() -> World {
    parse_world(ROOM).unwrap()
}

fn robot() -> RobotModel {
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../launch/convoy/robots/convoy_bot.urdf");
    caravan_world::load_robot(&urdf).unwrap()
}

fn params(v: Value) -> Params {
    caravan::parse_params("sensor", &v).unwrap()
}

/// The sensors of `p` with the robot's description, encoders every 2nd step, laser every
/// 10th.
fn suite(p: &Params, robot: Option<&RobotModel>) -> SensorSuite {
    SensorSuite::new(p, &world(), robot, SEED, 2, 10)
}

/// Robot 1 of 3 with a noisy laser and a noisy IMU on its base.
fn leader() -> Params {
    params(json!({
        "robot": 1, "count": 3, "world": "room.toml", "laser": true, "imu_noise": true
    }))
}

/// Robot 0 with its laser and IMU on link `hand` (its description unknown to the laser).
fn on_link(extra: Value) -> Params {
    let mut v = json!({
        "robot": 0, "count": 1, "world": "room.toml", "link": "hand", "laser": true,
        "laser_z_offset": 0.05, "imu_noise": true
    });
    v.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    params(v)
}

/// A `link_states` message holding link `name` at (x, y, z), yawed by `yaw`, turning at 0.5
/// rad/s.
fn link_states(name: &str, [x, y, z]: [f64; 3], yaw: f64) -> LinkStates {
    let mut m = placement_new::<LinkStates>();
    let pose = Pose3D {
        position: Vector3 { x, y, z },
        orientation: Quaternion::from_yaw(yaw),
    };
    let mut twist = Twist::default();
    twist.angular.z = 0.5;
    m.links.push(LinkState::new(name, pose, twist)).unwrap();
    m
}

fn bits(scan: &LaserScan) -> Vec<u32> {
    scan.ranges().iter().map(|r| r.to_bits()).collect()
}

fn pose(x: f64, y: f64, theta: f64) -> Pose2D {
    Pose2D { x, y, theta }
}

#[test]
fn the_laser_sees_every_other_robot_when_it_knows_their_shape() {
    let robot = robot();
    assert_eq!(suite(&leader(), Some(&robot)).others(), [0, 2]);
    assert!(suite(&leader(), None).others().is_empty(), "no description");
    let no_laser = Params {
        laser: false,
        ..leader()
    };
    assert!(suite(&no_laser, Some(&robot)).others().is_empty());
}

#[test]
fn encoder_ticks_come_every_nth_step_once_a_wheel_state_has() {
    let mut s = suite(&leader(), Some(&robot()));
    assert_eq!(s.encoder_ticks(0), None);
    let w = WheelState {
        left_angle_rad: std::f64::consts::TAU,
        right_angle_rad: -std::f64::consts::PI,
        ..WheelState::default()
    };
    s.wheel(w);
    assert_eq!(s.encoder_ticks(0), Some(encoder_ticks(&w, 360)));
    assert_eq!(
        s.encoder_ticks(0).map(|t| (t.left, t.right)),
        Some((360, -180))
    );
    assert_eq!(s.encoder_ticks(1), None);
    assert!(s.encoder_ticks(4).is_some());
}

#[test]
fn a_scan_is_due_every_nth_step_once_the_pose_is_known_and_sees_the_other_robots() {
    let (p, robot) = (leader(), robot());
    let mut s = suite(&p, Some(&robot));
    assert!(!s.scan_due(0), "no pose yet");
    let own = pose(1.0, 1.5, 0.0);
    s.pose(0, own);
    assert!(s.scan_due(0) && !s.scan_due(5) && s.scan_due(10));

    // Only robot 2's pose came: 1 m ahead.
    let ahead = pose(2.0, 1.5, 0.0);
    s.other_pose(1, ahead);
    // The scans of a laser of the same seed fed directly: the same noise draws, in order.
    let mut laser = Laser::new(p.laser_config(), &world(), &robot, SEED);
    let (mut got, mut want) = (LaserScan::default(), LaserScan::default());
    for _ in 0..2 {
        s.scan(&mut got);
        laser.scan(&own, &[ahead], &mut want);
        assert_eq!(bits(&got), bits(&want));
    }
    // Beam 341 looks straight ahead: at the other robot's chassis, not the wall 2.95 m away.
    assert!(got.ranges[341] < 1.0, "{}", got.ranges[341]);
}

#[test]
fn the_imu_reads_poses_and_twists_of_the_same_instant_only() {
    let p = leader();
    let mut s = suite(&p, Some(&robot()));
    let mut imu = VirtualImu::new(
        Mount {
            offset: p.imu_offset.into(),
        },
        p.imu_noise(),
        SEED,
    );
    let at = |k: u64| (k * DT_NS, pose(0.01 * k as f64, 0.0, 0.05 * k as f64));
    let twist = Twist::planar(1.0, 0.5);
    let body = |k: u64| BodyState::planar(at(k).0, &at(k).1, &twist);

    let (t0, p0) = at(0);
    s.pose(t0, p0);
    s.twist(t0, twist);
    s.pair_imu();
    assert_eq!(s.imu_message(), None, "the first instant gives no reading");
    assert_eq!(imu.update(&body(0)), None);

    // The pose of the next instant comes a step before its twist: no reading in between.
    let (t1, p1) = at(1);
    s.pose(t1, p1);
    s.pair_imu();
    assert_eq!(s.imu_message(), None);
    let (t2, p2) = at(2);
    s.twist(t1, twist);
    s.pose(t2, p2);
    s.twist(t2, twist);
    s.pair_imu();
    // Both instants read in order; the newest reading is published.
    imu.update(&body(1)).unwrap();
    let r2 = imu.update(&body(2)).unwrap();
    assert_eq!(s.imu_message(), Some(imu.message(&r2)));
    assert_eq!(s.imu_message(), None, "published once");

    let off = Params {
        imu: false,
        ..leader()
    };
    let mut s = suite(&off, Some(&robot()));
    for k in 0..3 {
        let (t, p) = at(k);
        s.pose(t, p);
        s.twist(t, twist);
        s.pair_imu();
        assert_eq!(s.imu_message(), None);
    }
}

#[test]
fn on_a_link_its_state_places_the_laser_and_moves_the_imu() {
    let p = on_link(json!({}));
    let mut s = suite(&p, None);
    assert!(s.others().is_empty() && !s.reads_forces());
    s.link_states(0, &link_states("foot", [1.0, 1.5, 0.3], 0.0));
    assert!(!s.scan_due(0), "another link");

    let first = link_states("hand", [1.0, 1.5, 0.3], 0.0);
    s.link_states(0, &first);
    assert!(s.scan_due(0));
    let mut laser = Laser::world_only(p.laser_config(), &world(), SEED);
    laser.set_mount_height(0.3);
    let (mut got, mut want) = (LaserScan::default(), LaserScan::default());
    s.scan(&mut got);
    laser.scan(&pose(1.0, 1.5, 0.0), &[], &mut want);
    assert_eq!(bits(&got), bits(&want));

    let mut imu = VirtualImu::new(
        Mount {
            offset: p.imu_offset.into(),
        },
        p.imu_noise(),
        SEED,
    );
    let second = link_states("hand", [1.01, 1.5, 0.3], 0.005);
    let body = |t: u64, m: &LinkStates| link_state(t, m, "hand").unwrap().0;
    assert_eq!(s.imu_message(), None);
    imu.update(&body(0, &first));
    s.link_states(DT_NS, &second);
    let r = imu.update(&body(DT_NS, &second)).unwrap();
    assert_eq!(s.imu_message(), Some(imu.message(&r)));
}

#[test]
fn the_force_sensor_accelerometer_reads_the_force_of_the_same_instant() {
    let p = on_link(json!({
        "imu_accelerometer": "force_sensor", "imu_test_mass_kg": 2.0, "imu_noise": false
    }));
    let mut s = suite(&p, None);
    assert!(s.reads_forces());
    let forces = |fz: f64| {
        let mut m = placement_new::<ForceTorques>();
        let mut ft = ForceTorque {
            joint: Name::new("accel_joint"),
            ..ForceTorque::default()
        };
        ft.force.z = fz;
        m.sensors.push(ft).unwrap();
        m
    };
    let mut imu = VirtualImu::new(
        Mount {
            offset: p.imu_offset.into(),
        },
        p.imu_noise(),
        SEED,
    );
    let states = [
        link_states("hand", [1.0, 1.5, 0.3], 0.0),
        link_states("hand", [1.01, 1.5, 0.3], 0.005),
    ];
    let mut last = None;
    for (k, (m, fz)) in states.iter().zip([19.6, 20.0]).enumerate() {
        let t = k as u64 * DT_NS;
        s.forces(t, &forces(fz));
        s.link_states(t, m);
        let body = link_state(t, m, "hand").unwrap().0;
        let f = nalgebra::Vector3::new(0.0, 0.0, fz / 2.0);
        last = imu.update_with(&body, Some(f));
    }
    let r = last.expect("a reading at the second instant");
    // Ideal (no noise): the second instant's force over the 2 kg mass, not the first's.
    assert_eq!(r.linear_acceleration.z, 10.0);
    assert_eq!(s.imu_message(), Some(imu.message(&r)));
}

#[test]
fn a_silent_link_is_reported_once_after_a_second() {
    let p = on_link(json!({}));
    let mut s = suite(&p, None);
    assert!(!s.link_silent(Duration::from_millis(500)));
    assert!(s.link_silent(Duration::from_secs(1)));
    assert!(!s.link_silent(Duration::from_secs(2)), "once");

    let mut s = suite(&p, None);
    s.link_states(0, &link_states("hand", [1.0, 1.5, 0.3], 0.0));
    assert!(!s.link_silent(Duration::from_secs(1)), "its state came");

    let mut s = suite(&leader(), Some(&robot()));
    assert!(!s.link_silent(Duration::from_secs(5)), "on the base");
}
