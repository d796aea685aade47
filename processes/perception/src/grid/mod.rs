//! A log-odds occupancy grid, updated Hector-style from laser scans.
//!
//! Each cell holds the log-odds `l = ln(p / (1 − p))` that it is occupied, starting at 0
//! (p = 0.5, unknown). A beam that ends in a cell adds the "hit" update and every cell it
//! crossed on the way gets the "pass" (free) update, as in Hector SLAM's
//! `GridMapLogOddsFunctions` with its default factors p_hit = 0.9 (+2.197) and p_pass = 0.4
//! (−0.405). Log-odds are clamped to ±[`DEFAULT_LOG_ODDS_LIMIT`] so that a cell that was free or
//! occupied for a long time can still change its mind (Hector caps only the occupied side).
//!
//! Near the sensor many beams cross the same cell; counting each would make near cells far
//! more certain than far ones and let a single scan saturate them. As in Hector (its
//! `updateIndex`), a cell takes at most one pass and one hit update per scan, and a hit wins
//! over a pass in the same scan.
//!
//! The probability `1 / (1 + e^−l)` of every cell is cached beside its log-odds because the
//! scan matcher reads four of them per point per iteration, while writes happen only at map
//! updates.
//!
//! Beside the occupancy, each cell keeps the counts of a reflection field, which is what
//! Caravan's matcher uses by default (see [`OccupancyMap`] for what it is and why).
//!
//! Cells are squares of side `resolution`; cell (ix, iy) covers
//! `[origin + ix·res, origin + (ix + 1)·res)` in x (and likewise in y), row-major, `ix` fastest.
//! Its value is taken to sit at the cell's centre when interpolating.

use caravan_schemas::{MAP_MAX_SIDE, OccupancyGrid, Pose2D};

/// Log-odds of Hector's default hit update, p = 0.9.
pub const LOG_ODDS_HIT: f32 = 2.197_224_6;
/// Log-odds of Hector's default pass (free) update, p = 0.4.
pub const LOG_ODDS_PASS: f32 = -0.405_465_1;
/// Default bound on |log-odds|: Hector's occupied cap, applied to both sides.
pub const DEFAULT_LOG_ODDS_LIMIT: f32 = 50.0;

/// Occupancy probability from which [`OccupancyMap::write_grid`] writes a cell as occupied.
pub const OCCUPIED_PROBABILITY: f32 = 0.66;
/// The value of an occupied cell that never reflected; one that always reflects reads 100.
pub const OCCUPIED_MIN: i8 = 66;

