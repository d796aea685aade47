//! World files: a floor with walls, boxes and cylinders, in the map frame (z up).
//!
//! ```toml
//! [world]
//! name = "lab"
//! size = [6.0, 4.0]        # floor from (0, 0) to (6, 4) m
//! wall_height = 0.3
//!
//! [[wall]]                 # a wall segment
//! from = [0.0, 0.0]
//! to = [6.0, 0.0]
//! thickness = 0.05         # optional, default 0.05
//!
//! [[box]]
//! center = [2.0, 1.5]
//! size = [0.4, 0.4]        # x, y extent
//! yaw = 0.0                # optional, rad
//! height = 0.3             # optional, default wall_height
//!
//! [[cylinder]]
//! center = [4.0, 2.5]
//! radius = 0.15
//!
//! [[survey]]               # a distance the run report measures on the SLAM map
//! name = "south wall to bench"
//! at = [3.5, 1.0]          # a free point between the two surfaces
//! direction = [0.0, 1.0]   # the line through it; the surfaces are the first hits either way
//!
//! [[start]]                # where robot 0, 1, … start: [x, y, yaw] (m, m, rad)
//! pose = [2.2, 1.0, 0.0]
//!
//! [[goal]]                 # waypoints a scenario drives to, in order
//! name = "A"
//! at = [5.0, 1.1]
//! ```
//!
//! Starts and goals belong to the world because they are designed with it (a free start line,
//! a route clear of obstacles): changing the world changes them too.

use serde::Deserialize;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
#[error("{file}: {message}")]
pub struct WorldError {
    pub file: String,
    pub message: String,
}

