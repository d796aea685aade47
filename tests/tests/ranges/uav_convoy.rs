//! The UAV processes' and the convoy agents' params out of their physical ranges: a shipped
//! launch file launched with one `--set` that puts a number out of range is bad input refused
//! before anything starts (exit 2), with a message naming the key and the `--set` that wrote
//! it, no panic and no run directory.

use caravan_tests::{TestGroup, workspace_bin, workspace_root};
use std::process::Command;

/// Launches `launch/<file>` with `--set set` into a runs directory of its own and checks that
/// it was refused before the start, naming `key` (as the message quotes it) and the `--set`.
fn assert_refused(file: &str, set: &str, key: &str) {
    let group = TestGroup::new("range");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(workspace_root().join("launch").join(file))
        // Short, so that a value let through does not run the whole scenario.
        .args(["--quiet", "--duration", "1s", "--set", set, "--set"])
        .arg(format!("group.name={}", group.name))
        .arg("--runs-dir")
        .arg(&runs)
        .output()
        .expect("run caravan launch");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let run_dirs = std::fs::read_dir(&runs).map_or(0, |d| d.count());
    let _ = std::fs::remove_dir_all(&runs);
    assert_eq!(out.status.code(), Some(2), "{set}: {err}");
    assert!(!err.contains("panicked"), "{set}: {err}");
    assert!(err.contains(key), "{set}: expected {key} in: {err}");
    assert!(
        err.contains("--set"),
        "{set}: the --set is not named: {err}"
    );
    assert_eq!(run_dirs, 0, "{set}: a run directory was made: {err}");
}

#[test]
fn a_uav_speed_of_1e308_is_refused_before_start() {
    assert_refused(
        "uav/encounter.toml",
        "process.env.params.encounter.speed_m_s=1e308",
        "key 'encounter.speed_m_s'",
    );
}

#[test]
fn a_uav_step_shorter_than_the_tick_is_refused_before_start() {
    assert_refused(
        "uav/encounter.toml",
        "process.opponent.params.encounter.step_s=1e-300",
        "key 'encounter.step_s'",
    );
}

#[test]
fn a_uav_agent_with_a_zero_collision_radius_is_refused_before_start() {
    assert_refused(
        "uav/encounter.toml",
        "process.agent.params.encounter.collision_radius_m=0",
        "key 'encounter.collision_radius_m'",
    );
}

#[test]
fn a_million_and_one_uav_episodes_are_refused_before_start() {
    assert_refused(
        "uav/encounter.toml",
        "args.episodes=1000001",
        "key 'episodes'",
    );
}

#[test]
fn a_uav_frame_origin_of_1e308_is_refused_before_start() {
    assert_refused(
        "uav/encounter.toml",
        "process.env.params.frame.origin=[2.0, 1e308]",
        "key 'frame.origin[1]'",
    );
}

#[test]
fn a_follower_gain_of_nan_is_refused_before_start() {
    // The launcher itself refuses a NaN param, naming its path.
    assert_refused(
        "convoy/convoy.toml",
        "process.follower-1.params.follower.k1=nan",
        "params.follower.k1",
    );
}

#[test]
fn a_follower_gain_of_1e308_is_refused_before_start() {
    assert_refused(
        "convoy/convoy.toml",
        "process.follower-1.params.follower.k1=1e308",
        "key 'follower.k1'",
    );
}

#[test]
fn a_follower_delay_of_1e308_is_refused_before_start() {
    assert_refused(
        "convoy/convoy.toml",
        "process.follower-3.params.follower.tau_s=1e308",
        "key 'follower.tau_s'",
    );
}

#[test]
fn a_negative_leader_speed_is_refused_before_start() {
    assert_refused(
        "convoy/convoy.toml",
        "process.leader.params.leader.v_max=-0.2",
        "key 'leader.v_max'",
    );
}

#[test]
fn a_leader_goal_at_1e308_is_refused_before_start() {
    assert_refused(
        "convoy/convoy.toml",
        "process.leader.params.leader.goals=[[1e308, 1.0]]",
        "key 'leader.goals[0].x'",
    );
}
