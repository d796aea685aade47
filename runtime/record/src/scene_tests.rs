//! Tests of the Foxglove views (`scene.rs`).

use super::*;
use prost::Message;
use serde_json::json;

/// The views of one message of `topic`, as the writer encodes them.
pub fn views(topic: &str, descriptor: &Descriptor, bytes: &[u8], stamp_ns: u64) -> Vec<View> {
    let Some(mut viewer) = Viewer::new(topic, descriptor) else {
        return Vec::new();
    };
    let (mut out, mut frames) = (Vec::new(), Vec::new());
    if !viewer.encode(descriptor, bytes, stamp_ns, &mut out, &mut frames) {
        return Vec::new();
    }
    let mut views: Vec<View> = (viewer.topics().iter().cloned())
        .zip(out)
        .map(|((topic, schema), bytes)| View {
            topic,
            schema,
            bytes,
        })
        .collect();
    // The `tf` message of a time holding only this message.
    if viewer.places_frames() {
        let (topic, schema) = tf_view();
        let mut bytes = Vec::new();
        put_frames(&mut frames, &mut bytes);
        views.push(View {
            topic,
            schema,
            bytes,
        });
    }
    views
}

/// The views of the message of `type_name` whose JSON view is `json` (the rest default).
fn json_views(topic: &str, type_name: &str, json: &serde_json::Value, stamp: u64) -> Vec<View> {
    let d = caravan_schemas::catalog::descriptor(type_name).unwrap();
    views(topic, d, &bytes_of(d, json), stamp)
}

#[test]
fn a_scene_is_one_world_entity_of_primitives() {
    let mut scene = caravan_schemas::boxed_placement_new::<caravan_schemas::Scene>();
    for kind in [0, 1, 2, 7] {
        let mut shape = caravan_schemas::Shape {
            kind,
            color: [0.5, 0.25, 1.0, 1.0],
            ..Default::default()
        };
        shape.size.z = 0.3;
        shape.pose.orientation.w = 1.0;
        scene.shapes.push(shape).unwrap();
    }
    let json = serde_json::to_value(scene.as_ref()).unwrap();
    let v = json_views("scene", "caravan::Scene", &json, 2_000_000_000);
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].topic, "foxglove/scene");
    assert_eq!((v[0].schema)().name, "foxglove.SceneUpdate");
    let update = SceneUpdate::decode(v[0].bytes.as_slice()).unwrap();
    let e = &update.entities[0];
    assert_eq!((e.id.as_str(), e.frame_id.as_str()), ("world", "map"));
    // An unknown kind is skipped, not drawn as something else.
    assert_eq!(
        (e.cubes.len(), e.cylinders.len(), e.spheres.len()),
        (1, 1, 1)
    );
    assert_eq!(e.cylinders[0].size.unwrap().z, 0.3);
    assert_eq!(e.spheres[0].color.unwrap().g, 0.25);
    assert_eq!(update.entities.len(), 1);
    // A robot's body is an entity of its own, in the frame of its true pose.
    let body = caravan_schemas::Shape {
        attached: 3,
        ..Default::default()
    };
    scene.shapes.push(body).unwrap();
    let json = serde_json::to_value(scene.as_ref()).unwrap();
    let v = json_views("scene", "caravan::Scene", &json, 2_000_000_000);
    let update = SceneUpdate::decode(v[0].bytes.as_slice()).unwrap();
    let ids: Vec<(&str, &str)> = update
        .entities
        .iter()
        .map(|e| (e.id.as_str(), e.frame_id.as_str()))
        .collect();
    assert_eq!(
        ids,
        [("world", "map"), ("robot_2", "robot_2/base_link_true")]
    );
    assert_eq!(update.entities[1].cubes.len(), 1);
}

#[test]
fn a_robot_pose_is_a_transform_and_a_pose_in_the_map() {
    let v = json_views(
        "robot/2/pose_true",
        "caravan::Pose2D",
        &json!({"x": 1.0, "y": -2.0, "theta": std::f64::consts::FRAC_PI_2}),
        1_500_000_000,
    );
    let topics: Vec<&str> = v.iter().map(|v| v.topic.as_str()).collect();
    assert_eq!(topics, ["foxglove/robot/2/pose_true", "tf"]);
    let tf = FrameTransforms::decode(v[1].bytes.as_slice()).unwrap();
    let t = &tf.transforms[0];
    assert_eq!(t.parent_frame_id, "map");
    assert_eq!(t.child_frame_id, "robot_2/base_link_true");
    assert_eq!(t.timestamp, Some(Timestamp::new(1, 500_000_000)));
    let q = t.rotation.unwrap();
    assert!((q.z - (0.5f64).sqrt()).abs() < 1e-12 && (q.w - (0.5f64).sqrt()).abs() < 1e-12);
    assert_eq!(t.translation.unwrap().y, -2.0);
    assert_eq!((v[1].schema)().name, "foxglove.FrameTransforms");
}

