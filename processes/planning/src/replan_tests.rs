use super::*;
use caravan_schemas::boxed_placement_new;

/// A 3 × 2 m map at 0.05 m per cell, free, or with a wall across x = 1.5 m from the bottom
/// edge up to y = 1.4 m (the straight line from `START` to `GOAL` crosses it).
fn grid(wall: bool) -> Box<OccupancyGrid> {
    const RES: f64 = 0.05;
    let (w, h) = (60, 40);
    let mut g = boxed_placement_new::<OccupancyGrid>();
    g.resolution = RES;
    g.origin = Pose2D::default();
    g.width = w as u32;
    g.height = h as u32;
    for iy in 0..h {
        for ix in 0..w {
            let (x, y) = ((ix as f64 + 0.5) * RES, (iy as f64 + 0.5) * RES);
            let in_wall = wall && (1.45..=1.55).contains(&x) && y <= 1.4;
            g.data[iy * w + ix] = if in_wall { 100 } else { 0 };
        }
    }
    g
}

const START: Pose2D = Pose2D {
    x: 0.5,
    y: 1.0,
    theta: 0.0,
};
const GOAL: Pose2D = Pose2D {
    x: 2.5,
    y: 1.0,
    theta: 0.0,
};

fn goal(index: u32, pose: Pose2D) -> Goal {
    Goal {
        index,
        total: 2,
        pose,
        tolerance_m: 0.1,
    }
}

fn replanner() -> Replanner {
    Replanner::new(
        1.0,
        CostmapParams::default(),
        GlobalParams::default(),
        LocalParams::default(),
    )
}

/// A replanner that planned from `START` to `GOAL` on the free map at t = 0 (map 1).
fn planned() -> Replanner {
    let mut r = replanner();
    r.map(1, &grid(false));
    r.goal(goal(0, GOAL));
    let d = r.step(0.0, Some(START));
    assert!(d.new_path && d.command.is_some(), "{d:?}");
    r
}

/// A decision that keeps the plan and commands the robot on.
fn keeps_plan(d: &Decision) -> bool {
    !d.new_path && d.command.is_some() && d.failure.is_none()
}

fn near(a: &Pose2D, b: &Pose2D) -> bool {
    (a.x - b.x).hypot(a.y - b.y) < 1e-9
}

#[test]
fn nothing_is_planned_until_a_map_a_goal_and_a_pose_are_known() {
    let mut r = replanner();
    assert_eq!(r.step(0.0, Some(START)), Decision::default());
    r.map(1, &grid(false));
    assert_eq!(r.step(0.1, Some(START)), Decision::default(), "no goal");
    r.goal(goal(0, GOAL));
    assert_eq!(r.step(0.2, None), Decision::default(), "no pose");
    assert!(r.path().is_empty());

    let d = r.step(0.3, Some(START));
    assert!(d.new_path && d.failure.is_none(), "{d:?}");
    let (v, omega) = d.command.expect("a command along the new path");
    assert!((0.1..=0.2).contains(&v) && (-1.5..=2.0).contains(&omega));
    let path = r.path();
    assert!(near(&path[0], &START) && near(path.last().unwrap(), &GOAL));
}

#[test]
fn the_plan_is_kept_while_map_and_goal_stay_the_same() {
    let mut r = planned();
    let path = r.path().to_vec();
    // Past the re-plan period too: the period only counts while the map changes.
    for k in 1..30 {
        r.map(1, &grid(false));
        r.goal(goal(0, GOAL));
        let d = r.step(0.1 * k as f64, Some(START));
        assert!(keeps_plan(&d), "step {k}: {d:?}");
    }
    assert_eq!(r.path(), path);
}

#[test]
fn a_repeated_map_is_ignored_even_when_its_contents_differ() {
    let mut r = planned();
    // The same sequence number: the same map, whatever the bytes say.
    r.map(1, &grid(true));
    assert!(keeps_plan(&r.step(0.1, Some(START))));
    // A new number with the wall: the path across it is blocked.
    r.map(2, &grid(true));
    assert!(r.step(0.2, Some(START)).new_path);
}

