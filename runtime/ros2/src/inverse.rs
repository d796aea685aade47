//! ROS 2's standard messages back into Caravan's, for playing a rosbag2 bag into a group: the
//! inverse of [`crate::mapping::to_ros`] for the types a recording holds. A Caravan message
//! taken to ROS 2 and back is the message it was, bit for bit (the tests below), but for a
//! planar pose's yaw, which crosses as a quaternion: it is read back as the angle nearest the
//! quaternion's whose quaternion it is exactly, which is the angle sent but for the few
//! neighbouring angles that share one quaternion (then it is one ulp off, and sent again
//! gives the same ROS message). A map's `float32` resolution is read back as the decimal it
//! prints as (0.05 stays 0.05).
//!
//! What Caravan cannot hold is refused, naming it: more beams than [`cv::SCAN_MAX_BEAMS`],
//! cells than [`cv::MAP_MAX_CELLS`], poses than [`cv::PATH_MAX_POSES`], joints than
//! [`cv::MAX_JOINTS`], or a joint name longer than [`cv::NAME_BYTES`].

use crate::mapping::{pose_2d_in, pose_3d_in, pose_planar_in, twist_in, wrench_in};
use crate::msgs::{self, from_cdr};
use crate::ros_type::RosType;
use caravan_schemas as cv;
use serde_json::Value;

/// A pose as a planar one. A pure yaw rotation (x = y = 0, as Caravan writes a `Pose2D`'s)
/// gives the angle nearest `2 atan2(z, w)` whose half-angle sine and cosine are its z and w
/// exactly, when there is one, so that the `Pose2D` it came from comes back (even an angle
/// outside (−π, π]), to within the one ulp by which angles that share a quaternion differ;
/// any other orientation its yaw, as [`pose_planar_in`].
pub fn planar(p: &msgs::Pose) -> cv::Pose2D {
    let mut out = pose_planar_in(p);
    let q = &p.orientation;
    if q.x == 0.0 && q.y == 0.0 {
        let is_q = |theta: f64| {
            let (s, c) = (theta / 2.0).sin_cos();
            s == q.z && c == q.w
        };
        let first = 2.0 * q.z.atan2(q.w);
        let (mut up, mut down) = (first, first);
        for _ in 0..=16 {
            if is_q(up) {
                out.theta = up;
                break;
            }
            if is_q(down) {
                out.theta = down;
                break;
            }
            (up, down) = (up.next_up(), down.next_down());
        }
    }
    out
}

/// A `float32` resolution as the decimal it prints as: a Caravan map's resolution (an `f64`
/// such as 0.05) survives its trip through ROS's `float32`.
fn resolution_in(r: f32) -> f64 {
    format!("{r}").parse().unwrap_or(r as f64)
}

/// `sensor_msgs/LaserScan` as Caravan's. Readings ROS marks as none (+∞ no return, −∞ too
/// close, NaN invalid; REP 117) become Caravan's no-return reading, `range_max + 1`, outside
/// the valid interval as Caravan's consumers expect; intensities past `ranges` are dropped.
pub fn scan_in(m: &msgs::LaserScan) -> Result<Box<cv::LaserScan>, String> {
    let n = m.ranges.len();
    if n > cv::SCAN_MAX_BEAMS {
        return Err(format!(
            "a scan of {n} beams; Caravan's LaserScan holds at most {}",
            cv::SCAN_MAX_BEAMS
        ));
    }
    let mut s = cv::boxed_placement_new::<cv::LaserScan>();
    s.angle_min = m.angle_min;
    s.angle_max = m.angle_max;
    s.angle_increment = m.angle_increment;
    s.time_increment = m.time_increment;
    s.scan_time = m.scan_time;
    s.range_min = m.range_min;
    s.range_max = m.range_max;
    s.beam_count = n as u32;
    for (out, r) in s.ranges.iter_mut().zip(&m.ranges) {
        *out = if r.is_finite() { *r } else { m.range_max + 1.0 };
    }
    for (out, i) in s.intensities[..n].iter_mut().zip(&m.intensities) {
        *out = if i.is_finite() { *i } else { 0.0 };
    }
    Ok(s)
}

