//! Hector-style laser SLAM for the leader: scan-to-map matching on a multi-resolution
//! occupancy map, from the laser alone.
//!
//! Per scan ([`Slam::update`]):
//! 1. The valid readings become end points in the robot frame (scanner offset applied).
//!    Readings outside the scan's `[range_min, range_max]` (no-return or too close) and outside
//!    `[min_range_m, max_range_m]` are dropped, as in Hector; no-return beams are not used to
//!    clear free space, so a beam that saw nothing never erases a surface.
//! 2. The pose is predicted with a constant-velocity model from the last two estimates
//!    (the leader's SLAM node has no odometry).
//! 3. The scan is matched coarse to fine ([`crate::matcher`]), each level starting from the
//!    previous level's result, to the reflection field by default (`match_field`; Hector's
//!    occupancy field drifts toward the walls in view with a 240° scanner, see the matcher).
//!    Coarse levels use every 2nd / 4th point: their cells are 2× / 4× larger, so neighbouring
//!    points mostly fall in the same cells and add little.
//! 4. Once the pose has moved more than `map_update_distance_m` or turned more than
//!    `map_update_angle_rad` since the last map update, the scan is written into every level.
//!    The first scan always goes into the map, at the initial pose.
//!
//! Nothing is allocated per scan after the first.
//!
//! Measured on the synthetic room (`tests/slam_room.rs`, URG noise, 1 m straight, a quarter
//! turn, 0.5 m straight): the pose stays within 1.7 cm of the truth over twelve noise seeds
//! (Hector's occupancy matching: 4–5 cm), and walls measured on the map with
//! [`crate::survey`] are 0.2–0.55 % too far apart.

use crate::grid::OccupancyMap;
use crate::matcher::{MatchField, MatchResult, match_scan, wrap_angle};
use caravan_schemas::{LaserScan, MAP_MAX_SIDE, OccupancyGrid, Pose2D};
use serde::Deserialize;
use std::ops::RangeInclusive;

/// The cell sizes a map may have, m: from 1 mm to 10 m; past these the map's arithmetic (cell
/// indices, world extents) overflows. The map files read back are held to it too.
pub const RESOLUTION_RANGE_M: RangeInclusive<f64> = 0.001..=10.0;

/// Fewer valid points than this and the scan is not matched: the pose is the prediction.
pub const MIN_POINTS: usize = 20;

/// The SLAM node's params.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SlamParams {
    /// Cell side of the finest map level, m, 0.001 to 10 (Hector's default, the reference's
    /// choice).
    pub resolution: f64,
    /// Map levels, 1 … 5, each with cells twice as large as the one below (Hector uses 3).
    pub levels: usize,
    /// Side of the finest level in cells (512 × 0.025 m = 12.8 m): a multiple of 2^(levels −
    /// 1), from 4·2^(levels − 1) to [`MAP_MAX_SIDE`] (1024).
    pub map_size: usize,
    /// Centre of the map, m, finite; the initial pose's position if absent.
    pub map_center: Option<[f64; 2]>,
    /// Add the scan to the map once the robot moved more than this since the last update (or
    /// turned more than `map_update_angle_rad`), m, > 0. 0.1 m is half a second at the leader's
    /// top speed: the map in front of the leader, which the planner needs, is refreshed at 2
    /// Hz, while a standing robot never feeds its own pose error back into the map. Hector's
    /// own default (0.4 m) is for fast robots with 30 m scanners.
    pub map_update_distance_m: f64,
    /// …or once it turned more than this, rad, > 0. 0.06 rad is the Hector tutorial's value:
    /// turning moves a beam's end at 2 m by 0.12 m, about as far as the distance threshold.
    pub map_update_angle_rad: f64,
    /// Scanner position ahead of base_link, m (not checked): the sensor node's
    /// `laser_x_offset`.
    pub laser_x_offset_m: f64,
    /// Gauss–Newton iterations on each coarse level, ≥ 0 (not checked; Hector: 3).
    pub iterations_coarse: usize,
    /// Gauss–Newton iterations on the finest level, ≥ 1 (Hector: 5).
    pub iterations_fine: usize,
    /// Readings shorter than this are not used, m, in [0, `max_range_m`). It keeps parts of the
    /// robot or a follower right beside it out of the map.
    pub min_range_m: f64,
    /// Readings longer than this are not used, m, > 0 (readings outside the scan's own valid
    /// range never are).
    pub max_range_m: f64,
    /// Hector's `update_factor_occupied`, in (0.5, 1) (see [`crate::grid`]).
    pub update_factor_occupied: f64,
    /// Hector's `update_factor_free`, in (0, 0.5).
    pub update_factor_free: f64,
    /// Log-odds are clamped to ± this, > 0.
    pub log_odds_limit: f32,
    /// The map field scans are matched to (see [`MatchField`]): `reflection`, or `occupancy`,
    /// Hector's, which pulls the pose toward walls in view with a 240° scanner.
    pub match_field: MatchField,
    /// How far past a beam's end the cells count as exposed, for the reflection field, m, ≥ 0:
    /// about twice the range noise at the longest ranges (1 % of 5 m).
    pub reflection_margin_m: f64,
    /// Reflection rate at which the matched field reads 1, in (0, 1] (0.25–1 all did about as
    /// well on the synthetic room).
    pub reflection_saturation: f32,
}

