//! Global planner: the least-cost route over the whole costmap, from the robot to the goal.
//!
//! move_base's navfn runs Dijkstra; this is A* with the octile distance as heuristic. Every
//! step costs at least its length (`length × (1 + cost_weight · cost / 252)`), so the octile
//! distance never overestimates and A* returns the same optimal route as Dijkstra while
//! expanding far fewer cells. Moves are 8-connected; a diagonal move may not cut the corner of
//! an impassable cell. Impassable means [`INSCRIBED`] or [`crate::LETHAL`]: the costmap has
//! already grown obstacles by the robot radius, so the robot is planned as a point.
//!
//! The grid route is then shortcut: a run of cells is replaced by a straight segment when the
//! segment's exact cost (the line integral over the cells it crosses) is no higher, so
//! smoothing never makes the route worse by the planner's own measure nor brings it into an
//! inflated cell. Finally poses are laid every `path_spacing` metres, each facing along the
//! path. The goal's heading is not used: the leader cannot turn in place (v ≥ 0.1 m/s).

use crate::costmap::{Costmap, INSCRIBED, MAX_INFLATED};
use crate::error::PlanError;
use crate::path::poses_along;
use crate::trace::segment_cells;
use caravan_schemas::Pose2D;
use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Global planner parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct GlobalParams {
    /// How much a costly cell lengthens a step, ≥ 0: a step costs `length × (1 + cost_weight ·
    /// cost / 252)`. navfn's `COST_FACTOR` and `COST_NEUTRAL` amount to about 4.
    pub cost_weight: f64,
    /// If the robot stands on an inflated cell (close to a wall), plan from the nearest free
    /// cell within this distance instead of failing, m, ≥ 0.
    pub start_escape_radius: f64,
    /// Search this far beyond the known part of the map (and the start and goal), m, 0 to
    /// 10000. Beyond it the map is uniformly unknown, so a detour further out never pays.
    pub search_margin: f64,
    /// Largest distance between consecutive poses of the returned path, m, > 0.
    pub path_spacing: f64,
    /// Replace runs of grid cells by straight segments where that costs no more.
    pub shortcut: bool,
}

impl Default for GlobalParams {
    fn default() -> Self {
        Self {
            cost_weight: 4.0,
            start_escape_radius: 0.3,
            search_margin: 1.0,
            path_spacing: 0.05,
            shortcut: true,
        }
    }
}

impl GlobalParams {
    /// Checks that the parameters make sense.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            ("cost_weight", self.cost_weight, 0.0),
            ("start_escape_radius", self.start_escape_radius, 0.0),
            ("search_margin", self.search_margin, 0.0),
        ];
        for (name, v, min) in checks {
            if !(v.is_finite() && v >= min) {
                return Err(format!("{name} must be ≥ {min}, got {v}"));
            }
        }
        if !(self.path_spacing.is_finite() && self.path_spacing > 0.0) {
            return Err(format!(
                "path_spacing must be positive, got {}",
                self.path_spacing
            ));
        }
        // Lengths in metres beyond any map (10 km) would overflow cell arithmetic.
        for (name, v) in [
            ("start_escape_radius", self.start_escape_radius),
            ("search_margin", self.search_margin),
            ("path_spacing", self.path_spacing),
        ] {
            if v > 10_000.0 {
                return Err(format!("{name} must be at most 10000 m, got {v}"));
            }
        }
        Ok(())
    }
}

/// 8-connected moves: (dx, dy, length in cells). Diagonals last.
const MOVES: [(i32, i32, f32); 8] = [
    (1, 0, 1.0),
    (-1, 0, 1.0),
    (0, 1, 1.0),
    (0, -1, 1.0),
    (1, 1, core::f32::consts::SQRT_2),
    (1, -1, core::f32::consts::SQRT_2),
    (-1, 1, core::f32::consts::SQRT_2),
    (-1, -1, core::f32::consts::SQRT_2),
];
const CLOSED: u8 = 0x80;

/// Longest straight segment the shortcut tries, cells.
const MAX_SHORTCUT_CELLS: usize = 200;
/// Consecutive failed shortcut candidates before giving up on a longer one.
const SHORTCUT_PATIENCE: usize = 8;

