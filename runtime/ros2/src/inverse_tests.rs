use super::*;
use crate::mapping::{Caravan, Frames, RosMessage, to_ros};
use crate::msgs::to_cdr;
use crate::naming;

/// `c` on `topic` taken to ROS 2 as `ty` (encoded as a bag holds it) and played back.
fn through_ros(topic: &str, ty: RosType, c: Caravan, stamp_ns: u64) -> Played {
    let frames = naming::frames(topic, ty);
    let m = to_ros(ty, c, stamp_ns, &frames).expect("a mapped pair");
    let caravan_type = caravan_type_in(ty, topic).expect("played back");
    caravan_json(ty, caravan_type, &to_cdr(&m)).unwrap()
}

/// Whether `a` and `b` are the same JSON, a yaw (`theta`) within one ulp: a Pose2D's yaw
/// crosses as a quaternion, which neighbouring angles may share (see [`planar`]).
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

/// `original` comes back exactly (a yaw within an ulp), with its stamp when the ROS type has a
/// header.
fn assert_round_trip<T: serde::Serialize>(
    topic: &str,
    ty: RosType,
    original: &T,
    c: Caravan,
    stamped: bool,
) {
    let stamp = 12_345_678_901;
    let back = through_ros(topic, ty, c, stamp);
    let expected = serde_json::to_value(original).unwrap();
    assert!(
        same(&back.json, &expected, ""),
        "{topic}: {} came back as {}",
        expected,
        back.json
    );
    assert_eq!(back.stamp_ns, stamped.then_some(stamp), "{topic}");
}

/// Angles of every kind: small, near ±π, past π, irrational, negative zero.
const ANGLES: [f64; 12] = [
    0.0,
    -0.0,
    1e-9,
    0.1,
    -std::f64::consts::FRAC_PI_4,
    1.2345678901234567,
    std::f64::consts::PI,
    -std::f64::consts::PI,
    std::f64::consts::PI - 1e-7,
    -2.9999999999,
    4.0,
    -5.5,
];

#[test]
fn a_scan_round_trips_exactly() {
    let mut s = cv::boxed_placement_new::<cv::LaserScan>();
    s.beam_count = 4;
    s.ranges[..4].copy_from_slice(&[0.5, 1.25, 7.0, 30.000002]);
    s.intensities[..4].copy_from_slice(&[1.0, 0.0, 0.5, 0.1]);
    (s.angle_min, s.angle_max, s.angle_increment) = (-2.35619, 2.35619, 0.004363323);
    (s.time_increment, s.scan_time) = (1e-5, 0.1);
    (s.range_min, s.range_max) = (0.05, 30.0);
    assert_round_trip(
        "robot/0/scan",
        RosType::LaserScan,
        s.as_ref(),
        Caravan::LaserScan(&s),
        true,
    );
    let ros = match to_ros(
        RosType::LaserScan,
        Caravan::LaserScan(&s),
        0,
        &Frames::default(),
    ) {
        Some(RosMessage::LaserScan(m)) => m,
        other => panic!("{other:?}"),
    };
    assert_eq!(scan_in(&ros).unwrap(), s);
    // The widest scan fits; one beam more is refused.
    let mut wide = ros.clone();
    wide.ranges = vec![1.0; cv::SCAN_MAX_BEAMS];
    assert_eq!(scan_in(&wide).unwrap().ranges().len(), cv::SCAN_MAX_BEAMS);
    wide.ranges.push(1.0);
    let e = scan_in(&wide).unwrap_err();
    assert!(e.contains("1082 beams") && e.contains("1081"), "{e}");
}

#[test]
fn readings_ros_marks_as_none_become_caravans_no_return() {
    let ros = msgs::LaserScan {
        range_max: 10.0,
        ranges: vec![f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 2.0],
        intensities: vec![f32::NAN],
        ..Default::default()
    };
    let s = scan_in(&ros).unwrap();
    assert_eq!(s.ranges(), [11.0, 11.0, 11.0, 2.0]);
    assert_eq!(s.intensities[..4], [0.0; 4]);
}

#[test]
fn an_imu_reading_round_trips_exactly() {
    let m = cv::Imu {
        orientation: cv::Quaternion {
            x: 0.1,
            y: -0.2,
            z: 0.3,
            w: 0.9273618495495704,
        },
        orientation_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        angular_velocity: cv::Vector3 {
            x: 0.01,
            y: 0.02,
            z: -0.5,
        },
        angular_velocity_covariance: [1e-4, 0.0, 0.0, 0.0, 1e-4, 0.0, 0.0, 0.0, 1e-4],
        linear_acceleration: cv::Vector3 {
            x: 0.3,
            y: 0.0,
            z: 9.80665,
        },
        linear_acceleration_covariance: [0.01; 9],
    };
    assert_round_trip("robot/1/imu", RosType::Imu, &m, Caravan::Imu(&m), true);
}