impl Default for SlamParams {
    fn default() -> Self {
        Self {
            resolution: 0.025,
            levels: 3,
            map_size: 512,
            map_center: None,
            map_update_distance_m: 0.1,
            map_update_angle_rad: 0.06,
            laser_x_offset_m: 0.0,
            iterations_coarse: 3,
            iterations_fine: 5,
            min_range_m: 0.1,
            max_range_m: 5.6,
            update_factor_occupied: 0.9,
            update_factor_free: 0.4,
            log_odds_limit: crate::grid::DEFAULT_LOG_ODDS_LIMIT,
            match_field: MatchField::default(),
            reflection_margin_m: crate::grid::DEFAULT_REFLECTION_MARGIN,
            reflection_saturation: crate::grid::DEFAULT_REFLECTION_SATURATION,
        }
    }
}

impl SlamParams {
    /// Checks what serde cannot; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |v: f64, name: &str| {
            (v.is_finite() && v > 0.0)
                .then_some(())
                .ok_or(format!("{name} must be positive, got {v}"))
        };
        let within = |v: f64, name: &str, low: f64, high: f64| {
            (low..=high)
                .contains(&v)
                .then_some(())
                .ok_or(format!("{name} must be in [{low}, {high}], got {v}"))
        };
        // Ranges up to 10 km, cells within RESOLUTION_RANGE_M.
        let (low, high) = (*RESOLUTION_RANGE_M.start(), *RESOLUTION_RANGE_M.end());
        within(self.resolution, "resolution (m)", low, high)?;
        positive(self.map_update_distance_m, "map_update_distance_m")?;
        positive(self.map_update_angle_rad, "map_update_angle_rad")?;
        within(self.max_range_m, "max_range_m", f64::MIN_POSITIVE, 10_000.0)?;
        if !(1..=5).contains(&self.levels) {
            return Err(format!("levels must be 1..=5, got {}", self.levels));
        }
        let step = 1usize << (self.levels - 1);
        if self.map_size > MAP_MAX_SIDE
            || self.map_size < 4 * step
            || !self.map_size.is_multiple_of(step)
        {
            return Err(format!(
                "map_size must be a multiple of {step} (2^(levels − 1)) in {}..={MAP_MAX_SIDE}, got {}",
                4 * step,
                self.map_size
            ));
        }
        if !(self.min_range_m >= 0.0 && self.min_range_m < self.max_range_m) {
            return Err(format!(
                "min_range_m must be in [0, max_range_m), got {}",
                self.min_range_m
            ));
        }
        if self.iterations_fine == 0 {
            return Err("iterations_fine must be at least 1".into());
        }
        if !(self.update_factor_occupied > 0.5 && self.update_factor_occupied < 1.0) {
            return Err("update_factor_occupied must be in (0.5, 1)".into());
        }
        if !(self.update_factor_free > 0.0 && self.update_factor_free < 0.5) {
            return Err("update_factor_free must be in (0, 0.5)".into());
        }
        if !(self.reflection_margin_m.is_finite() && self.reflection_margin_m >= 0.0) {
            return Err("reflection_margin_m must be non-negative".into());
        }
        if !(self.reflection_saturation > 0.0 && self.reflection_saturation <= 1.0) {
            return Err("reflection_saturation must be in (0, 1]".into());
        }
        if self.log_odds_limit.is_nan() || self.log_odds_limit <= 0.0 {
            return Err("log_odds_limit must be positive".into());
        }
        if let Some(c) = self.map_center
            && !(c[0].is_finite() && c[1].is_finite())
        {
            return Err("map_center must be finite".into());
        }
        Ok(())
    }
}

