//! Foxglove scene channels: Foxglove's well-known messages (`foxglove.*`, protobuf, the
//! Foxglove SDK's types) derived from recorded Caravan messages, so that Foxglove's 3D panel
//! shows the robots, scans, map, paths and goals of any scenario without a converter.
//!
//! Frames: `map` is the world; `robot_<i>/base_link` is robot i where its own estimate puts it
//! (`robot/<i>/pose`), `robot_<i>/base_link_true` where it is (`robot/<i>/pose_true`), and
//! `robot_<i>/<link>` each link of an articulated robot (`robot/<i>/link_states`). Transforms
//! go to one `tf` channel, as in ROS, one message per time holding every transform placed
//! then (the writer gathers them: [`Viewer::encode`]'s `frames`, [`put_frames`]); every other
//! view is on `foxglove/<raw topic>`. A scan is drawn in its robot's `base_link`; the world's
//! solids (`scene`, from the physics) are a `foxglove.SceneUpdate` on `foxglove/scene`.
//!
//! Views depend only on the raw message, so a lockstep recording stays byte-identical. They are
//! read from the message's bytes ([`caravan_schemas::reader`]), not from its JSON: a 1 MiB map
//! as a JSON tree was most of what the recording cost.

use caravan_schemas::descriptor::Descriptor;
use caravan_schemas::reader::Fields;
use caravan_schemas::topics::robot_frame;
use foxglove::Encode;
use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, FrameTransform, FrameTransforms, Grid, LaserScan,
    PackedElementField, Pose, PoseInFrame, PosesInFrame, Quaternion, SceneEntity, SceneUpdate,
    SpherePrimitive, Timestamp, Vector2, Vector3, packed_element_field::NumericType,
};

/// The channel every transform goes to.
pub const TF_TOPIC: &str = "tf";
/// The world frame.
pub const MAP_FRAME: &str = "map";

/// A channel's schema: name, encoding and the serialised descriptor set.
pub struct SceneSchema {
    pub name: String,
    pub encoding: String,
    pub data: Vec<u8>,
}

/// A view's topic and schema.
pub type ViewTopic = (String, fn() -> SceneSchema);

/// The `tf` channel's topic and schema.
pub fn tf_view() -> ViewTopic {
    (TF_TOPIC.to_string(), schema_of::<FrameTransforms>)
}

/// Encodes `frames` into `out` as one `tf` message, over what it held, and empties `frames`
/// (keeping its room).
pub fn put_frames(frames: &mut Vec<FrameTransform>, out: &mut Vec<u8>) {
    let message = FrameTransforms {
        transforms: std::mem::take(frames),
    };
    put(&message, out);
    *frames = message.transforms;
    frames.clear();
}

/// One Foxglove message derived from a recorded one.
#[cfg(test)]
pub struct View {
    pub topic: String,
    pub schema: fn() -> SceneSchema,
    pub bytes: Vec<u8>,
}

fn schema_of<T: Encode>() -> SceneSchema {
    let s = T::get_schema().expect("Foxglove's well-known messages have schemas");
    SceneSchema {
        name: s.name,
        encoding: s.encoding,
        data: s.data.into_owned(),
    }
}

/// Encodes `message` into `out`, over what it held.
fn put<T: Encode>(message: &T, out: &mut Vec<u8>) {
    out.clear();
    // Encoding into a growable Vec cannot run out of room.
    let _ = message.encode(out);
}

fn timestamp(ns: u64) -> Timestamp {
    let sec = u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX);
    Timestamp::new(sec, (ns % 1_000_000_000) as u32)
}

fn num(v: &Fields, key: &str) -> f64 {
    v.number(key).unwrap_or(0.0)
}

fn num_in(v: Option<Fields>, key: &str) -> f64 {
    v.map_or(0.0, |v| num(&v, key))
}

/// A `Pose2D` as a pose in the plane.
fn pose_2d(v: Option<Fields>) -> Pose {
    let half = num_in(v, "theta") / 2.0;
    Pose {
        position: Some(Vector3 {
            x: num_in(v, "x"),
            y: num_in(v, "y"),
            z: 0.0,
        }),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: half.sin(),
            w: half.cos(),
        }),
    }
}

/// A `Pose3D`.
fn pose_3d(v: Option<Fields>) -> Pose {
    let p = v.and_then(|v| v.get("position"));
    let q = v.and_then(|v| v.get("orientation"));
    Pose {
        position: Some(Vector3 {
            x: num_in(p, "x"),
            y: num_in(p, "y"),
            z: num_in(p, "z"),
        }),
        orientation: Some(Quaternion {
            x: num_in(q, "x"),
            y: num_in(q, "y"),
            z: num_in(q, "z"),
            w: num_in(q, "w"),
        }),
    }
}

fn transform(stamp: Timestamp, child: String, pose: Pose) -> FrameTransform {
    FrameTransform {
        timestamp: Some(stamp),
        parent_frame_id: MAP_FRAME.into(),
        child_frame_id: child,
        translation: pose.position,
        rotation: pose.orientation,
    }
}