/// A* over a [`Costmap`]. Keeps its search buffers between calls so re-planning does not
/// allocate.
#[derive(Debug, Clone)]
pub struct GlobalPlanner {
    params: GlobalParams,
    /// Cost from the start per cell of the search region.
    g: Vec<f32>,
    /// Per cell: [`CLOSED`] bit | index+1 of the move that reached it (0: none).
    info: Vec<u8>,
    /// Step-cost factor per cell (∞: impassable), padded by one impassable cell all round.
    factor: Vec<f32>,
    /// One row of costs, copied from the costmap.
    row: Vec<u8>,
    heap: BinaryHeap<Reverse<u64>>,
    expanded: usize,
}

/// The rectangle of cells searched (the search grids add one cell of padding all round).
#[derive(Debug, Clone, Copy)]
struct Region {
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
}

impl GlobalPlanner {
    /// A planner with these parameters; check them first with [`GlobalParams::validate`].
    pub fn new(params: GlobalParams) -> Self {
        Self {
            params,
            g: Vec::new(),
            info: Vec::new(),
            factor: Vec::new(),
            row: Vec::new(),
            heap: BinaryHeap::new(),
            expanded: 0,
        }
    }

    pub fn params(&self) -> &GlobalParams {
        &self.params
    }

    /// Cells expanded by the last [`GlobalPlanner::plan`] (for diagnostics and benchmarks).
    pub fn expanded_cells(&self) -> usize {
        self.expanded
    }

    /// Plans from `start` to `goal` (map frame; headings ignored). The path begins at the
    /// start's position and ends at the goal's; consecutive poses are at most `path_spacing`
    /// apart (except a first segment that leads out of an inflated start), each heading along
    /// the path.
    pub fn plan(
        &mut self,
        costmap: &Costmap,
        start: Pose2D,
        goal: Pose2D,
    ) -> Result<Vec<Pose2D>, PlanError> {
        let (sp, gp) = ((start.x, start.y), (goal.x, goal.y));
        let bounds = costmap.bounds();
        let start_cell = costmap
            .world_to_cell(start.x, start.y)
            .ok_or(PlanError::StartOutsideMap { start: sp, bounds })?;
        let goal_cell = costmap
            .world_to_cell(goal.x, goal.y)
            .ok_or(PlanError::GoalOutsideMap { goal: gp, bounds })?;
        if costmap.cost(goal_cell.0, goal_cell.1) >= INSCRIBED {
            return Err(PlanError::GoalInCollision {
                goal: gp,
                robot_radius: costmap.robot_radius(),
            });
        }
        let escaped = costmap.cost(start_cell.0, start_cell.1) >= INSCRIBED;
        let from = if escaped {
            self.nearest_free(costmap, start_cell)
                .ok_or(PlanError::StartInCollision {
                    start: sp,
                    search_radius: self.params.start_escape_radius,
                })?
        } else {
            start_cell
        };

        let cells = self.search(costmap, from, goal_cell).map_err(|e| match e {
            SearchFailure::Exhausted {
                touched_border: true,
                ..
            } => PlanError::GoalEnclosed {
                start: sp,
                goal: gp,
            },
            SearchFailure::Exhausted { closed, .. } => PlanError::StartEnclosed {
                start: sp,
                goal: gp,
                reachable_area: closed as f64 * costmap.resolution().powi(2),
            },
        })?;

        // Grid route in continuous cell coordinates, with the exact start and goal.
        let start_g = costmap.world_to_grid(start.x, start.y);
        let goal_g = costmap.world_to_grid(goal.x, goal.y);
        let mut pts: Vec<(f64, f64)> = Vec::with_capacity(cells.len() + 2);
        if escaped {
            pts.push(start_g);
        }
        pts.extend(cells.iter().map(|&(x, y)| (x as f64 + 0.5, y as f64 + 0.5)));
        if !escaped {
            pts[0] = start_g;
        }
        let last = pts.len() - 1;
        if last == 0 {
            pts.push(goal_g);
        } else {
            pts[last] = goal_g;
        }
        let first = usize::from(escaped);
        if self.params.shortcut {
            let tail = self.shortcut(costmap, &pts[first..]);
            pts.truncate(first);
            pts.extend(tail);
        }
        let world: Vec<(f64, f64)> = pts
            .iter()
            .map(|&(gx, gy)| costmap.grid_to_world(gx, gy))
            .collect();
        let keep_whole: &[usize] = if escaped { &[0] } else { &[] };
        Ok(poses_along(
            &world,
            self.params.path_spacing,
            keep_whole,
            start.theta,
        ))
    }