/// Log-odds of probability `p`.
pub fn log_odds(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

/// Probability of log-odds `l`. Beyond ±16 the answer is within 1.2e-7 of 0 or 1, so the
/// exponential is skipped there: saturated cells are cheap to update.
#[inline]
fn probability_of(l: f32) -> f32 {
    if l <= -16.0 {
        0.0
    } else if l >= 16.0 {
        1.0
    } else {
        1.0 / (1.0 + (-l).exp())
    }
}

/// Default extension of a beam's exposure past its end point, m (see [`OccupancyMap`]).
pub const DEFAULT_REFLECTION_MARGIN: f64 = 0.1;
/// Default reflection rate at and above which the matched field reads 1. Capping the ridge
/// top keeps the Gauss–Newton steps sane: without it the residual 1 − M stays large at the
/// top of a low ridge and each step overshoots (see [`crate::matcher`]).
pub const DEFAULT_REFLECTION_SATURATION: f32 = 0.5;

/// A log-odds occupancy grid, with a reflection field beside it for scan matching.
///
/// **Reflection field.** Besides the occupancy, each cell counts how often a beam ended in
/// it (`hits`, split bilinearly over the four cells around the end point, so the count keeps
/// the end point's sub-cell position) and how often a beam could have ended in it
/// (`exposure`: the beam crossed it, or the cell lies within `reflection_margin` behind the
/// beam's end), each at most once per scan. Their ratio is the rate at which beams reflect in
/// the cell: across a wall it is a ridge centred on the mean of the end points, as wide as the
/// range noise. The matched field is that rate over a saturation level, capped at 1. The occupancy
/// probability is instead a plateau: every cell behind the face that a long noisy reading ever
/// reached is occupied, while the cells in front only turn occupied where the short readings
/// outnumber the passes. Matching end points to that plateau pulls the pose toward the walls
/// in view by about the range noise (only noticeable with a scanner that does not see all
/// around, like the 240° URG); matching them to the ridge does not (see [`crate::matcher`]).
#[derive(Debug, Clone)]
pub struct OccupancyMap {
    resolution: f64,
    origin: [f64; 2],
    width: usize,
    height: usize,
    hit: f32,
    pass: f32,
    limit: f32,
    reflection_margin: f64,
    /// 1 / the reflection rate at which the matched field saturates.
    reflection_scale: f32,
    log_odds: Vec<f32>,
    /// Cached occupancy probability of each cell (0.5 where unknown).
    prob: Vec<f32>,
    /// Stamp of the last occupancy update of each cell; 0 = never updated.
    mark: Vec<u32>,
    /// Reflection counts, their cached ratio, and this scan's hit weight per cell.
    hits: Vec<f32>,
    exposure: Vec<f32>,
    reflection: Vec<f32>,
    scan_hit: Vec<f32>,
    /// Stamp of the last exposure of each cell (`scan_hit` is valid when it is this scan's).
    exposure_mark: Vec<u32>,
    /// Stamp of the current scan; its pass mark is `stamp − 1`, its hit mark `stamp`.
    stamp: u32,
}

impl OccupancyMap {
    /// An unknown map of `width × height` cells of side `resolution` (m) whose cell (0, 0) has
    /// its corner at `origin` (m), with Hector's default update factors.
    pub fn new(resolution: f64, origin: [f64; 2], width: usize, height: usize) -> Self {
        assert!(
            resolution > 0.0 && width >= 2 && height >= 2,
            "a map needs a positive resolution and at least 2 × 2 cells"
        );
        let n = width * height;
        Self {
            resolution,
            origin,
            width,
            height,
            hit: LOG_ODDS_HIT,
            pass: LOG_ODDS_PASS,
            limit: DEFAULT_LOG_ODDS_LIMIT,
            reflection_margin: DEFAULT_REFLECTION_MARGIN,
            reflection_scale: 1.0 / DEFAULT_REFLECTION_SATURATION,
            log_odds: vec![0.0; n],
            prob: vec![0.5; n],
            mark: vec![0; n],
            hits: vec![0.0; n],
            exposure: vec![0.0; n],
            reflection: vec![0.0; n],
            scan_hit: vec![0.0; n],
            exposure_mark: vec![0; n],
            stamp: 0,
        }
    }

    /// Sets the update factors as probabilities (Hector's `update_factor_occupied` and
    /// `update_factor_free`) and the log-odds bound.
    pub fn with_updates(mut self, p_hit: f64, p_pass: f64, limit: f32) -> Self {
        assert!(
            p_hit > 0.5 && p_hit < 1.0 && p_pass > 0.0 && p_pass < 0.5 && limit > 0.0,
            "need 0.5 < p_hit < 1, 0 < p_pass < 0.5 and a positive limit"
        );
        self.hit = log_odds(p_hit);
        self.pass = log_odds(p_pass);
        self.limit = limit;
        self
    }

    /// Sets how far past a beam's end point (m) the cells count as exposed to it (a few times
    /// the range noise, so that the reflection ridge of a wall is not cut off behind its face),
    /// and the reflection rate at which the matched field saturates at 1.
    pub fn with_reflection(mut self, margin: f64, saturation: f32) -> Self {
        assert!(margin >= 0.0, "the reflection margin cannot be negative");
        assert!(
            saturation > 0.0 && saturation <= 1.0,
            "saturation must be in (0, 1]"
        );
        self.reflection_margin = margin;
        self.reflection_scale = 1.0 / saturation;
        self
    }

    /// An empty map over the same area with cells `factor` times larger (the coarser levels of
    /// a multi-resolution map, which are updated with the same scans rather than derived).
    pub fn coarser(&self, factor: usize) -> Self {
        assert!(factor >= 1);
        let mut m = Self::new(
            self.resolution * factor as f64,
            self.origin,
            self.width.div_ceil(factor),
            self.height.div_ceil(factor),
        );
        (m.hit, m.pass, m.limit) = (self.hit, self.pass, self.limit);
        m.reflection_margin = self.reflection_margin;
        m.reflection_scale = self.reflection_scale;
        m
    }

    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Corner of cell (0, 0), m.
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// Cell containing world point (x, y), if inside the map.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let u = ((x - self.origin[0]) / self.resolution).floor();
        let v = ((y - self.origin[1]) / self.resolution).floor();
        (u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64)
            .then_some((u as usize, v as usize))
    }

    /// Log-odds of cell (ix, iy); panics outside the map.
    pub fn log_odds(&self, ix: usize, iy: usize) -> f32 {
        self.log_odds[self.index(ix, iy)]
    }

    /// Occupancy probability of cell (ix, iy) (0.5 if unknown); panics outside the map.
    pub fn probability(&self, ix: usize, iy: usize) -> f32 {
        self.prob[self.index(ix, iy)]
    }

    /// Matched reflection field of cell (ix, iy): hits / exposure / saturation, at most 1; 0 if
    /// never exposed.
    pub fn reflection(&self, ix: usize, iy: usize) -> f32 {
        self.reflection[self.index(ix, iy)]
    }

    /// Whether cell (ix, iy) was ever updated; panics outside the map.
    pub fn is_known(&self, ix: usize, iy: usize) -> bool {
        self.mark[self.index(ix, iy)] != 0
    }

    fn index(&self, ix: usize, iy: usize) -> usize {
        assert!(ix < self.width && iy < self.height, "cell outside the map");
        iy * self.width + ix
    }

    /// Occupancy probability at world point (x, y), bilinearly interpolated between cell
    /// centres, and its gradient (per metre): `(M, ∂M/∂x, ∂M/∂y)`. `None` where the four cells
    /// around the point are not all inside the map (Hector's `interpMapValueWithDerivatives`).
    #[inline]
    pub fn interpolated(&self, x: f64, y: f64) -> Option<(f64, f64, f64)> {
        self.bilinear(&self.prob, x, y)
    }

    /// The reflection rate at (x, y), interpolated like [`Self::interpolated`].
    #[inline]
    pub fn interpolated_reflection(&self, x: f64, y: f64) -> Option<(f64, f64, f64)> {
        self.bilinear(&self.reflection, x, y)
    }

    #[inline]
    fn bilinear(&self, field: &[f32], x: f64, y: f64) -> Option<(f64, f64, f64)> {
        let inv = 1.0 / self.resolution;
        // Continuous cell coordinates with cell centres at integers.
        let u = (x - self.origin[0]) * inv - 0.5;
        let v = (y - self.origin[1]) * inv - 0.5;
        let (u0, v0) = (u.floor(), v.floor());
        if !(u0 >= 0.0
            && v0 >= 0.0
            && u0 < (self.width - 1) as f64
            && v0 < (self.height - 1) as f64)
        {
            return None;
        }
        let (fx, fy) = (u - u0, v - v0);
        let i = v0 as usize * self.width + u0 as usize;
        let (m00, m10) = (field[i] as f64, field[i + 1] as f64);
        let (m01, m11) = (
            field[i + self.width] as f64,
            field[i + self.width + 1] as f64,
        );
        let bottom = m00 + fx * (m10 - m00);
        let top = m01 + fx * (m11 - m01);
        let value = bottom + fy * (top - bottom);
        let du = (m10 - m00) * (1.0 - fy) + (m11 - m01) * fy;
        let dv = top - bottom;
        Some((value, du * inv, dv * inv))
    }

    /// Updates the map with one scan: `endpoints[i]` (world frame) is where beam i from
    /// `sensor_origin` ended, and `hits[i]` whether it ended on a surface. Every beam clears the
    /// cells it crossed; a hit also marks its end cell occupied. A beam that was not a hit
    /// (a no-return capped at some distance) clears its end cell too. Parts of beams outside
    /// the map are ignored; an end point outside the map is not a hit.
    pub fn update(&mut self, sensor_origin: [f64; 2], endpoints: &[[f64; 2]], hits: &[bool]) {
        assert_eq!(endpoints.len(), hits.len(), "one hit flag per endpoint");
        self.next_stamp();
        let (pass_mark, hit_mark) = (self.stamp - 1, self.stamp);
        // Hits first, so that the passes of this scan skip cells a beam ended in.
        for (end, _) in endpoints.iter().zip(hits).filter(|(_, h)| **h) {
            if let Some((ix, iy)) = self.cell_of(end[0], end[1]) {
                let i = iy * self.width + ix;
                if self.mark[i] < hit_mark {
                    self.mark[i] = hit_mark;
                    self.add(i, self.hit);
                }
            }
            self.splat_hit(*end);
        }
        for (end, &hit) in endpoints.iter().zip(hits) {
            if let Some((a, b)) = self.clip(sensor_origin, *end) {
                for c in Bresenham::new(a, b, self.width) {
                    if self.mark[c] < pass_mark {
                        self.mark[c] = pass_mark;
                        self.add(c, self.pass);
                    }
                    self.expose(c);
                }
            }
            if hit && self.reflection_margin > 0.0 {
                let d = [end[0] - sensor_origin[0], end[1] - sensor_origin[1]];
                let k = self.reflection_margin / d[0].hypot(d[1]).max(1e-9);
                let beyond = [end[0] + k * d[0], end[1] + k * d[1]];
                if let Some((a, b)) = self.clip(*end, beyond) {
                    for c in Bresenham::new(a, b, self.width) {
                        self.expose(c);
                    }
                }
            }
        }
    }

    /// Adds a hit at `end` to the reflection counts of the four cells around it, with bilinear
    /// weights; a cell takes at most one whole hit per scan (like its exposure), so that the
    /// rate stays within 0..1 however many beams end in it.
    fn splat_hit(&mut self, end: [f64; 2]) {
        let inv = 1.0 / self.resolution;
        let u = (end[0] - self.origin[0]) * inv - 0.5;
        let v = (end[1] - self.origin[1]) * inv - 0.5;
        let (u0, v0) = (u.floor(), v.floor());
        let (fx, fy) = (u - u0, v - v0);
        for (du, dv, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (cu, cv) = (u0 + du, v0 + dv);
            if cu < 0.0 || cv < 0.0 || cu >= self.width as f64 || cv >= self.height as f64 {
                continue;
            }
            let c = cv as usize * self.width + cu as usize;
            self.expose(c);
            let w = (w as f32).min(1.0 - self.scan_hit[c]);
            if w > 0.0 {
                self.hits[c] += w;
                self.scan_hit[c] += w;
                self.reflection[c] =
                    (self.hits[c] * self.reflection_scale / self.exposure[c]).min(1.0);
            }
        }
    }

    /// Counts cell `c` as exposed to this scan (once per scan).
    #[inline]
    fn expose(&mut self, c: usize) {
        if self.exposure_mark[c] != self.stamp {
            self.exposure_mark[c] = self.stamp;
            self.scan_hit[c] = 0.0;
            self.exposure[c] += 1.0;
            self.reflection[c] = (self.hits[c] * self.reflection_scale / self.exposure[c]).min(1.0);
        }
    }

    /// Advances the scan stamp by two (a pass and a hit mark), renumbering on wrap-around.
    fn next_stamp(&mut self) {
        if self.stamp >= u32::MAX - 2 {
            for m in self.mark.iter_mut().chain(&mut self.exposure_mark) {
                *m = (*m != 0) as u32;
            }
            self.stamp = 1;
        }
        self.stamp += 2;
    }

    #[inline]
    fn add(&mut self, i: usize, delta: f32) {
        let l = (self.log_odds[i] + delta).clamp(-self.limit, self.limit);
        self.log_odds[i] = l;
        self.prob[i] = probability_of(l);
    }

    /// The segment a → b (world) clipped to the map (Liang–Barsky), as cell indices of its
    /// two ends.
    fn clip(&self, a: [f64; 2], b: [f64; 2]) -> Option<([i64; 2], [i64; 2])> {
        let inv = 1.0 / self.resolution;
        let a = [(a[0] - self.origin[0]) * inv, (a[1] - self.origin[1]) * inv];
        let b = [(b[0] - self.origin[0]) * inv, (b[1] - self.origin[1]) * inv];
        let d = [b[0] - a[0], b[1] - a[1]];
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        // Keep a hair inside the far edges so that floor() stays below width and height.
        let hi = [self.width as f64 - 1e-9, self.height as f64 - 1e-9];
        for k in 0..2 {
            for (p, q) in [(-d[k], a[k]), (d[k], hi[k] - a[k])] {
                if p == 0.0 {
                    if q < 0.0 {
                        return None;
                    }
                } else {
                    let r = q / p;
                    if p < 0.0 {
                        t0 = t0.max(r);
                    } else {
                        t1 = t1.min(r);
                    }
                }
            }
        }
        if t0 > t1 {
            return None;
        }
        let at = |t: f64| {
            [
                (a[0] + t * d[0]).floor().clamp(0.0, hi[0]) as i64,
                (a[1] + t * d[1]).floor().clamp(0.0, hi[1]) as i64,
            ]
        };
        Some((at(t0), at(t1)))
    }

    /// Writes the map into `out` as nav_msgs/OccupancyGrid values: −1 where never updated (or
    /// back at log-odds 0), else round(100·p). Panics if the map is larger than
    /// [`MAP_MAX_SIDE`] on a side.
    pub fn write_grid(&self, out: &mut OccupancyGrid) {
        assert!(
            self.width <= MAP_MAX_SIDE && self.height <= MAP_MAX_SIDE,
            "map larger than an OccupancyGrid"
        );
        out.resolution = self.resolution;
        out.origin = Pose2D {
            x: self.origin[0],
            y: self.origin[1],
            theta: 0.0,
        };
        out.width = self.width as u32;
        out.height = self.height as u32;
        let cells = self.log_odds.iter().zip(&self.prob).zip(&self.mark);
        for (c, (o, ((&l, &p), &m))) in out.data.iter_mut().zip(cells).enumerate() {
            *o = if m == 0 || l == 0.0 {
                -1
            } else if p >= OCCUPIED_PROBABILITY {
                // Occupied cells carry their reflection rate, so that a surface can be
                // located inside its occupied band (see `survey`); all stay above the
                // occupied threshold.
                let rate = if self.exposure[c] > 0.0 {
                    (self.hits[c] / self.exposure[c]).min(1.0)
                } else {
                    0.0
                };
                OCCUPIED_MIN + (rate * f32::from(100 - OCCUPIED_MIN)).round() as i8
            } else {
                (100.0 * p).round() as i8
            };
        }
    }
}