fn vector(v: &msgs::Vector3) -> cv::Vector3 {
    cv::Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn quaternion(q: &msgs::Quaternion) -> cv::Quaternion {
    cv::Quaternion {
        x: q.x,
        y: q.y,
        z: q.z,
        w: q.w,
    }
}

/// `sensor_msgs/Imu` as Caravan's: every field as it is.
pub fn imu_in(m: &msgs::Imu) -> cv::Imu {
    cv::Imu {
        orientation: quaternion(&m.orientation),
        orientation_covariance: m.orientation_covariance.0,
        angular_velocity: vector(&m.angular_velocity),
        angular_velocity_covariance: m.angular_velocity_covariance.0,
        linear_acceleration: vector(&m.linear_acceleration),
        linear_acceleration_covariance: m.linear_acceleration_covariance.0,
    }
}

/// `sensor_msgs/JointState` as Caravan's readings: joint k named `name[k]`; a field whose
/// array the message leaves empty or short (ROS allows it) reads 0.
pub fn joint_state_in(m: &msgs::JointState) -> Result<Box<cv::JointState>, String> {
    if m.name.len() > cv::MAX_JOINTS {
        return Err(format!(
            "{} joints; Caravan's JointState holds at most {}",
            m.name.len(),
            cv::MAX_JOINTS
        ));
    }
    let mut out = cv::boxed_placement_new::<cv::JointState>();
    let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
    for (i, name) in m.name.iter().enumerate() {
        if name.len() > cv::NAME_BYTES {
            return Err(format!(
                "joint name '{name}' is longer than Caravan's {} bytes",
                cv::NAME_BYTES
            ));
        }
        let value = cv::JointValue {
            name: cv::Name::new(name),
            position: at(&m.position, i),
            velocity: at(&m.velocity, i),
            effort: at(&m.effort, i),
        };
        // Within MAX_JOINTS, checked above.
        let _ = out.joints.push(value);
    }
    Ok(out)
}

/// `geometry_msgs/PoseStamped` as a planar pose ([`planar`]).
pub fn pose_stamped_in(m: &msgs::PoseStamped) -> cv::Pose2D {
    planar(&m.pose)
}

/// `nav_msgs/OccupancyGrid` as Caravan's: `width × height` cells from `origin` (planar), at
/// the resolution as it prints.
pub fn grid_in(m: &msgs::OccupancyGrid) -> Result<Box<cv::OccupancyGrid>, String> {
    let (w, h) = (m.info.width, m.info.height);
    let cells = w as u64 * h as u64;
    if cells > cv::MAP_MAX_CELLS as u64 {
        return Err(format!(
            "a {w} × {h} map ({cells} cells); Caravan's OccupancyGrid holds at most {}",
            cv::MAP_MAX_CELLS
        ));
    }
    if m.data.len() as u64 != cells {
        return Err(format!(
            "a {w} × {h} map with {} cells of data, not {cells}",
            m.data.len()
        ));
    }
    let mut g = cv::boxed_placement_new::<cv::OccupancyGrid>();
    g.resolution = resolution_in(m.info.resolution);
    g.origin = planar(&m.info.origin);
    g.width = w;
    g.height = h;
    g.data[..m.data.len()].copy_from_slice(&m.data);
    Ok(g)
}

/// `nav_msgs/Path` as Caravan's: each pose planar.
pub fn path_in(m: &msgs::Path) -> Result<Box<cv::Path2D>, String> {
    if m.poses.len() > cv::PATH_MAX_POSES {
        return Err(format!(
            "a path of {} poses; Caravan's Path2D holds at most {}",
            m.poses.len(),
            cv::PATH_MAX_POSES
        ));
    }
    let mut p = cv::boxed_placement_new::<cv::Path2D>();
    for pose in &m.poses {
        // Within PATH_MAX_POSES, checked above.
        let _ = p.poses.push(planar(&pose.pose));
    }
    Ok(p)
}

/// `nav_msgs/Odometry` as Caravan's: pose, twist and both covariances as they are (the
/// frames are the topic's).
pub fn odometry_in(m: &msgs::Odometry) -> cv::Odometry {
    cv::Odometry {
        pose: pose_3d_in(&m.pose.pose),
        pose_covariance: m.pose.covariance.0,
        twist: twist_in(&m.twist.twist),
        twist_covariance: m.twist.covariance.0,
    }
}

/// The Caravan type a ROS type plays back as on `caravan_topic`: `PoseStamped` is a
/// `Pose2D`, or a `Pose3D` on a well-known `Pose3D` topic (`robot/<i>/set_pose`);
/// `JointState` Caravan's readings. `None` for `/tf` and `/clock`, which a group derives.
pub fn caravan_type_in(ty: RosType, caravan_topic: &str) -> Option<&'static str> {
    let pose_3d = cv::type_name::<cv::Pose3D>();
    Some(match ty {
        RosType::LaserScan => cv::type_name::<cv::LaserScan>(),
        RosType::Imu => cv::type_name::<cv::Imu>(),
        RosType::JointState => cv::type_name::<cv::JointState>(),
        RosType::Twist => cv::type_name::<cv::Twist>(),
        RosType::Pose2D => cv::type_name::<cv::Pose2D>(),
        RosType::PoseStamped if cv::topics::type_of(caravan_topic) == Some(pose_3d) => pose_3d,
        RosType::PoseStamped => cv::type_name::<cv::Pose2D>(),
        RosType::WrenchStamped => cv::type_name::<cv::Wrench>(),
        RosType::OccupancyGrid => cv::type_name::<cv::OccupancyGrid>(),
        RosType::Path => cv::type_name::<cv::Path2D>(),
        RosType::Odometry => cv::type_name::<cv::Odometry>(),
        RosType::TfMessage | RosType::Clock => return None,
    })
}