/// Unit direction of each beam, recomputed only when the scan geometry changes.
#[derive(Debug, Default)]
struct Beams {
    key: (f32, f32, u32),
    dirs: Vec<[f64; 2]>,
}

impl Beams {
    fn of(&mut self, scan: &LaserScan) -> &[[f64; 2]] {
        let key = (scan.angle_min, scan.angle_increment, scan.beam_count);
        if key != self.key || self.dirs.is_empty() {
            self.key = key;
            self.dirs.clear();
            self.dirs.extend((0..scan.ranges().len()).map(|i| {
                let a = scan.angle_min as f64 + i as f64 * scan.angle_increment as f64;
                let (s, c) = a.sin_cos();
                [c, s]
            }));
        }
        &self.dirs
    }
}

/// Appends the valid end points of `scan` to `out`, robot frame (m), for a scanner
/// `laser_x_offset` ahead of base_link; readings outside both the scan's and
/// `[min_range, max_range]` are dropped.
fn push_points(
    scan: &LaserScan,
    dirs: &[[f64; 2]],
    laser_x_offset: f64,
    min_range: f64,
    max_range: f64,
    out: &mut Vec<[f64; 2]>,
) {
    let lo = min_range.max(scan.range_min as f64);
    let hi = max_range.min(scan.range_max as f64);
    for (&r, d) in scan.ranges().iter().zip(dirs) {
        let r = r as f64;
        if r >= lo && r <= hi {
            out.push([laser_x_offset + r * d[0], r * d[1]]);
        }
    }
}

/// The valid end points of `scan` in the robot frame (see [`Slam`] for which are valid).
pub fn scan_to_points(
    scan: &LaserScan,
    laser_x_offset: f64,
    min_range: f64,
    max_range: f64,
) -> Vec<[f64; 2]> {
    let mut beams = Beams::default();
    let mut out = Vec::new();
    push_points(
        scan,
        beams.of(scan),
        laser_x_offset,
        min_range,
        max_range,
        &mut out,
    );
    out
}

/// `a ∘ b`: pose `b`, given in the frame of `a`, in `a`'s parent frame.
fn compose(a: &Pose2D, b: &Pose2D) -> Pose2D {
    let (s, c) = a.theta.sin_cos();
    Pose2D {
        x: a.x + c * b.x - s * b.y,
        y: a.y + s * b.x + c * b.y,
        theta: wrap_angle(a.theta + b.theta),
    }
}

/// `a⁻¹ ∘ b`: pose `b` in the frame of `a`.
fn relative(a: &Pose2D, b: &Pose2D) -> Pose2D {
    let (s, c) = a.theta.sin_cos();
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    Pose2D {
        x: c * dx + s * dy,
        y: -s * dx + c * dy,
        theta: wrap_angle(b.theta - a.theta),
    }
}

/// The leader's laser SLAM.
#[derive(Debug)]
pub struct Slam {
    params: SlamParams,
    /// Finest level first.
    maps: Vec<OccupancyMap>,
    pose: Pose2D,
    previous: Pose2D,
    last_map_update: Option<Pose2D>,
    last_match: Option<MatchResult>,
    beams: Beams,
    /// End points of the current scan per level (robot frame): all of them, every 2nd, …
    points: Vec<Vec<[f64; 2]>>,
    endpoints: Vec<[f64; 2]>,
    hits: Vec<bool>,
}