    /// Nearest cell (by distance) that is not inflated, within the escape radius.
    fn nearest_free(&self, costmap: &Costmap, (sx, sy): (usize, usize)) -> Option<(usize, usize)> {
        let r = (self.params.start_escape_radius / costmap.resolution()).ceil() as i64;
        let mut best: Option<((usize, usize), i64)> = None;
        for dy in -r..=r {
            for dx in -r..=r {
                let d2 = dx * dx + dy * dy;
                if d2 > r * r || best.is_some_and(|(_, b)| d2 >= b) {
                    continue;
                }
                let (x, y) = (sx as i64 + dx, sy as i64 + dy);
                if costmap.cost_i(x, y) < INSCRIBED {
                    best = Some(((x as usize, y as usize), d2));
                }
            }
        }
        best.map(|(c, _)| c)
    }

    /// A* from `from` to `to` (cells); returns the cells of the route, both ends included.
    ///
    /// The region's step-cost factors are copied into a grid padded with one impassable cell
    /// on every side, so the inner loop needs no bounds checks and no costmap look-ups.
    fn search(
        &mut self,
        costmap: &Costmap,
        from: (usize, usize),
        to: (usize, usize),
    ) -> Result<Vec<(usize, usize)>, SearchFailure> {
        let region = self.region(costmap, from, to);
        let (pw, ph) = (region.w + 2, region.h + 2);
        let n = pw * ph;
        let factor = self.cost_factors();
        self.factor.clear();
        self.factor.resize(n, f32::INFINITY);
        self.row.resize(region.w, 0);
        for y in 0..region.h {
            costmap.costs_in_row(region.y0 + y, region.x0, &mut self.row);
            let out = &mut self.factor[(y + 1) * pw + 1..][..region.w];
            for (f, &c) in out.iter_mut().zip(&self.row) {
                *f = factor[usize::from(c)];
            }
        }
        self.g.clear();
        self.g.resize(n, f32::INFINITY);
        self.info.clear();
        self.info.resize(n, 0);
        self.heap.clear();
        self.expanded = 0;

        let padded = |(x, y): (usize, usize)| (y - region.y0 + 1) * pw + (x - region.x0 + 1);
        let (tx, ty) = ((to.0 - region.x0 + 1) as i32, (to.1 - region.y0 + 1) as i32);
        let heuristic = |x: i32, y: i32| {
            let (dx, dy) = (
                (x - tx).unsigned_abs() as f32,
                (y - ty).unsigned_abs() as f32,
            );
            dx.max(dy) + (core::f32::consts::SQRT_2 - 1.0) * dx.min(dy)
        };
        // Heap entries are single u64s, f's bits above the cell index: non-negative floats
        // order like their bits, and 8-byte entries keep the heap (the search's hot spot)
        // compact. Stale entries are skipped when popped.
        let key = |f: f32, idx: usize| (u64::from(f.to_bits()) << 32) | idx as u64;
        let start = padded(from);
        let goal = padded(to);
        self.g[start] = 0.0;
        let (sx, sy) = ((start % pw) as i32, (start / pw) as i32);
        self.heap.push(Reverse(key(heuristic(sx, sy), start)));
        let offsets = MOVES.map(|(dx, dy, _)| dy as isize * pw as isize + dx as isize);
        let mut touched_border = false;

        while let Some(Reverse(k)) = self.heap.pop() {
            let idx = (k & 0xffff_ffff) as usize;
            if self.info[idx] & CLOSED != 0 {
                continue;
            }
            self.info[idx] |= CLOSED;
            self.expanded += 1;
            if idx == goal {
                return Ok(self.route(region, pw, start, goal));
            }
            let (x, y) = ((idx % pw) as i32, (idx / pw) as i32);
            touched_border |= x == 1 || y == 1 || x == pw as i32 - 2 || y == ph as i32 - 2;
            let g = self.g[idx];
            for (m, &(dx, dy, len)) in MOVES.iter().enumerate() {
                // In range: the expanded cell is inside the padding.
                let nidx = idx.wrapping_add_signed(offsets[m]);
                let f = self.factor[nidx];
                if f == f32::INFINITY || self.info[nidx] & CLOSED != 0 {
                    continue;
                }
                if dx != 0
                    && dy != 0
                    && (self.factor[idx.wrapping_add_signed(dx as isize)] == f32::INFINITY
                        || self.factor[idx.wrapping_add_signed(offsets[m] - dx as isize)]
                            == f32::INFINITY)
                {
                    continue;
                }
                let ng = g + len * f;
                if ng < self.g[nidx] {
                    self.g[nidx] = ng;
                    self.info[nidx] = m as u8 + 1;
                    let h = heuristic(x + dx, y + dy);
                    self.heap.push(Reverse(key(ng + h, nidx)));
                }
            }
        }
        Err(SearchFailure::Exhausted {
            touched_border,
            closed: self.expanded,
        })
    }

