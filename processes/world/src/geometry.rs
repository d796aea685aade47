//! Plane geometry for trajectory metrics: polylines, projections, rectangle distances.

pub type P = [f64; 2];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn norm(a: P) -> f64 {
    a[0].hypot(a[1])
}

/// Distance from `p` to segment `ab`, and the fraction along it of the nearest point.
pub fn point_segment(p: P, a: P, b: P) -> (f64, f64) {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (norm(sub(p, [a[0] + t * ab[0], a[1] + t * ab[1]])), t)
}

/// A path: vertices with their arc length from the start.
pub struct Polyline {
    pub points: Vec<P>,
    pub arc: Vec<f64>,
}

impl Polyline {
    /// Keeps a vertex every `spacing` metres of travel, so long trajectories stay cheap.
    pub fn from_trajectory(points: &[P], spacing: f64) -> Self {
        let mut kept: Vec<P> = Vec::new();
        for &p in points {
            if kept
                .last()
                .is_none_or(|&last| norm(sub(p, last)) >= spacing)
            {
                kept.push(p);
            }
        }
        if let (Some(&last), Some(&end)) = (kept.last(), points.last())
            && last != end
        {
            kept.push(end);
        }
        let mut arc = vec![0.0; kept.len()];
        for i in 1..kept.len() {
            arc[i] = arc[i - 1] + norm(sub(kept[i], kept[i - 1]));
        }
        Self { points: kept, arc }
    }

    /// Distance from `p` to the path and the arc length of the nearest point.
    pub fn project(&self, p: P) -> (f64, f64) {
        match self.points.len() {
            0 => (f64::INFINITY, 0.0),
            1 => (norm(sub(p, self.points[0])), 0.0),
            _ => self
                .points
                .windows(2)
                .enumerate()
                .map(|(i, w)| {
                    let (d, t) = point_segment(p, w[0], w[1]);
                    (d, self.arc[i] + t * (self.arc[i + 1] - self.arc[i]))
                })
                .fold(
                    (f64::INFINITY, 0.0),
                    |best, c| if c.0 < best.0 { c } else { best },
                ),
        }
    }
}

/// Corners of a rectangle with half extents `half` centred `offset` ahead of a pose.
pub fn footprint(pose: [f64; 3], half: P, offset: f64) -> [P; 4] {
    let (s, c) = pose[2].sin_cos();
    let center = [pose[0] + c * offset, pose[1] + s * offset];
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(sx, sy)| {
        let (x, y) = (sx * half[0], sy * half[1]);
        [center[0] + c * x - s * y, center[1] + s * x + c * y]
    })
}

fn inside(p: P, poly: &[P; 4]) -> bool {
    (0..4).all(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % 4]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0.0
    })
}

/// Distance between two convex quadrilaterals (counter-clockwise); 0 when they overlap.
pub fn rect_distance(a: &[P; 4], b: &[P; 4]) -> f64 {
    if a.iter().any(|p| inside(*p, b)) || b.iter().any(|p| inside(*p, a)) {
        return 0.0;
    }
    // Between disjoint convex polygons the nearest pair has a vertex on one side.
    let vertex_to_edges = |r: &[P; 4], q: &[P; 4]| {
        let mut best = f64::INFINITY;
        for i in 0..4 {
            for p in q {
                best = best.min(point_segment(*p, r[i], r[(i + 1) % 4]).0);
            }
        }
        best
    };
    vertex_to_edges(a, b).min(vertex_to_edges(b, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_onto_a_bent_path() {
        let path = Polyline::from_trajectory(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], 0.01);
        let (d, s) = path.project([1.2, 0.5]);
        assert!((d - 0.2).abs() < 1e-12 && (s - 1.5).abs() < 1e-12);
    }

    #[test]
    fn rectangles_side_by_side_and_overlapping() {
        let a = footprint([0.0, 0.0, 0.0], [0.1, 0.09], 0.0);
        let b = footprint([0.5, 0.0, 0.0], [0.1, 0.09], 0.0);
        assert!((rect_distance(&a, &b) - 0.3).abs() < 1e-12);
        let c = footprint([0.15, 0.0, 0.3], [0.1, 0.09], 0.0);
        assert_eq!(rect_distance(&a, &c), 0.0);
    }
}
