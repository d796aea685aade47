//! The autonomous convoy: the leader maps an unknown world with laser SLAM and plans to its
//! goals; followers localise by wheel odometry. Real processes in lockstep, checked from the
//! run report.

use caravan_tests::{ConvoyRun, assert_convoy_succeeded, recording, run_convoy, run_convoy_with};
use serde_json::Value;

/// Every survey of the world was measured on the map, each within `limit_pct`.
fn assert_map_scale(slam: &Value, limit_pct: f64) {
    let errors = slam["map_scale_error_pct"]
        .as_array()
        .expect("map_scale_error_pct");
    assert!(errors.len() >= 2, "{slam}");
    for e in errors {
        let e = e
            .as_f64()
            .unwrap_or_else(|| panic!("a survey was not measured: {slam}"));
        assert!(
            e <= limit_pct,
            "map scale error {e} % > {limit_pct} %: {slam}"
        );
    }
}

fn assert_map_files(run: &ConvoyRun) {
    for file in ["map.yaml", "map.pgm", "map.svg", "trajectories.svg"] {
        assert!(run.dir.join(file).is_file(), "{file} missing");
    }
}

#[test]
fn autonomous_convoy_maps_the_lab_and_reaches_every_goal() {
    let run = run_convoy("convoy.toml");
    assert_convoy_succeeded(&run.report["convoy"]);
    let slam = &run.report["slam"];
    assert_map_scale(slam, 1.0);
    // Localised from the laser alone to within a few centimetres.
    assert!(
        slam["pose_error_m"]["mean"].as_f64().unwrap() < 0.03,
        "{slam}"
    );
    assert!(
        slam["pose_error_m"]["samples"].as_u64().unwrap() > 600,
        "{slam}"
    );
    assert_map_files(&run);
    assert_foxglove_scene(&run);
}

/// The recording shows the scene in Foxglove: well-known channels beside the raw ones, every
/// robot in `tf`, and a channel for every recorded topic, even one with no message.
fn assert_foxglove_scene(run: &ConvoyRun) {
    use foxglove::messages::{FrameTransforms, Grid, LaserScan};
    use prost::Message;
    let bytes = recording::read(&run.dir.join("record.mcap"));
    let channels = recording::channels(&bytes);
    for (topic, schema) in [
        ("tf", "foxglove.FrameTransforms"),
        ("foxglove/robot/0/scan", "foxglove.LaserScan"),
        ("foxglove/robot/0/path", "foxglove.PosesInFrame"),
        ("foxglove/robot/3/pose_true", "foxglove.PoseInFrame"),
        ("foxglove/goal", "foxglove.PoseInFrame"),
        ("foxglove/map", "foxglove.Grid"),
    ] {
        let c = &channels[topic];
        assert_eq!(
            (c.schema.as_str(), c.encoding.as_str()),
            (schema, "protobuf")
        );
        assert!(c.messages > 0, "{topic}: no messages");
    }
    let collisions = &channels["collisions"];
    assert_eq!(
        (collisions.encoding.as_str(), collisions.messages),
        ("json", 0)
    );

    let mut frames = std::collections::BTreeSet::new();
    // One `tf` message per time, holding every transform placed then: at a time the physics
    // published, every robot's true pose.
    let mut last_ns = None;
    for (_, topic, log_ns, m) in recording::all_messages(&bytes) {
        if topic != "tf" {
            continue;
        }
        assert!(last_ns < Some(log_ns), "two tf messages at {log_ns} ns");
        last_ns = Some(log_ns);
        let transforms = FrameTransforms::decode(m.as_slice()).unwrap().transforms;
        let true_poses = (transforms.iter())
            .filter(|t| t.child_frame_id.ends_with("/base_link_true"))
            .count();
        assert!(
            [0, 5].contains(&true_poses),
            "{true_poses} true poses at {log_ns} ns"
        );
        for t in transforms {
            assert_eq!(t.parent_frame_id, "map");
            let stamp = t.timestamp.unwrap();
            assert_eq!(
                stamp.sec() as u64 * 1_000_000_000 + stamp.nsec() as u64,
                log_ns
            );
            frames.insert(t.child_frame_id);
        }
    }
    for i in 0..5 {
        assert!(
            frames.contains(&format!("robot_{i}/base_link")),
            "{frames:?}"
        );
        assert!(
            frames.contains(&format!("robot_{i}/base_link_true")),
            "{frames:?}"
        );
    }
    let scans = recording::messages(&bytes, "foxglove/robot/0/scan");
    let scan = LaserScan::decode(scans[0].as_slice()).unwrap();
    assert_eq!(scan.frame_id, "robot_0/base_link");
    assert!(scan.ranges.len() > 600, "{}", scan.ranges.len());
    let maps = recording::messages(&bytes, "foxglove/map");
    let map = Grid::decode(maps.last().unwrap().as_slice()).unwrap();
    assert_eq!(map.data.len() as u32 % map.column_count, 0);
    assert!(
        map.data.iter().any(|&c| c as i8 > 50),
        "the map shows obstacles"
    );
}

#[test]
fn autonomous_convoy_reaches_every_goal_in_a_second_world() {
    // The hall's leader reaches D after about 67 s.
    let run = run_convoy_with("convoy-hall.toml", "80s", &[]);
    let c = &run.report["convoy"];
    assert_eq!(c["goals_reached"], 4, "{c}");
    assert_eq!(c["collisions"], 0, "{c}");
    assert_eq!(c["order_kept"], true, "{c}");
    assert_map_scale(&run.report["slam"], 1.0);
    assert_map_files(&run);
}

#[test]
fn ideal_localisation_switches_every_robot_to_its_true_pose() {
    let run = run_convoy_with("convoy.toml", "70s", &["args.localisation=ideal"]);
    assert_convoy_succeeded(&run.report["convoy"]);
    // The leader's estimate is the true pose at the scan's time, exactly.
    let error = &run.report["slam"]["pose_error_m"];
    assert!(error["max"].as_f64().unwrap() < 1e-9, "{error}");
    // The leader still maps, from its true poses.
    assert_map_scale(&run.report["slam"], 1.0);
}

#[test]
fn an_unreachable_goal_is_reported_and_the_leader_does_not_move() {
    // A goal far outside the lab and the leader's map.
    let run = run_convoy_with(
        "convoy.toml",
        "10s",
        &["process.leader.params.leader.goals=[[20.0, 1.0]]"],
    );
    let log = std::fs::read_to_string(run.dir.join("logs/planner.log")).unwrap();
    assert!(
        log.contains("cannot plan to goal 1 of 1: goal (20.00, 1.00) is outside the map"),
        "{log}"
    );
    let c = &run.report["convoy"];
    assert_eq!(c["goals_reached"], 0, "{c}");
    assert_eq!(c["collisions"], 0, "{c}");
}

/// A bad param of a perception or planning node stops the launch before the group runs, with
/// the node and key named.
#[test]
fn bad_perception_and_planning_params_are_named() {
    for (set, expected) in [
        ("process.slam.params.mode=mapping", ["slam", "mode"]),
        (
            "process.odometry-2.params.initial_pose=[1.0, 2.0]",
            ["odometry-2", "initial_pose"],
        ),
        (
            "process.planner.params.local.v_maxx=0.3",
            ["planner", "v_maxx"],
        ),
    ] {
        let (code, stderr) = caravan_tests::launch_with_set("convoy/convoy.toml", "5s", set);
        assert_ne!(code, 0, "{set}: launch succeeded\n{stderr}");
        for word in expected {
            assert!(stderr.contains(word), "{set}: '{word}' not in\n{stderr}");
        }
    }
}
