//! ROS 2 names for Caravan's topics and frames: `robot/0/scan` is `/robot_0/scan`, robot 0's
//! base is the frame `robot_0/base_link`, and the world is `map` (REP 105's global frame).

use crate::mapping::Frames;
use crate::ros_type::RosType;
use caravan_schemas::topics::{pose_frame, robot_frame, robot_of};

/// The global frame: poses, paths, maps and transforms are in it.
pub const MAP_FRAME: &str = "map";

/// The ROS 2 topic a Caravan topic is published on by default: `/` then the topic, with a
/// robot's index joined to `robot` (`robot/0/scan` → `/robot_0/scan`, ROS 2 names cannot have
/// a token that starts with a digit) and `-` as `_`.
pub fn ros_topic(caravan: &str) -> String {
    let mut out = String::new();
    for segment in caravan.split('/') {
        let segment = segment.replace('-', "_");
        if segment.starts_with(|c: char| c.is_ascii_digit()) && !out.is_empty() {
            out.push('_');
        } else {
            out.push('/');
        }
        out.push_str(&segment);
    }
    out
}

/// Checks a ROS 2 topic name as ROS 2 does (rcl's rules: letters, digits, `_` and `/`, no
/// token starting with a digit, no `//` or `__`, not ending in `/`); the bridge only takes
/// absolute names, since it has no namespace of its own to resolve others in.
pub fn check_topic(name: &str) -> Result<(), String> {
    if !name.starts_with('/') {
        return Err(format!(
            "'{name}' is not an absolute ROS 2 name (start it with '/')"
        ));
    }
    if name.contains("__") {
        return Err(format!("'{name}': ROS 2 names may not contain '__'"));
    }
    ros2_client::Name::parse(name)
        .map(|_| ())
        .map_err(|e| format!("'{name}' is not a valid ROS 2 topic name: {e:?}"))
}

/// The frames of a Caravan topic carried as `ty`: sensors in their robot's `base_link`, poses,
/// paths and maps in `map`, transforms and odometry with the frame the topic places as child
/// (`robot/0/pose` → `robot_0/base_link`, `robot/0/pose_true` → `robot_0/base_link_true`, another
/// robot topic `robot_<i>/<leaf>`).
pub fn frames(caravan: &str, ty: RosType) -> Frames {
    let robot = robot_of(caravan);
    let index = robot.map(|(i, _)| i);
    let frame_id = match (ty, index) {
        (RosType::LaserScan | RosType::Imu | RosType::JointState, Some(i)) => {
            robot_frame(i, "base_link")
        }
        _ => MAP_FRAME.into(),
    };
    let child_frame_id = pose_frame(caravan)
        .or_else(|| robot.map(|(i, leaf)| robot_frame(i, leaf)))
        .unwrap_or_else(|| caravan.replace('/', "_"));
    Frames {
        frame_id,
        child_frame_id,
        robot: index,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caravan_topics_get_ros_names() {
        assert_eq!(ros_topic("robot/0/scan"), "/robot_0/scan");
        assert_eq!(ros_topic("robot/12/cmd_vel"), "/robot_12/cmd_vel");
        assert_eq!(ros_topic("map"), "/map");
        assert_eq!(ros_topic("convoy/gap-1"), "/convoy/gap_1");
        for t in ["robot/0/scan", "map", "robot/3/pose_true", "convoy/gap-1"] {
            check_topic(&ros_topic(t)).unwrap();
        }
    }

    #[test]
    fn names_ros_2_rejects_are_refused() {
        for bad in [
            "scan",
            "/robot/0/scan",
            "/a//b",
            "/a/",
            "/a b",
            "/a__b",
            "/caf\u{e9}",
            "/",
        ] {
            assert!(check_topic(bad).is_err(), "{bad} was accepted");
        }
        check_topic("/robot_0/scan").unwrap();
        check_topic("/tf").unwrap();
    }

    #[test]
    fn frames_follow_the_recording() {
        let f = frames("robot/2/scan", RosType::LaserScan);
        assert_eq!(
            (f.frame_id.as_str(), f.robot),
            ("robot_2/base_link", Some(2))
        );
        let f = frames("robot/1/pose_true", RosType::TfMessage);
        assert_eq!(
            (f.frame_id.as_str(), f.child_frame_id.as_str()),
            ("map", "robot_1/base_link_true")
        );
        let f = frames("robot/1/odometry", RosType::Odometry);
        assert_eq!(f.child_frame_id, "robot_1/base_link");
        assert_eq!(frames("map", RosType::OccupancyGrid).frame_id, "map");
    }
}
