//! A planar laser scanner (Hokuyo URG-04LX-UG01 by default) by ray casting with parry.
//!
//! The scene is the world's solids (walls, boxes, cylinders, extruded from the floor to their
//! height) and the chassis boxes of the other robots at their latest true poses. Each beam is
//! a horizontal ray from the scanner, at base_link's height plus `z_offset`; the reading is the
//! distance to the first surface. The scanner's own robot is not in the scene: the scanner sits
//! inside its own chassis box and would otherwise see nothing but it.
//!
//! Choices (the datasheet and the reference leave them open):
//! - **Precision.** Rays are cast with `parry3d-f64`. The f32 build's ray–ball and GJK ray–
//!   cylinder casts are off by 1e-5–5e-5 m at a few metres (cancellation, iterative tolerance),
//!   far above what a unit test can pin down; in f64 they are below 1e-9 m.
//! - **Invalid readings** lie outside `[range_min, range_max]`, which is what sensor_msgs/
//!   LaserScan tells consumers to discard: no surface within `range_max` reads
//!   `range_max + 1 m` ([`NO_RETURN_MARGIN`]); a surface closer than `range_min` (the scanner
//!   touching or inside a solid) reads 0, like the URG's own error codes below 20 mm. REP 117
//!   would say +Inf/−Inf; we keep readings finite because recordings are JSON, where a
//!   non-finite float becomes `null` and breaks readers of the `ranges` array.
//! - **Noise.** The datasheet's accuracy (±10 mm up to 1 m, ±1 % of the distance beyond) is
//!   taken as one standard deviation of Gaussian noise: σ = 10 mm for r ≤ 1 m and σ = 0.01·r
//!   beyond (continuous at 1 m). Reading a tolerance as 1 σ makes the simulated sensor a
//!   little worse than the part, not better. A noisy reading of a detected surface is clamped
//!   into `[range_min, range_max]`: whether the scanner detects a surface depends on the true
//!   distance, not on the noise. One normal number is drawn per beam, hit or not, so the
//!   stream stays aligned across runs.
//! - **Timing.** All beams of a scan are cast at one instant from one pose, so a scan has no
//!   motion skew and `time_increment` is 0 (the real mirror sweeps 100 ms per turn).
//!   Intensities are not simulated (zeros).

use crate::noise::Gaussian;
use caravan_schemas::{LaserScan, Pose2D};
use caravan_world::{Obstacle, RobotModel, Shape, World};
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::query::{Ray, RayCast};
use parry3d_f64::shape::{Cuboid, Cylinder};

/// Beyond `range_max` by this much, m: the reading of a beam that hit nothing in range.
pub const NO_RETURN_MARGIN: f64 = 1.0;
/// The reading of a surface closer than `range_min`, m.
pub const TOO_CLOSE: f64 = 0.0;

/// The scanner's geometry, limits and noise switch (see `params.rs` for the defaults).
#[derive(Debug, Clone, PartialEq)]
pub struct LaserConfig {
    /// Angle of the first beam relative to the robot's x axis, rad (counter-clockwise).
    pub angle_min: f64,
    /// Angle between neighbouring beams, rad.
    pub angle_increment: f64,
    pub beams: usize,
    pub range_min: f64,
    pub range_max: f64,
    /// Time between scans, s.
    pub scan_time: f64,
    /// Scanner position relative to base_link: ahead along x, and up along z, m.
    pub x_offset: f64,
    pub z_offset: f64,
    pub noise: bool,
}

impl LaserConfig {
    /// Angle of beam `i` relative to the robot's x axis, rad.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min + i as f64 * self.angle_increment
    }

    pub fn angle_max(&self) -> f64 {
        self.angle(self.beams - 1)
    }

    /// The datasheet accuracy at true distance `r`, taken as 1 σ, m.
    pub fn noise_stddev(r: f64) -> f64 {
        if r <= 1.0 { 0.01 } else { 0.01 * r }
    }
}

#[derive(Debug, Clone, Copy)]
enum Solid {
    Cuboid(Cuboid),
    /// parry's cylinders stand on the y axis; the pose turns them upright.
    Cylinder(Cylinder),
}

