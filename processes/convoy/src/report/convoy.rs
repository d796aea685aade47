//! The convoy section of the report, computed from the recording: goals, gaps, collisions,
//! order, and each follower's cross-track error to its predecessor's and the leader's paths.
//!
//! Definitions (Caravan's, documented in report.json's doc):
//! - gap: distance between two robots' footprint rectangles (the URDF's chassis box: 0.20 ×
//!   0.18 m, centred 0.02 m behind base_link, for the convoy robot), from their true poses
//!   (`robot/<i>/pose_true`), at every recorded physics stamp; `min_gap_m` is the smallest gap
//!   between any two robots (not only neighbours) over the run: 0 when they touch, below the
//!   reference's 0.15 m safety distance when a follower came too close;
//! - order kept: along the leader's path (extended 5 m backwards along its start heading, so
//!   the followers' start line counts), every robot stays behind its predecessor, within 5 cm;
//! - cross-track error: distance from a follower's position to the other robot's whole path
//!   (extended the same way), over all recorded samples; `cross_track_to_leader_mean_m` and
//!   `cross_track_to_predecessor_mean_m` are the means of the followers' means (the measure of
//!   docs/fig9a.md).

use super::plot::Plot;
pub use crate::measures::Footprint;
use crate::measures::{gaps, path};
use caravan_report::RecordedMessage;
use caravan_schemas::topics;
use caravan_world::geometry::Polyline;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// What the convoy section measures against: the world (for the plot) and the footprint.
pub struct Scene {
    pub world: caravan_world::World,
    pub footprint: Footprint,
}

type Trajectory = Vec<(u64, [f64; 3])>;

fn robot_index(topic: &str) -> Option<usize> {
    topic
        .strip_prefix("robot/")?
        .strip_suffix("/pose_true")?
        .parse()
        .ok()
}

/// The convoy section, or `None` if the recording is not of a convoy.
pub fn section(messages: &[RecordedMessage], scene: &Scene, run_dir: &Path) -> Option<Value> {
    let mut robots: BTreeMap<usize, Trajectory> = BTreeMap::new();
    let mut goals: Vec<(u64, u64, u64, [f64; 2])> = Vec::new(); // (stamp, index, total, pose)
    let mut collisions = 0;
    for m in messages {
        let stamp = m.stamp_ns();
        let f = |k: &str| m.json[k].as_f64().unwrap_or(0.0);
        if let Some(i) = robot_index(&m.topic) {
            robots
                .entry(i)
                .or_default()
                .push((stamp, [f("x"), f("y"), f("theta")]));
        } else if m.topic == topics::goal().name() {
            let pose = &m.json["pose"];
            let p = [
                pose["x"].as_f64().unwrap_or(0.0),
                pose["y"].as_f64().unwrap_or(0.0),
            ];
            goals.push((
                stamp,
                m.json["index"].as_u64()?,
                m.json["total"].as_u64()?,
                p,
            ));
        } else if m.topic == topics::collisions().name() && m.json["started"] == 1 {
            collisions += 1;
        }
    }
    if robots.len() < 2 || !robots.contains_key(&0) || goals.is_empty() {
        return None;
    }
    let total = goals.iter().map(|g| g.2).max().unwrap_or(0);
    let goal_times_s: Vec<f64> = (0..total)
        .filter_map(|k| goals.iter().find(|g| g.1 > k).map(|g| g.0 as f64 * 1e-9))
        .collect();
    let trajectories: Vec<&Trajectory> = robots.values().collect();
    let paths: Vec<Polyline> = trajectories.iter().map(|t| extended_path(t)).collect();
    let (min_gap, order_kept, gap_series) =
        gaps_and_order(&trajectories, &paths[0], &scene.footprint);
    let followers: Vec<Value> = (1..trajectories.len())
        .map(|i| {
            let errors = |path: &Polyline| {
                stats(
                    trajectories[i]
                        .iter()
                        .map(|(_, p)| path.project([p[0], p[1]]).0)
                        .collect(),
                )
            };
            json!({
                "robot": robots.keys().nth(i),
                "cross_track_to_predecessor_m": errors(&paths[i - 1]),
                "cross_track_to_leader_m": errors(&paths[0]),
            })
        })
        .collect();
    let plot = plot(scene, &robots, &goals);
    let _ = std::fs::write(run_dir.join("trajectories.svg"), plot);
    let cross_track: Vec<Vec<(f64, f64)>> = (1..trajectories.len())
        .map(|i| {
            trajectories[i]
                .iter()
                .map(|(t, p)| (*t as f64 * 1e-9, paths[i - 1].project([p[0], p[1]]).0))
                .collect()
        })
        .collect();
    let series_written = series_plot(&run_dir.join(SERIES_FILE), &robots, gap_series, cross_track);
    Some(json!({
        "robots": robots.len(),
        "goals_total": total,
        "goals_reached": goal_times_s.len(),
        "goal_times_s": goal_times_s,
        "min_gap_m": min_gap,
        "collisions": collisions,
        "order_kept": order_kept,
        "cross_track_to_leader_mean_m": mean_over(&followers, "cross_track_to_leader_m"),
        "cross_track_to_predecessor_mean_m": mean_over(&followers, "cross_track_to_predecessor_m"),
        "followers": followers,
        "plot": "trajectories.svg",
        "series_plot": series_written.then_some(SERIES_FILE),
    }))
}

