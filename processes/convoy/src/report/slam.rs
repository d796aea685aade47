//! The `slam` section: how good the leader's laser-only map and localisation were.
//!
//! - **Map scale.** The SLAM node saves its final map as `map.yaml` + `map.pgm` (ROS
//!   map_server format) in the run directory. Each `[[survey]]` line of the world file is
//!   measured on that map (surface to surface through the survey's free point, see
//!   `caravan_perception::survey`) and against the world's true geometry, as the reference
//!   measured 2.05 m and 1.50 m on its map. `map_scale_error_pct` lists |map − true| / true.
//! - **Pose error.** Every estimate on `robot/0/pose` is compared with the true pose at the
//!   time of the scan it came from: the latest recorded `robot/0/scan` stamped before the
//!   estimate (the SLAM node publishes a tick after the scan), else the estimate's own stamp.
//! - **Plot.** `map.svg`: the map as an image with the true obstacles outlined over it.

use super::plot::Plot;
use base64::Engine;
use caravan_report::RecordedMessage;
use caravan_schemas::{OccupancyGrid, topics};
use caravan_world::World;
use serde_json::{Value, json};
use std::path::Path;

/// The map the SLAM node leaves in the run directory.
pub const MAP_FILE: &str = "map.yaml";
const PLOT_FILE: &str = "map.svg";
const LEADER: usize = 0;

/// The section, or `None` when the run had no SLAM (no map and no pose estimates).
pub fn section(
    messages: &[RecordedMessage],
    world: Option<&World>,
    run_dir: &Path,
) -> Option<Value> {
    let map = load_map(&run_dir.join(MAP_FILE));
    let pose_error = pose_error(messages);
    if map.is_none() && pose_error.is_none() {
        return None;
    }
    let mut section = json!({ "pose_error_m": pose_error });
    if let Some(map) = &map {
        let surveys: Vec<Value> = world
            .map(|w| w.surveys.iter().filter_map(|s| survey(map, w, s)).collect())
            .unwrap_or_default();
        section["map_scale_error_pct"] = surveys
            .iter()
            .map(|s| s["error_pct"].as_f64().map(f64::abs))
            .collect();
        section["surveys"] = Value::from(surveys);
        if std::fs::write(run_dir.join(PLOT_FILE), plot(map, world)).is_ok() {
            section["plot"] = json!(PLOT_FILE);
        }
    }
    Some(section)
}

fn load_map(path: &Path) -> Option<Box<OccupancyGrid>> {
    if !path.is_file() {
        return None;
    }
    let mut map = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
    caravan_perception::map_file::load_map(path, &mut map).ok()?;
    Some(map)
}

fn survey(map: &OccupancyGrid, world: &World, s: &caravan_world::Survey) -> Option<Value> {
    let truth = world.survey_length(s)?;
    let [dx, dy] = s.unit();
    let reach = truth + 1.0;
    let measured = caravan_perception::surface_distance(map, s.at, [dx, dy], reach)
        .zip(caravan_perception::surface_distance(
            map,
            s.at,
            [-dx, -dy],
            reach,
        ))
        .map(|(a, b)| a + b);
    Some(json!({
        "name": s.name,
        "true_m": truth,
        "map_m": measured,
        "error_pct": measured.map(|m| (m - truth) / truth * 100.0),
    }))
}

/// Mean and max position error of the leader's estimates, m, and how many were compared.
fn pose_error(messages: &[RecordedMessage]) -> Option<Value> {
    let (estimate_topic, truth_topic, scan_topic) = (
        topics::pose(LEADER),
        topics::pose_true(LEADER),
        topics::scan(LEADER),
    );
    let stamp = |m: &RecordedMessage| m.stamp_ns();
    let xy = |m: &RecordedMessage| {
        [
            m.json["x"].as_f64().unwrap_or(0.0),
            m.json["y"].as_f64().unwrap_or(0.0),
        ]
    };
    let mut truth: Vec<(u64, [f64; 2])> = Vec::new();
    let mut scans: Vec<u64> = Vec::new();
    let mut estimates: Vec<(u64, [f64; 2])> = Vec::new();
    for m in messages {
        if m.topic == truth_topic.name() {
            truth.push((stamp(m), xy(m)));
        } else if m.topic == scan_topic.name() {
            scans.push(stamp(m));
        } else if m.topic == estimate_topic.name() {
            estimates.push((stamp(m), xy(m)));
        }
    }
    truth.sort_by_key(|t| t.0);
    scans.sort_unstable();
    let errors: Vec<f64> = estimates
        .iter()
        .filter_map(|&(t, p)| {
            let k = scans.partition_point(|&s| s < t);
            let at = if k > 0 { scans[k - 1] } else { t };
            let q = interpolate(&truth, at)?;
            Some((p[0] - q[0]).hypot(p[1] - q[1]))
        })
        .collect();
    if errors.is_empty() {
        return None;
    }
    Some(json!({
        "mean": errors.iter().sum::<f64>() / errors.len() as f64,
        "max": errors.iter().copied().fold(0.0, f64::max),
        "samples": errors.len(),
    }))
}