impl Slam {
    /// A SLAM with empty maps and the robot at `initial` (map frame).
    pub fn new(params: SlamParams, initial: Pose2D) -> Result<Self, String> {
        params.validate()?;
        let center = params.map_center.unwrap_or([initial.x, initial.y]);
        let half = params.map_size as f64 * params.resolution / 2.0;
        let finest = OccupancyMap::new(
            params.resolution,
            [center[0] - half, center[1] - half],
            params.map_size,
            params.map_size,
        )
        .with_updates(
            params.update_factor_occupied,
            params.update_factor_free,
            params.log_odds_limit,
        )
        .with_reflection(params.reflection_margin_m, params.reflection_saturation);
        let maps: Vec<OccupancyMap> = (0..params.levels).map(|l| finest.coarser(1 << l)).collect();
        Ok(Self {
            points: vec![Vec::new(); params.levels],
            params,
            maps,
            pose: initial,
            previous: initial,
            last_map_update: None,
            last_match: None,
            beams: Beams::default(),
            endpoints: Vec::new(),
            hits: Vec::new(),
        })
    }

    pub fn params(&self) -> &SlamParams {
        &self.params
    }

    /// The latest pose estimate of base_link in the map frame.
    pub fn pose(&self) -> Pose2D {
        self.pose
    }

    /// Map level `level` (0 = finest).
    pub fn map(&self, level: usize) -> &OccupancyMap {
        &self.maps[level]
    }

    /// The finest level's match of the latest scan (`None` before the first match).
    pub fn last_match(&self) -> Option<&MatchResult> {
        self.last_match.as_ref()
    }

    /// Writes the finest map level into `out`.
    pub fn write_grid(&self, out: &mut OccupancyGrid) {
        self.maps[0].write_grid(out);
    }

    /// Processes one scan and returns the new pose estimate.
    pub fn update(&mut self, scan: &LaserScan) -> Pose2D {
        self.prepare_points(scan);
        let Some(last) = self.last_map_update else {
            // The first scan builds the initial map at the initial pose.
            if self.points[0].len() >= MIN_POINTS {
                self.update_maps();
            }
            return self.pose;
        };
        // Constant velocity: repeat the last motion, in the robot frame.
        let step = relative(&self.previous, &self.pose);
        let mut estimate = compose(&self.pose, &step);
        if self.points[0].len() >= MIN_POINTS {
            for level in (0..self.maps.len()).rev() {
                let iterations = if level == 0 {
                    self.params.iterations_fine
                } else {
                    self.params.iterations_coarse
                };
                let result = match_scan(
                    &self.maps[level],
                    self.params.match_field,
                    &self.points[level],
                    estimate,
                    iterations,
                );
                estimate = result.pose;
                if level == 0 {
                    self.last_match = Some(result);
                }
            }
        }
        self.previous = self.pose;
        self.pose = estimate;
        let moved = relative(&last, &estimate);
        if moved.x.hypot(moved.y) > self.params.map_update_distance_m
            || moved.theta.abs() > self.params.map_update_angle_rad
        {
            self.update_maps();
        }
        self.pose
    }

    /// Mapping with known poses: writes the scan into the maps at `pose` (under the same
    /// movement thresholds as [`Slam::update`]) without matching, and returns `pose`. For
    /// ablations where the leader's localisation is ideal but its map is still built.
    pub fn update_with_pose(&mut self, scan: &LaserScan, pose: Pose2D) -> Pose2D {
        self.prepare_points(scan);
        self.previous = self.pose;
        self.pose = pose;
        let due = self.last_map_update.is_none_or(|last| {
            let moved = relative(&last, &pose);
            moved.x.hypot(moved.y) > self.params.map_update_distance_m
                || moved.theta.abs() > self.params.map_update_angle_rad
        });
        if due && self.points[0].len() >= MIN_POINTS {
            self.update_maps();
        }
        self.pose
    }

    fn prepare_points(&mut self, scan: &LaserScan) {
        let dirs = self.beams.of(scan);
        let [all, coarse @ ..] = self.points.as_mut_slice() else {
            unreachable!("at least one level");
        };
        all.clear();
        push_points(
            scan,
            dirs,
            self.params.laser_x_offset_m,
            self.params.min_range_m,
            self.params.max_range_m,
            all,
        );
        for (l, pts) in coarse.iter_mut().enumerate() {
            pts.clear();
            pts.extend(all.iter().step_by(2 << l));
        }
    }