    /// The searched rectangle: the known window, start and goal, plus the search margin.
    fn region(&self, costmap: &Costmap, from: (usize, usize), to: (usize, usize)) -> Region {
        let (mut x0, mut y0) = (from.0.min(to.0), from.1.min(to.1));
        let (mut x1, mut y1) = (from.0.max(to.0) + 1, from.1.max(to.1) + 1);
        let known = costmap.known_window();
        if !known.is_empty() {
            x0 = x0.min(known.x0);
            y0 = y0.min(known.y0);
            x1 = x1.max(known.x0 + known.w);
            y1 = y1.max(known.y0 + known.h);
        }
        let m = (self.params.search_margin / costmap.resolution()).ceil() as usize;
        let (x0, y0) = (x0.saturating_sub(m), y0.saturating_sub(m));
        let (x1, y1) = (
            (x1 + m).min(costmap.width()),
            (y1 + m).min(costmap.height()),
        );
        Region {
            x0,
            y0,
            w: x1 - x0,
            h: y1 - y0,
        }
    }

    /// Step cost multiplier per cell cost.
    fn cost_factors(&self) -> [f32; 256] {
        let mut f = [f32::INFINITY; 256];
        for (c, v) in f.iter_mut().enumerate().take(usize::from(INSCRIBED)) {
            *v = (1.0 + self.params.cost_weight * c as f64 / f64::from(MAX_INFLATED)) as f32;
        }
        f
    }

    /// Follows the recorded moves back from the goal (indices in the padded grid).
    fn route(&self, region: Region, pw: usize, start: usize, goal: usize) -> Vec<(usize, usize)> {
        let mut cells = Vec::new();
        let mut idx = goal;
        loop {
            cells.push((region.x0 + idx % pw - 1, region.y0 + idx / pw - 1));
            if idx == start {
                break;
            }
            let (dx, dy, _) = MOVES[usize::from(self.info[idx] & !CLOSED) - 1];
            idx = idx.wrapping_add_signed(-(dy as isize * pw as isize + dx as isize));
        }
        cells.reverse();
        cells
    }

    /// Greedy shortcutting: from each kept point, jump to the furthest later point whose
    /// straight segment is collision-free and costs no more than the route it replaces.
    fn shortcut(&self, costmap: &Costmap, pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let factor = self.cost_factors();
        let line = |a: (f64, f64), b: (f64, f64)| {
            let mut sum = 0.0f64;
            let clear = segment_cells(a, b, |x, y, len| {
                let c = costmap.cost_i(x, y);
                sum += len * f64::from(factor[usize::from(c)]);
                c < INSCRIBED
            });
            (sum, clear)
        };
        // Cost of the route up to each point (a blocked step, possible only where the exact
        // start or goal sits off-centre by an inflated corner, counts at its length).
        let mut prefix = Vec::with_capacity(pts.len());
        prefix.push(0.0);
        for w in pts.windows(2) {
            let (c, clear) = line(w[0], w[1]);
            let c = if clear {
                c
            } else {
                (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1)
            };
            prefix.push(prefix.last().copied().unwrap_or(0.0) + c);
        }
        let mut out = vec![pts[0]];
        let mut i = 0;
        while i + 1 < pts.len() {
            let mut best = i + 1;
            let mut fails = 0;
            for j in i + 2..pts.len().min(i + MAX_SHORTCUT_CELLS) {
                let (c, clear) = line(pts[i], pts[j]);
                if clear && c <= prefix[j] - prefix[i] + 1e-9 {
                    best = j;
                    fails = 0;
                } else {
                    fails += 1;
                    if fails > SHORTCUT_PATIENCE {
                        break;
                    }
                }
            }
            out.push(pts[best]);
            i = best;
        }
        out
    }
}

enum SearchFailure {
    /// Every reachable cell was expanded without meeting the goal.
    Exhausted { touched_border: bool, closed: usize },
}