/// A message played back: the Caravan message as the recorder's JSON (no `header`), and the
/// ROS message's header stamp when it has a header.
#[derive(Debug, Clone, PartialEq)]
pub struct Played {
    pub json: Value,
    pub stamp_ns: Option<u64>,
}

fn json<T: serde::Serialize + ?Sized>(m: &T) -> Result<Value, String> {
    serde_json::to_value(m).map_err(|e| e.to_string())
}

/// A CDR message of type `ty` as a Caravan message of `caravan_type` (what
/// [`caravan_type_in`] gave), in the JSON the recorder writes: `serde_json`'s view of the
/// message, which is the recorder's (`caravan_schemas::view`).
pub fn caravan_json(ty: RosType, caravan_type: &str, cdr: &[u8]) -> Result<Played, String> {
    let stamp = |h: &msgs::Header| Some(h.stamp.to_ns());
    let pose_3d = caravan_type == cv::type_name::<cv::Pose3D>();
    let (json, stamp_ns) = match ty {
        RosType::LaserScan => {
            let m: msgs::LaserScan = from_cdr(cdr)?;
            (json(scan_in(&m)?.as_ref())?, stamp(&m.header))
        }
        RosType::Imu => {
            let m: msgs::Imu = from_cdr(cdr)?;
            (json(&imu_in(&m))?, stamp(&m.header))
        }
        RosType::JointState => {
            let m: msgs::JointState = from_cdr(cdr)?;
            (json(joint_state_in(&m)?.as_ref())?, stamp(&m.header))
        }
        RosType::Twist => (json(&twist_in(&from_cdr(cdr)?))?, None),
        RosType::Pose2D => (json(&pose_2d_in(&from_cdr(cdr)?))?, None),
        RosType::PoseStamped => {
            let m: msgs::PoseStamped = from_cdr(cdr)?;
            let value = if pose_3d {
                json(&pose_3d_in(&m.pose))?
            } else {
                json(&pose_stamped_in(&m))?
            };
            (value, stamp(&m.header))
        }
        RosType::WrenchStamped => {
            let m: msgs::WrenchStamped = from_cdr(cdr)?;
            (json(&wrench_in(&m))?, stamp(&m.header))
        }
        RosType::OccupancyGrid => {
            let m: msgs::OccupancyGrid = from_cdr(cdr)?;
            (json(grid_in(&m)?.as_ref())?, stamp(&m.header))
        }
        RosType::Path => {
            let m: msgs::Path = from_cdr(cdr)?;
            (json(path_in(&m)?.as_ref())?, stamp(&m.header))
        }
        RosType::Odometry => {
            let m: msgs::Odometry = from_cdr(cdr)?;
            (json(&odometry_in(&m))?, stamp(&m.header))
        }
        RosType::TfMessage | RosType::Clock => {
            return Err(format!("{} is not played into a group", ty.name()));
        }
    };
    Ok(Played { json, stamp_ns })
}

/// The Caravan topic of a ROS 2 topic, the inverse of [`crate::naming::ros_topic`] for
/// Caravan's own names: the leading `/` dropped and `robot_<i>` read as `robot/<i>`
/// (`/robot_0/scan` → `robot/0/scan`, `/map` → `map`); other names are kept as they are.
pub fn caravan_topic(ros: &str) -> String {
    let name = ros.strip_prefix('/').unwrap_or(ros);
    name.split('/')
        .map(|segment| match segment.strip_prefix("robot_") {
            Some(i) if !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()) => {
                format!("robot/{i}")
            }
            _ => segment.to_owned(),
        })
        .collect::<Vec<_>>()
        .join("/")
}

#[cfg(test)]
#[path = "inverse_tests.rs"]
mod tests;
