//! The UAV processes' and the convoy agents' params out of their physical ranges: a shipped
//! launch file launched with one `--set` that puts a number out of range is bad input refused
//! before anything starts (exit 2), with a message naming the key and the `--set` that wrote
//! it, no panic and no run directory.

use super::refused::assert_refused_before_start;

/// `launch/<file>` with `--set set` is refused before the start, saying `what` (a key as the
/// message quotes it, `key '…'`, or the launcher's own wording for a value it cannot pass,
/// which it reports at the process's `params`) and the `--set` that wrote it.
fn assert_refused(file: &str, set: &str, what: &str) {
    let key = match what.strip_prefix("key '") {
        Some(rest) => rest.trim_end_matches('\''),
        None => "params",
    };
    let err = assert_refused_before_start(file, set, key);
    assert!(err.contains(what), "{set}: expected {what} in: {err}");
    assert!(
        err.contains("--set"),
        "{set}: the --set is not named: {err}"
    );
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
