//! Issue 49: values a hostile user found accepted with exit 0 are refused before anything
//! starts, exit 2, the message naming the key (and its file and line, or the `--set` that
//! gave it). The tracked processes' params (each within its physical range,
//! `caravan_tracked::params`), the robot index of every process that takes one, and the
//! terrain specs of `caravan-tracked-terrain`.

use caravan_tests::{TestGroup, workspace_bin, workspace_root};
use std::path::{Path, PathBuf};

/// Launches the shipped `launch/<file>` with `sets` (each a `--set`) and expects it refused:
/// exit 2, no panic, no run directory and no shared memory of the group. Returns stderr.
fn refused(file: &str, sets: &[&str]) -> String {
    let group = TestGroup::new("range");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let mut cmd = std::process::Command::new(workspace_bin("caravan"));
    cmd.arg("launch")
        .arg(workspace_root().join("launch").join(file))
        .args(["--quiet", "--duration", "2s", "--runs-dir"])
        .arg(&runs)
        .arg("--set")
        .arg(format!("group.name={}", group.name));
    for set in sets {
        cmd.args(["--set", set]);
    }
    let out = cmd.output().expect("run caravan launch");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let run_dirs = std::fs::read_dir(&runs).map_or(0, |d| d.count());
    let _ = std::fs::remove_dir_all(&runs);
    assert_eq!(out.status.code(), Some(2), "{sets:?}: {err}");
    assert!(!err.contains("panicked"), "{sets:?}: {err}");
    assert_eq!(run_dirs, 0, "{sets:?}: a run directory was made: {err}");
    let prefix = caravan::group::prefix(&group.name);
    let shm: Vec<String> = std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default();
    assert!(shm.is_empty(), "{sets:?}: shared memory made: {shm:?}");
    err
}

/// `refused` for one `--set`, whose message must name `key` of `process`, and the `--set`.
fn refused_naming(file: &str, set: &str, process: &str, key: &str) -> String {
    let err = refused(file, &[set]);
    for part in [
        set,
        &format!("process '{process}'"),
        &format!("key '{key}'"),
    ] {
        assert!(err.contains(part), "{set}: expected '{part}' in: {err}");
    }
    err
}

#[test]
fn a_drive_wheel_radius_of_1e_300_is_refused() {
    let err = refused_naming(
        "tracked/flat.toml",
        "process.drive.params.limits.wheel_radius_m=1e-300",
        "drive",
        "limits.wheel_radius_m",
    );
    assert!(
        err.contains("must be between 0.001 and 100 m, got 1e-300"),
        "{err}"
    );
}

#[test]
fn a_drive_for_robot_9_on_a_one_robot_world_is_refused() {
    let err = refused_naming(
        "tracked/flat.toml",
        "process.drive.params.robot=9",
        "drive",
        "robot",
    );
    assert!(err.contains("robot 9 is not one of the group's 1"), "{err}");
}

/// `count` is the launch file's word for the robots the physics simulates: raised with the
/// robot, the drive's (the driver's, the IMU sensor's) own check passes, and the launcher finds robot 9 missing from what the
/// physics' check says it simulates (`caravan::facts`).
#[test]
fn a_drive_whose_count_is_raised_with_its_robot_is_refused_by_what_the_physics_simulates() {
    let cases = [
        ("tracked/flat.toml", "drive"),
        ("tracked/flat.toml", "driver"),
        ("imu/tilt.toml", "imu"),
    ];
    for (file, process) in cases {
        let sets = [
            format!("process.{process}.params.count=10"),
            format!("process.{process}.params.robot=9"),
        ];
        let err = refused(file, &[&sets[0], &sets[1]]);
        for part in [
            format!("process '{process}'"),
            "key 'robot'".into(),
            "robot 9 is not simulated (process 'physics' simulates one robot, robot 0".into(),
            sets[1].clone(),
        ] {
            assert!(err.contains(&part), "expected '{part}' in: {err}");
        }
    }
}

