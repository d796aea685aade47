//! The ROS 2 message types the bridge and the exporter know ([`RosType`]): their names, the
//! Caravan types they map from and to, and their `ros2msg` definitions (the `.msg` text with
//! every type it uses appended, as rosbag2 stores a schema).

/// A ROS 2 message type Caravan maps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RosType {
    LaserScan,
    Imu,
    JointState,
    Twist,
    Pose2D,
    PoseStamped,
    WrenchStamped,
    OccupancyGrid,
    Path,
    Odometry,
    TfMessage,
    Clock,
}

/// Which way a mapping goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Way {
    /// A Caravan topic published to ROS 2.
    Out,
    /// A ROS 2 topic published into the group.
    In,
}

impl RosType {
    /// Every type, in the order of the docs' mapping table.
    pub const ALL: [RosType; 12] = [
        RosType::LaserScan,
        RosType::Imu,
        RosType::JointState,
        RosType::Twist,
        RosType::Pose2D,
        RosType::PoseStamped,
        RosType::WrenchStamped,
        RosType::OccupancyGrid,
        RosType::Path,
        RosType::Odometry,
        RosType::TfMessage,
        RosType::Clock,
    ];

    /// `(package, type)`, e.g. `("sensor_msgs", "LaserScan")`.
    pub fn parts(self) -> (&'static str, &'static str) {
        match self {
            RosType::LaserScan => ("sensor_msgs", "LaserScan"),
            RosType::Imu => ("sensor_msgs", "Imu"),
            RosType::JointState => ("sensor_msgs", "JointState"),
            RosType::Twist => ("geometry_msgs", "Twist"),
            RosType::Pose2D => ("geometry_msgs", "Pose2D"),
            RosType::PoseStamped => ("geometry_msgs", "PoseStamped"),
            RosType::WrenchStamped => ("geometry_msgs", "WrenchStamped"),
            RosType::OccupancyGrid => ("nav_msgs", "OccupancyGrid"),
            RosType::Path => ("nav_msgs", "Path"),
            RosType::Odometry => ("nav_msgs", "Odometry"),
            RosType::TfMessage => ("tf2_msgs", "TFMessage"),
            RosType::Clock => ("rosgraph_msgs", "Clock"),
        }
    }

    /// The full name, `sensor_msgs/msg/LaserScan`.
    pub fn name(self) -> String {
        let (package, name) = self.parts();
        format!("{package}/msg/{name}")
    }

    /// The type a name gives: `sensor_msgs/msg/LaserScan` or `sensor_msgs/LaserScan`.
    pub fn parse(name: &str) -> Option<RosType> {
        let (package, rest) = name.split_once('/')?;
        let short = rest.strip_prefix("msg/").unwrap_or(rest);
        Self::ALL
            .into_iter()
            .find(|t| t.parts() == (package, short))
    }

    /// The Caravan types this ROS type maps from (out) or to (in), the first the default; empty
    /// where the bridge does not map that way.
    pub fn caravan_types(self, way: Way) -> &'static [&'static str] {
        match (self, way) {
            (RosType::LaserScan, Way::Out) => &["caravan::LaserScan"],
            (RosType::Imu, Way::Out) => &["caravan::Imu"],
            (RosType::JointState, Way::Out) => &["caravan::JointState"],
            (RosType::JointState, Way::In) => &["caravan::JointCommand"],
            (RosType::Twist, _) => &["caravan::Twist"],
            (RosType::Pose2D, _) => &["caravan::Pose2D"],
            (RosType::PoseStamped, Way::Out) => &["caravan::Pose2D", "caravan::Pose3D"],
            (RosType::PoseStamped, Way::In) => &["caravan::Pose2D", "caravan::Pose3D"],
            (RosType::WrenchStamped, _) => &["caravan::Wrench"],
            (RosType::OccupancyGrid, Way::Out) => &["caravan::OccupancyGrid"],
            (RosType::Path, Way::Out) => &["caravan::Path2D"],
            (RosType::Odometry, Way::Out) => &["caravan::Odometry"],
            (RosType::TfMessage, Way::Out) => &[
                "caravan::Pose2D",
                "caravan::LinkStates",
                "caravan::Odometry",
            ],
            _ => &[],
        }
    }

    /// The `ros2msg` schema: this type's fields, then each type it uses after a line of 80
    /// `=` and `MSG: package/Type`, as rosbag2 and Foxglove read it.
    pub fn definition(self) -> String {
        let (package, name) = self.parts();
        let mut text = fields(&format!("{package}/{name}")).to_owned();
        for dependency in dependencies(self) {
            text.push_str(&format!("\n{}\nMSG: {dependency}\n", "=".repeat(80)));
            text.push_str(fields(dependency));
        }
        text
    }
}

