//! The costmap: an occupancy grid turned into traversal costs for a robot of a given size.
//!
//! It follows ROS costmap_2d's static + inflation layers so that move_base's behaviour carries
//! over: occupied cells are [`LETHAL`]; cells closer to an obstacle than the robot's radius are
//! [`INSCRIBED`] (the robot's centre there means a collision); further out the cost decays as
//! `252·exp(−k·(d − r))` up to the inflation radius, so planners keep a margin where there is
//! room. The leader's footprint is a 0.20 × 0.18 m rectangle; its circumscribed radius (plus
//! padding) is used as the collision radius, so a centre-point check is safe at any heading.
//!
//! Unknown cells are traversable (move_base's `allow_unknown`): the leader explores a world it
//! has never seen, and its goals usually lie in unmapped space. They may carry a small cost so
//! that known free space is preferred.
//!
//! Only the bounding box of known cells (plus a margin wider than the inflation radius) is
//! transformed; everything outside it is unknown, far from any obstacle,
//! and costs [`CostmapParams::unknown_cost`]. An early SLAM map is mostly unknown, so this
//! keeps rebuilds cheap.

use crate::edt;
use crate::window::{CellWindow, known_window};
use caravan_schemas::{OccupancyGrid, Pose2D};
use serde::{Deserialize, Serialize};

/// Cost of a cell far from obstacles.
pub const FREE: u8 = 0;
/// Highest cost of a cell the robot can occupy (just outside the collision radius).
pub const MAX_INFLATED: u8 = 252;
/// Cost of a cell within the robot's collision radius of an obstacle: a collision.
pub const INSCRIBED: u8 = 253;
/// Cost of an occupied cell, and of anything off the map.
pub const LETHAL: u8 = 254;

/// How occupancy becomes cost. Deserialised from the planner's parameter file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct CostmapParams {
    /// Occupancy at or above which a cell is an obstacle, percent, 1 … 100 (costmap_2d's
    /// `occupied_thresh` 0.65).
    pub occupied_threshold: i8,
    /// Robot footprint along its heading, metres: the URDF's chassis box (the node sets it
    /// from the robot description; not a launch-file key).
    #[serde(skip)]
    pub footprint_length: f64,
    /// Robot footprint across its heading, metres (from the URDF, as the length).
    #[serde(skip)]
    pub footprint_width: f64,
    /// Added to the footprint's circumscribed radius, m, ≥ 0 (costmap_2d's
    /// `footprint_padding`); it also absorbs the cell discretisation of the distance. Robot
    /// radius = ½·hypot(length, width) + padding = 0.1445 m by default.
    pub footprint_padding: f64,
    /// Distance from obstacles beyond which cells cost nothing, m, ≥ the robot radius.
    pub inflation_radius: f64,
    /// Decay rate k of the inflated cost 252·exp(−k·(d − r)), 1/m, > 0.
    pub cost_scaling_factor: f64,
    /// Cost of an unknown cell, 0 … 252.
    pub unknown_cost: u8,
}

impl Default for CostmapParams {
    fn default() -> Self {
        Self {
            occupied_threshold: 65,
            // The convoy robot's chassis; the node takes it from the URDF.
            footprint_length: 0.20,
            footprint_width: 0.18,
            footprint_padding: 0.01,
            // costmap_2d defaults.
            inflation_radius: 0.55,
            cost_scaling_factor: 10.0,
            unknown_cost: 10,
        }
    }
}

impl CostmapParams {
    /// The collision radius: the footprint's circumscribed radius plus padding (0.1445 m by
    /// default).
    pub fn robot_radius(&self) -> f64 {
        0.5 * self.footprint_length.hypot(self.footprint_width) + self.footprint_padding
    }

    /// Checks that the parameters make sense.
    pub fn validate(&self) -> Result<(), String> {
        if !(1..=100).contains(&self.occupied_threshold) {
            return Err(format!(
                "occupied_threshold must be in 1..=100 (percent), got {}",
                self.occupied_threshold
            ));
        }
        let positive = [
            ("footprint_length", self.footprint_length),
            ("footprint_width", self.footprint_width),
            ("cost_scaling_factor", self.cost_scaling_factor),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} must be positive, got {v}"));
            }
        }
        if !(self.footprint_padding.is_finite() && self.footprint_padding >= 0.0) {
            return Err(format!(
                "footprint_padding must be ≥ 0, got {}",
                self.footprint_padding
            ));
        }
        if !(self.inflation_radius.is_finite() && self.inflation_radius >= self.robot_radius()) {
            return Err(format!(
                "inflation_radius ({} m) must be at least the robot radius ({:.3} m)",
                self.inflation_radius,
                self.robot_radius()
            ));
        }
        if self.unknown_cost > MAX_INFLATED {
            return Err(format!(
                "unknown_cost must be ≤ {MAX_INFLATED}, got {}",
                self.unknown_cost
            ));
        }
        Ok(())
    }
}

