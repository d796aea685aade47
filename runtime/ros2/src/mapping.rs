//! Caravan's messages as ROS 2's standard ones and back, field by field (docs/ros2.md has the
//! table). Units are SI on both sides (m, s, rad, N, N·m), so values pass unchanged; only
//! the shapes differ: fixed arrays become sequences of their valid items, 2-D poses get z = 0
//! and a yaw quaternion, and a header carries the Caravan stamp (simulated time) and a frame.

use crate::msgs::{self, Header};
use crate::ros_type::RosType;
use caravan_schemas as cv;
use serde::Serialize;

/// One ROS 2 message of any mapped type; serialises as the message itself. Each lives only
/// from its conversion to its encoding, so the sizes of the variants do not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum RosMessage {
    LaserScan(msgs::LaserScan),
    Imu(msgs::Imu),
    JointState(msgs::JointState),
    Twist(msgs::Twist),
    Pose2D(msgs::Pose2D),
    PoseStamped(msgs::PoseStamped),
    WrenchStamped(msgs::WrenchStamped),
    OccupancyGrid(msgs::OccupancyGrid),
    Path(msgs::Path),
    Odometry(msgs::Odometry),
    TfMessage(msgs::TfMessage),
    Clock(msgs::Clock),
}

/// Calls `$callback!` with the Caravan types that cross out, the variants of [`Caravan`]: the
/// one list of them.
macro_rules! outbound_types {
    ($callback:ident) => {
        $callback! {
            LaserScan,
            Imu,
            JointState,
            Twist,
            Pose2D,
            Pose3D,
            Wrench,
            OccupancyGrid,
            Path2D,
            Odometry,
            LinkStates
        }
    };
}
pub(crate) use outbound_types;