/// A solid placed in the map frame, with the radius of a vertical cylinder around it, so that
/// a beam can skip it with a cheap test before parry's exact cast.
#[derive(Debug, Clone, Copy)]
struct Placed {
    solid: Solid,
    pose: Pose,
    center: [f64; 2],
    bound: f64,
}

impl Placed {
    fn new(solid: Solid, center: [f64; 2], z_center: f64, yaw: f64) -> Self {
        let (rotation, bound) = match solid {
            Solid::Cuboid(c) => (
                Rotation::from_rotation_z(yaw),
                c.half_extents.x.hypot(c.half_extents.y),
            ),
            Solid::Cylinder(c) => (
                Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2),
                c.radius,
            ),
        };
        Self {
            solid,
            pose: Pose::from_parts(Vector::new(center[0], center[1], z_center), rotation),
            center,
            bound,
        }
    }

    fn from_obstacle(o: &Obstacle) -> Self {
        let half_h = o.height / 2.0;
        let solid = match o.shape {
            Shape::Box { half_x, half_y } => {
                Solid::Cuboid(Cuboid::new(Vector::new(half_x, half_y, half_h)))
            }
            Shape::Cylinder { radius } => Solid::Cylinder(Cylinder::new(half_h, radius)),
        };
        Self::new(solid, o.center, half_h, o.yaw)
    }

    /// Distance along `ray` (unit direction) to this solid, if below `max`. `solid = true`:
    /// a scanner inside a solid reads 0, which is then "too close".
    fn cast(&self, ray: &Ray, max: f64) -> Option<f64> {
        // Cheap reject in the plane: the beam misses the bounding circle, or reaches it only
        // beyond `max`.
        let (dx, dy) = (self.center[0] - ray.origin.x, self.center[1] - ray.origin.y);
        let along = dx * ray.dir.x + dy * ray.dir.y;
        let across_sq = dx * dx + dy * dy - along * along;
        if along + self.bound < 0.0
            || along - self.bound > max
            || across_sq > self.bound * self.bound
        {
            return None;
        }
        match &self.solid {
            Solid::Cuboid(c) => c.cast_ray(&self.pose, ray, max, true),
            Solid::Cylinder(c) => c.cast_ray(&self.pose, ray, max, true),
        }
    }
}

/// The scanner of one robot, with the static scene and its noise stream.
pub struct Laser {
    config: LaserConfig,
    statics: Vec<Placed>,
    /// Scene for the current scan: statics within reach, then other robots.
    scene: Vec<Placed>,
    chassis_half: [f64; 3],
    chassis_center: [f64; 3],
    /// Height of the scan plane above the floor, m.
    height: f64,
    noise: Gaussian,
}

impl Laser {
    /// A scanner in `world` on a robot described by `robot` (the other robots' chassis boxes
    /// and base_link's height come from it); `seed` seeds the noise.
    pub fn new(config: LaserConfig, world: &World, robot: &RobotModel, seed: u64) -> Self {
        let chassis = (robot.chassis_half_extents, robot.chassis_center);
        Self::build(config, world, chassis, robot.base_height(), seed)
    }

    /// A scanner that sees the world but no robots, its plane `z_offset` above the mount
    /// height given by [`Laser::set_mount_height`] (a scanner on an arm's link).
    pub fn world_only(config: LaserConfig, world: &World, seed: u64) -> Self {
        Self::build(config, world, ([0.0; 3], [0.0; 3]), 0.0, seed)
    }

    fn build(
        config: LaserConfig,
        world: &World,
        (chassis_half, chassis_center): ([f64; 3], [f64; 3]),
        base_height: f64,
        seed: u64,
    ) -> Self {
        let statics: Vec<Placed> = world.obstacles.iter().map(Placed::from_obstacle).collect();
        Self {
            scene: Vec::with_capacity(statics.len() + 8),
            statics,
            chassis_half,
            chassis_center,
            height: base_height + config.z_offset,
            noise: Gaussian::new(seed, crate::noise::LASER_STREAM),
            config,
        }
    }

    /// Puts the scan plane `z_offset` above a mount at height `z` (a link's origin) instead of
    /// above base_link standing on the floor.
    pub fn set_mount_height(&mut self, z: f64) {
        self.height = z + self.config.z_offset;
    }