/// Cell indices of a Bresenham line from cell `a` to cell `b` (both inside a map `width`
/// cells wide), both ends included.
struct Bresenham {
    index: isize,
    left: i64,
    err: i64,
    major: i64,
    minor: i64,
    step_major: isize,
    step_minor: isize,
}

impl Bresenham {
    fn new(a: [i64; 2], b: [i64; 2], width: usize) -> Self {
        let w = width as isize;
        let (dx, dy) = ((b[0] - a[0]).abs(), (b[1] - a[1]).abs());
        let sx: isize = if b[0] >= a[0] { 1 } else { -1 };
        let sy: isize = if b[1] >= a[1] { w } else { -w };
        // Step along the major axis every time, along the minor one when the error says so.
        let (major, minor, step_major, step_minor) = if dx >= dy {
            (dx, dy, sx, sy)
        } else {
            (dy, dx, sy, sx)
        };
        Self {
            index: a[1] as isize * w + a[0] as isize,
            left: major + 1,
            err: major / 2,
            major,
            minor,
            step_major,
            step_minor,
        }
    }
}

impl Iterator for Bresenham {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let c = self.index as usize;
        self.err -= self.minor;
        if self.err < 0 {
            self.err += self.major;
            self.index += self.step_minor;
        }
        self.index += self.step_major;
        Some(c)
    }
}

#[cfg(test)]
mod tests;
