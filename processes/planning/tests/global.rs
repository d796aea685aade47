//! Global planner behaviour on small hand-drawn maps.

mod common;

use caravan_planning::{
    Costmap, GlobalParams, GlobalPlanner, INSCRIBED, PlanError, path_blocked, path_length,
};
use caravan_schemas::Pose2D;
use common::{Sketch, assert_clear, pose};

fn plan(map: &Costmap, from: (f64, f64), to: (f64, f64)) -> Result<Vec<Pose2D>, PlanError> {
    GlobalPlanner::new(GlobalParams::default()).plan(
        map,
        pose(from.0, from.1, 0.0),
        pose(to.0, to.1, 0.0),
    )
}

fn assert_ends(path: &[Pose2D], from: (f64, f64), to: (f64, f64)) {
    let (a, b) = (path.first().unwrap(), path.last().unwrap());
    assert!((a.x, a.y) == from, "path starts at {a:?}");
    assert!((b.x, b.y) == to, "path ends at {b:?}");
    assert!(
        path.windows(2)
            .all(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y) <= 0.05 + 1e-9),
        "poses further apart than path_spacing"
    );
    // Headings point along the path.
    for w in path.windows(2) {
        let dir = (w[1].y - w[0].y).atan2(w[1].x - w[0].x);
        assert!((w[0].theta - dir).abs() < 1e-9);
    }
}

/// A 4 × 3 m room split by a wall at x = 2 with a 0.6 m gap centred at y = 2.5.
fn wall_with_gap() -> Sketch {
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05)
        .rect(1.95, 0.0, 2.05, 2.2, 100)
        .rect(1.95, 2.8, 2.05, 3.0, 100);
    s
}

#[test]
fn routes_through_the_gap_in_a_wall() {
    let map = wall_with_gap().costmap();
    let (from, to) = ((1.0, 1.0), (3.0, 1.0));
    let path = plan(&map, from, to).unwrap();
    assert_ends(&path, from, to);
    assert_clear(&map, &path);
    // Through the gap: some pose crosses x = 2 between y = 2.2 and 2.8.
    let crossing = path
        .windows(2)
        .find(|w| w[0].x < 2.0 && w[1].x >= 2.0)
        .expect("path never crosses the wall line");
    assert!((2.3..2.7).contains(&crossing[0].y), "{:?}", crossing[0]);
    // The detour via the gap's centre is 2·√(1² + 1.5²) = 3.61 m. The inflation cost on both
    // sides of the wall makes the cost-aware route cross the gap squarely, which adds a
    // little (as navfn would); allow 10 %.
    let len = path_length(&path);
    let expected = 2.0 * 1.0f64.hypot(1.5);
    assert!(
        (expected..expected * 1.1).contains(&len),
        "length {len:.3} m, expected about {expected:.3} m"
    );

    // Without cell costs the route hugs the wall's end: the shortest collision-free detour
    // rounds the inflated wall end (cell centres within 0.1445 + ½ cell of the wall's cells),
    // which is 3.43 m long; grid vertices may add a few centimetres.
    let mut planner = GlobalPlanner::new(GlobalParams {
        cost_weight: 0.0,
        ..GlobalParams::default()
    });
    let tight = planner
        .plan(&map, pose(1.0, 1.0, 0.0), pose(3.0, 1.0, 0.0))
        .unwrap();
    assert_clear(&map, &tight);
    let shortest = 3.43;
    let tight_len = path_length(&tight);
    assert!(
        (shortest - 0.02..shortest + 0.07).contains(&tight_len),
        "length {tight_len:.3} m, expected about {shortest:.3} m"
    );
}

#[test]
fn routes_around_a_box() {
    // A 1 × 1.4 m box in the middle of a 4 × 3 m room; going round it either side costs the
    // same, the straight line is blocked.
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05).rect(1.5, 0.8, 2.5, 2.2, 100);
    let map = s.costmap();
    let (from, to) = ((0.5, 1.5), (3.5, 1.5));
    let path = plan(&map, from, to).unwrap();
    assert_ends(&path, from, to);
    assert_clear(&map, &path);
    // Hugging the box at the collision radius (0.1445 m) is the shortest conceivable detour;
    // passing 0.35 m off is the longest sensible one.
    let around = |c: f64| 2.0 * (1.0 - c).hypot(0.7 + c) + 1.0 + 2.0 * c;
    let len = path_length(&path);
    assert!(
        (around(0.1445)..around(0.35)).contains(&len),
        "length {len:.3} m, expected between {:.3} and {:.3}",
        around(0.1445),
        around(0.35)
    );
    // It really goes round: some pose is beyond the box's top or bottom edge plus the radius.
    assert!(
        path.iter()
            .any(|p| (1.5..2.5).contains(&p.x) && (p.y > 2.34 || p.y < 0.66))
    );
}

#[test]
fn straight_line_in_open_space_is_straight() {
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05);
    let map = s.costmap();
    let path = plan(&map, (0.7, 0.9), (3.3, 2.1)).unwrap();
    let straight = (2.6f64).hypot(1.2);
    assert!((path_length(&path) - straight).abs() < 1e-6);
}