    pub fn config(&self) -> &LaserConfig {
        &self.config
    }

    /// The scanner's position in the map frame for a robot at `pose`.
    pub fn origin(&self, pose: &Pose2D) -> Vector {
        let (s, c) = pose.theta.sin_cos();
        Vector::new(
            pose.x + c * self.config.x_offset,
            pose.y + s * self.config.x_offset,
            self.height,
        )
    }

    /// Fills the scene for a scan from `origin`: the static solids that can be within reach,
    /// and the chassis of each robot in `others`.
    fn build_scene(&mut self, origin: &Vector, others: &[Pose2D]) {
        self.scene.clear();
        let reach = self.config.range_max;
        self.scene.extend(self.statics.iter().filter(|p| {
            let d = (p.center[0] - origin.x).hypot(p.center[1] - origin.y);
            d - p.bound <= reach
        }));
        let [hx, hy, hz] = self.chassis_half;
        let [cx, cy, cz] = self.chassis_center;
        let base_height = self.height - self.config.z_offset;
        for pose in others {
            let (s, c) = pose.theta.sin_cos();
            let center = [pose.x + c * cx - s * cy, pose.y + s * cx + c * cy];
            let chassis = Solid::Cuboid(Cuboid::new(Vector::new(hx, hy, hz)));
            self.scene
                .push(Placed::new(chassis, center, base_height + cz, pose.theta));
        }
    }

    /// True distances, one per beam, for the robot at `own` with the other robots at
    /// `others`: `Some(r)` for the first surface within `range_max`, `None` for no return.
    pub fn true_ranges(&mut self, own: &Pose2D, others: &[Pose2D], out: &mut [Option<f64>]) {
        let origin = self.origin(own);
        self.build_scene(&origin, others);
        for (i, slot) in out.iter_mut().enumerate().take(self.config.beams) {
            *slot = self.cast_beam(&origin, own.theta + self.config.angle(i));
        }
    }

    fn cast_beam(&self, origin: &Vector, heading: f64) -> Option<f64> {
        let (s, c) = heading.sin_cos();
        let ray = Ray::new(*origin, Vector::new(c, s, 0.0));
        let mut best: Option<f64> = None;
        for p in &self.scene {
            let max = best.unwrap_or(self.config.range_max);
            if let Some(t) = p.cast(&ray, max) {
                best = Some(best.map_or(t, |b| b.min(t)));
            }
        }
        best
    }

    /// The published reading for true distance `r` (see the module notes), drawing noise.
    fn reading(&mut self, r: Option<f64>) -> f64 {
        let c = &self.config;
        let z = self.noise.standard();
        match r {
            None => c.range_max + NO_RETURN_MARGIN,
            Some(r) if r < c.range_min => TOO_CLOSE,
            Some(r) if c.noise => {
                (r + z * LaserConfig::noise_stddev(r)).clamp(c.range_min, c.range_max)
            }
            Some(r) => r,
        }
    }