    /// Writes the current scan at the current pose into every level.
    fn update_maps(&mut self) {
        let (s, c) = self.pose.theta.sin_cos();
        let (px, py) = (self.pose.x, self.pose.y);
        self.endpoints.clear();
        self.endpoints.extend(
            self.points[0]
                .iter()
                .map(|p| [px + c * p[0] - s * p[1], py + s * p[0] + c * p[1]]),
        );
        self.hits.clear();
        self.hits.resize(self.endpoints.len(), true);
        let off = self.params.laser_x_offset_m;
        let origin = [px + c * off, py + s * off];
        for map in &mut self.maps {
            map.update(origin, &self.endpoints, &self.hits);
        }
        self.last_map_update = Some(self.pose);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::Room;

    #[test]
    fn params_defaults_and_checks() {
        let p: SlamParams = serde_json::from_str(r#"{"map_size": 256}"#).unwrap();
        assert_eq!(p.map_size, 256);
        assert_eq!(p.resolution, 0.025);
        assert!(serde_json::from_str::<SlamParams>(r#"{"map_sise": 256}"#).is_err());
        let bad = |f: fn(&mut SlamParams), name: &str| {
            let mut p = SlamParams::default();
            f(&mut p);
            let e = p.validate().unwrap_err();
            assert!(e.contains(name), "{e}");
        };
        bad(|p| p.map_size = 2048, "map_size");
        bad(|p| p.map_size = 514, "map_size");
        bad(|p| p.resolution = 0.0, "resolution");
        bad(|p| p.min_range_m = 6.0, "min_range_m");
        bad(|p| p.levels = 0, "levels");
        assert!(SlamParams::default().validate().is_ok());
    }

    #[test]
    fn pose_algebra() {
        let a = Pose2D {
            x: 1.0,
            y: 2.0,
            theta: 0.5,
        };
        let b = Pose2D {
            x: -0.3,
            y: 0.7,
            theta: 2.9,
        };
        let back = relative(&a, &compose(&a, &b));
        assert!((back.x - b.x).abs() < 1e-12 && (back.y - b.y).abs() < 1e-12);
        assert!((back.theta - b.theta).abs() < 1e-12);
    }

    #[test]
    fn points_drop_invalid_readings_and_apply_the_offset() {
        let room = Room::default();
        let pose = Pose2D {
            x: 1.0,
            y: 1.0,
            theta: 0.0,
        };
        let mut scan = room.scan(&pose, 0.1, None);
        scan.ranges[0] = 0.0;
        scan.ranges[1] = scan.range_max + 1.0;
        scan.ranges[2] = 0.05;
        let pts = scan_to_points(&scan, 0.1, 0.1, 5.6);
        assert_eq!(pts.len(), 679);
        // The middle beam sees the far wall at x = 4 (3 m from base_link at x = 1).
        let mid = pts[340 - 3];
        assert!(
            (mid[0] - 3.0).abs() < 0.01 && mid[1].abs() < 0.01,
            "{mid:?}"
        );
    }

    #[test]
    fn first_scan_builds_the_map_at_the_initial_pose() {
        let room = Room::default();
        let pose = Pose2D {
            x: 1.0,
            y: 1.0,
            theta: 0.0,
        };
        let params = SlamParams {
            map_size: 256,
            ..Default::default()
        };
        let mut slam = Slam::new(params, pose).unwrap();
        assert_eq!(slam.update(&room.scan(&pose, 0.0, None)), pose);
        let map = slam.map(0);
        // The far wall at x = 4 is 3 m ahead; the map is centred on the robot.
        let (ix, iy) = map.cell_of(4.01, 1.0).unwrap();
        assert!(map.probability(ix, iy) > 0.8);
        let (ix, iy) = map.cell_of(2.5, 1.0).unwrap();
        assert!(map.probability(ix, iy) < 0.5);
        assert!(slam.map(2).probability(ix / 4, iy / 4) < 0.5);
        // Standing still: the same scan gives the same pose and no map update.
        let again = slam.update(&room.scan(&pose, 0.0, None));
        assert!(
            (again.x - 1.0).hypot(again.y - 1.0) < 0.01 && again.theta.abs() < 0.01,
            "{again:?}"
        );
        assert!(slam.last_match().unwrap().points > 600);
    }
}