/// The kinds of Caravan messages with views.
#[derive(Clone, Copy)]
enum Kind {
    Pose2D,
    Odometry,
    Goal,
    Path,
    Scan,
    Grid,
    Links,
    Scene,
}

/// The Foxglove views of one raw topic, worked out when the topic is discovered: their topics,
/// and what a message needs besides its bytes (frames, the robot). A message then costs no name
/// formatting, and its views are encoded into buffers kept between messages; a pose's view
/// (most of a recording's) is kept whole and only its numbers refilled.
pub struct Viewer {
    kind: Kind,
    /// The views' topics and schemas, in the order [`Viewer::encode`] fills its buffers (`tf`
    /// not among them: see [`Viewer::places_frames`]).
    topics: Vec<ViewTopic>,
    /// A scan's frame (its robot's `base_link`, else `map`).
    frame: String,
    robot: Option<usize>,
    /// A pose's view in the map.
    pose: PoseInFrame,
    /// The frame a pose places (its robot's `base_link` or `base_link_true`), if it does.
    tf_child: Option<String>,
}

impl Viewer {
    /// The views of `topic`'s messages, laid out as `descriptor` says; `None` for a type
    /// without views.
    pub fn new(topic: &str, descriptor: &Descriptor) -> Option<Viewer> {
        let robot = caravan_schemas::topics::robot_of(topic).map(|(i, _)| i);
        let kind = match descriptor.type_name() {
            "caravan::Pose2D" => Kind::Pose2D,
            "caravan::Odometry" => Kind::Odometry,
            "caravan::Goal" => Kind::Goal,
            "caravan::Path2D" => Kind::Path,
            "caravan::LaserScan" => Kind::Scan,
            "caravan::OccupancyGrid" => Kind::Grid,
            "caravan::LinkStates" if robot.is_some() => Kind::Links,
            "caravan::Scene" => Kind::Scene,
            _ => return None,
        };
        let own = format!("foxglove/{topic}");
        let (topics, tf_child) = match kind {
            Kind::Pose2D | Kind::Odometry | Kind::Goal => {
                let child = match kind {
                    Kind::Pose2D => caravan_schemas::topics::pose_frame(topic),
                    _ => None,
                };
                (vec![(own, schema_of::<PoseInFrame> as fn() -> _)], child)
            }
            Kind::Path => (vec![(own, schema_of::<PosesInFrame> as fn() -> _)], None),
            Kind::Scan => (vec![(own, schema_of::<LaserScan> as fn() -> _)], None),
            Kind::Grid => (vec![(own, schema_of::<Grid> as fn() -> _)], None),
            Kind::Links => (Vec::new(), None),
            Kind::Scene => (vec![(own, schema_of::<SceneUpdate> as fn() -> _)], None),
        };
        Some(Viewer {
            kind,
            topics,
            frame: match robot {
                Some(i) => robot_frame(i, "base_link"),
                None => MAP_FRAME.into(),
            },
            robot,
            pose: PoseInFrame {
                timestamp: None,
                frame_id: MAP_FRAME.into(),
                pose: None,
            },
            tf_child,
        })
    }

    /// The views' topics and schemas, in the order [`Viewer::encode`] fills its buffers.
    pub fn topics(&self) -> &[ViewTopic] {
        &self.topics
    }

    /// Whether its messages place frames on the `tf` channel ([`tf_view`]).
    pub fn places_frames(&self) -> bool {
        self.tf_child.is_some() || matches!(self.kind, Kind::Links)
    }