#[test]
fn a_driver_for_robot_9_on_a_one_robot_world_is_refused() {
    refused_naming(
        "tracked/step.toml",
        "process.driver.params.robot=9",
        "driver",
        "robot",
    );
}

#[test]
fn a_drive_asking_its_wheels_past_their_velocity_limit_is_refused() {
    // 1 m/s on gears of 0.06256 m while turning at 0.5 rad/s: 16.8 rad/s, v4's wheels 14.
    let err = refused_naming(
        "tracked/flat.toml",
        "process.drive.params.limits.max_v_m_s=1.0",
        "drive",
        "limits.max_v_m_s",
    );
    assert!(
        err.contains("up to 16.78") && err.contains("velocity limit of 14 rad/s"),
        "{err}"
    );
}

#[test]
fn a_report_goal_off_the_worlds_floor_is_refused() {
    // The flat world is 6 m long: a goal at 9 m is never reached.
    let err = refused("tracked/flat.toml", &["args.goal_x=9.0"]);
    assert!(
        err.contains("key 'goal_x_m'") && err.contains("must lie on the floor"),
        "{err}"
    );
}

#[test]
fn every_tracked_param_past_its_range_is_refused_naming_it() {
    for (set, process, key) in [
        (
            "process.drive.params.limits.max_v_m_s=6.0",
            "drive",
            "limits.max_v_m_s",
        ),
        (
            "process.drive.params.limits.max_w_rad_s=11.0",
            "drive",
            "limits.max_w_rad_s",
        ),
        (
            "process.drive.params.limits.max_accel_m_s2=0.0",
            "drive",
            "limits.max_accel_m_s2",
        ),
        (
            "process.drive.params.limits.max_alpha_rad_s2=1e3",
            "drive",
            "limits.max_alpha_rad_s2",
        ),
        (
            "process.drive.params.limits.wheel_separation_m=1e-3",
            "drive",
            "limits.wheel_separation_m",
        ),
        (
            "process.drive.params.flipper_angle_rad=2.0",
            "drive",
            "flipper_angle_rad",
        ),
        ("process.drive.params.count=0", "drive", "count"),
        (
            "process.driver.params.speed_m_s=-6.0",
            "driver",
            "speed_m_s",
        ),
        ("process.driver.params.start_s=-1.0", "driver", "start_s"),
        ("process.driver.params.stop_s=1e12", "driver", "stop_s"),
        (
            "process.driver.params.keep_line.gain_per_s=1e300",
            "driver",
            "keep_line.gain_per_s",
        ),
        (
            "process.driver.params.keep_line.lookahead_m=2e4",
            "driver",
            "keep_line.lookahead_m",
        ),
        (
            "process.driver.params.keep_line.max_turn_rad_s=100.0",
            "driver",
            "keep_line.max_turn_rad_s",
        ),
        (
            "process.driver.params.keep_line.line=[1e5, 1.5, 0.0]",
            "driver",
            "keep_line.line[0]",
        ),
    ] {
        refused_naming("tracked/flat.toml", set, process, key);
    }
}

#[test]
fn a_sensor_for_robot_9_on_a_five_robot_world_is_refused() {
    // The lab world lists five [[start]] poses; count = 10 passes the sensor's own bound.
    let err = refused(
        "convoy/convoy.toml",
        &[
            "process.sensor-0.params.robot=9",
            "process.sensor-0.params.count=10",
        ],
    );
    assert!(
        err.contains("process 'sensor-0'")
            && err.contains("key 'robot'")
            && err.contains("lists 5 [[start]] pose(s)"),
        "{err}"
    );
}

#[test]
fn a_slam_for_robot_9_on_a_five_robot_world_is_refused() {
    let err = refused_naming(
        "convoy/convoy.toml",
        "process.slam.params.robot=9",
        "slam",
        "robot",
    );
    assert!(err.contains("lists 5 [[start]] pose(s)"), "{err}");
}