#[test]
fn a_new_goal_replans_and_a_new_tolerance_alone_does_not() {
    let mut r = planned();
    r.goal(Goal {
        tolerance_m: 0.5,
        ..goal(0, GOAL)
    });
    assert!(keeps_plan(&r.step(0.1, Some(START))));

    r.goal(goal(1, GOAL));
    assert!(r.step(0.2, Some(START)).new_path, "a new index");

    let elsewhere = Pose2D { y: 0.5, ..GOAL };
    r.goal(goal(1, elsewhere));
    assert!(r.step(0.3, Some(START)).new_path, "a new pose");
    assert!(near(r.path().last().unwrap(), &elsewhere));
}

#[test]
fn a_new_map_replans_at_once_when_it_blocks_the_path() {
    let mut r = planned();
    r.map(2, &grid(false));
    assert!(keeps_plan(&r.step(0.1, Some(START))), "still clear");
    r.map(3, &grid(true));
    let d = r.step(0.2, Some(START));
    assert!(d.new_path && d.command.is_some(), "{d:?}");
    assert!(
        r.path().iter().any(|p| p.y > 1.4),
        "goes round the wall's end"
    );
}

#[test]
fn a_new_map_replans_when_the_period_has_passed_since_the_last_plan() {
    let mut r = planned();
    r.map(2, &grid(false));
    // Times in whole binary fractions, so that the differences are exact.
    assert!(keeps_plan(&r.step(0.875, Some(START))), "within the period");
    assert!(keeps_plan(&r.step(1.5, Some(START))), "no new map");
    r.map(3, &grid(false));
    assert!(r.step(1.75, Some(START)).new_path, "1.75 s since the plan");
    r.map(4, &grid(false));
    assert!(
        keeps_plan(&r.step(2.0, Some(START))),
        "0.25 s since the plan"
    );
    r.map(5, &grid(false));
    assert!(r.step(2.75, Some(START)).new_path, "exactly the period");
}

#[test]
fn once_every_goal_is_reached_nothing_is_commanded() {
    let mut r = planned();
    r.goal(Goal {
        index: 2,
        ..goal(0, GOAL)
    });
    assert_eq!(r.step(0.1, Some(START)), Decision::default());
}

#[test]
fn a_failure_is_reported_once_and_again_after_a_success() {
    let mut r = replanner();
    r.map(1, &grid(false));
    let outside = Pose2D { x: 5.0, ..GOAL };
    r.goal(goal(1, outside));
    let d = r.step(0.0, Some(START));
    let text = d.failure.expect("reported");
    assert!(
        text.starts_with("goal 2 of 2: ") && text.contains("outside the map"),
        "{text}"
    );
    assert!(!d.new_path && d.command.is_none() && r.path().is_empty());
    // Planned again (there is no path), failing for the same reason: not reported again.
    assert_eq!(r.step(0.1, Some(START)), Decision::default());

    r.goal(goal(1, GOAL));
    assert!(r.step(0.2, Some(START)).new_path);
    r.goal(goal(1, outside));
    let d = r.step(0.3, Some(START));
    assert_eq!(d.failure.as_deref(), Some(text.as_str()));
    assert!(r.path().is_empty(), "a failed plan leaves no path");
}

#[test]
fn with_no_safe_rollout_nothing_is_commanded_and_the_next_step_plans_from_standstill() {
    let first = {
        let mut r = replanner();
        r.map(1, &grid(false));
        r.goal(goal(0, GOAL));
        r.step(0.0, Some(START))
    };
    // Driving on ramps the command up from the last one.
    let mut r = planned();
    let d = r.step(0.1, Some(START));
    assert!(keeps_plan(&d) && d.command != first.command, "{d:?}");

    // Off the map every rollout collides; the map and the goal did not change.
    let mut r = planned();
    let path = r.path().to_vec();
    let off = Pose2D { x: -1.0, ..START };
    assert_eq!(r.step(0.1, Some(off)), Decision::default());
    // Back at the start: a new plan (the same one), and the command a standstill gives.
    let d = r.step(0.2, Some(START));
    assert!(d.new_path, "{d:?}");
    assert_eq!(d.command, first.command);
    assert_eq!(r.path(), path);
}