#[test]
fn a_map_is_a_grid_with_unknown_cells_kept() {
    let v = json_views(
        "map",
        "caravan::OccupancyGrid",
        &json!({"resolution": 0.05, "width": 2, "height": 2,
                "origin": {"x": -1.0, "y": 0.0, "theta": 0.0}, "data": [-1, 0, 100, 50]}),
        0,
    );
    let grid = Grid::decode(v[0].bytes.as_slice()).unwrap();
    assert_eq!(grid.column_count, 2);
    assert_eq!(grid.row_stride, 2);
    assert_eq!(&grid.data[..], &[255, 0, 100, 50]);
    assert_eq!(grid.fields[0].r#type, NumericType::Int8 as i32);
}

#[test]
fn a_scan_is_drawn_in_its_robot_and_a_path_in_the_map() {
    let scan = json_views(
        "robot/0/scan",
        "caravan::LaserScan",
        &json!({"angle_min": -1.0, "angle_max": 1.0, "ranges": [1.0, 2.0], "intensities": [0.0, 0.0]}),
        0,
    );
    let s = LaserScan::decode(scan[0].bytes.as_slice()).unwrap();
    assert_eq!(
        (s.frame_id.as_str(), s.ranges.as_slice()),
        ("robot_0/base_link", &[1.0, 2.0][..])
    );
    let path = json_views(
        "robot/0/path",
        "caravan::Path2D",
        &json!({"poses": [{"x": 0.0, "y": 0.0, "theta": 0.0}, {"x": 1.0, "y": 0.0, "theta": 0.0}]}),
        0,
    );
    assert_eq!(
        PosesInFrame::decode(path[0].bytes.as_slice())
            .unwrap()
            .poses
            .len(),
        2
    );
}

/// The bytes of the message of `d` whose JSON view is `json` (the rest default).
fn bytes_of(d: &Descriptor, json: &serde_json::Value) -> Box<[u8]> {
    let mut bytes = d.default_bytes().unwrap();
    d.write(json, &mut bytes).unwrap();
    bytes
}

#[test]
fn a_viewer_fills_one_buffer_per_announced_view_and_no_other() {
    // One set of buffers across topics of one and no views, as the writer keeps it; before
    // each message every buffer holds bytes no view encodes to. The transforms a message
    // places go to the time's `tf` message, not to a buffer of its own.
    let mut out: Vec<Vec<u8>> = vec![Vec::new(); 3];
    let unwritten = [0xEE; 3];
    for (topic, type_name, sample, count, placed) in [
        (
            "robot/1/pose",
            "caravan::Pose2D",
            json!({"x": 1.0, "theta": 0.5}),
            1,
            1,
        ),
        ("goal", "caravan::Goal", json!({"pose": {"x": 3.0}}), 1, 0),
        (
            "robot/0/link_states",
            "caravan::LinkStates",
            json!({"links": [{"name": "a", "pose": {}}, {"name": "b", "pose": {}}]}),
            0,
            2,
        ),
        (
            "robot/2/pose_true",
            "caravan::Pose2D",
            json!({"y": -1.0}),
            1,
            1,
        ),
        ("estimate", "caravan::Pose2D", json!({}), 1, 0),
        (
            "robot/0/wheel_setpoint",
            "caravan::WheelSetpoint",
            json!({}),
            0,
            0,
        ),
        ("links", "caravan::LinkStates", json!({}), 0, 0),
    ] {
        let d = caravan_schemas::catalog::descriptor(type_name).unwrap();
        let Some(mut viewer) = Viewer::new(topic, d) else {
            assert_eq!(count, 0, "{topic} has views");
            continue;
        };
        assert_eq!(viewer.topics().len(), count, "{topic}");
        assert_eq!(viewer.places_frames(), placed > 0, "{topic}");
        for b in &mut out {
            b.clear();
            b.extend(unwritten);
        }
        let mut frames = Vec::new();
        assert!(viewer.encode(d, &bytes_of(d, &sample), 7, &mut out, &mut frames));
        assert_eq!(frames.len(), placed, "{topic}");
        for (i, (view, _)) in viewer.topics().iter().enumerate() {
            assert_ne!(out[i], unwritten, "{topic}: {view} not encoded");
        }
        assert!(out[count..].iter().all(|b| *b == unwritten), "{topic}");
    }
}

#[test]
fn a_refilled_pose_encodes_as_a_fresh_one_and_a_wrong_length_as_nothing() {
    let d = caravan_schemas::catalog::descriptor("caravan::Pose2D").unwrap();
    let mut kept = Viewer::new("robot/3/pose", d).unwrap();
    let (mut out, mut frames) = (Vec::new(), Vec::new());
    let first = bytes_of(d, &json!({"x": 5.0, "y": 6.0, "theta": 1.0}));
    assert!(kept.encode(d, &first, 10, &mut out, &mut frames));
    frames.clear();
    let second = bytes_of(d, &json!({"x": -2.0, "theta": -0.5}));
    assert!(kept.encode(d, &second, 20, &mut out, &mut frames));
    let (mut fresh, mut fresh_frames) = (Vec::new(), Vec::new());
    let mut new = Viewer::new("robot/3/pose", d).unwrap();
    assert!(new.encode(d, &second, 20, &mut fresh, &mut fresh_frames));
    assert_eq!((out.clone(), frames), (fresh, fresh_frames));
    let mut none = Vec::new();
    assert!(!kept.encode(d, &second[1..], 30, &mut out, &mut none));
    assert!(none.is_empty());
}
