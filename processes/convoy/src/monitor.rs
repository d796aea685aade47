//! `caravan-convoy-monitor`: the convoy's measures as the run goes, on `convoy/metrics`
//! ([`caravan_schemas::Metrics`]), for live plots (Foxglove, `caravan topic echo`) and the
//! recording. At each step (10 Hz unless the launch file says otherwise) it reads every
//! robot's latest true pose and publishes, with the definitions of [`crate::measures`]:
//! - `gap_<i>_m`: follower i's gap to its predecessor i − 1;
//! - `cross_track_<i>_m`: follower i's distance to its predecessor's path over the last
//!   [`PATH_WINDOW_S`] (with the run-up behind the start while the start is in it);
//! - `min_gap_m`: the smallest gap between any two robots.
//!
//! It only reads and publishes what no other node reads, so adding it changes no run.

use crate::measures::{Footprint, gaps, path};
use caravan::{Error, Node, Topic, Trigger};
use caravan_schemas::{MAX_METRICS, Metrics, Pose2D, topics};
use serde::Deserialize;
use std::collections::VecDeque;

/// The monitor's topic.
pub const METRICS_TOPIC: &str = "convoy/metrics";

/// How much of the predecessor's path the cross-track error looks at, s: a follower tracks its
/// predecessor a few seconds behind, and a bounded window keeps a step's cost bounded.
pub const PATH_WINDOW_S: f64 = 60.0;

const RATE_HZ: f64 = 10.0;

/// The most robots whose measures fit one message: 2 per follower, and the minimum gap.
pub const MAX_ROBOTS: usize = MAX_METRICS.div_ceil(2);

/// The monitor's params.
#[derive(Debug, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Robots in the convoy, 2 … [`MAX_ROBOTS`] (16); robot 0 leads.
    pub count: usize,
    /// The robots' description, relative to the launch file, for their footprint.
    pub urdf: String,
}

/// Checks the params and reads the footprint, before the node joins the group.
pub fn setup(p: Params, identity: &caravan::NodeIdentity) -> Result<(usize, Footprint), String> {
    if !(2..=MAX_ROBOTS).contains(&p.count) {
        return Err(format!(
            "key 'count': {} robots; the monitor measures 2 to {MAX_ROBOTS}",
            p.count
        ));
    }
    let robot = caravan_world::load_robot(&identity.resolve_path(&p.urdf))
        .map_err(|e| format!("key 'urdf': robot description {e}"))?;
    Ok((p.count, Footprint::of(&robot)))
}

/// Publishes the measures until the group stops.
pub fn run(mut node: Node, (count, fp): (usize, Footprint)) -> Result<(), Error> {
    let poses = (0..count)
        .map(|i| node.subscriber(&topics::pose_true(i)))
        .collect::<Result<Vec<_>, _>>()?;
    let out = node.publisher(&Topic::<Metrics>::new(METRICS_TOPIC))?;
    let trigger = node.trigger(Trigger::every_hz(RATE_HZ))?;
    let window = match trigger.period() {
        Some(period) => (PATH_WINDOW_S / period.as_secs_f64()).ceil() as usize,
        None => (PATH_WINDOW_S * RATE_HZ) as usize,
    };
    let mut latest: Vec<Option<[f64; 3]>> = vec![None; count];
    let mut paths = vec![Trail::new(window); count];
    node.run(trigger, |_| {
        for (i, sub) in poses.iter().enumerate() {
            if let Some(p) = sub.latest()? {
                latest[i] = Some(pose(&p));
            }
        }
        // Until physics published every robot once, there is nothing to measure.
        let Some(now) = latest.iter().copied().collect::<Option<Vec<_>>>() else {
            return Ok(());
        };
        for (trail, p) in paths.iter_mut().zip(&now) {
            trail.push(*p);
        }
        let mut loan = out.loan()?;
        measure(&now, &paths, &fp, &mut loan);
        loan.send()
    })?;
    Ok(())
}

fn pose(p: &Pose2D) -> [f64; 3] {
    [p.x, p.y, p.theta]
}

/// The last poses of one robot, and its first (the run-up is drawn behind it).
#[derive(Clone)]
struct Trail {
    first: Option<[f64; 3]>,
    recent: VecDeque<[f64; 3]>,
    window: usize,
}

impl Trail {
    fn new(window: usize) -> Self {
        Self {
            first: None,
            recent: VecDeque::with_capacity(window.min(4096)),
            window: window.max(2),
        }
    }

    fn push(&mut self, p: [f64; 3]) {
        self.first.get_or_insert(p);
        if self.recent.len() == self.window {
            self.recent.pop_front();
        }
        self.recent.push_back(p);
    }

    /// Whether the window still starts at the first pose.
    fn holds_start(&self) -> bool {
        self.recent.front() == self.first.as_ref()
    }
}

/// Writes the measures of robots at `now`, with paths `paths`, into `out`.
fn measure(now: &[[f64; 3]], paths: &[Trail], fp: &Footprint, out: &mut Metrics) {
    let (neighbours, smallest) = gaps(now, fp);
    for (k, gap) in neighbours.iter().enumerate() {
        out.push(&format!("gap_{}_m", k + 1), *gap);
    }
    for i in 1..now.len() {
        let trail = &paths[i - 1];
        let trail_path = path(&trail.recent, trail.holds_start());
        out.push(
            &format!("cross_track_{i}_m"),
            trail_path.project([now[i][0], now[i][1]]).0,
        );
    }
    out.push("min_gap_m", smallest);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_follower_on_its_predecessors_path_has_no_cross_track_error() {
        let fp = Footprint {
            half: [0.1, 0.09],
            offset: 0.0,
        };
        let mut trails = vec![Trail::new(100); 2];
        // The leader drives along x; the follower starts behind it, then drifts 0.3 m aside.
        for k in 0..20 {
            let x = k as f64 * 0.1;
            trails[0].push([x + 1.0, 0.0, 0.0]);
            trails[1].push([x, if k < 10 { 0.0 } else { 0.3 }, 0.0]);
        }
        let now = [[2.9, 0.0, 0.0], [1.9, 0.3, 0.0]];
        let mut m = caravan_schemas::boxed_placement_new::<Metrics>();
        measure(&now, &trails, &fp, &mut m);
        assert!((m.get("gap_1_m").unwrap() - (1.0 - 0.2)).abs() < 0.1);
        assert!((m.get("cross_track_1_m").unwrap() - 0.3).abs() < 1e-9);
        assert!(m.get("min_gap_m").unwrap() > 0.0);
        // A follower on the run-up behind the leader's start is on its path.
        let now = [[1.0, 0.0, 0.0], [-2.0, 0.0, 0.0]];
        let mut m = caravan_schemas::boxed_placement_new::<Metrics>();
        measure(&now, &trails, &fp, &mut m);
        assert!(m.get("cross_track_1_m").unwrap() < 1e-9);
    }

    #[test]
    fn a_trail_keeps_its_window_and_forgets_its_start() {
        let mut t = Trail::new(3);
        for k in 0..3 {
            t.push([k as f64, 0.0, 0.0]);
        }
        assert!(t.holds_start());
        t.push([3.0, 0.0, 0.0]);
        assert!(!t.holds_start());
        assert_eq!(t.recent.len(), 3);
    }
}
