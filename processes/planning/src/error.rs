//! Why a global plan failed, worded for the operator: what is wrong and what to change.

/// A point in the map frame, metres.
pub type Point = (f64, f64);

/// The global planner could not produce a path.
#[derive(Debug, Clone, PartialEq)]
pub enum PlanError {
    /// The robot's pose lies off the map: localisation and map disagree.
    StartOutsideMap {
        start: Point,
        /// The map's extent `(min_x, min_y, max_x, max_y)`.
        bounds: (f64, f64, f64, f64),
    },
    /// The goal lies off the map.
    GoalOutsideMap {
        goal: Point,
        bounds: (f64, f64, f64, f64),
    },
    /// The robot's pose is in an obstacle or inflated cell and no free cell lies near it.
    StartInCollision { start: Point, search_radius: f64 },
    /// The goal is in an obstacle, or closer to one than the robot radius.
    GoalInCollision { goal: Point, robot_radius: f64 },
    /// Obstacles close the goal off from the robot, which itself has room to move.
    GoalEnclosed { start: Point, goal: Point },
    /// Obstacles close the robot in.
    StartEnclosed {
        start: Point,
        goal: Point,
        /// Free area reachable from the start, m².
        reachable_area: f64,
    },
}

/// Formats a point as `(x.xx, y.yy)`.
struct P(Point);

impl core::fmt::Display for P {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "({:.2}, {:.2})", self.0.0, self.0.1)
    }
}

fn extent((x0, y0, x1, y1): (f64, f64, f64, f64)) -> String {
    format!("x ∈ [{x0:.2}, {x1:.2}] m, y ∈ [{y0:.2}, {y1:.2}] m")
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::StartOutsideMap { start, bounds } => write!(
                f,
                "start {} is outside the map, which spans {}; check the robot's localisation \
                 and that the pose and the map share a frame",
                P(start),
                extent(bounds)
            ),
            Self::GoalOutsideMap { goal, bounds } => write!(
                f,
                "goal {} is outside the map, which spans {}; choose a goal inside it",
                P(goal),
                extent(bounds)
            ),
            Self::StartInCollision {
                start,
                search_radius,
            } => write!(
                f,
                "start {} is in collision: the map shows obstacles around the robot with no \
                 free cell within {search_radius:.2} m; check the localisation or the map",
                P(start)
            ),
            Self::GoalInCollision { goal, robot_radius } => write!(
                f,
                "goal {} is unreachable: it lies inside an obstacle (or within {robot_radius:.2} \
                 m of one); move the goal further from obstacles",
                P(goal)
            ),
            Self::GoalEnclosed { start, goal } => write!(
                f,
                "no path from {} to {}: the goal is enclosed by obstacles (or by gaps narrower \
                 than the robot)",
                P(start),
                P(goal)
            ),
            Self::StartEnclosed {
                start,
                goal,
                reachable_area,
            } => write!(
                f,
                "no path from {} to {}: the robot is enclosed by obstacles (only \
                 {reachable_area:.2} m² reachable around it)",
                P(start),
                P(goal)
            ),
        }
    }
}

impl std::error::Error for PlanError {}
