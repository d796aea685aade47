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
//! history; near the predecessor the speed is capped at k_gap·(gap − safety − margin), so it
//! eases to a stop before the gap between the two footprints reaches the 0.15 m safety
//! distance (a robot rolls about 6 cm after a zero set-point).

use crate::agent::angle::wrap;
use crate::agent::history::PoseHistory;
use caravan_schemas::Pose2D;
use caravan_world::geometry::{footprint, rect_distance};
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct FollowerParams {
    pub k1: f64,
    pub k2: f64,
    pub k3: f64,
    /// Delay τ, s.
    pub tau_s: f64,
    pub safety_distance_m: f64,
    /// Extra gap kept for the distance a robot rolls after it is told to stop, m.
    pub stop_margin_m: f64,
    /// Speed allowed per metre of gap beyond safety distance and margin, s⁻¹.
    pub k_gap: f64,
    /// Footprint half extents (x, y) and its centre's offset ahead of base_link, m: the URDF's
    /// chassis box (set by the node from the robot description, not a launch-file key).
    #[serde(skip)]
    pub footprint_half_m: [f64; 2],
    #[serde(skip)]
    pub footprint_offset_m: f64,
    pub v_max: f64,
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

/// (v, ω) for a follower at `own`, given its predecessor's history, at time `now_s`.
pub fn command(
    own: Pose2D,
    predecessor: &PoseHistory,
    now_s: f64,
    p: &FollowerParams,
) -> (f64, f64, Reason) {
    let (Some(target), Some(current)) = (predecessor.at(now_s - p.tau_s), predecessor.latest())
    else {
        return (0.0, 0.0, Reason::Waiting);
    };
    let rect = |q: Pose2D| {
        footprint(
            [q.x, q.y, q.theta],
            p.footprint_half_m,
            p.footprint_offset_m,
        )
    };
    let room = rect_distance(&rect(own), &rect(current)) - p.safety_distance_m - p.stop_margin_m;
    if room <= 0.0 {
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
        let (v, w, why) = command(pose(2.4, 0.0, 0.0), &h, 10.0, &FollowerParams::default());
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
        let (_, w, _) = command(pose(-1.0, 0.0, -3.0), &h, 10.0, &FollowerParams::default());
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
            pose(3.0 - 2.0 * p.footprint_half_m[0] - gap, 0.0, 0.0),
            &h,
            10.0,
            &p,
        );
        assert_eq!((v, w, why), (0.0, 0.0, Reason::SafetyStop));
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
            pose(3.0 - 2.0 * p.footprint_half_m[0] - gap, 0.0, 0.0),
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
        let (v, w, why) = command(pose(0.0, 0.0, 0.0), &h, 1.0, &FollowerParams::default());
        assert_eq!((v, w, why), (0.0, 0.0, Reason::Waiting));
    }

    #[test]
    fn respects_limits_and_never_reverses() {
        let h = straight_history(10.0);
        let p = FollowerParams::default();
        let (v, _, _) = command(pose(-5.0, 0.0, 0.0), &h, 10.0, &p);
        assert_eq!(v, p.v_max);
        let (v, _, _) = command(pose(2.4, 0.0, std::f64::consts::PI), &h, 10.0, &p);
        assert_eq!(v, 0.0);
        let (_, w, _) = command(pose(2.4, 0.0, 2.5), &h, 10.0, &p);
        assert_eq!(w, -p.omega_max);
    }

    #[test]
    fn lateral_offset_is_not_corrected() {
        // Beside the delayed pose, same heading: the law commands nothing sideways.
        let h = straight_history(10.0);
        let (v, w, _) = command(pose(2.6, 0.3, 0.0), &h, 10.0, &FollowerParams::default());
        assert!(v.abs() < 1e-12 && w.abs() < 1e-12);
    }
}