/// A solid's cross-section in the plane; it is extruded from the floor up to its height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    Box { half_x: f64, half_y: f64 },
    Cylinder { radius: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObstacleKind {
    Wall,
    Box,
    Cylinder,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    pub kind: ObstacleKind,
    pub center: [f64; 2],
    pub yaw: f64,
    pub height: f64,
    pub shape: Shape,
}

#[derive(Debug, Clone, PartialEq)]
pub struct World {
    pub name: String,
    /// Floor extent from the origin, m.
    pub size: [f64; 2],
    pub obstacles: Vec<Obstacle>,
    /// Friction coefficient of the floor, walls, boxes and cylinders, ≥ 0; a robot's part
    /// grips with the smaller of this and its own. `None`: obstacles 0.5 and a floor that
    /// leaves the grip to the robot's parts ([`DEFAULT_FRICTION`], [`FREE_FLOOR_FRICTION`]).
    pub friction: Option<f64>,
    /// Surface-to-surface distances to check maps against (the reference's map-scale test).
    pub surveys: Vec<Survey>,
    /// Start poses `[x, y, yaw]` of robot 0, 1, …
    pub starts: Vec<[f64; 3]>,
    /// Waypoints, in order.
    pub goals: Vec<Waypoint>,
}

/// A named point a scenario drives to.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    pub name: String,
    /// Position in the map frame, m.
    pub at: [f64; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Start {
    pose: [f64; 3],
}

/// A line between two surfaces through a free point; its true length comes from the world.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Survey {
    pub name: String,
    pub at: [f64; 2],
    pub direction: [f64; 2],
}

impl Survey {
    /// The direction scaled to unit length.
    pub fn unit(&self) -> [f64; 2] {
        let n = self.direction[0].hypot(self.direction[1]);
        [self.direction[0] / n, self.direction[1] / n]
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    world: Header,
    #[serde(default)]
    wall: Vec<Wall>,
    #[serde(default, rename = "box")]
    boxes: Vec<BoxSpec>,
    #[serde(default)]
    cylinder: Vec<Cylinder>,
    #[serde(default)]
    survey: Vec<Survey>,
    #[serde(default)]
    start: Vec<Start>,
    #[serde(default)]
    goal: Vec<Waypoint>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    name: String,
    size: [f64; 2],
    #[serde(default = "default_height")]
    wall_height: f64,
    friction: Option<f64>,
}

/// Friction of obstacles when the world file gives none.
pub const DEFAULT_FRICTION: f64 = 0.5;
/// Friction of the floor when the world file gives none: high, so that each robot part's
/// own coefficient decides its grip.
pub const FREE_FLOOR_FRICTION: f64 = 10.0;

fn default_height() -> f64 {
    0.3
}

fn default_thickness() -> f64 {
    0.05
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Wall {
    from: [f64; 2],
    to: [f64; 2],
    #[serde(default = "default_thickness")]
    thickness: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSpec {
    center: [f64; 2],
    size: [f64; 2],
    #[serde(default)]
    yaw: f64,
    height: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Cylinder {
    center: [f64; 2],
    radius: f64,
    height: Option<f64>,
}

/// Reads and checks a world file.
pub fn load_world(path: &Path) -> Result<World, WorldError> {
    let file = path.display().to_string();
    let err = |message: String| WorldError {
        file: file.clone(),
        message,
    };
    let text =
        caravan::input::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    parse_world(&text).map_err(err)
}

/// Parses a world file's text; errors name the line and key.
pub fn parse_world(text: &str) -> Result<World, String> {
    let f: File = toml::from_str(text).map_err(|e| e.to_string().trim_end().replace('\n', " "))?;
    let positive = |what: String, v: f64| {
        crate::limits::length(&what, v, crate::limits::MAX_WORLD_EXTENT_M).map(|_| ())
    };
    positive("world.size[0]".into(), f.world.size[0])?;
    positive("world.size[1]".into(), f.world.size[1])?;
    positive("world.wall_height".into(), f.world.wall_height)?;
    let h = f.world.wall_height;
    if let Some(mu) = f.world.friction
        && !(mu.is_finite() && mu >= 0.0)
    {
        return Err(format!("world.friction must be zero or positive, got {mu}"));
    }
    use crate::limits::{MAX_ANGLE_RAD, MAX_WORLD_EXTENT_M, coordinate};
    let point = |what: String, p: [f64; 2]| {
        coordinate(&format!("{what}[0]"), p[0], MAX_WORLD_EXTENT_M)?;
        coordinate(&format!("{what}[1]"), p[1], MAX_WORLD_EXTENT_M).map(|_| ())
    };
    for (i, w) in f.wall.iter().enumerate() {
        point(format!("wall[{i}].from"), w.from)?;
        point(format!("wall[{i}].to"), w.to)?;
    }
    for (i, b) in f.boxes.iter().enumerate() {
        point(format!("box[{i}].center"), b.center)?;
        coordinate(&format!("box[{i}].yaw"), b.yaw, MAX_ANGLE_RAD)?;
        if let Some(height) = b.height {
            positive(format!("box[{i}].height"), height)?;
        }
    }
    for (i, c) in f.cylinder.iter().enumerate() {
        point(format!("cylinder[{i}].center"), c.center)?;
        if let Some(height) = c.height {
            positive(format!("cylinder[{i}].height"), height)?;
        }
    }
    for (i, s) in f.start.iter().enumerate() {
        point(format!("start[{i}].pose"), [s.pose[0], s.pose[1]])?;
        coordinate(
            &format!("start[{i}].pose[2] (yaw)"),
            s.pose[2],
            MAX_ANGLE_RAD,
        )?;
    }
    let mut obstacles = Vec::new();
    for (i, w) in f.wall.iter().enumerate() {
        let (dx, dy) = (w.to[0] - w.from[0], w.to[1] - w.from[1]);
        let len = dx.hypot(dy);
        positive(format!("wall[{i}] length"), len)?;
        positive(format!("wall[{i}].thickness"), w.thickness)?;
        obstacles.push(Obstacle {
            kind: ObstacleKind::Wall,
            center: [(w.from[0] + w.to[0]) / 2.0, (w.from[1] + w.to[1]) / 2.0],
            yaw: dy.atan2(dx),
            height: h,
            // Walls overlap by half a thickness at corners so rays cannot slip through.
            shape: Shape::Box {
                half_x: len / 2.0 + w.thickness / 2.0,
                half_y: w.thickness / 2.0,
            },
        });
    }
    for (i, b) in f.boxes.iter().enumerate() {
        positive(format!("box[{i}].size[0]"), b.size[0])?;
        positive(format!("box[{i}].size[1]"), b.size[1])?;
        obstacles.push(Obstacle {
            kind: ObstacleKind::Box,
            center: b.center,
            yaw: b.yaw,
            height: b.height.unwrap_or(h),
            shape: Shape::Box {
                half_x: b.size[0] / 2.0,
                half_y: b.size[1] / 2.0,
            },
        });
    }
    for (i, c) in f.cylinder.iter().enumerate() {
        positive(format!("cylinder[{i}].radius"), c.radius)?;
        obstacles.push(Obstacle {
            kind: ObstacleKind::Cylinder,
            center: c.center,
            yaw: 0.0,
            height: c.height.unwrap_or(h),
            shape: Shape::Cylinder { radius: c.radius },
        });
    }
    let mut world = World {
        name: f.world.name,
        size: f.world.size,
        obstacles,
        friction: f.world.friction,
        surveys: Vec::new(),
        starts: f.start.iter().map(|s| s.pose).collect(),
        goals: f.goal,
    };
    let on_floor = |p: [f64; 2]| {
        p.iter().all(|v| v.is_finite())
            && (0.0..=f.world.size[0]).contains(&p[0])
            && (0.0..=f.world.size[1]).contains(&p[1])
    };
    for (i, p) in world.starts.iter().enumerate() {
        if !on_floor([p[0], p[1]]) || !p[2].is_finite() {
            return Err(format!(
                "start[{i}].pose {p:?} must lie on the floor with a finite yaw"
            ));
        }
    }
    for (i, g) in world.goals.iter().enumerate() {
        if !on_floor(g.at) || world.clearance(g.at) <= 0.0 {
            return Err(format!(
                "goal[{i}] ('{}'): 'at' {:?} must lie on the floor, outside every obstacle",
                g.name, g.at
            ));
        }
    }
    for (i, s) in f.survey.iter().enumerate() {
        positive(
            format!("survey[{i}].direction length"),
            s.direction[0].hypot(s.direction[1]),
        )?;
        if world.clearance(s.at) <= 0.0 {
            return Err(format!(
                "survey[{i}] ('{}'): 'at' lies inside an obstacle",
                s.name
            ));
        }
        if world.survey_length(s).is_none() {
            return Err(format!(
                "survey[{i}] ('{}'): the line through 'at' must hit a surface both ways",
                s.name
            ));
        }
    }
    world.surveys = f.survey;
    Ok(world)
}

impl World {
    /// Whether `robot` is one of the robots this world names, for the params of a process
    /// that reads `file`: a world that lists `[[start]]` poses names its robots, and an index
    /// past them is a process for no robot (one that lists none leaves the robots to the
    /// physics' `poses`). The error names the key `robot`.
    pub fn check_robot(&self, file: &str, robot: usize) -> Result<(), String> {
        let starts = self.starts.len();
        if starts > 0 && robot >= starts {
            return Err(format!(
                "key 'robot': world file {file} lists {starts} [[start]] pose(s), for robots 0 \
                 to {}; robot {robot} is not among them",
                starts - 1
            ));
        }
        Ok(())
    }

    /// Distance along the unit vector `dir` from the free point `from` to the first surface,
    /// if one lies within `max` (sphere tracing on the exact distance field).
    pub fn ray_distance(&self, from: [f64; 2], dir: [f64; 2], max: f64) -> Option<f64> {
        let mut s = 0.0;
        for _ in 0..10_000 {
            let d = self.clearance([from[0] + s * dir[0], from[1] + s * dir[1]]);
            if d < 1e-9 {
                return Some(s);
            }
            s += d;
            if s > max {
                return None;
            }
        }
        None
    }

    /// The true surface-to-surface length of a survey line.
    pub fn survey_length(&self, survey: &Survey) -> Option<f64> {
        let [dx, dy] = survey.unit();
        let max = self.size[0].hypot(self.size[1]) + 1.0;
        Some(
            self.ray_distance(survey.at, [dx, dy], max)?
                + self.ray_distance(survey.at, [-dx, -dy], max)?,
        )
    }

    /// Distance from point `p` to the nearest obstacle surface (negative inside one), m.
    pub fn clearance(&self, p: [f64; 2]) -> f64 {
        self.obstacles
            .iter()
            .map(|o| o.distance(p))
            .fold(f64::INFINITY, f64::min)
    }
}

impl Obstacle {
    /// Signed distance from `p` to this obstacle's outline in the plane.
    pub fn distance(&self, p: [f64; 2]) -> f64 {
        let (dx, dy) = (p[0] - self.center[0], p[1] - self.center[1]);
        match self.shape {
            Shape::Cylinder { radius } => dx.hypot(dy) - radius,
            Shape::Box { half_x, half_y } => {
                let (s, c) = self.yaw.sin_cos();
                let (lx, ly) = (
                    (c * dx + s * dy).abs() - half_x,
                    (-s * dx + c * dy).abs() - half_y,
                );
                let outside = lx.max(0.0).hypot(ly.max(0.0));
                outside + lx.max(ly).min(0.0)
            }
        }
    }

    /// Corners of a box obstacle's outline (counter-clockwise), for plots; empty for cylinders.
    pub fn corners(&self) -> Vec<[f64; 2]> {
        let Shape::Box { half_x, half_y } = self.shape else {
            return Vec::new();
        };
        let (s, c) = self.yaw.sin_cos();
        [
            (-half_x, -half_y),
            (half_x, -half_y),
            (half_x, half_y),
            (-half_x, half_y),
        ]
        .iter()
        .map(|(x, y)| {
            [
                self.center[0] + c * x - s * y,
                self.center[1] + s * x + c * y,
            ]
        })
        .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAB: &str = r#"
[world]
name = "t"
size = [4.0, 3.0]

[[wall]]
from = [0.0, 0.0]
to = [4.0, 0.0]

[[box]]
center = [2.0, 1.5]
size = [0.4, 0.2]

[[cylinder]]
center = [3.0, 2.0]
radius = 0.1
"#;

    #[test]
    fn a_robot_past_the_worlds_start_poses_is_refused() {
        let none = parse_world(LAB).unwrap();
        assert!(
            none.check_robot("lab.toml", 9).is_ok(),
            "no [[start]]: physics' poses"
        );
        let two = parse_world(&format!(
            "{LAB}\n[[start]]\npose = [1.0, 1.0, 0.0]\n[[start]]\npose = [0.5, 1.0, 0.0]\n"
        ))
        .unwrap();
        assert!(two.check_robot("lab.toml", 1).is_ok());
        let e = two.check_robot("lab.toml", 2).unwrap_err();
        assert!(
            e.starts_with("key 'robot': world file lab.toml lists 2"),
            "{e}"
        );
    }

    #[test]
    fn parses_and_measures_clearance() {
        let w = parse_world(LAB).unwrap();
        assert_eq!(w.obstacles.len(), 3);
        assert!((w.clearance([2.0, 1.0]) - 0.4).abs() < 1e-9); // box edge at y = 1.4
        assert!((w.obstacles[0].distance([1.0, 0.5]) - 0.475).abs() < 1e-9);
        assert!(w.obstacles[1].distance([2.0, 1.5]) < 0.0);
    }

    #[test]
    fn surveys_measure_between_surfaces() {
        let text = format!(
            "{LAB}\n[[survey]]\nname = \"wall to box\"\nat = [2.0, 1.0]\ndirection = [0.0, 2.0]\n"
        );
        let w = parse_world(&text).unwrap();
        // Wall face at y = 0.025, box face at y = 1.4.
        let length = w.survey_length(&w.surveys[0]).unwrap();
        assert!((length - 1.375).abs() < 1e-6, "{length}");
        let e = parse_world(&text.replace("[2.0, 1.0]", "[2.0, 1.5]")).unwrap_err();
        assert!(
            e.contains("survey[0]") && e.contains("inside an obstacle"),
            "{e}"
        );
        let e = parse_world(&text.replace("[0.0, 2.0]", "[1.0, 0.0]")).unwrap_err();
        assert!(e.contains("hit a surface both ways"), "{e}");
    }

    #[test]
    fn unknown_key_names_line_and_key() {
        let e = parse_world("[world]\nname = \"x\"\nsize = [1.0, 1.0]\n\n[[box]]\ncentre = [0.0, 0.0]\nsize = [1.0, 1.0]\n").unwrap_err();
        assert!(e.contains("line 6") && e.contains("centre"), "{e}");
    }

    #[test]
    fn negative_sizes_are_rejected() {
        let e = parse_world("[world]\nname = \"x\"\nsize = [1.0, -1.0]\n").unwrap_err();
        assert!(e.contains("world.size[1]"), "{e}");
    }

    #[test]
    fn absurd_sizes_are_rejected() {
        let e = parse_world("[world]\nname = \"x\"\nsize = [1e308, 1e308]\n").unwrap_err();
        assert!(e.contains("world.size[0]") && e.contains("10000 m"), "{e}");
    }

    #[test]
    fn non_finite_placements_are_blamed_on_their_own_key() {
        let base = "[world]\nname = \"x\"\nsize = [4.0, 4.0]\n";
        for (extra, key) in [
            (
                "[[box]]\ncenter = [nan, 2.0]\nsize = [0.5, 0.5]\n",
                "box[0].center[0]",
            ),
            (
                "[[box]]\ncenter = [1.0, 2.0]\nyaw = nan\nsize = [0.5, 0.5]\n",
                "box[0].yaw",
            ),
            (
                "[[box]]\ncenter = [1.0, 2.0]\nheight = 1e308\nsize = [0.5, 0.5]\n",
                "box[0].height",
            ),
            (
                "[[cylinder]]\ncenter = [1.0, inf]\nradius = 0.2\n",
                "cylinder[0].center[1]",
            ),
            (
                "[[start]]\npose = [1.0, 1.0, 1e308]\n",
                "start[0].pose[2] (yaw)",
            ),
        ] {
            let e = parse_world(&format!("{base}{extra}")).unwrap_err();
            assert!(e.contains(key), "{extra}: {e}");
        }
    }
}