#[test]
fn joint_states_round_trip_exactly_and_what_caravan_cannot_hold_is_refused() {
    let mut j = cv::boxed_placement_new::<cv::JointState>();
    for (k, name) in ["shoulder", "elbow", "gripper_left"]
        .into_iter()
        .enumerate()
    {
        let v = cv::JointValue {
            name: cv::Name::new(name),
            position: 0.1 * k as f64 - 1.0,
            velocity: 2.5e-3,
            effort: -3.75 * k as f64,
        };
        j.joints.push(v).unwrap();
    }
    assert_round_trip(
        "robot/2/joint_states",
        RosType::JointState,
        j.as_ref(),
        Caravan::JointState(&j),
        true,
    );
    // Empty arrays (ROS allows them) read 0.
    let sparse = msgs::JointState {
        name: vec!["a".into()],
        position: vec![1.5],
        ..Default::default()
    };
    let back = joint_state_in(&sparse).unwrap();
    let v = back.joints.as_slice()[0];
    assert_eq!((v.position, v.velocity, v.effort), (1.5, 0.0, 0.0));
    let many = msgs::JointState {
        name: (0..65).map(|k| format!("j{k}")).collect(),
        ..Default::default()
    };
    assert!(joint_state_in(&many).unwrap_err().contains("65 joints"));
    let long = msgs::JointState {
        name: vec!["x".repeat(61)],
        ..Default::default()
    };
    assert!(joint_state_in(&long).unwrap_err().contains("60 bytes"));
}

#[test]
fn twists_and_planar_poses_round_trip_exactly() {
    let t = cv::Twist {
        linear: cv::Vector3 {
            x: 0.4,
            y: -0.01,
            z: 0.0,
        },
        angular: cv::Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.35,
        },
    };
    assert_round_trip(
        "robot/0/cmd_vel",
        RosType::Twist,
        &t,
        Caravan::Twist(&t),
        false,
    );
    for theta in ANGLES {
        let p = cv::Pose2D {
            x: 12.5 + theta,
            y: -3.0000000001,
            theta,
        };
        assert_round_trip(
            "robot/3/pose",
            RosType::PoseStamped,
            &p,
            Caravan::Pose2D(&p),
            true,
        );
        assert_round_trip(
            "robot/3/pose",
            RosType::Pose2D,
            &p,
            Caravan::Pose2D(&p),
            false,
        );
        if theta == 0.0 {
            // Negative zero included.
            let back = planar(&mapping_pose(&p));
            assert_eq!(back.theta.to_bits(), theta.to_bits(), "{theta}");
        }
    }
    // Every angle of a fine sweep over (−2π, 2π) comes back within an ulp, as an angle with
    // the same quaternion (so a pose sent again is the same ROS message); nearly all exactly.
    let mut exact = 0;
    for k in -1998..=1998 {
        let theta = k as f64 * std::f64::consts::TAU / 1999.0 + 1e-7;
        let p = cv::Pose2D {
            x: 0.0,
            y: 0.0,
            theta,
        };
        let back = planar(&mapping_pose(&p)).theta;
        assert!(
            same(&back.into(), &theta.into(), "theta"),
            "{theta}: {back}"
        );
        let again = cv::Pose2D { theta: back, ..p };
        assert_eq!(mapping_pose(&again), mapping_pose(&p), "{theta}");
        exact += (back == theta) as u32;
    }
    assert!(exact > 3800, "{exact} of 3997 exact");
    // A tilted orientation gives its yaw.
    let tilted = msgs::Pose {
        orientation: msgs::Quaternion {
            x: 0.0,
            y: (0.25f64).sin(),
            z: 0.0,
            w: (0.25f64).cos(),
        },
        ..Default::default()
    };
    assert!(planar(&tilted).theta.abs() < 1e-15);
}

