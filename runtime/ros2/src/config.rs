//! The bridge's params (`caravan-ros2` in a launch file): the DDS domain, `/clock`, and one
//! entry per topic that crosses, checked whole before the group starts ([`Config::check`]).

use crate::mapping::Frames;
use crate::naming;
use crate::ros_type::{RosType, Way};
use serde::Deserialize;

/// The params as the launch file writes them.
#[derive(Debug, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The DDS domain id, 0–232; default `ROS_DOMAIN_ID` from the environment, else 0.
    pub domain: Option<u16>,
    /// Publish the group's time on `/clock` (`rosgraph_msgs/Clock`) at every step.
    #[serde(default = "yes")]
    pub clock: bool,
    /// The topics that cross, each one way.
    #[serde(default)]
    pub topics: Vec<Entry>,
}

fn yes() -> bool {
    true
}

/// One topic that crosses.
#[derive(Debug, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// The Caravan topic, e.g. `robot/0/scan`.
    pub caravan: String,
    /// `out` (Caravan → ROS 2, the default) or `in` (ROS 2 → Caravan).
    #[serde(default)]
    pub direction: Direction,
    /// The ROS 2 topic, absolute; default the Caravan topic's ROS name (`/robot_0/scan`), and
    /// `/tf` for transforms.
    pub ros: Option<String>,
    /// The ROS 2 type, `sensor_msgs/msg/LaserScan`; default the one the Caravan type maps to.
    #[serde(rename = "type")]
    pub ros_type: Option<String>,
    /// The Caravan topic's type, `caravan::Pose2D`; needed only for a topic Caravan does not
    /// name itself whose ROS type maps from several (a `/tf` from a `Pose3D` topic, say).
    pub caravan_type: Option<String>,
    /// The header's frame; default as docs/ros2.md lists.
    pub frame_id: Option<String>,
    /// The child frame of a transform or an odometry.
    pub child_frame_id: Option<String>,
    /// Quality of service; default reliable, volatile, depth 10 (ROS 2's default).
    #[serde(default)]
    pub qos: Qos,
}

/// Which way an entry crosses.
#[derive(
    Debug, Default, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    #[default]
    Out,
    In,
}

/// A topic's quality of service, in ROS 2's words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Qos {
    pub reliability: Reliability,
    pub durability: Durability,
    /// Messages kept (history keep-last), 1–10000.
    pub depth: u32,
}

impl Default for Qos {
    fn default() -> Self {
        Self {
            reliability: Reliability::Reliable,
            durability: Durability::Volatile,
            depth: 10,
        }
    }
}

/// `reliable` (a reliable writer also serves best-effort readers) or `best_effort`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Reliability {
    Reliable,
    BestEffort,
}

/// `volatile`, or `transient_local`: late readers get the last `depth` messages (a map).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Durability {
    Volatile,
    TransientLocal,
}

/// One checked entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Route {
    pub caravan: String,
    pub caravan_type: &'static str,
    pub ros: String,
    pub ty: RosType,
    pub way: Way,
    pub qos: Qos,
    pub frames: Frames,
}

/// The checked params.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    pub domain: u16,
    pub clock: bool,
    pub routes: Vec<Route>,
}

/// The highest domain id ROS 2 accepts (its port arithmetic ends there).
pub const MAX_DOMAIN: u16 = 232;

/// The ROS type a Caravan type crosses as when the entry names none.
pub fn default_ros_type(caravan_type: &str, way: Way) -> Option<RosType> {
    Some(match (caravan_type, way) {
        ("caravan::LaserScan", Way::Out) => RosType::LaserScan,
        ("caravan::Imu", Way::Out) => RosType::Imu,
        ("caravan::JointState", Way::Out) | ("caravan::JointCommand", Way::In) => {
            RosType::JointState
        }
        ("caravan::Twist", _) => RosType::Twist,
        ("caravan::Pose2D" | "caravan::Pose3D", _) => RosType::PoseStamped,
        ("caravan::Wrench", _) => RosType::WrenchStamped,
        ("caravan::OccupancyGrid", Way::Out) => RosType::OccupancyGrid,
        ("caravan::Path2D", Way::Out) => RosType::Path,
        ("caravan::Odometry", Way::Out) => RosType::Odometry,
        ("caravan::LinkStates", Way::Out) => RosType::TfMessage,
        _ => return None,
    })
}

