//! A robot's recent poses, to look up where it was τ seconds ago.

use crate::agent::angle::wrap;
use caravan_schemas::Pose2D;
use std::collections::VecDeque;

/// Time-stamped poses in arrival order (stamps increase).
#[derive(Debug, Default)]
pub struct PoseHistory {
    samples: VecDeque<(f64, Pose2D)>,
    /// How much history to keep, s.
    keep_s: f64,
}

impl PoseHistory {
    pub fn new(keep_s: f64) -> Self {
        Self {
            samples: VecDeque::new(),
            keep_s,
        }
    }

    /// Adds a pose at time `t` (s); older samples beyond the horizon are dropped.
    pub fn push(&mut self, t: f64, pose: Pose2D) {
        if self.samples.back().is_some_and(|(last, _)| t <= *last) {
            return;
        }
        self.samples.push_back((t, pose));
        while self
            .samples
            .front()
            .is_some_and(|(t0, _)| *t0 < t - self.keep_s)
        {
            self.samples.pop_front();
        }
    }

    pub fn latest(&self) -> Option<Pose2D> {
        self.samples.back().map(|(_, p)| *p)
    }

    /// The newest sample: its stamp (s) and pose.
    pub fn latest_stamped(&self) -> Option<(f64, Pose2D)> {
        self.samples.back().copied()
    }

    /// The highest of the forward speeds measured over `window_s` at each sample of the last
    /// `span_s`, m/s (0 with fewer than two samples).
    pub fn peak_forward_speed(&self, window_s: f64, span_s: f64) -> f64 {
        let Some(&(t_last, _)) = self.samples.back() else {
            return 0.0;
        };
        let first = self.samples.partition_point(|(t, _)| *t < t_last - span_s);
        (first..self.samples.len())
            .map(|end| self.speed_until(end, window_s))
            .fold(0.0, f64::max)
    }

    /// Speed along the newest heading over the last `window_s` of history, m/s: negative when
    /// the robot rolls back, 0 with fewer than two samples.
    pub fn forward_speed(&self, window_s: f64) -> f64 {
        self.speed_until(self.samples.len().saturating_sub(1), window_s)
    }

    /// Forward speed over the `window_s` that ends at sample `end`, along its heading.
    fn speed_until(&self, end: usize, window_s: f64) -> f64 {
        let (Some(&(t_first, _)), Some(&(t_last, last))) =
            (self.samples.front(), self.samples.get(end))
        else {
            return 0.0;
        };
        let t0 = (t_last - window_s).max(t_first);
        let Some(from) = self.at(t0).filter(|_| t_last > t0) else {
            return 0.0;
        };
        let (s, c) = last.theta.sin_cos();
        ((last.x - from.x) * c + (last.y - from.y) * s) / (t_last - t0)
    }

    /// The pose at time `t`, linearly interpolated (heading along the shorter arc). `None` if
    /// `t` precedes the history: the caller holds position then.
    pub fn at(&self, t: f64) -> Option<Pose2D> {
        let (&(t_first, _), &(t_last, last)) = (self.samples.front()?, self.samples.back()?);
        if t < t_first {
            return None;
        }
        if t >= t_last {
            return Some(last);
        }
        let i = self.samples.partition_point(|(ts, _)| *ts <= t);
        let ((t0, p0), (t1, p1)) = (self.samples[i - 1], self.samples[i]);
        let a = (t - t0) / (t1 - t0);
        Some(Pose2D {
            x: p0.x + a * (p1.x - p0.x),
            y: p0.y + a * (p1.y - p0.y),
            theta: wrap(p0.theta + a * wrap(p1.theta - p0.theta)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, theta: f64) -> Pose2D {
        Pose2D { x, y: 0.0, theta }
    }

    #[test]
    fn interpolates_between_samples_and_wraps_heading() {
        let mut h = PoseHistory::new(10.0);
        h.push(0.0, pose(0.0, 3.0));
        h.push(1.0, pose(1.0, -3.0)); // across ±π: the short way is +0.283 rad
        let p = h.at(0.5).unwrap();
        assert!((p.x - 0.5).abs() < 1e-12);
        assert!(
            (p.theta.abs() - std::f64::consts::PI).abs() < 1e-9,
            "{}",
            p.theta
        );
    }

    #[test]
    fn before_the_history_there_is_nothing() {
        let mut h = PoseHistory::new(10.0);
        h.push(5.0, pose(0.0, 0.0));
        assert!(h.at(4.9).is_none());
        assert_eq!(h.at(7.0).unwrap().x, 0.0);
    }

    #[test]
    fn forward_speed_is_signed_along_the_heading() {
        let mut h = PoseHistory::new(10.0);
        assert_eq!(h.forward_speed(0.2), 0.0);
        h.push(0.0, pose(1.0, 0.0));
        assert_eq!(h.forward_speed(0.2), 0.0);
        for k in 1..=10 {
            h.push(k as f64 * 0.05, pose(1.0 + 0.01 * k as f64, 0.0));
        }
        assert!((h.forward_speed(0.2) - 0.2).abs() < 1e-9);
        // Rolling back while facing +x, then facing −x while moving +x.
        h.push(0.55, pose(1.09, 0.0));
        assert!(h.forward_speed(0.05) < 0.0);
        h.push(0.6, pose(1.1, std::f64::consts::PI));
        assert!(h.forward_speed(0.05) < 0.0);
        // It drove at 0.2 m/s until 0.5 s; in the last 0.05 s it only went backwards.
        assert!((h.peak_forward_speed(0.05, 1.0) - 0.2).abs() < 1e-9);
        assert_eq!(h.peak_forward_speed(0.05, 0.05), 0.0);
        assert!((h.peak_forward_speed(0.05, 0.1) - 0.2).abs() < 1e-9);
    }

    #[test]
    fn old_samples_are_dropped() {
        let mut h = PoseHistory::new(2.0);
        for k in 0..100 {
            h.push(k as f64 * 0.1, pose(k as f64, 0.0));
        }
        // Kept: samples from 9.9 − 2 = 7.9 s on.
        assert!(h.at(7.85).is_none());
        assert_eq!(h.at(8.0).unwrap().x, 80.0);
    }
}