/// A `Pose2D` as the ROS pose it is sent as.
fn mapping_pose(p: &cv::Pose2D) -> msgs::Pose {
    match to_ros(
        RosType::PoseStamped,
        Caravan::Pose2D(p),
        0,
        &Frames::default(),
    ) {
        Some(RosMessage::PoseStamped(m)) => m.pose,
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_3d_pose_topic_plays_back_as_a_3d_pose() {
    let p = cv::Pose3D {
        position: cv::Vector3 {
            x: 1.0,
            y: 2.0,
            z: 0.25,
        },
        orientation: cv::Quaternion {
            x: 0.5,
            y: 0.5,
            z: 0.5,
            w: 0.5,
        },
    };
    assert_eq!(
        caravan_type_in(RosType::PoseStamped, "robot/1/set_pose"),
        Some("caravan::Pose3D")
    );
    assert_round_trip(
        "robot/1/set_pose",
        RosType::PoseStamped,
        &p,
        Caravan::Pose3D(&p),
        true,
    );
}

#[test]
fn wrenches_round_trip_exactly_in_the_world_and_on_a_link() {
    let mut w = cv::Wrench {
        frame: cv::Wrench::WORLD,
        force: cv::Vector3 {
            x: 1.5,
            y: -2.0,
            z: 9.0,
        },
        torque: cv::Vector3 {
            x: 0.0,
            y: 0.125,
            z: -0.3,
        },
        ..Default::default()
    };
    assert_round_trip(
        "robot/0/wrench",
        RosType::WrenchStamped,
        &w,
        Caravan::Wrench(&w),
        true,
    );
    (w.frame, w.link) = (cv::Wrench::LINK, cv::Name::new("arm_link"));
    assert_round_trip(
        "robot/4/wrench",
        RosType::WrenchStamped,
        &w,
        Caravan::Wrench(&w),
        true,
    );
}

#[test]
fn a_map_round_trips_exactly_and_a_bad_one_is_refused() {
    let mut g = cv::boxed_placement_new::<cv::OccupancyGrid>();
    (g.width, g.height, g.resolution) = (3, 2, 0.05);
    g.origin = cv::Pose2D {
        x: -10.0,
        y: -7.5,
        theta: 0.0,
    };
    g.data[..6].copy_from_slice(&[-1, 0, 100, 50, 0, -1]);
    assert_round_trip(
        "map",
        RosType::OccupancyGrid,
        g.as_ref(),
        Caravan::OccupancyGrid(&g),
        true,
    );
    for resolution in [0.1, 0.025, 0.2, 1.0, 0.03] {
        g.resolution = resolution;
        let back = through_ros("map", RosType::OccupancyGrid, Caravan::OccupancyGrid(&g), 0);
        assert_eq!(back.json["resolution"], resolution);
    }
    let mut m = match to_ros(
        RosType::OccupancyGrid,
        Caravan::OccupancyGrid(&g),
        0,
        &Frames::default(),
    ) {
        Some(RosMessage::OccupancyGrid(m)) => m,
        other => panic!("{other:?}"),
    };
    m.data.pop();
    assert!(grid_in(&m).unwrap_err().contains("5 cells of data, not 6"));
    (m.info.width, m.info.height) = (1025, 1024);
    assert!(grid_in(&m).unwrap_err().contains("1049600 cells"));
}

#[test]
fn a_path_round_trips_exactly() {
    let mut p = cv::boxed_placement_new::<cv::Path2D>();
    for (k, theta) in ANGLES.into_iter().enumerate() {
        let pose = cv::Pose2D {
            x: k as f64 * 0.3,
            y: -(k as f64) / 7.0,
            theta,
        };
        p.poses.push(pose).unwrap();
    }
    assert_round_trip(
        "robot/0/path",
        RosType::Path,
        p.as_ref(),
        Caravan::Path2D(&p),
        true,
    );
    let long = msgs::Path {
        poses: vec![msgs::PoseStamped::default(); cv::PATH_MAX_POSES + 1],
        ..Default::default()
    };
    assert!(path_in(&long).unwrap_err().contains("1025 poses"));
}

#[test]
fn odometry_round_trips_exactly() {
    let mut o = cv::Odometry::default();
    o.pose.position = cv::Vector3 {
        x: 3.0,
        y: -1.0,
        z: 0.0,
    };
    o.pose.orientation = cv::Quaternion::from_yaw(0.7);
    o.twist = cv::Twist::planar(0.5, -0.1);
    for k in 0..36 {
        o.pose_covariance[k] = k as f64 * 1e-3;
        o.twist_covariance[k] = 1.0 / (k as f64 + 1.0);
    }
    assert_round_trip(
        "robot/2/odometry",
        RosType::Odometry,
        &o,
        Caravan::Odometry(&o),
        true,
    );
}

#[test]
fn ros_names_give_caravan_topics_back() {
    for t in [
        "robot/0/scan",
        "robot/12/cmd_vel",
        "map",
        "robot/3/pose_true",
        "goal",
    ] {
        assert_eq!(caravan_topic(&naming::ros_topic(t)), t);
    }
    assert_eq!(caravan_topic("/robot_x/scan"), "robot_x/scan");
    assert_eq!(caravan_topic("/a/robot_/b"), "a/robot_/b");
    assert_eq!(caravan_type_in(RosType::TfMessage, "tf"), None);
    assert_eq!(caravan_type_in(RosType::Clock, "clock"), None);
}

#[test]
fn bad_cdr_is_an_error_not_a_panic() {
    let scan = to_cdr(&msgs::LaserScan {
        ranges: vec![1.0; 10],
        ..Default::default()
    });
    for cut in [0, 3, 4, 10, scan.len() - 1] {
        let r = caravan_json(RosType::LaserScan, "caravan::LaserScan", &scan[..cut]);
        assert!(r.is_err(), "{cut}");
    }
    // A sequence length far past the data.
    let mut huge = scan.clone();
    let at = scan.len() - 4 * 10 - 8;
    huge[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(caravan_json(RosType::LaserScan, "caravan::LaserScan", &huge).is_err());
}