    /// Encodes the views of one message (its bytes, laid out as `descriptor` says) into
    /// `out[i]` for the view `topics()[i]`, and appends the transforms it places to `frames`
    /// (one `tf` message per time holds them all): false, with nothing encoded, for bytes of
    /// the wrong length.
    pub fn encode(
        &mut self,
        descriptor: &Descriptor,
        bytes: &[u8],
        stamp_ns: u64,
        out: &mut Vec<Vec<u8>>,
        frames: &mut Vec<FrameTransform>,
    ) -> bool {
        let Ok(json) = descriptor.fields(bytes) else {
            return false;
        };
        if out.len() < self.topics.len() {
            out.resize_with(self.topics.len(), Vec::new);
        }
        let json = &json;
        let stamp = timestamp(stamp_ns);
        let mut in_map = |pose: Pose, out: &mut Vec<u8>| {
            self.pose.timestamp = Some(stamp);
            self.pose.pose = Some(pose);
            put(&self.pose, out);
        };
        match self.kind {
            Kind::Pose2D => {
                let pose = pose_2d(Some(*json));
                in_map(pose, &mut out[0]);
                if let Some(child) = &self.tf_child {
                    frames.push(transform(stamp, child.clone(), pose));
                }
            }
            Kind::Odometry => in_map(pose_3d(json.get("pose")), &mut out[0]),
            Kind::Goal => in_map(pose_2d(json.get("pose")), &mut out[0]),
            Kind::Path => {
                let path = PosesInFrame {
                    timestamp: Some(stamp),
                    frame_id: MAP_FRAME.into(),
                    poses: json
                        .structs("poses")
                        .into_iter()
                        .map(|p| pose_2d(Some(p)))
                        .collect(),
                };
                put(&path, &mut out[0]);
            }
            Kind::Scan => {
                let scan = LaserScan {
                    timestamp: Some(stamp),
                    frame_id: self.frame.clone(),
                    pose: Some(Pose {
                        position: Some(Vector3::default()),
                        orientation: Some(Quaternion {
                            w: 1.0,
                            ..Default::default()
                        }),
                    }),
                    start_angle: num(json, "angle_min"),
                    end_angle: num(json, "angle_max"),
                    ranges: json.numbers("ranges"),
                    intensities: json.numbers("intensities"),
                };
                put(&scan, &mut out[0]);
            }
            Kind::Grid => put(&grid(json, stamp), &mut out[0]),
            Kind::Links => {
                let i = self.robot.unwrap_or(0);
                frames.extend(json.structs("links").into_iter().map(|l| {
                    let name = l.text("name").unwrap_or("");
                    transform(stamp, robot_frame(i, name), pose_3d(l.get("pose")))
                }));
            }
            Kind::Scene => put(&scene_update(json, stamp), &mut out[0]),
        }
        true
    }
}

/// An `OccupancyGrid` as a grid of one `int8` field.
fn grid(json: &Fields, stamp: Timestamp) -> Grid {
    let width = json.unsigned("width").unwrap_or(0) as u32;
    let resolution = num(json, "resolution");
    // Cells are i8 (−1 unknown, 0–100 occupancy), one byte each, row-major from the origin,
    // as ROS's OccupancyGrid and Foxglove's Grid both lay them out: the message's own bytes.
    let data: Vec<u8> = json.bytes("data").unwrap_or_default().to_vec();
    Grid {
        timestamp: Some(stamp),
        frame_id: MAP_FRAME.into(),
        pose: Some(pose_2d(json.get("origin"))),
        column_count: width,
        cell_size: Some(Vector2 {
            x: resolution,
            y: resolution,
        }),
        row_stride: width,
        cell_stride: 1,
        fields: vec![PackedElementField {
            name: "occupancy".into(),
            offset: 0,
            r#type: NumericType::Int8 as i32,
        }],
        data: data.into(),
    }
}

/// A `Scene` as entities of cubes, cylinders and spheres, each replacing the previous one of
/// its id each time it is sent: `world` in the map frame, and `robot_<i>` for the shapes
/// attached to robot i, in `robot_<i>/base_link_true`, so they move with it.
fn scene_update(json: &Fields, stamp: Timestamp) -> SceneUpdate {
    let mut entities: std::collections::BTreeMap<u64, SceneEntity> = Default::default();
    let entity = |attached: u64| {
        let (frame_id, id) = match attached {
            0 => (MAP_FRAME.to_string(), "world".to_string()),
            k => (
                format!("robot_{}/base_link_true", k - 1),
                format!("robot_{}", k - 1),
            ),
        };
        SceneEntity {
            timestamp: Some(stamp),
            frame_id,
            id,
            // Zero: shown until replaced.
            lifetime: Some(foxglove::messages::Duration::new(0, 0)),
            frame_locked: true,
            ..Default::default()
        }
    };
    // The world first, even when empty, so that a scene always replaces it.
    entities.insert(0, entity(0));
    for s in json.structs("shapes") {
        let attached = s.unsigned("attached").unwrap_or(0);
        let entity = entities.entry(attached).or_insert_with(|| entity(attached));
        let c = s.numbers("color");
        let color = Some(Color {
            r: c.first().copied().unwrap_or(1.0),
            g: c.get(1).copied().unwrap_or(1.0),
            b: c.get(2).copied().unwrap_or(1.0),
            a: c.get(3).copied().unwrap_or(1.0),
        });
        let pose = Some(pose_3d(s.get("pose")));
        let size = s.get("size");
        let size = Some(Vector3 {
            x: num_in(size, "x"),
            y: num_in(size, "y"),
            z: num_in(size, "z"),
        });
        match s.unsigned("kind") {
            Some(0) => entity.cubes.push(CubePrimitive { pose, size, color }),
            Some(1) => entity.cylinders.push(CylinderPrimitive {
                pose,
                size,
                bottom_scale: 1.0,
                top_scale: 1.0,
                color,
            }),
            Some(2) => entity.spheres.push(SpherePrimitive { pose, size, color }),
            _ => {}
        }
    }
    SceneUpdate {
        deletions: Vec::new(),
        entities: entities.into_values().collect(),
    }
}

#[cfg(test)]
#[path = "scene_tests.rs"]
mod tests;
