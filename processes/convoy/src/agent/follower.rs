//! The reference follower law. Robot i tracks where its predecessor was τ seconds ago:
//!
//!   v = k1·(x_p(t−τ) − x)·cos θ + k2·(y_p(t−τ) − y)·sin θ
//!   ω = k3·wrap(θ_p(t−τ) − θ)
//!
//! (poses in the map frame). Nothing corrects lateral error, so lateral offsets persist and
//! pass down the chain, as in the paper. Caravan's choices where the paper is silent: gains
//! k1 = k2 = 1.5 s⁻¹ and k3 = 1 s⁻¹ (the wheel-speed loop settles in 2.5 s on the floor and
//! overshoots; higher heading gains make the chain oscillate); no reversing (v ≥ 0); limits
//! |ω| ≤ 2 rad/s, v ≤ 0.25 m/s; the robot holds still while t − τ precedes the predecessor's
//! history; near the predecessor the speed is capped at k_gap·room, with
//! room = gap − safety − margin (gap: the distance between the two footprints as last
//! reported). It stops when room is no more than how much nearer the two can come once both
//! are at rest, if both stopped now:
//!
//!   closing = max(v·(age + t_brake) − (max(v_p, 0)·t_coast + min(v_p, 0)·age_p
//!                                       − t_rollback·v_p,peak), 0)
//!
//! v and v_p are the follower's and its predecessor's forward speeds, measured from their
//! stamped pose histories; age and age_p are how old the two poses are (now − header stamp):
//! the follower has driven on since its pose, and a predecessor rolling back has rolled on.
//! The wheel loop is slow and underdamped (it settles in 2.5 s on the floor): a robot told to
//! stop rolls on for 0.33·v typically and 0.44·v at most, and then rolls *back* by up to 0.18 s
//! times the speed it had (v_p,peak: the predecessor's highest speed over the last second;
//! figures measured in the fig9a runs, docs/fig9a.md). So the follower charges itself the longest roll-out
//! from where it is by now, and credits the predecessor only the shortest. A predecessor that
//! drives forward gets no credit for its pose's age: its older pose places it nearer, which
//! errs safe. With a fixed margin alone, a follower arriving at full speed behind a
//! stopped predecessor came within 0.13 m of it (docs/fig9a.md). The speed cap is left as it
//! was, so followers drive as before until a stop is needed.

use crate::agent::angle::wrap;
use crate::agent::history::PoseHistory;
use caravan_schemas::Pose2D;
use caravan_world::geometry::{footprint, rect_distance};
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct FollowerParams {
    /// Gain on the x error, 1/s, above 0, at most 20 (one over the tick).
    pub k1: f64,
    /// Gain on the y error, 1/s, above 0, at most 20.
    pub k2: f64,
    /// Heading gain, 1/s, above 0, at most 20.
    pub k3: f64,
    /// Delay τ: track the predecessor's pose τ ago, s, 0 to 60.
    pub tau_s: f64,
    /// Smallest gap between the two footprints, m, 0 to 10.
    pub safety_distance_m: f64,
    /// Extra gap kept at a standstill, m, 0 to 10: pose errors and the last step's travel.
    pub stop_margin_m: f64,
    /// Upper bound on how long the follower's own speed may still carry it after a zero
    /// set-point, s, 0 to 10: above every roll-out measured over 706 stops (0.33·v median,
    /// 0.40·v p95, 0.44·v most, while turning). A robot still speeding up rolls further; the
    /// margin absorbs that.
    pub brake_time_s: f64,
    /// Lower bound on how long the predecessor's speed carries it after a zero set-point, s, 0
    /// to 10 (0.30·v p10 in the same stops).
    pub coast_time_s: f64,
    /// A robot that stopped from speed V rolls back up to V times this, s, 0 to 10: the wheel
    /// loop's undershoot below zero (at most 0.18·V measured).
    pub rollback_time_s: f64,
    /// How far back the predecessor's highest speed is looked for, s, 0 to 1.
    pub rollback_window_s: f64,
    /// Window over which both speeds are measured from the pose histories, s, 0.01 to 1.
    pub speed_window_s: f64,
    /// Speed allowed per metre of gap beyond safety distance and margin, 1/s, above 0, at most
    /// 20.
    pub k_gap: f64,
    /// Footprint half extents (x, y) and its centre's offset ahead of base_link, m: the URDF's
    /// chassis box (set by the node from the robot description, not a launch-file key).
    #[serde(skip)]
    pub footprint_half_m: [f64; 2],
    #[serde(skip)]
    pub footprint_offset_m: f64,
    /// Top speed, m/s, above 0, at most 2.5 (v ≥ 0 always).
    pub v_max: f64,
    /// Turn-rate limit, ±, rad/s, above 0, at most 20.
    pub omega_max: f64,
}

