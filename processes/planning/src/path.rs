//! Paths as lists of poses: building them from polylines, checking them against a changed
//! map, and packing them into a [`Path2D`] message.

use crate::costmap::{Costmap, INSCRIBED};
use crate::trace::segment_cells;
use caravan_schemas::{PATH_MAX_POSES, Path2D, Pose2D};

/// Total length of a path, metres.
pub fn path_length(path: &[Pose2D]) -> f64 {
    path.windows(2)
        .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y))
        .sum()
}

/// Index of the pose nearest to `(x, y)`, or `None` for an empty path.
pub fn nearest_pose_index(path: &[Pose2D], x: f64, y: f64) -> Option<usize> {
    path.iter()
        .enumerate()
        .map(|(i, p)| (i, (p.x - x).powi(2) + (p.y - y).powi(2)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Whether the path, from pose `from_index` on, now crosses an obstacle or an inflated
/// ([`INSCRIBED`]) cell, or leaves the map: the node should re-plan. Every cell the polyline
/// passes through is checked, not just the poses.
///
/// Pass an index ahead of the robot (e.g. [`nearest_pose_index`] + 1): the robot's own
/// surroundings may be inflated when it drives close to a wall, and a path planned from an
/// inflated start begins with a single segment straight out to free space.
pub fn path_blocked(costmap: &Costmap, path: &[Pose2D], from_index: usize) -> bool {
    let rest = path.get(from_index..).unwrap_or(&[]);
    let free = |gx: f64, gy: f64| {
        costmap
            .grid_cell(gx, gy)
            .is_some_and(|(ix, iy)| costmap.cost(ix, iy) < INSCRIBED)
    };
    match rest {
        [] => false,
        [only] => {
            let (gx, gy) = costmap.world_to_grid(only.x, only.y);
            !free(gx, gy)
        }
        _ => rest.windows(2).any(|w| {
            let a = costmap.world_to_grid(w[0].x, w[0].y);
            let b = costmap.world_to_grid(w[1].x, w[1].y);
            !segment_cells(a, b, |ix, iy, _| costmap.cost_i(ix, iy) < INSCRIBED)
        }),
    }
}

/// Copies a path into a [`Path2D`] message; a path longer than [`PATH_MAX_POSES`] is
/// down-sampled evenly by index, keeping its first and last poses. Returns the number of
/// poses stored.
pub fn fill_path2d(out: &mut Path2D, path: &[Pose2D]) -> usize {
    let n = path.len();
    if n <= PATH_MAX_POSES {
        return out.poses.set_from_slice(path);
    }
    out.poses.clear();
    let last = PATH_MAX_POSES - 1;
    for k in 0..PATH_MAX_POSES {
        // Rounded k·(n−1)/last: 0 → first, last → n − 1.
        let i = (k * (n - 1) + last / 2) / last;
        // Capacity is exactly PATH_MAX_POSES, so this never fails.
        let _ = out.poses.push(path[i]);
    }
    PATH_MAX_POSES
}

/// Poses along a polyline, with points inserted so that none are more than `spacing` apart.
/// Every vertex is kept (so the path is exactly the polyline, never cutting its corners),
/// and each pose faces the next one; the last pose keeps the previous heading. Segments in
/// `keep_whole` (by index of their first vertex) are not subdivided.
pub(crate) fn poses_along(
    points: &[(f64, f64)],
    spacing: f64,
    keep_whole: &[usize],
    fallback_theta: f64,
) -> Vec<Pose2D> {
    // A floor on the spacing, so that an unvalidated zero cannot explode the path.
    let spacing = spacing.max(1e-3);
    let mut xy: Vec<(f64, f64)> = Vec::with_capacity(points.len() * 2);
    for (i, &p) in points.iter().enumerate() {
        if let Some(&prev) = xy.last() {
            let (dx, dy) = (p.0 - prev.0, p.1 - prev.1);
            let len = dx.hypot(dy);
            if len < 1e-9 {
                continue;
            }
            let pieces = if keep_whole.contains(&(i - 1)) {
                1
            } else {
                (len / spacing).ceil().max(1.0) as usize
            };
            for k in 1..pieces {
                let t = k as f64 / pieces as f64;
                xy.push((prev.0 + dx * t, prev.1 + dy * t));
            }
        }
        xy.push(p);
    }
    let mut poses: Vec<Pose2D> = xy
        .windows(2)
        .map(|w| Pose2D {
            x: w[0].0,
            y: w[0].1,
            theta: (w[1].1 - w[0].1).atan2(w[1].0 - w[0].0),
        })
        .collect();
    if let Some(&(x, y)) = xy.last() {
        let theta = poses.last().map_or(fallback_theta, |p| p.theta);
        poses.push(Pose2D { x, y, theta });
    }
    poses
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, y: f64) -> Pose2D {
        Pose2D { x, y, theta: 0.0 }
    }

    #[test]
    fn poses_along_keeps_vertices_and_spacing() {
        let poses = poses_along(&[(0.0, 0.0), (1.0, 0.0), (1.0, 0.5)], 0.1, &[], 0.3);
        assert!(poses.windows(2).all(|w| {
            let d = (w[1].x - w[0].x).hypot(w[1].y - w[0].y);
            d <= 0.1 + 1e-9 && d > 0.05
        }));
        assert!(poses.iter().any(|p| p.x == 1.0 && p.y == 0.0));
        assert!((path_length(&poses) - 1.5).abs() < 1e-9);
        assert_eq!(poses[0].theta, 0.0);
        let last = poses.last().unwrap();
        assert!((last.theta - core::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert_eq!(poses_along(&[(2.0, 2.0)], 0.1, &[], 0.3)[0].theta, 0.3);
        // A whole segment stays one segment.
        assert_eq!(
            poses_along(&[(0.0, 0.0), (1.0, 0.0)], 0.1, &[0], 0.0).len(),
            2
        );
    }

    #[test]
    fn fill_path2d_downsamples_keeping_ends() {
        let mut msg = caravan_schemas::boxed_placement_new::<Path2D>();
        let short: Vec<Pose2D> = (0..10).map(|i| pose(f64::from(i), 0.0)).collect();
        assert_eq!(fill_path2d(&mut msg, &short), 10);
        assert_eq!(msg.poses.as_slice(), &short[..]);
        let long: Vec<Pose2D> = (0..3000).map(|i| pose(f64::from(i), 0.0)).collect();
        assert_eq!(fill_path2d(&mut msg, &long), PATH_MAX_POSES);
        let s = msg.poses.as_slice();
        assert_eq!(s.len(), PATH_MAX_POSES);
        assert_eq!(s[0], long[0]);
        assert_eq!(s[PATH_MAX_POSES - 1], long[2999]);
        assert!(
            s.windows(2)
                .all(|w| w[1].x > w[0].x && w[1].x - w[0].x <= 3.0)
        );
    }

    #[test]
    fn nearest_index() {
        let path: Vec<Pose2D> = (0..5).map(|i| pose(f64::from(i), 0.0)).collect();
        assert_eq!(nearest_pose_index(&path, 2.2, 1.0), Some(2));
        assert_eq!(nearest_pose_index(&[], 2.2, 1.0), None);
    }
}