/// Traversal costs and obstacle clearance over an occupancy grid's extent.
#[derive(Clone)]
pub struct Costmap {
    params: CostmapParams,
    robot_radius: f64,
    resolution: f64,
    origin: Pose2D,
    cos: f64,
    sin: f64,
    width: usize,
    height: usize,
    /// Where costs were computed; outside it every cell is unknown and far from obstacles.
    window: CellWindow,
    /// Cell costs inside `window`, row-major.
    cost: Vec<u8>,
    /// Squared distance to the nearest obstacle in cells², saturated at `cap²`, inside `window`.
    d2: Vec<u16>,
    /// Saturation distance in cells; also the window's margin around known cells.
    cap: u16,
    /// Clearance in metres and cost, indexed by squared cell distance `0 ..= cap²`.
    clearance_lut: Vec<f32>,
    cost_lut: Vec<u8>,
    scratch: edt::Scratch,
}

impl core::fmt::Debug for Costmap {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Costmap")
            .field("resolution", &self.resolution)
            .field("origin", &self.origin)
            .field("width", &self.width)
            .field("height", &self.height)
            .field("window", &self.window)
            .field("robot_radius", &self.robot_radius)
            .finish_non_exhaustive()
    }
}

impl Costmap {
    /// Builds the costmap of an occupancy grid (taken by reference: it is ~1 MiB).
    pub fn from_grid(grid: &OccupancyGrid, params: &CostmapParams) -> Self {
        let mut map = Self::empty(params);
        map.update(grid);
        map
    }

    /// Builds a costmap from raw cells (row-major, `width` per row, −1 unknown, 0 … 100
    /// occupancy), e.g. in tests.
    ///
    /// # Panics
    /// If `cells` holds fewer than `width × height` values.
    pub fn from_cells(
        resolution: f64,
        origin: Pose2D,
        width: usize,
        height: usize,
        cells: &[i8],
        params: &CostmapParams,
    ) -> Self {
        let mut map = Self::empty(params);
        map.update_from_cells(resolution, origin, width, height, cells);
        map
    }

    /// An empty (0 × 0) costmap; every point is off the map until [`Costmap::update`].
    pub fn empty(params: &CostmapParams) -> Self {
        Self {
            params: params.clone(),
            robot_radius: params.robot_radius(),
            resolution: 1.0,
            origin: Pose2D::default(),
            cos: 1.0,
            sin: 0.0,
            width: 0,
            height: 0,
            window: CellWindow::default(),
            cost: Vec::new(),
            d2: Vec::new(),
            cap: 0,
            clearance_lut: Vec::new(),
            cost_lut: Vec::new(),
            scratch: edt::Scratch::default(),
        }
    }

    /// Rebuilds from a new map, reusing this costmap's buffers.
    pub fn update(&mut self, grid: &OccupancyGrid) {
        let width = grid.width as usize;
        let cells = grid.cells();
        let height = cells
            .len()
            .checked_div(width)
            .map_or(0, |rows| rows.min(grid.height as usize));
        self.update_from_cells(grid.resolution, grid.origin, width, height, cells);
    }

