//! A Caravan recording's messages (the recorder's JSON) as ROS 2 messages: what
//! `caravan export --ros2` writes. Each recorded topic whose type has a default ROS 2 type
//! ([`crate::config::default_ros_type`]) keeps its own topic under its ROS name, and `/tf`
//! holds the transforms of the recording's own `tf` channel: one per message of a robot's
//! pose (`robot/<i>/pose`, `robot/<i>/pose_true`) and of its links (`robot/<i>/link_states`).

use crate::config::default_ros_type;
use crate::mapping::{Caravan, Frames, RosMessage, to_ros};
use crate::naming;
use crate::ros_type::{RosType, Way};
use caravan_schemas as cv;
use caravan_schemas::from_json::message_from_json;
use serde_json::Value;

/// The ROS 2 topic transforms go to.
pub const TF_TOPIC: &str = "/tf";

/// The ROS 2 type a recorded topic of `caravan_type` is exported as on a topic of its own;
/// `None` for a type with no ROS 2 counterpart, and for `LinkStates`, which goes to `/tf`
/// only.
pub fn exported_type(caravan_type: &str) -> Option<RosType> {
    default_ros_type(caravan_type, Way::Out).filter(|t| *t != RosType::TfMessage)
}

/// Whether messages of `caravan_type` on `topic` place frames, as the recorder's `tf`
/// channel has them (`caravan_record::scene`): a `Pose2D` on a robot's pose topic, a
/// robot's `LinkStates`.
pub fn places_frames(topic: &str, caravan_type: &str) -> bool {
    if caravan_type == cv::type_name::<cv::Pose2D>() {
        cv::topics::pose_frame(topic).is_some()
    } else {
        caravan_type == cv::type_name::<cv::LinkStates>() && cv::topics::robot_of(topic).is_some()
    }
}

/// One recorded message as ROS 2 messages: on its own topic (if its type has one) and on
/// `/tf` (if it places frames).
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    pub own: Option<RosMessage>,
    pub tf: Option<RosMessage>,
}

/// Converts one recorded message (its JSON, `header` ignored) of `caravan_type` on `topic`,
/// stamped `stamp_ns`; an error names what in the JSON is wrong.
pub fn export(
    topic: &str,
    caravan_type: &str,
    json: &Value,
    stamp_ns: u64,
) -> Result<Exported, String> {
    let own = exported_type(caravan_type);
    let tf = places_frames(topic, caravan_type);
    let convert = |c: Caravan| Exported {
        own: own.and_then(|ty| to_ros(ty, c, stamp_ns, &naming::frames(topic, ty))),
        tf: tf
            .then(|| {
                let frames: Frames = naming::frames(topic, RosType::TfMessage);
                to_ros(RosType::TfMessage, c, stamp_ns, &frames)
            })
            .flatten(),
    };
    macro_rules! types {
        ($($ty:ident),*) => {
            $(if caravan_type == cv::type_name::<cv::$ty>() {
                let m = message_from_json::<cv::$ty>(json)?;
                return Ok(convert(Caravan::$ty(&m)));
            })*
        };
    }
    crate::mapping::outbound_types!(types);
    Ok(Exported {
        own: None,
        tf: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_robot_pose_is_a_pose_stamped_and_a_transform() {
        let e = export(
            "robot/2/pose_true",
            "caravan::Pose2D",
            &json!({"x": 1.0, "y": -2.0, "theta": 0.5, "header": {"seq": 3}}),
            1_500_000_000,
        )
        .unwrap();
        let Some(RosMessage::PoseStamped(p)) = e.own else {
            panic!("{e:?}")
        };
        assert_eq!(
            (p.header.frame_id.as_str(), p.pose.position.y),
            ("map", -2.0)
        );
        assert_eq!(p.header.stamp.to_ns(), 1_500_000_000);
        let Some(RosMessage::TfMessage(tf)) = e.tf else {
            panic!("no transform")
        };
        let t = &tf.transforms[0];
        assert_eq!(
            (t.header.frame_id.as_str(), t.child_frame_id.as_str()),
            ("map", "robot_2/base_link_true")
        );
        // Another Pose2D topic places no frame.
        let goal = export("target", "caravan::Pose2D", &json!({}), 0).unwrap();
        assert!(goal.own.is_some() && goal.tf.is_none());
    }

    #[test]
    fn links_go_to_tf_only_and_unmapped_types_nowhere() {
        let links = json!({"links": [
            {"name": "base", "pose": {"position": {"x": 1.0, "y": 0.0, "z": 0.5},
             "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
            {"name": "arm", "pose": {}}]});
        let e = export("robot/1/link_states", "caravan::LinkStates", &links, 7).unwrap();
        assert!(e.own.is_none());
        let Some(RosMessage::TfMessage(tf)) = e.tf else {
            panic!("{e:?}")
        };
        let children: Vec<&str> = tf
            .transforms
            .iter()
            .map(|t| t.child_frame_id.as_str())
            .collect();
        assert_eq!(children, ["robot_1/base", "robot_1/arm"]);
        assert_eq!(tf.transforms[0].transform.translation.z, 0.5);
        assert_eq!(exported_type("caravan::LinkStates"), None);
        assert_eq!(exported_type("caravan::WheelSetpoint"), None);
        assert_eq!(
            exported_type("caravan::Wrench"),
            Some(RosType::WrenchStamped)
        );
        let none = export(
            "robot/0/wheel_setpoint",
            "caravan::WheelSetpoint",
            &json!({}),
            0,
        );
        assert_eq!(
            none.unwrap(),
            Exported {
                own: None,
                tf: None
            }
        );
    }

    #[test]
    fn bad_json_is_an_error_naming_the_field() {
        let e = export(
            "robot/0/scan",
            "caravan::LaserScan",
            &json!({"ranges": [1.0, "x"]}),
            0,
        )
        .unwrap_err();
        assert!(e.contains("ranges[1]"), "{e}");
    }
}