impl Config {
    /// Checks the params; `ros_domain_id` is the environment's `ROS_DOMAIN_ID`. Errors name
    /// the key (`topics[2].type`) as the launcher locates them in the file.
    pub fn check(p: Params, ros_domain_id: Option<&str>) -> Result<Config, String> {
        let domain = match (p.domain, ros_domain_id) {
            (Some(d), _) if d > MAX_DOMAIN => {
                return Err(format!("key 'domain': must be 0–{MAX_DOMAIN}, got {d}"));
            }
            (Some(d), _) => d,
            (None, Some(text)) if !text.trim().is_empty() => match text.trim().parse::<u16>() {
                Ok(d) if d <= MAX_DOMAIN => d,
                _ => {
                    return Err(format!(
                        "environment ROS_DOMAIN_ID='{text}': must be a domain id 0–{MAX_DOMAIN} \
                         (or set key 'domain')"
                    ));
                }
            },
            _ => 0,
        };
        let mut routes: Vec<Route> = Vec::new();
        for (i, e) in p.topics.into_iter().enumerate() {
            let route = route(e).map_err(|(key, m)| format!("key 'topics[{i}].{key}': {m}"))?;
            if let Some(other) = routes.iter().find(|r| r.ros == route.ros) {
                let clash = if other.way != route.way {
                    Some("crosses both ways (a loop)")
                } else if other.ty != route.ty {
                    Some("has another type in an earlier entry")
                } else if route.way == Way::In {
                    Some("comes in twice")
                } else {
                    None
                };
                if let Some(clash) = clash {
                    return Err(format!("key 'topics[{i}].ros': '{}' {clash}", route.ros));
                }
            }
            routes.push(route);
        }
        Ok(Config {
            domain,
            clock: p.clock,
            routes,
        })
    }
}

