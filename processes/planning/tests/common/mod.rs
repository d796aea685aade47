//! Test maps drawn with rectangles, in metres, on a 0.025 m grid whose origin is (0, 0).

#![allow(dead_code)]

use caravan_planning::{Costmap, CostmapParams, INSCRIBED, LETHAL};
use caravan_schemas::Pose2D;

pub const RES: f64 = 0.025;

pub struct Sketch {
    pub w: usize,
    pub h: usize,
    pub cells: Vec<i8>,
}

impl Sketch {
    /// A `width_m × height_m` map filled with `fill` (0 free, 100 occupied, −1 unknown).
    pub fn new(width_m: f64, height_m: f64, fill: i8) -> Self {
        let (w, h) = (
            (width_m / RES).round() as usize,
            (height_m / RES).round() as usize,
        );
        Self {
            w,
            h,
            cells: vec![fill; w * h],
        }
    }

    /// Sets every cell whose centre lies in `[x0, x1] × [y0, y1]` to `value`.
    pub fn rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, value: i8) -> &mut Self {
        for iy in 0..self.h {
            let cy = (iy as f64 + 0.5) * RES;
            if cy < y0 || cy > y1 {
                continue;
            }
            for ix in 0..self.w {
                let cx = (ix as f64 + 0.5) * RES;
                if cx >= x0 && cx <= x1 {
                    self.cells[iy * self.w + ix] = value;
                }
            }
        }
        self
    }

    /// Walls `t` metres thick along the map's edges.
    pub fn border(&mut self, t: f64) -> &mut Self {
        let (wm, hm) = (self.w as f64 * RES, self.h as f64 * RES);
        self.rect(0.0, 0.0, wm, t, 100)
            .rect(0.0, hm - t, wm, hm, 100)
            .rect(0.0, 0.0, t, hm, 100)
            .rect(wm - t, 0.0, wm, hm, 100)
    }

    pub fn costmap(&self) -> Costmap {
        Costmap::from_cells(
            RES,
            Pose2D::default(),
            self.w,
            self.h,
            &self.cells,
            &CostmapParams::default(),
        )
    }
}

pub fn pose(x: f64, y: f64, theta: f64) -> Pose2D {
    Pose2D { x, y, theta }
}

/// The highest cost met along the path's polyline, sampled every 2 mm.
pub fn max_cost_along(costmap: &Costmap, path: &[Pose2D]) -> u8 {
    let mut worst = 0;
    for w in path.windows(2) {
        let len = (w[1].x - w[0].x).hypot(w[1].y - w[0].y);
        let n = (len / 0.002).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (x, y) = (
                w[0].x + (w[1].x - w[0].x) * t,
                w[0].y + (w[1].y - w[0].y) * t,
            );
            worst = worst.max(costmap.cost_at(x, y).unwrap_or(LETHAL));
        }
    }
    worst
}

/// Asserts that no point of the path is in an obstacle or inflated cell.
pub fn assert_clear(costmap: &Costmap, path: &[Pose2D]) {
    let worst = max_cost_along(costmap, path);
    assert!(
        worst < INSCRIBED,
        "path enters an inflated cell (cost {worst})"
    );
}
