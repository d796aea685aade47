//! Physical ranges of the agent's numeric params (`follower.*`, `leader.*`,
//! `cmd_vel_timeout_s`), checked by [`Params::validate`](crate::agent::params::Params::validate)
//! in the node's `setup`, so under the launcher's check before the group starts: every number
//! finite, of its sign and within what the convoy's small diff-drive robots have, so that a typo
//! (`1e308`, `nan`) is refused with the key named (`key 'follower.k1': must be above 0 and at
//! most 20 1/s, got NaN`) instead of a robot driving off or never moving. Each bound's constant
//! says why.

use caravan::range::{above, between};

use crate::agent::follower::FollowerParams;
use crate::agent::leader::LeaderParams;
use crate::agent::params::Params;

/// The agents' tick, s: they step at 20 Hz unless the launch file says otherwise.
pub const TICK_S: f64 = 1.0 / 20.0;

/// The largest gain, 1/s (`k1`, `k2`, `k3`, `k_gap`, `k_heading`): one over the tick. A
/// proportional step with gain·tick above 1 overshoots its whole error each step, so the chain
/// oscillates; the reference's gains are 0.7 to 1.5 1/s.
pub const MAX_GAIN_PER_S: f64 = 1.0 / TICK_S;

/// The longest delay τ, s: at the follower's 0.25 m/s a minute behind is 15 m, far beyond any
/// convoy's spacing (the reference's τ is 2 s); the predecessor's history holds τ + 2 s.
pub const MAX_TAU_S: f64 = 60.0;

/// The largest distance kept (`safety_distance_m`, `stop_margin_m`) and goal tolerance, m: the
/// robots are 0.2 m long and the shipped worlds a few tens of metres; 10 m apart is no convoy.
pub const MAX_DISTANCE_M: f64 = 10.0;

/// The longest roll-out and roll-back times (`brake_time_s`, `coast_time_s`,
/// `rollback_time_s`), s: four times the 2.5 s the wheel-speed loop takes to settle (the
/// measured times are 0.44, 0.30 and 0.18 s, docs/fig9a.md).
pub const MAX_ROLL_TIME_S: f64 = 10.0;

/// The longest speed and roll-back windows, s: each at most a second, so that both together
/// look no further back than the 2 s of the predecessor's history kept beyond τ.
pub const MAX_WINDOW_S: f64 = 1.0;

/// The shortest speed window, s: a speed is measured over at least 10 ms of poses (the
/// physics' ground truth arrives every few ms); a shorter window holds a single pose.
pub const MIN_SPEED_WINDOW_S: f64 = 0.01;

/// The fastest forward speed, m/s: ten times the convoy robot's 0.25 m/s, beyond what a small
/// indoor diff-drive robot's wheels reach.
pub const MAX_SPEED_M_S: f64 = 2.5;

/// The fastest turn, rad/s: ten times the reference's 2 rad/s; at the 20 Hz tick that is a
/// full turn in about 6 steps.
pub const MAX_TURN_RAD_S: f64 = 20.0;

/// The oldest command still driven, s: a planner's command 10 s old is not its current one.
pub const MAX_CMD_TIMEOUT_S: f64 = 10.0;

/// Checks every numeric key of `p` (both modes': keys of the other mode are accepted, so
/// they are checked too).
pub fn check(p: &Params) -> Result<(), String> {
    // At least one tick: a shorter timeout makes every command stale at once.
    between(
        "cmd_vel_timeout_s",
        p.cmd_vel_timeout_s,
        TICK_S,
        MAX_CMD_TIMEOUT_S,
        "s",
    )?;
    follower(&p.follower)?;
    leader(&p.leader)
}

/// The `follower.*` keys.
pub fn follower(f: &FollowerParams) -> Result<(), String> {
    let key = |k: &str| format!("follower.{k}");
    // A zero gain never closes its error; a negative one drives away from it.
    for (k, v) in [("k1", f.k1), ("k2", f.k2), ("k3", f.k3), ("k_gap", f.k_gap)] {
        above(&key(k), v, 0.0, MAX_GAIN_PER_S, "1/s")?;
    }
    between(&key("tau_s"), f.tau_s, 0.0, MAX_TAU_S, "s")?;
    for (k, v) in [
        ("safety_distance_m", f.safety_distance_m),
        ("stop_margin_m", f.stop_margin_m),
    ] {
        between(&key(k), v, 0.0, MAX_DISTANCE_M, "m")?;
    }
    for (k, v) in [
        ("brake_time_s", f.brake_time_s),
        ("coast_time_s", f.coast_time_s),
        ("rollback_time_s", f.rollback_time_s),
    ] {
        between(&key(k), v, 0.0, MAX_ROLL_TIME_S, "s")?;
    }
    between(
        &key("rollback_window_s"),
        f.rollback_window_s,
        0.0,
        MAX_WINDOW_S,
        "s",
    )?;
    between(
        &key("speed_window_s"),
        f.speed_window_s,
        MIN_SPEED_WINDOW_S,
        MAX_WINDOW_S,
        "s",
    )?;
    // A zero top speed or turn rate never moves the robot (v ≥ 0 always).
    above(&key("v_max"), f.v_max, 0.0, MAX_SPEED_M_S, "m/s")?;
    above(&key("omega_max"), f.omega_max, 0.0, MAX_TURN_RAD_S, "rad/s")?;
    Ok(())
}

