//! Measuring on a map: how far is the surface? Used by the run report to judge map scale.
//!
//! A surface does not appear on a log-odds map as a sharp free → occupied step at the face:
//! range noise spreads the end points over a band a few σ deep (σ = 1–5 cm for the URG), and
//! the band is lopsided with respect to the face.
//! - **In front**, a cell turns occupied as soon as the short readings that end in it outweigh
//!   the passes of the longer ones, at Hector's factors 1 hit per 5.4 passes; and a cell that
//!   any beam of a scan ended in takes no pass from that scan. With several beams per cell
//!   near a wall, cells up to about 2σ in front of the face end up occupied.
//! - **Behind**, cells only ever see the long readings and their passes, and are occupied
//!   wherever a reading ever ended, up to the longest reading's reach (2–3σ).
//!
//! So the inner edge of the band, where the interpolated probability first crosses 0.5 from
//! the free side (what one would measure by eye on the picture), lies 1–2σ plus up to half a
//! cell in front of the face: on maps built by [`crate::Slam`] from the synthetic room with
//! URG noise (twelve runs, 22 probes of 4 walls each) it read 2.6–5.1 cm short per face (mean
//! 3.7 cm), a −1.9 to −2.4 % scale error in the 4 m × 3 m room. The middle of the band read
//! +0.7 cm per face on the same maps, but +1.2–1.9 cm on the convoy's lab maps, where the
//! band runs up to 5 cm behind the face (+1.4–2 % on 1.8–2 m).
//!
//! The maps Caravan's SLAM writes grade their occupied cells by reflection rate (how often a
//! beam that reached the cell ended there, see `grid::OccupancyMap::write_grid`), which peaks
//! at the face. [`surface_distance`] therefore returns the centroid of the band weighted by
//! the square of that grade (the square favours the ridge's top over its flanks); on maps
//! without grades (plain 0/100 occupancy) it falls back to the middle of the band. On the
//! convoy's maps (lab and hall, 4 surveys) this reads +0.2 to +0.65 % long; [`band`] returns
//! both edges.
//!
//! Where a wall is seen from both sides its band covers the whole wall, and the middle is the
//! wall's middle, not the face: measure such walls with [`band`]'s inner edge instead.
//!
//! Values between cell centres are interpolated bilinearly (unknown cells count as 0.5), and
//! crossings are located by bisection, so the result is not tied to cell boundaries.

use caravan_schemas::OccupancyGrid;

/// Bisection steps locating a crossing: 2⁻³⁰ of a quarter cell.
const BISECTIONS: usize = 30;

/// Occupancy probability of cell (ix, iy): 0..1, or `None` if unknown or outside.
fn cell(grid: &OccupancyGrid, ix: i64, iy: i64) -> Option<f64> {
    if ix < 0 || iy < 0 || ix > u32::MAX as i64 || iy > u32::MAX as i64 {
        return None;
    }
    match grid.get(ix as u32, iy as u32) {
        Some(v) if v >= 0 => Some(v.min(100) as f64 / 100.0),
        _ => None,
    }
}

/// Bilinear occupancy probability at world point `p` between cell centres (unknown cells
/// count as 0.5), and whether the cell containing `p` is known.
fn sample(grid: &OccupancyGrid, p: [f64; 2]) -> (f64, bool) {
    let inv = 1.0 / grid.resolution;
    let u = (p[0] - grid.origin.x) * inv;
    let v = (p[1] - grid.origin.y) * inv;
    let known = cell(grid, u.floor() as i64, v.floor() as i64).is_some();
    let (u, v) = (u - 0.5, v - 0.5);
    let (u0, v0) = (u.floor(), v.floor());
    let (fx, fy) = (u - u0, v - v0);
    let (i, j) = (u0 as i64, v0 as i64);
    let m = |di, dj| cell(grid, i + di, j + dj).unwrap_or(0.5);
    let bottom = m(0, 0) + fx * (m(1, 0) - m(0, 0));
    let top = m(0, 1) + fx * (m(1, 1) - m(0, 1));
    (bottom + fy * (top - bottom), known)
}

/// Walks along a ray in quarter-cell steps.
struct Ray<'a> {
    grid: &'a OccupancyGrid,
    from: [f64; 2],
    dir: [f64; 2],
}

impl Ray<'_> {
    fn at(&self, t: f64) -> (f64, bool) {
        sample(
            self.grid,
            [
                self.from[0] + t * self.dir[0],
                self.from[1] + t * self.dir[1],
            ],
        )
    }

    /// First `t` in (t0, max] where `stop(value, known)` holds, located to sub-cell precision:
    /// stepped in quarter cells, then bisected.
    fn find(&self, t0: f64, max: f64, stop: impl Fn(f64, bool) -> bool) -> Option<f64> {
        let step = self.grid.resolution / 4.0;
        let mut lo = t0;
        while lo < max {
            let hi = (lo + step).min(max);
            let (p, known) = self.at(hi);
            if stop(p, known) {
                let (mut a, mut b) = (lo, hi);
                for _ in 0..BISECTIONS {
                    let mid = 0.5 * (a + b);
                    let (p, known) = self.at(mid);
                    if stop(p, known) {
                        b = mid;
                    } else {
                        a = mid;
                    }
                }
                return Some(0.5 * (a + b));
            }
            lo = hi;
        }
        None
    }
}