    /// Rebuilds from raw cells, reusing this costmap's buffers. A non-positive or non-finite
    /// resolution yields an empty costmap (a malformed map must not bring the planner down).
    ///
    /// # Panics
    /// If `cells` holds fewer than `width × height` values.
    pub fn update_from_cells(
        &mut self,
        resolution: f64,
        origin: Pose2D,
        width: usize,
        height: usize,
        cells: &[i8],
    ) {
        assert!(
            cells.len() >= width * height,
            "costmap: {} cells given for a {width} × {height} grid",
            cells.len()
        );
        let valid = resolution.is_finite() && resolution > 0.0;
        let (width, height) = if valid { (width, height) } else { (0, 0) };
        if resolution != self.resolution || self.clearance_lut.is_empty() {
            self.resolution = if valid { resolution } else { 1.0 };
            self.build_luts();
        }
        self.origin = origin;
        (self.sin, self.cos) = origin.theta.sin_cos();
        self.width = width;
        self.height = height;
        let cells = &cells[..width * height];

        self.window = known_window(cells, width, height, usize::from(self.cap));
        let win = self.window;
        let n = win.w * win.h;
        self.d2.clear();
        self.d2.resize(n, 0);
        let threshold = self.params.occupied_threshold;
        edt::squared_distances(
            &mut self.d2,
            win.w,
            self.cap,
            |y| &cells[(win.y0 + y) * width + win.x0..],
            |c| c >= threshold,
            &mut self.scratch,
        );
        self.cost.clear();
        self.cost.reserve(n);
        let unknown_cost = self.params.unknown_cost;
        for row in 0..win.h {
            let src = &cells[(win.y0 + row) * width + win.x0..][..win.w];
            let d2 = &self.d2[row * win.w..][..win.w];
            self.cost.extend(src.iter().zip(d2).map(|(&c, &d)| {
                let cost = self.cost_lut[usize::from(d)];
                if c < 0 { cost.max(unknown_cost) } else { cost }
            }));
        }
    }

    /// Tables from squared cell distance to clearance and cost, for this resolution.
    fn build_luts(&mut self) {
        let res = self.resolution;
        let p = &self.params;
        let reach = p.inflation_radius.max(self.robot_radius);
        // Saturate just beyond the inflation radius: (cap − ½)·res > reach.
        self.cap = ((reach / res + 0.5).ceil() + 1.0).clamp(2.0, 255.0) as u16;
        let cap2 = usize::from(self.cap) * usize::from(self.cap);
        self.clearance_lut.clear();
        self.cost_lut.clear();
        for d2 in 0..=cap2 {
            let clearance = clearance_of(d2, res);
            self.clearance_lut.push(clearance as f32);
            self.cost_lut.push(if d2 == 0 {
                LETHAL
            } else if clearance < self.robot_radius {
                INSCRIBED
            } else if clearance <= p.inflation_radius {
                let c = f64::from(MAX_INFLATED)
                    * (-p.cost_scaling_factor * (clearance - self.robot_radius)).exp();
                c.round().min(f64::from(MAX_INFLATED)) as u8
            } else {
                FREE
            });
        }
    }

    pub fn params(&self) -> &CostmapParams {
        &self.params
    }

    /// Collision radius used for [`INSCRIBED`] cells, metres.
    pub fn robot_radius(&self) -> f64 {
        self.robot_radius
    }