/// The position at `t` on a time-sorted track, linear between samples; `None` outside it.
fn interpolate(track: &[(u64, [f64; 2])], t: u64) -> Option<[f64; 2]> {
    let k = track.partition_point(|s| s.0 < t);
    let after = track.get(k)?;
    if after.0 == t || k == 0 {
        return (after.0 == t).then_some(after.1);
    }
    let before = track[k - 1];
    let f = (t - before.0) as f64 / (after.0 - before.0) as f64;
    Some([
        before.1[0] + f * (after.1[0] - before.1[0]),
        before.1[1] + f * (after.1[1] - before.1[1]),
    ])
}

/// The map over the world's floor (or the whole map without a world), obstacles outlined.
fn plot(map: &OccupancyGrid, world: Option<&World>) -> String {
    let res = map.resolution;
    let origin = [map.origin.x, map.origin.y];
    let (w, h) = (map.width as usize, map.height as usize);
    // The cells to show: the floor plus a margin, clipped to the map.
    let (lo, hi) = match world {
        Some(world) => ([-0.25, -0.25], [world.size[0] + 0.25, world.size[1] + 0.25]),
        None => (
            origin,
            [origin[0] + w as f64 * res, origin[1] + h as f64 * res],
        ),
    };
    let cell = |v: f64, o: f64, n: usize| (((v - o) / res).floor().max(0.0) as usize).min(n);
    let (x0, x1) = (cell(lo[0], origin[0], w), cell(hi[0], origin[0], w));
    let (y0, y1) = (cell(lo[1], origin[1], h), cell(hi[1], origin[1], h));
    let (cols, rows) = (x1.saturating_sub(x0).max(1), y1.saturating_sub(y0).max(1));
    let mut pixels = Vec::with_capacity(cols * rows);
    // Image rows run top-down, map rows bottom-up.
    for iy in (y0..y0 + rows).rev() {
        for ix in x0..x0 + cols {
            let v = map.get(ix as u32, iy as u32).unwrap_or(-1);
            pixels.push(match v {
                v if v < 0 => 205,
                v => 254 - (v as i32 * 254 / 100) as u8,
            });
        }
    }
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, cols as u32, rows as u32);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        if let Ok(mut writer) = encoder.write_header() {
            let _ = writer.write_image_data(&pixels);
        }
    }
    let href = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png_bytes)
    );
    let size = world.map_or([w as f64 * res, h as f64 * res], |w| w.size);
    let mut plot = Plot::new(size, 120.0);
    plot.image(
        &href,
        [origin[0] + x0 as f64 * res, origin[1] + y0 as f64 * res],
        [
            origin[0] + (x0 + cols) as f64 * res,
            origin[1] + (y0 + rows) as f64 * res,
        ],
    );
    if let Some(world) = world {
        plot.world_outline(world);
    }
    plot.finish()
}

#[cfg(test)]
mod tests {
    use super::interpolate;

    #[test]
    fn interpolates_inside_the_track_only() {
        let track = [(10, [0.0, 0.0]), (20, [1.0, 2.0])];
        assert_eq!(interpolate(&track, 15), Some([0.5, 1.0]));
        assert_eq!(interpolate(&track, 10), Some([0.0, 0.0]));
        assert_eq!(interpolate(&track, 20), Some([1.0, 2.0]));
        assert_eq!(interpolate(&track, 5), None);
        assert_eq!(interpolate(&track, 25), None);
    }
}