#[test]
fn a_leader_for_robot_9_on_a_five_robot_world_is_refused() {
    let err = refused_naming(
        "convoy/convoy.toml",
        "process.leader.params.robot=9",
        "leader",
        "robot",
    );
    assert!(err.contains("lists 5 [[start]] pose(s)"), "{err}");
}

#[test]
fn a_planner_for_robot_9_on_a_five_robot_world_is_refused() {
    let err = refused_naming(
        "convoy/convoy.toml",
        "process.planner.params.robot=9",
        "planner",
        "robot",
    );
    assert!(err.contains("lists 5 [[start]] pose(s)"), "{err}");
}

#[test]
fn a_follower_for_robot_9_on_a_five_robot_world_is_refused() {
    // The ground-truth convoy's followers too: they are given the world for this check.
    for file in ["convoy/convoy.toml", "convoy/convoy-truth.toml"] {
        let err = refused_naming(
            file,
            "process.follower-1.params.robot=9",
            "follower-1",
            "robot",
        );
        assert!(err.contains("robot 9 is not among them"), "{file}: {err}");
    }
    // A custom follower swapped in (the pure-pursuit example) checks it too.
    let err = refused_naming(
        "convoy/convoy-custom.toml",
        "process.follower-2.params.robot=9",
        "follower-2",
        "robot",
    );
    assert!(err.contains("robot 9 is not among them"), "{err}");
}

/// Runs `caravan-tracked-terrain` on `spec` (written as `bad.toml` in a directory of its
/// own) and expects it refused: exit 2, the message naming the file, `line` and `key`, and
/// no world written. Returns stderr.
fn terrain_refused(tag: &str, spec: &str, line: usize, key: &str) -> String {
    let dir = std::env::temp_dir().join(format!("caravan-terrain-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (file, world): (PathBuf, PathBuf) = (dir.join("bad.toml"), dir.join("world.toml"));
    std::fs::write(&file, spec).unwrap();
    let out = std::process::Command::new(workspace_bin("caravan-tracked-terrain"))
        .arg(&file)
        .arg("--out")
        .arg(&world)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let written = Path::new(&world).exists();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!written, "a world was written: {err}");
    let named = format!("bad.toml: line {line}: key '{key}': ");
    assert!(err.contains(&named), "expected '{named}' in: {err}");
    err
}

const FIELD: &str = "[terrain]\nseed = 1\nfield = [3.0, 3.0]\n";

#[test]
fn a_terrain_peak_outside_the_field_is_refused() {
    let spec = format!(
        "{FIELD}[[primitive]]\ntype = \"peak\"\ncenter = [1.5, 7.0]\nheight = 0.4\nradius = 1.0\n"
    );
    let err = terrain_refused("peak-out", &spec, 6, "primitive[0].center[1]");
    assert!(err.contains("outside the field"), "{err}");
}

#[test]
fn a_terrain_peak_below_the_ground_is_refused() {
    let spec = format!(
        "{FIELD}[[primitive]]\ntype = \"peak\"\ncenter = [1.5, 1.5]\nheight = 0.05\nradius = 1.0\n"
    );
    let err = terrain_refused("peak-low", &spec, 7, "primitive[0].height");
    assert!(err.contains("must be above the ground"), "{err}");
}

#[test]
fn a_terrain_spec_without_primitives_is_refused() {
    let err = terrain_refused("empty", FIELD, 3, "primitive");
    assert!(err.contains("none given"), "{err}");
}

#[test]
fn terrain_hills_too_wide_for_the_field_are_refused() {
    // σ = 1 m: every hill would stand at the 3 m field's centre.
    let spec =
        format!("{FIELD}[[primitive]]\ntype = \"hills\"\ncount = 4\nheight = 0.3\nsigma = 1.0\n");
    let err = terrain_refused("hills-wide", &spec, 8, "primitive[0].sigma");
    assert!(err.contains("too wide for the 3 × 3 m field"), "{err}");
}