/// The mean over the followers of their mean cross-track error `key` (the Fig. 9a measure).
fn mean_over(followers: &[Value], key: &str) -> Option<f64> {
    let means: Vec<f64> = followers
        .iter()
        .filter_map(|f| f[key]["mean"].as_f64())
        .collect();
    (!means.is_empty()).then(|| means.iter().sum::<f64>() / means.len() as f64)
}

/// A robot's path, extended behind its start ([`crate::measures::path`]).
fn extended_path(t: &Trajectory) -> Polyline {
    path(t.iter().map(|(_, p)| p), true)
}

/// Gaps and cross-track errors against time, one line per follower.
const SERIES_FILE: &str = "series.svg";

/// Writes the gap of each follower to its predecessor and its cross-track error to the
/// predecessor's path against time; whether it could.
fn series_plot(
    path: &Path,
    robots: &BTreeMap<usize, Trajectory>,
    gaps: Vec<Vec<(f64, f64)>>,
    cross_track: Vec<Vec<(f64, f64)>>,
) -> bool {
    use caravan_report::plot::{Panel, Series, lines_svg};
    let names: Vec<String> = robots.keys().skip(1).map(|i| format!("R{i}")).collect();
    let lines = |data: Vec<Vec<(f64, f64)>>| -> Vec<Series> {
        names
            .iter()
            .zip(data)
            .map(|(label, points)| Series {
                label: label.clone(),
                segments: vec![points],
            })
            .collect()
    };
    let panels = [
        Panel {
            y_label: "gap to predecessor (m)".into(),
            series: lines(gaps),
        },
        Panel {
            y_label: "cross-track to predecessor's path (m)".into(),
            series: lines(cross_track),
        },
    ];
    lines_svg(path, "Convoy: gaps and cross-track errors", &panels).is_ok()
}

/// The minimum gap between any two robots, whether the order was kept along the leader's
/// path, and each follower's gap to its predecessor against time (s, m).
fn gaps_and_order(
    robots: &[&Trajectory],
    leader_path: &Polyline,
    fp: &Footprint,
) -> (f64, bool, Vec<Vec<(f64, f64)>>) {
    // Physics publishes every robot at the same stamps; compare robots at the stamps where all
    // were recorded (a realtime recording may start a robot's topic a little later).
    let mut at_stamp: BTreeMap<u64, Vec<[f64; 3]>> = BTreeMap::new();
    for t in robots {
        for (stamp, pose) in t.iter() {
            at_stamp.entry(*stamp).or_default().push(*pose);
        }
    }
    let mut min_gap = f64::INFINITY;
    let mut order_kept = true;
    let mut series = vec![Vec::new(); robots.len().saturating_sub(1)];
    for (stamp, poses) in at_stamp.iter().filter(|(_, p)| p.len() == robots.len()) {
        let (neighbours, smallest) = gaps(poses, fp);
        min_gap = min_gap.min(smallest);
        for (line, gap) in series.iter_mut().zip(neighbours) {
            line.push((*stamp as f64 * 1e-9, gap));
        }
        let along: Vec<f64> = poses
            .iter()
            .map(|p| leader_path.project([p[0], p[1]]).1)
            .collect();
        order_kept &= along.windows(2).all(|w| w[1] <= w[0] + 0.05);
    }
    (min_gap, order_kept, series)
}

fn stats(mut v: Vec<f64>) -> Value {
    if v.is_empty() {
        return Value::Null;
    }
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let p95 = v[((v.len() as f64 * 0.95) as usize).min(v.len() - 1)];
    json!({"mean": mean, "p95": p95, "max": v[v.len() - 1]})
}

fn plot(
    scene: &Scene,
    robots: &BTreeMap<usize, Trajectory>,
    goals: &[(u64, u64, u64, [f64; 2])],
) -> String {
    let mut plot = Plot::new(scene.world.size, 120.0);
    plot.world(&scene.world);
    for (i, t) in robots {
        let points: Vec<[f64; 2]> = t.iter().step_by(10).map(|(_, p)| [p[0], p[1]]).collect();
        plot.path(*i, &format!("R{i}"), &points);
    }
    let mut seen = std::collections::BTreeSet::new();
    for g in goals {
        if g.1 < g.2 && seen.insert(g.1) {
            plot.goal(&((b'A' + g.1 as u8) as char).to_string(), g.3);
        }
    }
    plot.finish()
}
