//! A link's surface in the arm's plane: a closed, convex contour of [`SEGMENTS`] line
//! segments (the reference's Ω_k), and the geometry the identification needs on it: where a
//! line of action enters it, its outward normals, points by arc length, containment and the
//! distance to it, and where a ray first hits it.

use nalgebra::{Isometry2, Point2, Vector2};

/// Segments of every contour, as in the reference.
pub const SEGMENTS: usize = 16;

/// A convex polygon, vertices counter-clockwise; segment `j` runs from vertex `j` to `j + 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contour {
    pub vertices: [Point2<f64>; SEGMENTS],
}

/// Where a line of action enters a contour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    pub point: Point2<f64>,
    /// The segment it enters through.
    pub segment: usize,
    /// Cosine of the angle between the line's direction and the segment's inward normal.
    pub cos_to_normal: f64,
}

impl Contour {
    /// A stadium (the outline of a capsule) around the segment `a`–`b` at distance `radius`:
    /// two straight sides and a half circle of 7 segments at each end.
    pub fn stadium(a: Point2<f64>, b: Point2<f64>, radius: f64) -> Self {
        const ARC: usize = SEGMENTS / 2 - 1;
        let axis = b - a;
        let heading = axis.y.atan2(axis.x);
        let mut vertices = [Point2::origin(); SEGMENTS];
        for k in 0..=ARC {
            let t = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * k as f64 / ARC as f64;
            let (s, c) = (heading + t).sin_cos();
            vertices[k] = b + radius * Vector2::new(c, s);
            let (s, c) = (heading + t + std::f64::consts::PI).sin_cos();
            vertices[ARC + 1 + k] = a + radius * Vector2::new(c, s);
        }
        Self { vertices }
    }

    /// The contour moved by `iso`.
    pub fn transformed(&self, iso: &Isometry2<f64>) -> Self {
        Self {
            vertices: self.vertices.map(|v| iso * v),
        }
    }

    /// End points of segment `j`.
    pub fn segment(&self, j: usize) -> (Point2<f64>, Point2<f64>) {
        (self.vertices[j], self.vertices[(j + 1) % SEGMENTS])
    }

    /// Unit normal of segment `j` pointing out of the contour.
    pub fn outward_normal(&self, j: usize) -> Vector2<f64> {
        let (a, b) = self.segment(j);
        let d = b - a;
        Vector2::new(d.y, -d.x).normalize()
    }

    /// Length of the whole contour, m.
    pub fn perimeter(&self) -> f64 {
        (0..SEGMENTS)
            .map(|j| {
                let (a, b) = self.segment(j);
                (b - a).norm()
            })
            .sum()
    }

    /// The point at arc length `s` (m, wrapped into [0, perimeter)) from vertex 0, and its
    /// segment.
    pub fn point_at(&self, s: f64) -> (Point2<f64>, usize) {
        let mut s = s.rem_euclid(self.perimeter());
        for j in 0..SEGMENTS {
            let (a, b) = self.segment(j);
            let len = (b - a).norm();
            if s <= len || j == SEGMENTS - 1 {
                return (a + (b - a) * (s / len).min(1.0), j);
            }
            s -= len;
        }
        unreachable!("a contour has segments")
    }

    /// Whether `p` lies strictly inside, deeper than `margin` (m) from every side.
    pub fn contains(&self, p: &Point2<f64>, margin: f64) -> bool {
        (0..SEGMENTS).all(|j| self.outward_normal(j).dot(&(p - self.vertices[j])) < -margin)
    }

    /// The point of the contour nearest to `p`, its distance (m, 0 on the boundary, and also
    /// measured to the boundary from inside) and its segment.
    pub fn nearest(&self, p: &Point2<f64>) -> (Point2<f64>, f64, usize) {
        let mut best = (self.vertices[0], f64::INFINITY, 0);
        for j in 0..SEGMENTS {
            let (a, b) = self.segment(j);
            let d = b - a;
            let t = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            let q = a + d * t;
            let dist = (p - q).norm();
            if dist < best.1 {
                best = (q, dist, j);
            }
        }
        best
    }