/// One entry checked; the error is (key within the entry, message).
fn route(e: Entry) -> Result<Route, (&'static str, String)> {
    let way = match e.direction {
        Direction::Out => Way::Out,
        Direction::In => Way::In,
    };
    let topic = &e.caravan;
    if topic.is_empty()
        || topic.starts_with('/')
        || topic.ends_with('/')
        || topic.contains("//")
        || topic.contains(char::is_whitespace)
        || topic.contains('*')
    {
        return Err((
            "caravan",
            format!("'{topic}' is not a Caravan topic name (like robot/0/scan)"),
        ));
    }
    let known = caravan_schemas::topics::type_of(&e.caravan);
    let caravan_type = match (&e.caravan_type, known) {
        (Some(given), Some(known)) if given != known => {
            return Err((
                "caravan_type",
                format!("'{}' is a {known}, not a {given}", e.caravan),
            ));
        }
        (Some(given), _) => Some(given.as_str()),
        (None, known) => known,
    };
    let ty = match &e.ros_type {
        Some(name) => RosType::parse(name).ok_or_else(|| {
            let known: Vec<String> = RosType::ALL
                .iter()
                .filter(|t| !t.caravan_types(way).is_empty())
                .map(|t| t.name())
                .collect();
            (
                "type",
                format!(
                    "unknown ROS 2 type '{name}'; the bridge maps {}",
                    known.join(", ")
                ),
            )
        })?,
        None => caravan_type
            .and_then(|c| default_ros_type(c, way))
            .ok_or_else(|| {
                (
                    "type",
                    format!(
                        "give the ROS 2 type of '{}': Caravan has no default for it",
                        e.caravan
                    ),
                )
            })?,
    };
    let mapped = ty.caravan_types(way);
    let caravan_type: &'static str = match caravan_type {
        Some(c) => mapped.iter().copied().find(|m| *m == c).ok_or_else(|| {
            let key = if e.ros_type.is_some() {
                "type"
            } else {
                "caravan_type"
            };
            let way = if way == Way::Out { "from" } else { "to" };
            let how = if mapped.is_empty() {
                "nothing".to_owned()
            } else {
                mapped.join(" or ")
            };
            (
                key,
                format!("'{}' is a {c}; {} maps {way} {how}", e.caravan, ty.name()),
            )
        })?,
        None if mapped.is_empty() => {
            let way = if way == Way::Out { "out" } else { "in" };
            return Err(("type", format!("{} does not cross {way}", ty.name())));
        }
        None => mapped[0],
    };
    let ros = match e.ros {
        Some(ros) => ros,
        None if ty == RosType::TfMessage => "/tf".to_owned(),
        None => naming::ros_topic(&e.caravan),
    };
    naming::check_topic(&ros).map_err(|m| ("ros", m))?;
    if !(1..=10_000).contains(&e.qos.depth) {
        return Err(("qos.depth", format!("must be 1–10000, got {}", e.qos.depth)));
    }
    let mut frames = naming::frames(&e.caravan, ty);
    if let Some(f) = e.frame_id {
        frames.frame_id = f;
    }
    if let Some(f) = e.child_frame_id {
        frames.child_frame_id = f;
    }
    Ok(Route {
        caravan: e.caravan,
        caravan_type,
        ros,
        ty,
        way,
        qos: e.qos,
        frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(topics: serde_json::Value) -> Result<Config, String> {
        let p: Params = serde_json::from_value(serde_json::json!({ "topics": topics })).unwrap();
        Config::check(p, None)
    }

    #[test]
    fn entries_take_ros_names_types_and_frames_by_default() {
        let c = check(serde_json::json!([
            { "caravan": "robot/0/scan" },
            { "caravan": "robot/2/pose", "type": "tf2_msgs/msg/TFMessage" },
            { "caravan": "robot/4/cmd_vel", "direction": "in" },
            { "caravan": "map", "qos": { "durability": "transient_local", "depth": 1 } },
        ]))
        .unwrap();
        let r = &c.routes;
        assert_eq!(
            (r[0].ros.as_str(), r[0].ty, r[0].way),
            ("/robot_0/scan", RosType::LaserScan, Way::Out)
        );
        assert_eq!(r[0].frames.frame_id, "robot_0/base_link");
        assert_eq!(
            (r[1].ros.as_str(), r[1].frames.child_frame_id.as_str()),
            ("/tf", "robot_2/base_link")
        );
        assert_eq!(
            (r[2].ros.as_str(), r[2].ty, r[2].way),
            ("/robot_4/cmd_vel", RosType::Twist, Way::In)
        );
        assert_eq!(r[3].qos.durability, Durability::TransientLocal);
        assert_eq!((c.domain, c.clock), (0, true));
    }

    #[test]
    fn bad_entries_name_their_key() {
        let cases = [
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "type": "sensor_msgs/msg/PointCloud2" }]),
                "topics[0].type",
                "unknown ROS 2 type",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "type": "sensor_msgs/msg/Imu" }]),
                "topics[0].type",
                "is a caravan::LaserScan",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "ros": "/robot/0/scan" }]),
                "topics[0].ros",
                "not a valid ROS 2 topic name",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "ros": "scan" }]),
                "topics[0].ros",
                "absolute",
            ),
            (
                serde_json::json!([{ "caravan": "my/topic" }]),
                "topics[0].type",
                "give the ROS 2 type",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "direction": "in" }]),
                "topics[0].type",
                "give the ROS 2 type",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/cmd_vel", "type": "sensor_msgs/msg/LaserScan", "direction": "in" }]),
                "topics[0].type",
                "maps to nothing",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "qos": { "depth": 0 } }]),
                "topics[0].qos.depth",
                "1–10000",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/scan", "caravan_type": "caravan::Imu" }]),
                "topics[0].caravan_type",
                "is a caravan::LaserScan",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/cmd_vel" }, { "caravan": "robot/0/cmd_vel", "direction": "in" }]),
                "topics[1].ros",
                "both ways",
            ),
            (
                serde_json::json!([{ "caravan": "robot/0/pose" }, { "caravan": "robot/0/pose_true", "ros": "/robot_0/pose", "type": "geometry_msgs/msg/Pose2D" }]),
                "topics[1].ros",
                "another type",
            ),
            (
                serde_json::json!([{ "caravan": "/robot/0/scan" }]),
                "topics[0].caravan",
                "not a Caravan topic",
            ),
        ];
        for (topics, key, words) in cases {
            let e = check(topics.clone()).unwrap_err();
            assert!(
                e.starts_with(&format!("key '{key}'")) && e.contains(words),
                "{topics}: {e}"
            );
        }
    }

    #[test]
    fn qos_words_are_ros_2_s() {
        let bad = serde_json::json!({ "topics": [{ "caravan": "map", "qos": { "reliability": "sometimes" } }] });
        let e = serde_json::from_value::<Params>(bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains("reliable") && e.contains("best_effort"), "{e}");
    }

    #[test]
    fn the_domain_comes_from_ros_domain_id_unless_set() {
        let p = || serde_json::from_value::<Params>(serde_json::json!({})).unwrap();
        assert_eq!(Config::check(p(), Some("42")).unwrap().domain, 42);
        assert_eq!(Config::check(p(), Some("")).unwrap().domain, 0);
        let e = Config::check(p(), Some("lots")).unwrap_err();
        assert!(e.contains("ROS_DOMAIN_ID='lots'"), "{e}");
        assert!(Config::check(p(), Some("233")).is_err());
        let set = serde_json::from_value::<Params>(serde_json::json!({ "domain": 7 })).unwrap();
        assert_eq!(Config::check(set, Some("42")).unwrap().domain, 7);
        let high = serde_json::from_value::<Params>(serde_json::json!({ "domain": 300 })).unwrap();
        assert!(
            Config::check(high, None)
                .unwrap_err()
                .starts_with("key 'domain'")
        );
    }
}