/// The types a type uses, each once, each after those that use it.
fn dependencies(t: RosType) -> &'static [&'static str] {
    const HEADER: &str = "std_msgs/Header";
    const TIME: &str = "builtin_interfaces/Time";
    const VECTOR3: &str = "geometry_msgs/Vector3";
    const QUATERNION: &str = "geometry_msgs/Quaternion";
    const POSE: &str = "geometry_msgs/Pose";
    const POINT: &str = "geometry_msgs/Point";
    match t {
        RosType::LaserScan => &[HEADER, TIME],
        RosType::Imu => &[HEADER, TIME, QUATERNION, VECTOR3],
        RosType::JointState => &[HEADER, TIME],
        RosType::Twist => &[VECTOR3],
        RosType::Pose2D => &[],
        RosType::PoseStamped => &[HEADER, TIME, POSE, POINT, QUATERNION],
        RosType::WrenchStamped => &[HEADER, TIME, "geometry_msgs/Wrench", VECTOR3],
        RosType::OccupancyGrid => &[
            HEADER,
            TIME,
            "nav_msgs/MapMetaData",
            POSE,
            POINT,
            QUATERNION,
        ],
        RosType::Path => &[
            HEADER,
            TIME,
            "geometry_msgs/PoseStamped",
            POSE,
            POINT,
            QUATERNION,
        ],
        RosType::Odometry => &[
            HEADER,
            TIME,
            "geometry_msgs/PoseWithCovariance",
            POSE,
            POINT,
            QUATERNION,
            "geometry_msgs/TwistWithCovariance",
            "geometry_msgs/Twist",
            VECTOR3,
        ],
        RosType::TfMessage => &[
            "geometry_msgs/TransformStamped",
            HEADER,
            TIME,
            "geometry_msgs/Transform",
            VECTOR3,
            QUATERNION,
        ],
        RosType::Clock => &[TIME],
    }
}

/// The fields of a `.msg` file (ROS 2 Jazzy, comments left out).
fn fields(full: &str) -> &'static str {
    match full {
        "builtin_interfaces/Time" => "int32 sec\nuint32 nanosec\n",
        "std_msgs/Header" => "builtin_interfaces/Time stamp\nstring frame_id\n",
        "geometry_msgs/Vector3" | "geometry_msgs/Point" => "float64 x\nfloat64 y\nfloat64 z\n",
        "geometry_msgs/Quaternion" => "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
        "geometry_msgs/Pose" => {
            "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n"
        }
        "geometry_msgs/Pose2D" => "float64 x\nfloat64 y\nfloat64 theta\n",
        "geometry_msgs/PoseStamped" => "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
        "geometry_msgs/PoseWithCovariance" => "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
        "geometry_msgs/Twist" => "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
        "geometry_msgs/TwistWithCovariance" => {
            "geometry_msgs/Twist twist\nfloat64[36] covariance\n"
        }
        "geometry_msgs/Transform" => {
            "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n"
        }
        "geometry_msgs/TransformStamped" => {
            "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n"
        }
        "geometry_msgs/Wrench" => "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n",
        "geometry_msgs/WrenchStamped" => "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n",
        "sensor_msgs/LaserScan" => concat!(
            "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n",
            "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n",
            "float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n"
        ),
        "sensor_msgs/Imu" => concat!(
            "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n",
            "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n",
            "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n",
            "float64[9] linear_acceleration_covariance\n"
        ),
        "sensor_msgs/JointState" => concat!(
            "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n",
            "float64[] effort\n"
        ),
        "nav_msgs/MapMetaData" => concat!(
            "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n",
            "uint32 height\ngeometry_msgs/Pose origin\n"
        ),
        "nav_msgs/OccupancyGrid" => {
            "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n"
        }
        "nav_msgs/Path" => "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n",
        "nav_msgs/Odometry" => concat!(
            "std_msgs/Header header\nstring child_frame_id\n",
            "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n"
        ),
        "tf2_msgs/TFMessage" => "geometry_msgs/TransformStamped[] transforms\n",
        "rosgraph_msgs/Clock" => "builtin_interfaces/Time clock\n",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_in_both_spellings() {
        for t in RosType::ALL {
            assert_eq!(RosType::parse(&t.name()), Some(t));
            let (package, name) = t.parts();
            assert_eq!(RosType::parse(&format!("{package}/{name}")), Some(t));
        }
        assert_eq!(RosType::parse("sensor_msgs/msg/PointCloud2"), None);
        assert_eq!(RosType::parse("LaserScan"), None);
    }

    #[test]
    fn every_type_a_definition_uses_is_defined_after_it() {
        for t in RosType::ALL {
            let text = t.definition();
            let sections: Vec<&str> = text.split(&format!("\n{}\n", "=".repeat(80))).collect();
            let defined: Vec<&str> = sections[1..]
                .iter()
                .map(|s| s.lines().next().unwrap().strip_prefix("MSG: ").unwrap())
                .collect();
            for section in &sections {
                for line in section.lines().filter(|l| !l.starts_with("MSG: ")) {
                    let ty = line.split_whitespace().next().unwrap();
                    let ty = ty.split('[').next().unwrap();
                    if ty.contains('/') {
                        assert!(defined.contains(&ty), "{}: {ty} is not defined", t.name());
                    }
                }
            }
            for d in defined {
                assert!(!fields(d).is_empty(), "{}: no fields for {d}", t.name());
            }
        }
    }

    #[test]
    fn the_docs_table_lists_every_mapping() {
        let docs = include_str!("../../../docs/ros2.md");
        let rows: Vec<&str> = docs.lines().filter(|l| l.starts_with("| `")).collect();
        for t in RosType::ALL {
            for (way, word) in [(Way::Out, "out"), (Way::In, "in")] {
                for c in t.caravan_types(way) {
                    let head = format!("| `{}` | `{c}` |", t.name());
                    let row = rows.iter().find(|r| r.starts_with(&head));
                    let listed = row.is_some_and(|r| r.split('|').nth(3).unwrap().contains(word));
                    assert!(listed, "docs/ros2.md has no row {head} … {word}");
                }
            }
        }
    }
}