/// The `leader.*` keys.
pub fn leader(l: &LeaderParams) -> Result<(), String> {
    let key = |k: &str| format!("leader.{k}");
    // Goals lie in a world: within its largest extent.
    let far = caravan_world::limits::MAX_WORLD_EXTENT_M;
    for (i, g) in l.goals.iter().enumerate() {
        for (axis, v) in ["x", "y"].iter().zip(g) {
            between(&format!("leader.goals[{i}].{axis}"), *v, -far, far, "m")?;
        }
    }
    // A zero tolerance is never met by a pose that is never exact.
    above(&key("tolerance_m"), l.tolerance_m, 0.0, MAX_DISTANCE_M, "m")?;
    above(&key("v_max"), l.v_max, 0.0, MAX_SPEED_M_S, "m/s")?;
    // The slowest speed is no faster than the fastest; 0 lets a planner stop the leader.
    between(&key("v_min"), l.v_min, 0.0, l.v_max, "m/s (leader.v_max)")?;
    // Clockwise limit ≤ 0 ≤ counter-clockwise limit, the latter non-zero so the leader can turn
    // toward any goal.
    between(
        &key("omega_min"),
        l.omega_min,
        -MAX_TURN_RAD_S,
        0.0,
        "rad/s",
    )?;
    above(&key("omega_max"), l.omega_max, 0.0, MAX_TURN_RAD_S, "rad/s")?;
    above(&key("k_heading"), l.k_heading, 0.0, MAX_GAIN_PER_S, "1/s")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Params {
        Params {
            urdf: "robot.urdf".into(),
            robot: 1,
            ..Params::default()
        }
    }

    #[test]
    fn the_defaults_are_in_range() {
        check(&params()).unwrap();
        let mut p = params();
        p.leader.goals = vec![[3.0, -2.0], [20.0, 1.0]];
        check(&p).unwrap();
    }

    #[test]
    fn out_of_range_follower_keys_are_named() {
        let bad = |f: fn(&mut FollowerParams)| {
            let mut p = FollowerParams::default();
            f(&mut p);
            follower(&p).unwrap_err()
        };
        assert_eq!(
            bad(|p| p.k1 = f64::NAN),
            "key 'follower.k1': must be above 0 and at most 20 1/s, got NaN"
        );
        assert_eq!(
            bad(|p| p.tau_s = 1e308),
            "key 'follower.tau_s': must be between 0 and 60 s, got 1e308"
        );
        assert!(bad(|p| p.k3 = -1.0).starts_with("key 'follower.k3'"));
        assert!(bad(|p| p.k_gap = 0.0).starts_with("key 'follower.k_gap'"));
        assert!(
            bad(|p| p.safety_distance_m = -0.1).starts_with("key 'follower.safety_distance_m'")
        );
        assert!(bad(|p| p.brake_time_s = 1e3).starts_with("key 'follower.brake_time_s'"));
        assert!(bad(|p| p.speed_window_s = 0.0).starts_with("key 'follower.speed_window_s'"));
        assert!(bad(|p| p.rollback_window_s = 5.0).starts_with("key 'follower.rollback_window_s'"));
        assert!(bad(|p| p.v_max = f64::INFINITY).starts_with("key 'follower.v_max'"));
        assert!(bad(|p| p.omega_max = 0.0).starts_with("key 'follower.omega_max'"));
    }

    #[test]
    fn out_of_range_leader_keys_are_named() {
        let bad = |f: fn(&mut LeaderParams)| {
            let mut p = LeaderParams::default();
            f(&mut p);
            leader(&p).unwrap_err()
        };
        assert_eq!(
            bad(|p| p.v_min = 0.3),
            "key 'leader.v_min': must be between 0 and 0.2 m/s (leader.v_max), got 0.3"
        );
        assert_eq!(
            bad(|p| p.goals = vec![[1.0, 2.0], [f64::NAN, 0.0]]),
            "key 'leader.goals[1].x': must be between -10000 and 10000 m, got NaN"
        );
        assert!(bad(|p| p.tolerance_m = 0.0).starts_with("key 'leader.tolerance_m'"));
        assert!(bad(|p| p.v_max = 1e308).starts_with("key 'leader.v_max'"));
        assert!(bad(|p| p.omega_min = 0.5).starts_with("key 'leader.omega_min'"));
        assert!(bad(|p| p.omega_max = -1.0).starts_with("key 'leader.omega_max'"));
        assert!(bad(|p| p.k_heading = -1e-300).starts_with("key 'leader.k_heading'"));
    }

    #[test]
    fn a_timeout_shorter_than_a_tick_is_refused() {
        let mut p = params();
        p.cmd_vel_timeout_s = 1e-300;
        assert_eq!(
            check(&p).unwrap_err(),
            "key 'cmd_vel_timeout_s': must be between 0.05 and 10 s, got 1e-300"
        );
    }
}