#[test]
fn refuses_a_goal_inside_an_obstacle() {
    let map = wall_with_gap().costmap();
    let err = plan(&map, (1.0, 1.0), (2.0, 1.0)).unwrap_err();
    assert!(matches!(err, PlanError::GoalInCollision { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("goal (2.00, 1.00) is unreachable"), "{msg}");
    assert!(
        msg.contains("inside an obstacle (or within 0.14 m of one)"),
        "{msg}"
    );
    // Within the robot radius of the wall also counts.
    let err = plan(&map, (1.0, 1.0), (1.85, 1.0)).unwrap_err();
    assert!(err.to_string().contains("goal (1.85, 1.00)"), "{err}");
}

#[test]
fn refuses_a_goal_enclosed_by_a_ring_wall() {
    let mut s = Sketch::new(5.0, 4.0, -1);
    // Known free floor around a closed square ring (outer 1.6 m, wall 0.1 m).
    s.rect(0.5, 0.5, 4.5, 3.5, 0)
        .rect(2.7, 1.2, 4.3, 2.8, 100)
        .rect(2.8, 1.3, 4.2, 2.7, 0);
    let map = s.costmap();
    let err = plan(&map, (1.0, 2.0), (3.5, 2.0)).unwrap_err();
    assert!(matches!(err, PlanError::GoalEnclosed { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("no path from (1.00, 2.00) to (3.50, 2.00): the goal is enclosed"),
        "{msg}"
    );
    // The other way round, the robot is the one boxed in.
    let err = plan(&map, (3.5, 2.0), (1.0, 2.0)).unwrap_err();
    assert!(matches!(err, PlanError::StartEnclosed { .. }), "{err:?}");
    assert!(err.to_string().contains("the robot is enclosed"), "{err}");
}

#[test]
fn refuses_a_goal_outside_the_map() {
    let map = wall_with_gap().costmap();
    let err = plan(&map, (1.0, 1.0), (5.6, 3.0)).unwrap_err();
    assert!(matches!(err, PlanError::GoalOutsideMap { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("goal (5.60, 3.00) is outside the map"),
        "{msg}"
    );
    assert!(
        msg.contains("x ∈ [0.00, 4.00] m, y ∈ [0.00, 3.00] m"),
        "{msg}"
    );
    let err = plan(&map, (-1.0, 1.0), (3.0, 1.0)).unwrap_err();
    assert!(
        err.to_string()
            .contains("start (-1.00, 1.00) is outside the map"),
        "{err}"
    );
}

#[test]
fn plans_from_a_start_close_to_a_wall() {
    let map = wall_with_gap().costmap();
    // 0.1 m from the wall's face: inside the robot radius.
    let from = (1.85, 1.0);
    assert!(map.cost_at(from.0, from.1).unwrap() >= INSCRIBED);
    let path = plan(&map, from, (3.0, 1.0)).unwrap();
    assert_eq!((path[0].x, path[0].y), from);
    // One straight step out to free space, then clear all the way.
    assert!(map.cost_at(path[1].x, path[1].y).unwrap() < INSCRIBED);
    assert_clear(&map, &path[1..]);
    assert!(!path_blocked(&map, &path, 1));
}

#[test]
fn refuses_a_start_buried_in_an_obstacle() {
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.rect(0.5, 0.5, 2.0, 2.0, 100);
    let err = plan(&s.costmap(), (1.25, 1.25), (3.0, 1.0)).unwrap_err();
    assert!(matches!(err, PlanError::StartInCollision { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains("start (1.25, 1.25) is in collision"),
        "{err}"
    );
}

#[test]
fn plans_into_unknown_space() {
    // Only a strip around the robot is mapped; the goal lies in the unknown.
    let mut s = Sketch::new(6.0, 4.0, -1);
    s.rect(0.5, 0.5, 2.0, 2.0, 0).rect(2.0, 0.5, 2.1, 1.6, 100);
    let map = s.costmap();
    let path = plan(&map, (1.0, 1.0), (5.0, 3.0)).unwrap();
    assert_clear(&map, &path);
    assert!((path.last().unwrap().x, path.last().unwrap().y) == (5.0, 3.0));
}

#[test]
fn detects_an_obstacle_dropped_on_the_path() {
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05);
    let map = s.costmap();
    let path = plan(&map, (0.5, 1.5), (3.5, 1.5)).unwrap();
    assert!(!path_blocked(&map, &path, 0));
    // A 0.2 m box appears on the path at x ≈ 2.
    s.rect(1.9, 1.4, 2.1, 1.6, 100);
    let changed = s.costmap();
    assert!(path_blocked(&changed, &path, 0));
    let ahead = path.iter().position(|p| p.x > 1.0).unwrap();
    assert!(path_blocked(&changed, &path, ahead));
    // Once past the box (and its inflation), the rest of the path is clear again.
    let past = path.iter().position(|p| p.x > 2.5).unwrap();
    assert!(!path_blocked(&changed, &path, past));
    // A box beside the path, outside the robot radius, does not block it.
    let mut side = Sketch::new(4.0, 3.0, 0);
    side.border(0.05).rect(1.9, 1.75, 2.1, 1.95, 100);
    assert!(!path_blocked(&side.costmap(), &path, 0));
    // Re-planning on the changed map goes round the box.
    let replanned = plan(&changed, (0.5, 1.5), (3.5, 1.5)).unwrap();
    assert!(!path_blocked(&changed, &replanned, 0));
}

#[test]
fn works_from_an_occupancy_grid_message() {
    let sketch = wall_with_gap();
    let mut grid = caravan_schemas::boxed_placement_new::<caravan_schemas::OccupancyGrid>();
    grid.resolution = common::RES;
    grid.origin = Pose2D {
        x: -2.0,
        y: -1.0,
        theta: 0.0,
    };
    grid.width = sketch.w as u32;
    grid.height = sketch.h as u32;
    grid.data[..sketch.cells.len()].copy_from_slice(&sketch.cells);
    let map = Costmap::from_grid(&grid, &caravan_planning::CostmapParams::default());
    let path = plan(&map, (-1.0, 0.0), (1.0, 0.0)).unwrap();
    assert_clear(&map, &path);
    assert!(
        path.iter().any(|p| p.y > 1.2),
        "must pass the gap at y ≈ 1.5"
    );
}