impl Default for FollowerParams {
    fn default() -> Self {
        Self {
            k1: 1.5,
            k2: 1.5,
            k3: 1.0,
            tau_s: 2.0,
            safety_distance_m: 0.15,
            stop_margin_m: 0.05,
            brake_time_s: 0.45,
            coast_time_s: 0.2,
            rollback_time_s: 0.18,
            rollback_window_s: 1.0,
            speed_window_s: 0.1,
            k_gap: 1.5,
            // The convoy robot's chassis; the node takes it from the URDF.
            footprint_half_m: [0.10, 0.09],
            footprint_offset_m: -0.02,
            v_max: 0.25,
            omega_max: 2.0,
        }
    }
}

/// Why the follower commanded what it did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason {
    Tracking,
    /// No predecessor pose old enough yet.
    Waiting,
    /// Too close to the predecessor.
    SafetyStop,
}

/// (v, ω) for a follower whose own recent poses are `own_history`, given its predecessor's
/// history, at time `now_s`. Both histories are keyed by the poses' header stamps.
pub fn command(
    own_history: &PoseHistory,
    predecessor: &PoseHistory,
    now_s: f64,
    p: &FollowerParams,
) -> (f64, f64, Reason) {
    let (Some((own_t, own)), Some(target), Some((pred_t, current))) = (
        own_history.latest_stamped(),
        predecessor.at(now_s - p.tau_s),
        predecessor.latest_stamped(),
    ) else {
        return (0.0, 0.0, Reason::Waiting);
    };
    let rect = |q: Pose2D| {
        footprint(
            [q.x, q.y, q.theta],
            p.footprint_half_m,
            p.footprint_offset_m,
        )
    };
    // How much nearer the two will be once both are at rest, at worst, if both stopped now: the
    // follower drives on from its (older) reported pose for the longest roll-out; the
    // predecessor coasts for the shortest, then rolls back in proportion to its recent speed.
    let own_speed = own_history.forward_speed(p.speed_window_s).max(0.0);
    let own_travel = own_speed * ((now_s - own_t).max(0.0) + p.brake_time_s);
    let pred_speed = predecessor.forward_speed(p.speed_window_s);
    let pred_travel = p.coast_time_s * pred_speed.max(0.0)
        + pred_speed.min(0.0) * (now_s - pred_t).max(0.0)
        - p.rollback_time_s * predecessor.peak_forward_speed(p.speed_window_s, p.rollback_window_s);
    let closing = (own_travel - pred_travel).max(0.0);
    let room = rect_distance(&rect(own), &rect(current)) - p.safety_distance_m - p.stop_margin_m;
    if room <= closing {
        return (0.0, 0.0, Reason::SafetyStop);
    }
    let (s, c) = own.theta.sin_cos();
    let v = p.k1 * (target.x - own.x) * c + p.k2 * (target.y - own.y) * s;
    let omega = p.k3 * wrap(target.theta - own.theta);
    // Ease off near the predecessor: the wheels need time (and distance) to stop.
    let v_max = p.v_max.min(p.k_gap * room);
    (
        v.clamp(0.0, v_max),
        omega.clamp(-p.omega_max, p.omega_max),
        Reason::Tracking,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, y: f64, theta: f64) -> Pose2D {
        Pose2D { x, y, theta }
    }

    /// A follower's own history: standing at `q`.
    fn still(q: Pose2D) -> PoseHistory {
        let mut h = PoseHistory::new(1.0);
        h.push(0.0, q);
        h
    }

    /// A predecessor that drove along +x at 0.2 m/s from x = 1 for `until` seconds.
    fn straight_history(until: f64) -> PoseHistory {
        let mut h = PoseHistory::new(5.0);
        let mut t = 0.0;
        while t <= until + 1e-9 {
            h.push(t, pose(1.0 + 0.2 * t, 0.0, 0.0));
            t += 0.05;
        }
        h
    }

    #[test]
    fn drives_toward_the_delayed_pose() {
        let h = straight_history(10.0);
        // τ = 2 s ago the predecessor was at x = 2.6; we are at 2.4 heading +x.
        let (v, w, why) = command(
            &still(pose(2.4, 0.0, 0.0)),
            &h,
            10.0,
            &FollowerParams::default(),
        );
        assert_eq!(why, Reason::Tracking);
        assert!(
            (v - 0.3_f64.min(0.25)).abs() < 1e-9 && w.abs() < 1e-12,
            "{v} {w}"
        );
    }

    #[test]
    fn heading_error_turns_the_short_way() {
        let mut h = PoseHistory::new(20.0);
        h.push(0.0, pose(0.0, 0.0, 3.0));
        h.push(10.0, pose(5.0, 0.0, 3.0));
        let (_, w, _) = command(
            &still(pose(-1.0, 0.0, -3.0)),
            &h,
            10.0,
            &FollowerParams::default(),
        );
        // θ_p − θ = 6 rad ≡ −0.283 rad: turn right, not 6 rad left.
        assert!(
            w < 0.0
                && (w - FollowerParams::default().k3 * (6.0 - std::f64::consts::TAU)).abs() < 1e-9,
            "{w}"
        );
    }

    #[test]
    fn stops_inside_the_safety_distance() {
        let h = straight_history(10.0); // predecessor now at x = 3.0
        let p = FollowerParams::default();
        let gap = p.safety_distance_m + p.stop_margin_m - 0.01;
        let (v, w, why) = command(
            &still(pose(3.0 - 2.0 * p.footprint_half_m[0] - gap, 0.0, 0.0)),
            &h,
            10.0,
            &p,
        );
        assert_eq!((v, w, why), (0.0, 0.0, Reason::SafetyStop));
    }

    /// A predecessor that drove as `straight_history(10.0)` and has stood at x = 3.0 since,
    /// until `until`.
    fn parked(until: f64) -> PoseHistory {
        let mut h = straight_history(10.0);
        let mut t = 10.05;
        while t <= until + 1e-9 {
            h.push(t, pose(3.0, 0.0, 0.0));
            t += 0.05;
        }
        h
    }

    /// A follower that drove along +x at `speed` until `until`, its front `gap` behind the
    /// back of a predecessor at x = 3.0.
    fn approaching(speed: f64, until: f64, gap: f64, p: &FollowerParams) -> PoseHistory {
        let x = 3.0 - 2.0 * p.footprint_half_m[0] - gap;
        let mut h = PoseHistory::new(1.0);
        for k in 0..=10 {
            let dt = 0.05 * k as f64;
            h.push(until - 0.5 + dt, pose(x - speed * (0.5 - dt), 0.0, 0.0));
        }
        h
    }

    /// The gap at which `room` is left beyond safety distance and margin.
    fn gap_with_room(room: f64, p: &FollowerParams) -> f64 {
        p.safety_distance_m + p.stop_margin_m + room
    }

    #[test]
    fn a_fast_follower_stops_earlier_than_a_slow_one() {
        let p = FollowerParams::default();
        // Behind a predecessor that stopped 0.5 s ago from 0.2 m/s (it may roll back
        // 0.18 × 0.2 = 3.6 cm): 6 cm of room is enough at a crawl; at 0.2 m/s the follower
        // may roll 0.2 × 0.45 = 9 cm more.
        let (v, _, why) = command(
            &approaching(0.01, 10.5, gap_with_room(0.06, &p), &p),
            &parked(10.5),
            10.5,
            &p,
        );
        assert_eq!(why, Reason::Tracking);
        assert!(v > 0.0, "{v}");
        let fast = approaching(0.2, 10.5, gap_with_room(0.1, &p), &p);
        let (_, _, why) = command(&fast, &parked(10.5), 10.5, &p);
        assert_eq!(why, Reason::SafetyStop);
        // Behind a predecessor driving as fast, which coasts too, 10 cm is enough.
        let (_, _, why) = command(
            &approaching(0.2, 10.0, gap_with_room(0.1, &p), &p),
            &straight_history(10.0),
            10.0,
            &p,
        );
        assert_eq!(why, Reason::Tracking);
    }

    #[test]
    fn an_older_own_pose_counts_as_distance_driven() {
        let p = FollowerParams::default();
        let closing = 0.2 * p.brake_time_s + p.rollback_time_s * 0.2;
        let gap = gap_with_room(closing + 0.01, &p);
        // Reported now, the last 1 cm is room; reported 0.1 s ago at 0.2 m/s, it is gone.
        let (_, _, why) = command(&approaching(0.2, 10.5, gap, &p), &parked(10.5), 10.5, &p);
        assert_eq!(why, Reason::Tracking);
        let (_, _, why) = command(&approaching(0.2, 10.4, gap, &p), &parked(10.5), 10.5, &p);
        assert_eq!(why, Reason::SafetyStop);
    }

    #[test]
    fn a_predecessor_that_just_stopped_keeps_room_to_roll_back() {
        let p = FollowerParams::default();
        let own = still(pose(
            3.0 - 2.0 * p.footprint_half_m[0] - gap_with_room(0.02, &p),
            0.0,
            0.0,
        ));
        // Stopped 0.5 s ago from 0.2 m/s: it may roll back 3.6 cm, more than the 2 cm of room.
        let (_, _, why) = command(&own, &parked(10.5), 10.5, &p);
        assert_eq!(why, Reason::SafetyStop);
        // Standing for more than the rollback window: the room is the follower's.
        let (_, _, why) = command(&own, &parked(11.5), 11.5, &p);
        assert_eq!(why, Reason::Tracking);
    }

    #[test]
    fn a_predecessor_rolling_back_rolls_on_while_its_pose_travels() {
        let p = FollowerParams::default();
        // Stood since 10 s (no roll-back charge left after 1 s), then rolls back at 0.1 m/s.
        let mut h = parked(11.5);
        h.push(11.55, pose(2.995, 0.0, 0.0));
        h.push(11.6, pose(2.99, 0.0, 0.0));
        let own = still(pose(
            2.99 - 2.0 * p.footprint_half_m[0] - gap_with_room(0.02, &p),
            0.0,
            0.0,
        ));
        // Its pose is fresh: 2 cm of room is enough.
        let (_, _, why) = command(&own, &h, 11.6, &p);
        assert_eq!(why, Reason::Tracking);
        // The same pose 0.25 s old: it has rolled back 2.5 cm more by now.
        let (_, _, why) = command(&own, &h, 11.85, &p);
        assert_eq!(why, Reason::SafetyStop);
    }

    #[test]
    fn slows_down_when_closing_in() {
        let h = straight_history(10.0);
        // Stiff gains, so the law alone would drive at full speed.
        let p = FollowerParams {
            k1: 10.0,
            k2: 10.0,
            ..Default::default()
        };
        // Predecessor at x = 3.0; 0.05 m of room beyond safety distance and margin.
        let room = 0.05;
        let gap = p.safety_distance_m + p.stop_margin_m + room;
        let (v, _, why) = command(
            &still(pose(3.0 - 2.0 * p.footprint_half_m[0] - gap, 0.0, 0.0)),
            &h,
            10.0,
            &p,
        );
        assert_eq!(why, Reason::Tracking);
        assert!((v - p.k_gap * room).abs() < 1e-9, "{v}");
    }

    #[test]
    fn holds_until_history_reaches_back_tau() {
        let h = straight_history(1.0);
        let (v, w, why) = command(
            &still(pose(0.0, 0.0, 0.0)),
            &h,
            1.0,
            &FollowerParams::default(),
        );
        assert_eq!((v, w, why), (0.0, 0.0, Reason::Waiting));
    }

    #[test]
    fn respects_limits_and_never_reverses() {
        let h = straight_history(10.0);
        let p = FollowerParams::default();
        let (v, _, _) = command(&still(pose(-5.0, 0.0, 0.0)), &h, 10.0, &p);
        assert_eq!(v, p.v_max);
        let (v, _, _) = command(&still(pose(2.4, 0.0, std::f64::consts::PI)), &h, 10.0, &p);
        assert_eq!(v, 0.0);
        let (_, w, _) = command(&still(pose(2.4, 0.0, 2.5)), &h, 10.0, &p);
        assert_eq!(w, -p.omega_max);
    }

    #[test]
    fn lateral_offset_is_not_corrected() {
        // Beside the delayed pose, same heading: the law commands nothing sideways.
        let h = straight_history(10.0);
        let (v, w, _) = command(
            &still(pose(2.6, 0.3, 0.0)),
            &h,
            10.0,
            &FollowerParams::default(),
        );
        assert!(v.abs() < 1e-12 && w.abs() < 1e-12);
    }
}
