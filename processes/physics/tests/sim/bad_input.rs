//! Bad input gives a clear one-paragraph error naming the file or key, never a panic.

use crate::common::launch_dir;
use caravan_physics::{Params, load};
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caravan-physics-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn error(params: &Params, dir: &std::path::Path) -> String {
    match load(params, dir, 2_000_000) {
        Ok(_) => panic!("accepted {params:?}"),
        Err(e) => e.to_string(),
    }
}

fn one_robot(pose: [f64; 3]) -> Params {
    Params {
        poses: vec![pose],
        ..Params::one_kind("worlds/lab.toml", "robots/convoy_bot.urdf", 1)
    }
}

#[test]
fn bad_world_file_names_file_line_and_key() {
    let dir = temp_dir("world");
    std::fs::write(
        dir.join("bad.toml"),
        "[world]\nname = \"x\"\nsize = [4.0, 4.0]\n\n[[box]]\ncentre = [1.0, 1.0]\nsize = [0.2, 0.2]\n",
    )
    .unwrap();
    std::fs::copy(
        launch_dir().join("robots/convoy_bot.urdf"),
        dir.join("bot.urdf"),
    )
    .unwrap();
    let params = Params {
        world: Some("bad.toml".into()),
        urdf: Some("bot.urdf".into()),
        ..one_robot([0.5, 0.5, 0.0])
    };
    let e = error(&params, &dir);
    assert!(e.contains("key 'world'") && e.contains("bad.toml"), "{e}");
    assert!(e.contains("line 6") && e.contains("centre"), "{e}");
    assert!(!e.contains('\n'), "not one paragraph: {e}");
}

#[test]
fn missing_world_file_is_named() {
    let params = Params {
        world: Some("worlds/nowhere.toml".into()),
        ..one_robot([0.5, 0.5, 0.0])
    };
    let e = error(&params, &launch_dir());
    assert!(
        e.contains("nowhere.toml") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn bad_urdf_is_named() {
    let dir = temp_dir("urdf");
    std::fs::write(dir.join("bad.urdf"), "<robot name='x'><link name='a'>").unwrap();
    std::fs::copy(launch_dir().join("worlds/lab.toml"), dir.join("lab.toml")).unwrap();
    let params = Params {
        world: Some("lab.toml".into()),
        urdf: Some("bad.urdf".into()),
        ..one_robot([0.5, 0.5, 0.0])
    };
    let e = error(&params, &dir);
    assert!(e.contains("key 'urdf'") && e.contains("bad.urdf"), "{e}");
    assert!(e.contains("not a valid URDF"), "{e}");
}

#[test]
fn wrong_number_of_poses_is_rejected() {
    let params = Params {
        count: Some(3),
        ..one_robot([0.5, 0.5, 0.0])
    };
    let e = error(&params, &launch_dir());
    assert!(e.contains("'poses'") && e.contains("count = 3"), "{e}");
}

#[test]
fn pose_inside_an_obstacle_is_rejected() {
    // The bench in the middle of the lab.
    let e = error(&one_robot([3.5, 2.3, 0.0]), &launch_dir());
    assert!(
        e.contains("poses[0]") && e.contains("inside the box"),
        "{e}"
    );
    // Against the south wall.
    let e = error(&one_robot([1.0, 0.05, 0.0]), &launch_dir());
    assert!(e.contains("poses[0]") && e.contains("wall"), "{e}");
}

#[test]
fn overlapping_robots_and_poses_off_the_floor_are_rejected() {
    let params = Params {
        count: Some(2),
        poses: vec![[1.0, 0.7, 0.0], [1.1, 0.7, 0.0]],
        ..one_robot([0.5, 0.5, 0.0])
    };
    let e = error(&params, &launch_dir());
    assert!(e.contains("robots 0 and 1"), "{e}");
    let e = error(&one_robot([8.0, 1.0, 0.0]), &launch_dir());
    assert!(e.contains("poses[0]") && e.contains("off the floor"), "{e}");
}

#[test]
fn the_binary_reports_bad_params_without_panicking() {
    for (params, says) in [
        (
            r#"{"world": "worlds/nowhere.toml", "urdf": "robots/convoy_bot.urdf", "count": 1,
                "poses": [[0.5, 0.5, 0.0]]}"#,
            "nowhere.toml",
        ),
        // Neither the world nor the robots have a default.
        (
            r#"{"urdf": "robots/convoy_bot.urdf", "count": 5}"#,
            "key 'world': missing",
        ),
        (r#"{"world": "worlds/lab.toml"}"#, "key 'robots': missing"),
        (
            r#"{"world": "worlds/lab.toml", "urdf": "robots/convoy_bot.urdf"}"#,
            "key 'count': missing",
        ),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_caravan-physics"))
            .env("CARAVAN_GROUP", "physics-bad-input")
            .env("CARAVAN_NODE", "physics")
            .env("CARAVAN_LAUNCH_DIR", launch_dir())
            .env("CARAVAN_PARAMS", params)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.starts_with("caravan-physics: ") && stderr.contains(says),
            "{says}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn kinematic_joints_refuse_what_rapier_cannot_solve_beside_them() {
    // (robot, the entry named, what the message says)
    let cases = [
        // Impulse joints cannot be kinematic.
        (
            serde_json::json!({ "urdf": "overlap.urdf", "joints": "impulse",
                "actuators": [{ "type": "kinematic", "joints": ["*"] }] }),
            0,
            "needs joints = \"multibody\"",
        ),
        // A motor beside a kinematic joint.
        (
            serde_json::json!({ "urdf": "overlap.urdf", "joints": "multibody",
                "actuators": [{ "type": "kinematic", "joints": ["left_a_joint"] },
                    { "type": "motor", "joints": ["right_a_joint"] }] }),
            1,
            "joint 'right_a_joint'",
        ),
        // A limited joint whose limits nothing would hold.
        (
            serde_json::json!({ "urdf": "arm3.urdf", "base": "fixed", "joints": "multibody",
                "actuators": [{ "type": "kinematic", "joints": ["upper_joint"] },
                    { "type": "position", "joints": ["fore_joint", "hand_joint"] }] }),
            1,
            "joint 'fore_joint'",
        ),
    ];
    check_actuator_errors(&cases);
}

#[test]
fn a_rim_is_refused_on_a_joint_that_is_not_a_wheels_or_outside_a_multibody() {
    check_actuator_errors(&[
        (
            serde_json::json!({ "urdf": "arm3.urdf", "base": "fixed", "joints": "multibody",
                "actuators": [{ "type": "position", "joints": ["*"] },
                    { "type": "rim", "joints": ["fore_joint"] }] }),
            1,
            "is not continuous; a rim turns wheels",
        ),
        (
            serde_json::json!({ "urdf": "overlap.urdf", "joints": "impulse",
                "actuators": [{ "type": "rim", "joints": ["*"] }] }),
            0,
            "a rim needs joints = \"multibody\"",
        ),
    ]);
}

/// Each robot's params fail naming `robots[0].actuators[entry]` and saying `says`.
fn check_actuator_errors(cases: &[(serde_json::Value, usize, &str)]) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    for (robot, entry, says) in cases {
        let mut robot = robot.clone();
        robot["poses"] = serde_json::json!([[2.0, 2.0, 0.0]]);
        let params: Params = caravan::parse_params(
            "physics",
            &serde_json::json!({ "world": "empty.toml", "robots": [robot] }),
        )
        .unwrap();
        let e = error(&params, &dir);
        assert!(
            e.contains(&format!("'robots[0].actuators[{entry}]'")) && e.contains(says),
            "{e}"
        );
    }
}