/// The first occupied band from `from` along `direction` (need not be unit length): distances
/// to its inner edge (the interpolated probability first rises above 0.5) and its outer edge
/// (it falls back to 0.5 or below, or the map turns unknown). `None` if `from` is not in a known
/// free cell, if the ray meets unknown cells before the band, or if either edge lies beyond
/// `max` (m).
pub fn band(
    grid: &OccupancyGrid,
    from: [f64; 2],
    direction: [f64; 2],
    max: f64,
) -> Option<(f64, f64)> {
    let norm = direction[0].hypot(direction[1]);
    if [norm, grid.resolution, max]
        .iter()
        .any(|v| v.is_nan() || *v <= 0.0)
    {
        return None;
    }
    let ray = Ray {
        grid,
        from,
        dir: [direction[0] / norm, direction[1] / norm],
    };
    let (p0, known) = ray.at(0.0);
    if !known || p0 > 0.5 {
        return None;
    }
    let inner = ray.find(0.0, max, |p, known| p > 0.5 || !known)?;
    if !ray.at(inner + 1e-9).1 {
        return None;
    }
    let outer = ray.find(inner, max, |p, known| p <= 0.5 || !known)?;
    Some((inner, outer))
}

/// Distance from the free point `from` along `direction` to the first surface on `grid`:
/// the grade-weighted centroid of the surface's occupied band, or its middle on an ungraded
/// map (see the module documentation for why, and for the bias measured). `None` as for
/// [`band`].
pub fn surface_distance(
    grid: &OccupancyGrid,
    from: [f64; 2],
    direction: [f64; 2],
    max: f64,
) -> Option<f64> {
    let (inner, outer) = band(grid, from, direction, max)?;
    let norm = direction[0].hypot(direction[1]);
    let ray = Ray {
        grid,
        from,
        dir: [direction[0] / norm, direction[1] / norm],
    };
    // The centroid of the graded part of the band: occupied cells above the plain occupied
    // value weigh by their reflection rate (see `grid::OccupancyMap::write_grid`).
    let floor = f64::from(crate::grid::OCCUPIED_MIN) / 100.0 - 0.005;
    let step = grid.resolution / 16.0;
    let (mut sum_w, mut sum_tw) = (0.0, 0.0);
    let mut t = inner;
    while t <= outer {
        let w = (ray.at(t).0 - floor).max(0.0).powi(2);
        sum_w += w;
        sum_tw += w * t;
        t += step;
    }
    Some(if sum_w > 0.0 {
        sum_tw / sum_w
    } else {
        0.5 * (inner + outer)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{OccupancyGrid, Pose2D, boxed_placement_new};

    const RES: f64 = 0.025;

    /// A 64 × 64 grid, origin (−0.3, −0.2), free up to x = `front`, occupied from `front` to
    /// `back`, then `beyond`; cells cut by an edge get the occupied fraction of their area.
    fn wall(front: f64, back: f64, beyond: i8) -> Box<OccupancyGrid> {
        let mut g = boxed_placement_new::<OccupancyGrid>();
        g.resolution = RES;
        g.origin = Pose2D {
            x: -0.3,
            y: -0.2,
            theta: 0.0,
        };
        (g.width, g.height) = (64, 64);
        for ix in 0..64 {
            let x0 = -0.3 + ix as f64 * RES;
            let occupied = ((x0 + RES).min(back) - x0.max(front)).max(0.0) / RES;
            let v = if x0 >= back {
                beyond
            } else {
                (100.0 * occupied).round() as i8
            };
            for iy in 0..64 {
                g.data[iy * 64 + ix] = v;
            }
        }
        g
    }

    #[test]
    fn finds_a_face_at_any_sub_cell_offset() {
        // A symmetric band 3 cells deep around a face at x = 0.5 + k/10 of a cell: the middle
        // of the band is the face, to within a tenth of a cell.
        for k in 0..10 {
            let face = 0.5 + k as f64 * RES / 10.0;
            let g = wall(face - 1.5 * RES, face + 1.5 * RES, 0);
            for (from, y) in [(0.0, 0.0), (0.1, 0.031), (-0.2, -0.1)] {
                let d = surface_distance(&g, [from, y], [1.0, 0.0], 2.0).unwrap();
                let err = from + d - face;
                assert!(err.abs() < 0.1 * RES, "offset {k}/10: error {err}");
            }
            // Along a slanted ray the distance scales with 1 / cos.
            let (c, s) = (0.8, 0.6);
            let d = surface_distance(&g, [0.0, -0.1], [c, s], 2.0).unwrap();
            assert!(
                (d * c - face).abs() < 0.1 * RES,
                "slanted: {}",
                d * c - face
            );
        }
    }

    #[test]
    fn a_band_ending_in_unknown_space_ends_where_the_map_does() {
        // Occupied from 0.5 to 0.55, then never seen: the middle is 0.525.
        let g = wall(0.5, 0.55, -1);
        let (inner, outer) = band(&g, [0.0, 0.0], [1.0, 0.0], 2.0).unwrap();
        assert!((inner - 0.5).abs() < 0.1 * RES && (outer - 0.55).abs() < 1e-6);
        assert!(
            (surface_distance(&g, [0.0, 0.0], [1.0, 0.0], 2.0).unwrap() - 0.525).abs() < 0.1 * RES
        );
    }

    #[test]
    fn no_answer_without_a_free_start_or_a_surface_in_reach() {
        let g = wall(0.5, 0.6, 0);
        assert!(surface_distance(&g, [0.55, 0.0], [1.0, 0.0], 2.0).is_none());
        assert!(surface_distance(&g, [0.0, 0.0], [1.0, 0.0], 0.3).is_none());
        assert!(surface_distance(&g, [0.0, 0.0], [-1.0, 0.0], 2.0).is_none());
        assert!(surface_distance(&g, [0.0, 0.0], [0.0, 0.0], 2.0).is_none());
        assert!(surface_distance(&g, [-5.0, 0.0], [1.0, 0.0], 2.0).is_none());
    }
}