    /// Writes a full scan for the robot at `own` into `out` (a loaned message).
    pub fn scan(&mut self, own: &Pose2D, others: &[Pose2D], out: &mut LaserScan) {
        let origin = self.origin(own);
        self.build_scene(&origin, others);
        let c = &self.config;
        out.angle_min = c.angle_min as f32;
        out.angle_max = c.angle_max() as f32;
        out.angle_increment = c.angle_increment as f32;
        out.time_increment = 0.0;
        out.scan_time = c.scan_time as f32;
        out.range_min = c.range_min as f32;
        out.range_max = c.range_max as f32;
        out.beam_count = c.beams as u32;
        for i in 0..self.config.beams {
            let r = self.cast_beam(&origin, own.theta + self.config.angle(i));
            out.ranges[i] = self.reading(r) as f32;
            out.intensities[i] = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_world::world::parse_world;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    /// A 4 × 3 m room (walls 0.1 m thick on its outline, so the inner faces are at x = 0.05,
    /// 3.95 and y = 0.05, 2.95), a 0.4 × 0.4 m box at (3, 1), a yawed box and a cylinder.
    const ROOM: &str = r#"
[world]
name = "room"
size = [4.0, 3.0]
[[wall]]
from = [0.0, 0.0]
to = [4.0, 0.0]
thickness = 0.1
[[wall]]
from = [4.0, 0.0]
to = [4.0, 3.0]
thickness = 0.1
[[wall]]
from = [4.0, 3.0]
to = [0.0, 3.0]
thickness = 0.1
[[wall]]
from = [0.0, 3.0]
to = [0.0, 0.0]
thickness = 0.1
[[box]]
center = [3.0, 1.0]
size = [0.4, 0.4]
[[box]]
center = [2.0, 2.3]
size = [0.3, 0.3]
yaw = 0.7853981633974483
[[cylinder]]
center = [1.0, 2.2]
radius = 0.2
"#;

    fn robot() -> RobotModel {
        let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../launch/convoy/robots/convoy_bot.urdf");
        caravan_world::load_robot(&urdf).unwrap()
    }

    /// 1° beams over 240°: beam 120 looks straight ahead, 30 to the right, 210 to the left.
    fn config(noise: bool) -> LaserConfig {
        LaserConfig {
            angle_min: -120f64.to_radians(),
            angle_increment: 1f64.to_radians(),
            beams: 241,
            range_min: 0.02,
            range_max: 5.6,
            scan_time: 0.1,
            x_offset: 0.0,
            z_offset: 0.0,
            noise,
        }
    }

    fn laser(noise: bool) -> Laser {
        Laser::new(config(noise), &parse_world(ROOM).unwrap(), &robot(), 42)
    }

    fn pose(x: f64, y: f64, theta: f64) -> Pose2D {
        Pose2D { x, y, theta }
    }

    fn beam_for(l: &Laser, relative_deg: i32) -> usize {
        (relative_deg + 120) as usize * (l.config().beams - 1) / 240
    }

    /// Reference distance from (x, y) along `heading` to the first of: the four inner wall
    /// faces, the axis-aligned box, the yawed box and the cylinder, all by plane geometry.
    fn analytic(x: f64, y: f64, heading: f64) -> f64 {
        let (s, c) = heading.sin_cos();
        let mut best = f64::INFINITY;
        // Ray vs an oriented rectangle (slab method in the rectangle's frame).
        let mut rect = |cx: f64, cy: f64, hx: f64, hy: f64, yaw: f64| {
            let (sy, cyaw) = yaw.sin_cos();
            let (ox, oy) = (
                cyaw * (x - cx) + sy * (y - cy),
                -sy * (x - cx) + cyaw * (y - cy),
            );
            let (dx, dy) = (cyaw * c + sy * s, -sy * c + cyaw * s);
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for (o, d, h) in [(ox, dx, hx), (oy, dy, hy)] {
                if d.abs() < 1e-15 {
                    if o.abs() > h {
                        return;
                    }
                    continue;
                }
                let (a, b) = ((-h - o) / d, (h - o) / d);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
            if t0 <= t1 {
                best = best.min(t0);
            }
        };
        rect(2.0, 0.0, 2.05, 0.05, 0.0);
        rect(2.0, 3.0, 2.05, 0.05, 0.0);
        rect(0.0, 1.5, 0.05, 1.55, 0.0);
        rect(4.0, 1.5, 0.05, 1.55, 0.0);
        rect(3.0, 1.0, 0.2, 0.2, 0.0);
        rect(2.0, 2.3, 0.15, 0.15, FRAC_PI_4);
        // Ray vs circle.
        let (dx, dy) = (1.0 - x, 2.2 - y);
        let b = dx * c + dy * s;
        let disc = b * b - (dx * dx + dy * dy - 0.04);
        if disc >= 0.0 && b - disc.sqrt() >= 0.0 {
            best = best.min(b - disc.sqrt());
        }
        best
    }

    #[test]
    fn beams_toward_walls_box_and_cylinder_read_the_analytic_distance() {
        let mut l = laser(false);
        let mut scan = LaserScan::default();
        // From (1, 1) facing +x: ahead the box face at x = 2.8, left the cylinder at y = 2.0,
        // right the wall face at y = 0.05.
        l.scan(&pose(1.0, 1.0, 0.0), &[], &mut scan);
        let r = |deg| scan.ranges[beam_for(&l, deg)] as f64;
        assert!((r(0) - 1.8).abs() < 1e-6, "{}", r(0));
        assert!((r(90) - 1.0).abs() < 1e-6, "{}", r(90));
        assert!((r(-90) - 0.95).abs() < 1e-6, "{}", r(-90));
        // Facing −x, ahead the wall face at x = 0.05.
        l.scan(&pose(1.0, 1.0, PI), &[], &mut scan);
        assert!((scan.ranges[beam_for(&l, 0)] as f64 - 0.95).abs() < 1e-6);
        // Facing +y from (3.5, 1.5): ahead the top wall, to the right the right wall.
        l.scan(&pose(3.5, 1.5, FRAC_PI_2), &[], &mut scan);
        assert!((scan.ranges[beam_for(&l, 0)] as f64 - 1.45).abs() < 1e-6);
        assert!((scan.ranges[beam_for(&l, -90)] as f64 - 0.45).abs() < 1e-6);

        // Every beam of several poses against the plane-geometry reference.
        let mut worst = 0.0f64;
        for p in [
            pose(1.0, 1.0, 0.0),
            pose(1.0, 1.0, 2.5),
            pose(2.6, 1.7, -0.4),
            pose(0.6, 2.6, -1.2),
            pose(3.4, 2.4, 3.0),
        ] {
            l.scan(&p, &[], &mut scan);
            for (i, &got) in scan.ranges().iter().enumerate() {
                let want = analytic(p.x, p.y, p.theta + l.config().angle(i));
                assert!(want < 5.6, "the room is smaller than the range");
                let err = (got as f64 - want).abs();
                assert!(err < 1e-6, "pose {p:?} beam {i}: {got} vs {want}");
                worst = worst.max(err);
            }
        }
        eprintln!("worst error over all beams: {worst:e} m");
        // Header fields as sensor_msgs/LaserScan.
        assert_eq!(scan.beam_count, 241);
        assert!((scan.angle_max as f64 - 120f64.to_radians()).abs() < 1e-6);
        assert_eq!((scan.range_min, scan.range_max), (0.02, 5.6));
    }

    #[test]
    fn the_default_urg_04lx_geometry_reads_the_analytic_distance() {
        let defaults: crate::params::Params =
            serde_json::from_value(serde_json::json!({"robot": 0, "count": 1, "world": "w"}))
                .unwrap();
        let mut cfg = defaults.laser_config();
        cfg.noise = false;
        let mut l = Laser::new(cfg, &parse_world(ROOM).unwrap(), &robot(), 0);
        let mut scan = LaserScan::default();
        let p = pose(2.6, 1.7, -0.4);
        l.scan(&p, &[], &mut scan);
        assert_eq!(scan.ranges().len(), 682);
        for (i, &got) in scan.ranges().iter().enumerate() {
            let want = analytic(p.x, p.y, p.theta + l.config().angle(i));
            assert!(
                (got as f64 - want).abs() < 1e-6,
                "beam {i}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn nothing_in_range_reads_above_range_max_and_too_close_reads_zero() {
        let mut c = config(false);
        c.range_max = 1.2;
        let mut l = Laser::new(c, &parse_world(ROOM).unwrap(), &robot(), 1);
        let mut scan = LaserScan::default();
        l.scan(&pose(1.0, 1.0, 0.0), &[], &mut scan);
        let (ahead, right) = (scan.ranges[120], scan.ranges[30]);
        assert_eq!(
            ahead,
            (1.2 + NO_RETURN_MARGIN) as f32,
            "box at 1.8 m is beyond 1.2 m"
        );
        assert!((right as f64 - 0.95).abs() < 1e-6);
        // Standing inside the box: every beam starts in a solid.
        l.scan(&pose(3.0, 1.0, 0.0), &[], &mut scan);
        assert!(scan.ranges().iter().all(|&r| r == TOO_CLOSE as f32));
        for r in scan.ranges() {
            assert!(
                !(scan.range_min..=scan.range_max).contains(r),
                "{r} must read invalid"
            );
        }
    }

    #[test]
    fn another_robots_chassis_is_seen_at_its_pose() {
        // Robot 1 at (2.0, 1.0) turned 90°: its chassis (0.20 × 0.18 m, centre 2 cm behind
        // base_link) then spans x = 2.0 ± 0.09 and y = 0.98 ± 0.10, so a beam along y = 1
        // meets its face at x = 1.91.
        let mut l = laser(false);
        let mut scan = LaserScan::default();
        let other = pose(2.0, 1.0, FRAC_PI_2);
        l.scan(&pose(1.0, 1.0, 0.0), &[other], &mut scan);
        assert!(
            (scan.ranges[120] as f64 - 0.91).abs() < 1e-6,
            "{}",
            scan.ranges[120]
        );
        // Facing it head-on from the side: the chassis' rear face is at y = 0.98 − 0.10.
        l.scan(&pose(2.0, 0.3, FRAC_PI_2), &[other], &mut scan);
        assert!(
            (scan.ranges[120] as f64 - 0.58).abs() < 1e-6,
            "{}",
            scan.ranges[120]
        );
        // A scanner 5 cm ahead of base_link is 5 cm closer.
        let mut c = config(false);
        c.x_offset = 0.05;
        let mut l = Laser::new(c, &parse_world(ROOM).unwrap(), &robot(), 1);
        l.scan(&pose(1.0, 1.0, 0.0), &[other], &mut scan);
        assert!((scan.ranges[120] as f64 - 0.86).abs() < 1e-6);
        // Without the other robot the beam goes on to the box.
        l.scan(&pose(1.0, 1.0, 0.0), &[], &mut scan);
        assert!((scan.ranges[120] as f64 - 1.75).abs() < 1e-6);
    }

    #[test]
    fn a_scan_plane_above_an_obstacle_passes_over_it() {
        let low = "[world]\nname = \"low\"\nsize = [4.0, 3.0]\n[[box]]\ncenter = [2.0, 1.0]\nsize = [0.2, 0.2]\nheight = 0.05\n";
        let mut l = Laser::new(config(false), &parse_world(low).unwrap(), &robot(), 1);
        let mut scan = LaserScan::default();
        l.scan(&pose(1.0, 1.0, 0.0), &[], &mut scan);
        assert_eq!(scan.ranges[120], (5.6 + NO_RETURN_MARGIN) as f32);
    }

    #[test]
    fn noise_follows_the_datasheet_accuracy() {
        let mut l = laser(true);
        let mut scan = LaserScan::default();
        let p = pose(1.0, 1.0, 0.0);
        let mut truth = vec![None; 241];
        l.true_ranges(&p, &[], &mut truth);
        // Every reading of a scan lies within 4 σ of the truth.
        l.scan(&p, &[], &mut scan);
        for (i, t) in truth.iter().enumerate() {
            let t = t.unwrap();
            let sigma = LaserConfig::noise_stddev(t);
            assert!((scan.ranges[i] as f64 - t).abs() <= 4.0 * sigma, "beam {i}");
        }
        // Many readings of a short (0.95 m, σ = 10 mm) and a long (3.5 m, σ = 35 mm) distance
        // scatter around the truth with the datasheet σ.
        let n = 20_000;
        for t in [0.95f64, 3.5] {
            let sigma = LaserConfig::noise_stddev(t);
            let xs: Vec<f64> = (0..n).map(|_| l.reading(Some(t))).collect();
            let mean = xs.iter().sum::<f64>() / n as f64;
            let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
            assert!(
                (mean - t).abs() < 4.0 * sigma / (n as f64).sqrt(),
                "{mean} vs {t}"
            );
            assert!((sd / sigma - 1.0).abs() < 0.05, "σ {sd} vs {sigma}");
        }
        // Near the limits the noise never turns a detection into an invalid reading.
        assert!((0..1000).all(|_| (0.02..=5.6).contains(&l.reading(Some(5.59)))));
        assert!((0..1000).all(|_| (0.02..=5.6).contains(&l.reading(Some(0.021)))));
    }

    #[test]
    fn the_same_seed_gives_the_same_scans() {
        let (mut a, mut b) = (laser(true), laser(true));
        let (mut sa, mut sb) = (LaserScan::default(), LaserScan::default());
        for k in 0..3 {
            let p = pose(1.0 + 0.1 * k as f64, 1.0, 0.2);
            a.scan(&p, &[], &mut sa);
            b.scan(&p, &[], &mut sb);
            assert_eq!(sa.ranges(), sb.ranges());
        }
    }
}
