//! Walking the grid cells a straight segment passes through.
//!
//! Path shortcutting and [`crate::path_blocked`] must not miss a cell that a segment merely
//! clips, or a "clear" path could still brush an inflated obstacle. Sampling points along the
//! segment can miss such corners; the grid traversal of Amanatides & Woo ("A Fast Voxel
//! Traversal Algorithm", 1987) visits every cell exactly and also yields the length of the
//! segment inside each cell, which makes the line integral of cost exact.

/// Calls `visit(ix, iy, length)` for every cell the segment from `a` to `b` passes through,
/// in order. Coordinates are continuous cell coordinates (cell `(i, j)` spans `[i, i+1) ×
/// [j, j+1)`); `length` is the segment's length inside that cell in cells. Cells may have
/// negative indices; the caller decides what lies off the grid. Stops early and returns
/// `false` as soon as `visit` returns `false`.
pub(crate) fn segment_cells(
    a: (f64, f64),
    b: (f64, f64),
    mut visit: impl FnMut(i64, i64, f64) -> bool,
) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let total = dx.hypot(dy);
    let (mut ix, mut iy) = (a.0.floor() as i64, a.1.floor() as i64);
    let (ex, ey) = (b.0.floor() as i64, b.1.floor() as i64);
    let (step_x, t_delta_x, mut t_max_x) = axis(a.0, dx);
    let (step_y, t_delta_y, mut t_max_y) = axis(a.1, dy);
    let mut t = 0.0;
    // A segment crosses at most |Δx| + |Δy| + 2 cells; the bound guards against rounding.
    let max_steps = (ex - ix).unsigned_abs() + (ey - iy).unsigned_abs() + 2;
    for _ in 0..=max_steps {
        let t_next = t_max_x.min(t_max_y).min(1.0);
        if !visit(ix, iy, (t_next - t) * total) {
            return false;
        }
        if t_next >= 1.0 || (ix == ex && iy == ey) {
            return true;
        }
        if (t_max_x - t_max_y).abs() < 1e-12 {
            // Through a corner exactly: also report the cell the corner touches, with no
            // length, so that a point sampled on the corner is never in an unvisited cell.
            if !visit(ix + step_x, iy, 0.0) || !visit(ix, iy + step_y, 0.0) {
                return false;
            }
            ix += step_x;
            iy += step_y;
            t = t_max_x;
            t_max_x += t_delta_x;
            t_max_y += t_delta_y;
        } else if t_max_x < t_max_y {
            ix += step_x;
            t = t_max_x;
            t_max_x += t_delta_x;
        } else {
            iy += step_y;
            t = t_max_y;
            t_max_y += t_delta_y;
        }
    }
    true
}

/// Step direction, parameter step per cell, and parameter of the first cell boundary.
fn axis(start: f64, delta: f64) -> (i64, f64, f64) {
    if delta > 0.0 {
        (1, 1.0 / delta, (start.floor() + 1.0 - start) / delta)
    } else if delta < 0.0 {
        (-1, -1.0 / delta, (start - start.floor()) / -delta)
    } else {
        (0, f64::INFINITY, f64::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(a: (f64, f64), b: (f64, f64)) -> (Vec<(i64, i64)>, f64) {
        let mut v = Vec::new();
        let mut len = 0.0;
        segment_cells(a, b, |x, y, l| {
            v.push((x, y));
            len += l;
            true
        });
        (v, len)
    }

    #[test]
    fn horizontal_segment_visits_each_cell_once() {
        let (v, len) = cells((0.5, 0.5), (3.5, 0.5));
        assert_eq!(v, vec![(0, 0), (1, 0), (2, 0), (3, 0)]);
        assert!((len - 3.0).abs() < 1e-9);
    }

    #[test]
    fn shallow_diagonal_visits_clipped_cells_and_sums_length() {
        let (v, len) = cells((0.2, 0.2), (3.8, 1.9));
        assert_eq!(v.first(), Some(&(0, 0)));
        assert_eq!(v.last(), Some(&(3, 1)));
        assert!((len - 3.6f64.hypot(1.7)).abs() < 1e-9);
        // Every point sampled along the segment lies in a visited cell.
        for k in 0..=1000 {
            let t = f64::from(k) / 1000.0;
            let p = (0.2 + 3.6 * t, 0.2 + 1.7 * t);
            assert!(v.contains(&(p.0.floor() as i64, p.1.floor() as i64)));
        }
    }

    #[test]
    fn exact_corner_crossing_reports_both_touching_cells() {
        let (v, _) = cells((2.5, 0.5), (0.5, 2.5));
        for c in [(2, 0), (2, 1), (1, 1), (1, 2), (0, 2)] {
            assert!(v.contains(&c), "{c:?} missing from {v:?}");
        }
    }

    #[test]
    fn early_stop() {
        let mut n = 0;
        assert!(!segment_cells((0.5, 0.5), (9.5, 0.5), |_, _, _| {
            n += 1;
            n < 3
        }));
        assert_eq!(n, 3);
    }
}