/// A Caravan message of a type the bridge maps, borrowed.
#[derive(Clone, Copy)]
pub enum Caravan<'a> {
    LaserScan(&'a cv::LaserScan),
    Imu(&'a cv::Imu),
    JointState(&'a cv::JointState),
    Twist(&'a cv::Twist),
    Pose2D(&'a cv::Pose2D),
    Pose3D(&'a cv::Pose3D),
    Wrench(&'a cv::Wrench),
    OccupancyGrid(&'a cv::OccupancyGrid),
    Path2D(&'a cv::Path2D),
    Odometry(&'a cv::Odometry),
    LinkStates(&'a cv::LinkStates),
}

/// Where a message is placed: its header's frame, and the child frame of a transform or an
/// odometry (a link of robot `robot` is `robot_<robot>/<link>`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Frames {
    pub frame_id: String,
    pub child_frame_id: String,
    pub robot: Option<usize>,
}

fn vector(v: &cv::Vector3) -> msgs::Vector3 {
    msgs::Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn quaternion(q: &cv::Quaternion) -> msgs::Quaternion {
    msgs::Quaternion {
        x: q.x,
        y: q.y,
        z: q.z,
        w: q.w,
    }
}

fn pose_2d(p: &cv::Pose2D) -> msgs::Pose {
    msgs::Pose {
        position: msgs::Vector3 {
            x: p.x,
            y: p.y,
            z: 0.0,
        },
        orientation: quaternion(&cv::Quaternion::from_yaw(p.theta)),
    }
}

fn pose_3d(p: &cv::Pose3D) -> msgs::Pose {
    msgs::Pose {
        position: vector(&p.position),
        orientation: quaternion(&p.orientation),
    }
}

fn twist(t: &cv::Twist) -> msgs::Twist {
    msgs::Twist {
        linear: vector(&t.linear),
        angular: vector(&t.angular),
    }
}

fn transform(header: &Header, child: String, pose: msgs::Pose) -> msgs::TransformStamped {
    msgs::TransformStamped {
        header: header.clone(),
        child_frame_id: child,
        transform: msgs::Transform {
            translation: pose.position,
            rotation: pose.orientation,
        },
    }
}

fn cross(a: &cv::Vector3, b: &cv::Vector3) -> cv::Vector3 {
    cv::Vector3 {
        x: a.y * b.z - a.z * b.y,
        y: a.z * b.x - a.x * b.z,
        z: a.x * b.y - a.y * b.x,
    }
}

/// `msg` as a ROS 2 message of type `ty` stamped `stamp_ns`; `None` when the bridge does not
/// map that pair (the configuration refuses such pairs before anything starts).
pub fn to_ros(ty: RosType, msg: Caravan, stamp_ns: u64, frames: &Frames) -> Option<RosMessage> {
    let header = Header {
        stamp: msgs::Time::from_ns(stamp_ns),
        frame_id: frames.frame_id.clone(),
    };
    let stamped = |pose: msgs::Pose| msgs::PoseStamped {
        header: header.clone(),
        pose,
    };
    let link = |name: &str| match frames.robot {
        Some(i) => cv::topics::robot_frame(i, name),
        None => name.to_owned(),
    };
    Some(match (ty, msg) {
        (RosType::LaserScan, Caravan::LaserScan(s)) => RosMessage::LaserScan(msgs::LaserScan {
            header,
            angle_min: s.angle_min,
            angle_max: s.angle_max,
            angle_increment: s.angle_increment,
            time_increment: s.time_increment,
            scan_time: s.scan_time,
            range_min: s.range_min,
            range_max: s.range_max,
            ranges: s.ranges().to_vec(),
            intensities: s.intensities[..s.ranges().len()].to_vec(),
        }),
        (RosType::Imu, Caravan::Imu(m)) => RosMessage::Imu(msgs::Imu {
            header,
            orientation: quaternion(&m.orientation),
            orientation_covariance: msgs::Fixed(m.orientation_covariance),
            angular_velocity: vector(&m.angular_velocity),
            angular_velocity_covariance: msgs::Fixed(m.angular_velocity_covariance),
            linear_acceleration: vector(&m.linear_acceleration),
            linear_acceleration_covariance: msgs::Fixed(m.linear_acceleration_covariance),
        }),
        (RosType::JointState, Caravan::JointState(j)) => {
            let joints = j.joints.as_slice();
            RosMessage::JointState(msgs::JointState {
                header,
                name: joints.iter().map(|v| v.name.as_str().to_owned()).collect(),
                position: joints.iter().map(|v| v.position).collect(),
                velocity: joints.iter().map(|v| v.velocity).collect(),
                effort: joints.iter().map(|v| v.effort).collect(),
            })
        }
        (RosType::Twist, Caravan::Twist(t)) => RosMessage::Twist(twist(t)),
        (RosType::Pose2D, Caravan::Pose2D(p)) => RosMessage::Pose2D(msgs::Pose2D {
            x: p.x,
            y: p.y,
            theta: p.theta,
        }),
        (RosType::PoseStamped, Caravan::Pose2D(p)) => RosMessage::PoseStamped(stamped(pose_2d(p))),
        (RosType::PoseStamped, Caravan::Pose3D(p)) => RosMessage::PoseStamped(stamped(pose_3d(p))),
        (RosType::WrenchStamped, Caravan::Wrench(w)) => {
            // ROS's wrench acts at the frame's origin: move Caravan's application point there.
            let moment = cross(&w.point, &w.force);
            let torque = cv::Vector3 {
                x: w.torque.x + moment.x,
                y: w.torque.y + moment.y,
                z: w.torque.z + moment.z,
            };
            let frame_id = match w.frame {
                cv::Wrench::LINK => link(w.link.as_str()),
                _ => header.frame_id.clone(),
            };
            RosMessage::WrenchStamped(msgs::WrenchStamped {
                header: Header { frame_id, ..header },
                wrench: msgs::Wrench {
                    force: vector(&w.force),
                    torque: vector(&torque),
                },
            })
        }
        (RosType::OccupancyGrid, Caravan::OccupancyGrid(g)) => {
            RosMessage::OccupancyGrid(msgs::OccupancyGrid {
                info: msgs::MapMetaData {
                    map_load_time: header.stamp,
                    resolution: g.resolution as f32,
                    width: g.width,
                    height: g.height,
                    origin: pose_2d(&g.origin),
                },
                header,
                data: g.cells().to_vec(),
            })
        }
        (RosType::Path, Caravan::Path2D(p)) => RosMessage::Path(msgs::Path {
            poses: p
                .poses
                .as_slice()
                .iter()
                .map(|q| stamped(pose_2d(q)))
                .collect(),
            header,
        }),
        (RosType::Odometry, Caravan::Odometry(o)) => RosMessage::Odometry(msgs::Odometry {
            header,
            child_frame_id: frames.child_frame_id.clone(),
            pose: msgs::PoseWithCovariance {
                pose: pose_3d(&o.pose),
                covariance: msgs::Fixed(o.pose_covariance),
            },
            twist: msgs::TwistWithCovariance {
                twist: twist(&o.twist),
                covariance: msgs::Fixed(o.twist_covariance),
            },
        }),
        (RosType::TfMessage, Caravan::Pose2D(p)) => RosMessage::TfMessage(msgs::TfMessage {
            transforms: vec![transform(
                &header,
                frames.child_frame_id.clone(),
                pose_2d(p),
            )],
        }),
        (RosType::TfMessage, Caravan::Odometry(o)) => RosMessage::TfMessage(msgs::TfMessage {
            transforms: vec![transform(
                &header,
                frames.child_frame_id.clone(),
                pose_3d(&o.pose),
            )],
        }),
        (RosType::TfMessage, Caravan::LinkStates(l)) => RosMessage::TfMessage(msgs::TfMessage {
            transforms: l
                .links
                .as_slice()
                .iter()
                .map(|s| transform(&header, link(s.name.as_str()), pose_3d(&s.pose)))
                .collect(),
        }),
        _ => return None,
    })
}

/// `/clock` at `ns` of simulated time.
pub fn clock(ns: u64) -> RosMessage {
    RosMessage::Clock(msgs::Clock {
        clock: msgs::Time::from_ns(ns),
    })
}

/// The yaw of a quaternion (rotation about z), rad.
fn yaw(q: &msgs::Quaternion) -> f64 {
    (2.0 * (q.w * q.z + q.x * q.y)).atan2(1.0 - 2.0 * (q.y * q.y + q.z * q.z))
}

fn from_vector(v: &msgs::Vector3) -> cv::Vector3 {
    cv::Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// A `geometry_msgs/Twist` as Caravan's.
pub fn twist_in(t: &msgs::Twist) -> cv::Twist {
    cv::Twist {
        linear: from_vector(&t.linear),
        angular: from_vector(&t.angular),
    }
}

/// A `geometry_msgs/Pose2D` as Caravan's.
pub fn pose_2d_in(p: &msgs::Pose2D) -> cv::Pose2D {
    cv::Pose2D {
        x: p.x,
        y: p.y,
        theta: p.theta,
    }
}

/// A pose as a planar one: x, y and the yaw (z and the tilt are dropped).
pub fn pose_planar_in(p: &msgs::Pose) -> cv::Pose2D {
    cv::Pose2D {
        x: p.position.x,
        y: p.position.y,
        theta: yaw(&p.orientation),
    }
}

/// A pose as Caravan's 3-D one.
pub fn pose_3d_in(p: &msgs::Pose) -> cv::Pose3D {
    let q = &p.orientation;
    cv::Pose3D {
        position: from_vector(&p.position),
        orientation: cv::Quaternion {
            x: q.x,
            y: q.y,
            z: q.z,
            w: q.w,
        },
    }
}

/// A `geometry_msgs/WrenchStamped` as a Caravan wrench at the frame's origin, held until the
/// next: in the world frame when `frame_id` is the map frame or empty, else on the link the
/// frame names (`robot_0/arm` or `arm`), in the link's frame.
pub fn wrench_in(w: &msgs::WrenchStamped) -> cv::Wrench {
    let frame = w.header.frame_id.as_str();
    let world = frame.is_empty() || frame == "map";
    let link = frame.rsplit_once('/').map_or(frame, |(_, l)| l);
    cv::Wrench {
        link: cv::Name::new(if world { "" } else { link }),
        frame: if world {
            cv::Wrench::WORLD
        } else {
            cv::Wrench::LINK
        },
        force: from_vector(&w.wrench.force),
        torque: from_vector(&w.wrench.torque),
        ..Default::default()
    }
}

/// A `sensor_msgs/JointState` as a joint command: each named joint's position, velocity and
/// effort targets; a field the message leaves out (a shorter array) is NaN, which leaves that
/// target as it was. Joints past Caravan's 64 are dropped.
pub fn joint_command_in(j: &msgs::JointState) -> Box<cv::JointCommand> {
    let mut out = cv::boxed_placement_new::<cv::JointCommand>();
    let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    for (i, name) in j.name.iter().enumerate() {
        let value = cv::JointValue {
            name: cv::Name::new(name),
            position: at(&j.position, i),
            velocity: at(&j.velocity, i),
            effort: at(&j.effort, i),
        };
        if out.joints.push(value).is_err() {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{from_cdr, to_cdr};

    #[test]
    fn cdr_is_what_ros_2_middlewares_write() {
        // rosgraph_msgs/Clock at 1.5 s: encapsulation CDR_LE, int32 sec, uint32 nanosec.
        assert_eq!(
            to_cdr(&clock(1_500_000_000)),
            [0, 1, 0, 0, 1, 0, 0, 0, 0x00, 0x65, 0xcd, 0x1d]
        );
        // A header's string: uint32 length with the NUL, the bytes, the NUL; then the float32s
        // start at the next multiple of 4 (relative to the data after the encapsulation).
        let scan = msgs::LaserScan {
            header: Header {
                stamp: msgs::Time { sec: 2, nanosec: 0 },
                frame_id: "ab".into(),
            },
            angle_min: 1.0,
            ranges: vec![0.5],
            ..Default::default()
        };
        let bytes = to_cdr(&scan);
        assert_eq!(
            &bytes[4..20],
            [2, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0]
        );
        assert_eq!(&bytes[20..24], 1.0f32.to_le_bytes());
        assert_eq!(from_cdr::<msgs::LaserScan>(&bytes).unwrap(), scan);
    }

    #[test]
    fn a_scan_keeps_its_valid_beams_and_stamp() {
        let mut s = cv::boxed_placement_new::<cv::LaserScan>();
        s.beam_count = 3;
        s.ranges[..3].copy_from_slice(&[1.0, 2.0, f32::INFINITY]);
        s.intensities[..3].copy_from_slice(&[7.0, 8.0, 9.0]);
        s.angle_min = -1.5;
        let frames = Frames {
            frame_id: "robot_0/base_link".into(),
            ..Default::default()
        };
        let Some(RosMessage::LaserScan(m)) = to_ros(
            RosType::LaserScan,
            Caravan::LaserScan(&s),
            2_250_000_000,
            &frames,
        ) else {
            panic!("not a scan");
        };
        assert_eq!(m.ranges, [1.0, 2.0, f32::INFINITY]);
        assert_eq!(m.intensities, [7.0, 8.0, 9.0]);
        assert_eq!(
            (m.header.stamp.sec, m.header.stamp.nanosec),
            (2, 250_000_000)
        );
        assert_eq!(
            (m.header.frame_id.as_str(), m.angle_min),
            ("robot_0/base_link", -1.5)
        );
    }

    #[test]
    fn poses_round_trip_through_ros_types() {
        let p = cv::Pose2D {
            x: 1.0,
            y: -2.0,
            theta: 2.5,
        };
        let frames = Frames {
            frame_id: "map".into(),
            child_frame_id: "robot_1/base_link".into(),
            robot: Some(1),
        };
        let Some(RosMessage::PoseStamped(s)) =
            to_ros(RosType::PoseStamped, Caravan::Pose2D(&p), 0, &frames)
        else {
            panic!("not a pose");
        };
        let back = pose_planar_in(&s.pose);
        assert!(
            (back.x - 1.0).abs() < 1e-12
                && (back.y + 2.0).abs() < 1e-12
                && (back.theta - 2.5).abs() < 1e-12
        );
        let Some(RosMessage::TfMessage(tf)) =
            to_ros(RosType::TfMessage, Caravan::Pose2D(&p), 0, &frames)
        else {
            panic!("not a transform");
        };
        assert_eq!(tf.transforms[0].child_frame_id, "robot_1/base_link");
        assert_eq!(tf.transforms[0].header.frame_id, "map");
        assert_eq!(
            to_ros(RosType::LaserScan, Caravan::Pose2D(&p), 0, &frames),
            None
        );
    }

    #[test]
    fn a_wrench_acts_at_the_frame_origin_both_ways() {
        let w = cv::Wrench {
            link: cv::Name::new("arm"),
            frame: cv::Wrench::LINK,
            point: cv::Vector3 {
                x: 0.5,
                y: 0.0,
                z: 0.0,
            },
            force: cv::Vector3 {
                x: 0.0,
                y: 2.0,
                z: 0.0,
            },
            ..Default::default()
        };
        let frames = Frames {
            robot: Some(3),
            ..Default::default()
        };
        let Some(RosMessage::WrenchStamped(r)) =
            to_ros(RosType::WrenchStamped, Caravan::Wrench(&w), 0, &frames)
        else {
            panic!("not a wrench");
        };
        // 2 N along y at 0.5 m along x: 1 N·m about z at the link's origin.
        assert_eq!(
            (r.header.frame_id.as_str(), r.wrench.torque.z),
            ("robot_3/arm", 1.0)
        );
        let back = wrench_in(&r);
        assert_eq!(
            (back.link.as_str(), back.frame, back.torque.z),
            ("arm", cv::Wrench::LINK, 1.0)
        );
        let world = wrench_in(&msgs::WrenchStamped {
            header: Header {
                frame_id: "map".into(),
                ..Default::default()
            },
            ..Default::default()
        });
        assert_eq!(world.frame, cv::Wrench::WORLD);
    }

    #[test]
    fn a_joint_state_commands_the_joints_it_names() {
        let j = msgs::JointState {
            name: vec!["a".into(), "b".into()],
            position: vec![0.5, 1.0],
            velocity: vec![2.0],
            ..Default::default()
        };
        let c = joint_command_in(&j);
        let joints = c.joints.as_slice();
        assert_eq!(
            (
                joints[0].name.as_str(),
                joints[0].position,
                joints[0].velocity
            ),
            ("a", 0.5, 2.0)
        );
        assert!(joints[1].velocity.is_nan() && joints[1].effort.is_nan());
        assert_eq!(joints[1].position, 1.0);
    }
}