    /// Where the line through `on_line` along `direction` enters the contour travelling along
    /// `direction` (Cyrus–Beck clipping); `None` when it misses. `direction` need not be unit.
    pub fn entry(&self, on_line: &Point2<f64>, direction: &Vector2<f64>) -> Option<Entry> {
        let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
        let mut entering = None;
        for j in 0..SEGMENTS {
            let n = self.outward_normal(j);
            let along = n.dot(direction);
            let outside = n.dot(&(on_line - self.vertices[j]));
            if along == 0.0 {
                if outside > 0.0 {
                    return None;
                }
                continue;
            }
            let t = -outside / along;
            if along < 0.0 {
                if t > t_in {
                    t_in = t;
                    entering = Some(j);
                }
            } else {
                t_out = t_out.min(t);
            }
        }
        let segment = entering?;
        if t_in > t_out {
            return None;
        }
        Some(Entry {
            point: on_line + direction * t_in,
            segment,
            cos_to_normal: -self.outward_normal(segment).dot(&direction.normalize()),
        })
    }

    /// Distance along the unit ray from `origin` to where it first meets the contour from
    /// outside; `None` when it misses or starts inside.
    pub fn ray_hit(&self, origin: &Point2<f64>, direction: &Vector2<f64>) -> Option<f64> {
        let entry = self.entry(origin, direction)?;
        let t = (entry.point - origin).dot(direction);
        (t >= 0.0).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bar() -> Contour {
        Contour::stadium(Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), 0.1)
    }

    #[test]
    fn a_stadium_is_convex_counter_clockwise_and_wraps_its_segment() {
        let c = bar();
        for j in 0..SEGMENTS {
            let (a, b) = c.segment(j);
            let (_, d) = c.segment((j + 1) % SEGMENTS);
            let turn = (b - a).perp(&(d - b));
            assert!(turn > 0.0, "segment {j} turns clockwise");
        }
        assert!(c.contains(&Point2::new(0.5, 0.0), 0.0));
        assert!(c.contains(&Point2::new(-0.05, 0.0), 0.0));
        assert!(!c.contains(&Point2::new(0.5, 0.2), 0.0));
        // Two straight sides of 1 m and a polygon close to a circle of radius 0.1 m.
        let circle = 2.0 * std::f64::consts::PI * 0.1;
        assert!((c.perimeter() - 2.0 - circle).abs() < 0.01 * circle);
    }

    #[test]
    fn a_line_enters_where_it_first_crosses_going_along_its_direction() {
        let c = bar();
        // Straight down onto the top side at x = 0.4.
        let e = c
            .entry(&Point2::new(0.4, 5.0), &Vector2::new(0.0, -3.0))
            .unwrap();
        assert!((e.point - Point2::new(0.4, 0.1)).norm() < 1e-12, "{e:?}");
        assert!((e.cos_to_normal - 1.0).abs() < 1e-12);
        // The same line the other way enters through the bottom side.
        let e = c
            .entry(&Point2::new(0.4, 5.0), &Vector2::new(0.0, 1.0))
            .unwrap();
        assert!((e.point - Point2::new(0.4, -0.1)).norm() < 1e-12, "{e:?}");
        // Slanted 45° onto the top: cos = 1/√2.
        let e = c
            .entry(&Point2::new(0.0, 0.6), &Vector2::new(1.0, -1.0))
            .unwrap();
        assert!((e.point - Point2::new(0.5, 0.1)).norm() < 1e-12, "{e:?}");
        assert!((e.cos_to_normal - 0.5f64.sqrt()).abs() < 1e-12);
        // A line that passes above misses.
        assert!(
            c.entry(&Point2::new(0.0, 0.5), &Vector2::new(1.0, 0.0))
                .is_none()
        );
    }

    #[test]
    fn points_by_arc_length_lie_on_the_contour() {
        let c = bar();
        let p = c.perimeter();
        for k in 0..50 {
            let (q, j) = c.point_at(p * k as f64 / 50.0);
            let (_, dist, _) = c.nearest(&q);
            assert!(dist < 1e-12);
            let (a, b) = c.segment(j);
            assert!(((q - a).norm() + (b - q).norm() - (b - a).norm()).abs() < 1e-12);
        }
    }

    #[test]
    fn a_ray_hits_from_outside_only() {
        let c = bar();
        let t = c
            .ray_hit(&Point2::new(0.5, -1.0), &Vector2::new(0.0, 1.0))
            .unwrap();
        assert!((t - 0.9).abs() < 1e-12);
        assert!(
            c.ray_hit(&Point2::new(0.5, -1.0), &Vector2::new(0.0, -1.0))
                .is_none()
        );
        assert!(
            c.ray_hit(&Point2::new(0.5, 0.0), &Vector2::new(0.0, 1.0))
                .is_none()
        );
    }
}