    /// Metres per cell.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Pose of cell (0, 0)'s corner.
    pub fn origin(&self) -> Pose2D {
        self.origin
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The cells whose cost was computed (known cells plus a margin); outside it, cells
    /// are unknown and far from obstacles.
    pub fn known_window(&self) -> CellWindow {
        self.window
    }

    /// Largest value [`Costmap::clearance`] returns: a little beyond the inflation radius.
    pub fn max_clearance(&self) -> f64 {
        clearance_of(
            usize::from(self.cap) * usize::from(self.cap),
            self.resolution,
        )
    }

    /// The map's axis-aligned extent in the world: `(min_x, min_y, max_x, max_y)`.
    pub fn bounds(&self) -> (f64, f64, f64, f64) {
        let (w, h) = (
            self.width as f64 * self.resolution,
            self.height as f64 * self.resolution,
        );
        let corners = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)].map(|(mx, my)| {
            (
                self.origin.x + self.cos * mx - self.sin * my,
                self.origin.y + self.sin * mx + self.cos * my,
            )
        });
        corners.iter().fold(
            (
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), &(x, y)| (a.min(x), b.min(y), c.max(x), d.max(y)),
        )
    }

    /// Continuous cell coordinates of a world point: cell `(i, j)` spans `[i, i+1) × [j, j+1)`.
    pub fn world_to_grid(&self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.origin.x, y - self.origin.y);
        (
            (self.cos * dx + self.sin * dy) / self.resolution,
            (-self.sin * dx + self.cos * dy) / self.resolution,
        )
    }

    /// World coordinates of continuous cell coordinates.
    pub fn grid_to_world(&self, gx: f64, gy: f64) -> (f64, f64) {
        let (mx, my) = (gx * self.resolution, gy * self.resolution);
        (
            self.origin.x + self.cos * mx - self.sin * my,
            self.origin.y + self.sin * mx + self.cos * my,
        )
    }

    /// The cell containing a world point, if it is on the map.
    pub fn world_to_cell(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let (gx, gy) = self.world_to_grid(x, y);
        self.grid_cell(gx, gy)
    }

    /// The cell containing continuous cell coordinates, if on the map.
    pub fn grid_cell(&self, gx: f64, gy: f64) -> Option<(usize, usize)> {
        // Negative and NaN coordinates fail the comparisons.
        (gx >= 0.0 && gy >= 0.0 && gx < self.width as f64 && gy < self.height as f64)
            .then_some((gx as usize, gy as usize))
    }

    /// World coordinates of a cell's centre.
    pub fn cell_to_world(&self, ix: usize, iy: usize) -> (f64, f64) {
        self.grid_to_world(ix as f64 + 0.5, iy as f64 + 0.5)
    }

    /// Cost of a cell; [`LETHAL`] off the map.
    #[inline]
    pub fn cost(&self, ix: usize, iy: usize) -> u8 {
        if ix >= self.width || iy >= self.height {
            LETHAL
        } else if self.window.contains(ix, iy) {
            self.cost[(iy - self.window.y0) * self.window.w + ix - self.window.x0]
        } else {
            self.params.unknown_cost
        }
    }

    /// Copies the costs of row `iy`, columns `x0 .. x0 + out.len()`, into `out` ([`LETHAL`]
    /// off the map): the bulk form of [`Costmap::cost`] for searches.
    pub(crate) fn costs_in_row(&self, iy: usize, x0: usize, out: &mut [u8]) {
        if iy >= self.height {
            out.fill(LETHAL);
            return;
        }
        let win = self.window;
        if !(iy >= win.y0 && iy < win.y0 + win.h) || win.is_empty() {
            for (i, o) in out.iter_mut().enumerate() {
                *o = self.cost(x0 + i, iy);
            }
            return;
        }
        let row = &self.cost[(iy - win.y0) * win.w..][..win.w];
        for (i, o) in out.iter_mut().enumerate() {
            let x = x0 + i;
            *o = if x >= self.width {
                LETHAL
            } else if x >= win.x0 && x < win.x0 + win.w {
                row[x - win.x0]
            } else {
                self.params.unknown_cost
            };
        }
    }

    /// Cost of a cell with signed indices; [`LETHAL`] off the map.
    #[inline]
    pub(crate) fn cost_i(&self, ix: i64, iy: i64) -> u8 {
        match (usize::try_from(ix), usize::try_from(iy)) {
            (Ok(x), Ok(y)) => self.cost(x, y),
            _ => LETHAL,
        }
    }

    /// Cost at a world point, or `None` off the map.
    pub fn cost_at(&self, x: f64, y: f64) -> Option<u8> {
        self.world_to_cell(x, y).map(|(ix, iy)| self.cost(ix, iy))
    }

    /// Whether the robot's centre at this point means a collision: an obstacle, within the
    /// robot radius of one, or off the map.
    pub fn is_lethal(&self, x: f64, y: f64) -> bool {
        self.cost_at(x, y).is_none_or(|c| c >= INSCRIBED)
    }

    /// Clearance of a cell, metres; 0 off the map.
    #[inline]
    pub fn cell_clearance(&self, ix: usize, iy: usize) -> f64 {
        if ix >= self.width || iy >= self.height {
            0.0
        } else if self.window.contains(ix, iy) {
            let d2 = self.d2[(iy - self.window.y0) * self.window.w + ix - self.window.x0];
            f64::from(self.clearance_lut[usize::from(d2)])
        } else {
            self.max_clearance()
        }
    }

    /// Distance from the point's cell to the nearest obstacle cell's edge, metres (centre to
    /// centre minus half a cell), saturated at [`Costmap::max_clearance`]; 0 in an obstacle
    /// or off the map. The robot's centre collides where this is below
    /// [`Costmap::robot_radius`].
    pub fn clearance(&self, x: f64, y: f64) -> f64 {
        self.world_to_cell(x, y)
            .map_or(0.0, |(ix, iy)| self.cell_clearance(ix, iy))
    }
}

/// Clearance in metres of a cell whose squared distance to an obstacle is `d2` cells².
fn clearance_of(d2: usize, res: f64) -> f64 {
    if d2 == 0 {
        0.0
    } else {
        ((d2 as f64).sqrt() - 0.5) * res
    }
}

#[cfg(test)]
mod tests;
