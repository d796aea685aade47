//! The local planner in closed loop with ideal unicycle kinematics at 10 Hz.

mod common;

use caravan_planning::{
    Costmap, GlobalParams, GlobalPlanner, INSCRIBED, LETHAL, LocalParams, LocalPlanner,
};
use caravan_schemas::Pose2D;
use common::{Sketch, pose};

const DT: f64 = 0.1;

/// Poses every 5 cm along a polyline, each facing the next.
fn polyline(points: &[(f64, f64)]) -> Vec<Pose2D> {
    let mut out = Vec::new();
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        let theta = (b.1 - a.1).atan2(b.0 - a.0);
        let n = (len / 0.05).ceil() as usize;
        for k in 0..n {
            let t = k as f64 / n as f64;
            out.push(pose(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t, theta));
        }
    }
    let last = *points.last().unwrap();
    let theta = out.last().map_or(0.0, |p| p.theta);
    out.push(pose(last.0, last.1, theta));
    out
}

struct Run {
    reached: bool,
    time: f64,
    /// Highest cost met by the robot's centre, sampled every 1 cm of travel.
    worst_cost: u8,
    commands: Vec<(f64, f64)>,
}

/// Drives from `start` along `path` until within `tolerance` of its end, for at most
/// `max_time` seconds: each 0.1 s the planner's command is applied exactly (ideal unicycle).
fn drive(map: &Costmap, path: &[Pose2D], start: Pose2D, tolerance: f64, max_time: f64) -> Run {
    drive_with(
        LocalParams::default(),
        map,
        path,
        start,
        tolerance,
        max_time,
    )
}

fn drive_with(
    params: LocalParams,
    map: &Costmap,
    path: &[Pose2D],
    start: Pose2D,
    tolerance: f64,
    max_time: f64,
) -> Run {
    let planner = LocalPlanner::new(params);
    let goal = *path.last().unwrap();
    let mut p = start;
    let mut current = (0.0, 0.0);
    let mut run = Run {
        reached: false,
        time: 0.0,
        worst_cost: map.cost_at(p.x, p.y).unwrap(),
        commands: Vec::new(),
    };
    while run.time < max_time {
        if (p.x - goal.x).hypot(p.y - goal.y) <= tolerance {
            run.reached = true;
            break;
        }
        let Some((v, w)) = planner.command(map, p, current, path) else {
            panic!("no collision-free command at {p:?} after {:.1} s", run.time);
        };
        run.commands.push((v, w));
        current = (v, w);
        // Exact arc integration in 20 sub-steps (1 cm each at 0.2 m/s).
        let sub = DT / 20.0;
        for _ in 0..20 {
            if w.abs() < 1e-12 {
                p.x += v * sub * p.theta.cos();
                p.y += v * sub * p.theta.sin();
            } else {
                let th = p.theta + w * sub;
                p.x += v / w * (th.sin() - p.theta.sin());
                p.y -= v / w * (th.cos() - p.theta.cos());
                p.theta = th;
            }
            run.worst_cost = run.worst_cost.max(map.cost_at(p.x, p.y).unwrap_or(LETHAL));
        }
        run.time += DT;
    }
    run
}

/// Speed and turn-rate limits on every command, and the acceleration limits between
/// consecutive ones (from standstill the speed may jump to v_min, no further).
fn assert_limits(commands: &[(f64, f64)]) {
    assert_limits_of(&LocalParams::default(), commands);
}

fn assert_limits_of(l: &LocalParams, commands: &[(f64, f64)]) {
    assert!(!commands.is_empty());
    for &(v, w) in commands {
        assert!((l.v_min..=l.v_max).contains(&v), "v = {v}");
        assert!((l.omega_min..=l.omega_max).contains(&w), "ω = {w}");
    }
    let (dv, dw) = (l.acc_lim_v * DT + 1e-9, l.acc_lim_omega * DT + 1e-9);
    assert!(
        commands[0].0 <= l.v_min.max(dv),
        "first v = {}",
        commands[0].0
    );
    assert!(commands[0].1.abs() <= dw, "first ω = {}", commands[0].1);
    for pair in commands.windows(2) {
        let ((v0, w0), (v1, w1)) = (pair[0], pair[1]);
        assert!((v1 - v0).abs() <= dv, "v jumps from {v0} to {v1}");
        assert!((w1 - w0).abs() <= dw, "ω jumps from {w0} to {w1}");
    }
}

/// A 0.7 m wide L-shaped corridor: east along y ≈ 0.55, then north along x ≈ 2.95.
fn l_corridor() -> Sketch {
    let mut s = Sketch::new(4.0, 4.0, 100);
    s.rect(0.2, 0.2, 3.3, 0.9, 0).rect(2.6, 0.2, 3.3, 3.8, 0);
    s
}

/// The same L, only 0.5 m wide: 0.19 m of room for the robot's centre.
fn narrow_l_corridor() -> Sketch {
    let mut s = Sketch::new(4.0, 4.0, 100);
    s.rect(0.3, 0.3, 3.2, 0.8, 0).rect(2.7, 0.3, 3.2, 3.8, 0);
    s
}

#[test]
fn follows_an_l_shaped_path_through_a_corridor() {
    let map = l_corridor().costmap();
    let path = polyline(&[(0.5, 0.55), (2.95, 0.55), (2.95, 3.5)]);
    let run = drive(&map, &path, pose(0.5, 0.55, 0.0), 0.1, 60.0);
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert!(
        run.worst_cost < INSCRIBED,
        "the robot's centre entered an inflated cell (cost {})",
        run.worst_cost
    );
    assert_limits(&run.commands);
    // 5.4 m of path: mostly at full speed, allowing for the corner.
    assert!(run.time < 40.0, "took {:.1} s", run.time);
}

#[test]
fn keeps_out_of_inflated_cells_when_the_path_hugs_a_wall() {
    // A bad global path 0.12 m from a wall, inside the robot radius, in a 0.5 m corridor; with
    // no obstacle-cost term, only the rollouts' collision checks keep the robot off it.
    let params = LocalParams {
        occdist_scale: 0.0,
        ..LocalParams::default()
    };
    let map = narrow_l_corridor().costmap();
    let path = polyline(&[(0.5, 0.42), (3.0, 0.42)]);
    assert!(map.cost_at(1.5, 0.42).unwrap() >= INSCRIBED);
    let run = drive_with(params, &map, &path, pose(0.5, 0.55, 0.0), 0.1, 60.0);
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert!(run.worst_cost < INSCRIBED, "cost {}", run.worst_cost);
    assert_limits(&run.commands);
}

#[test]
fn steers_round_an_obstacle_on_a_stale_path() {
    // A small box appeared on the global path after it was planned; until the node re-plans,
    // the rollouts' collision checks must take the robot round it.
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05).rect(1.95, 1.45, 2.05, 1.55, 100);
    let map = s.costmap();
    let path = polyline(&[(0.5, 1.5), (3.5, 1.5)]);
    // An agile robot: with the convoy's gentle default turn-rate ramp (0.5 rad/s²) the box is
    // too close to swerve round, and the node re-plans instead (`path_blocked`).
    let params = LocalParams {
        acc_lim_omega: 3.0,
        sim_time: 1.7,
        lookahead: 0.5,
        ..LocalParams::default()
    };
    let run = drive_with(params.clone(), &map, &path, pose(0.5, 1.5, 0.0), 0.1, 60.0);
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert!(run.worst_cost < INSCRIBED, "cost {}", run.worst_cost);
    assert_limits_of(&params, &run.commands);
}

#[test]
fn turns_round_when_starting_backwards() {
    // Facing away from the path in the corridor's 0.7 m width: the leader cannot turn in
    // place, so it must loop round without touching the walls.
    let map = l_corridor().costmap();
    let path = polyline(&[(0.8, 0.55), (2.95, 0.55), (2.95, 3.5)]);
    let run = drive(
        &map,
        &path,
        pose(0.8, 0.55, core::f64::consts::PI),
        0.1,
        60.0,
    );
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert!(run.worst_cost < INSCRIBED, "cost {}", run.worst_cost);
    assert_limits(&run.commands);
}

#[test]
fn drives_a_global_plan_through_a_gap() {
    let mut s = Sketch::new(4.0, 3.0, 0);
    s.border(0.05)
        .rect(1.95, 0.0, 2.05, 2.2, 100)
        .rect(1.95, 2.8, 2.05, 3.0, 100);
    let map = s.costmap();
    let start = pose(1.0, 1.0, -1.0);
    let path = GlobalPlanner::new(GlobalParams::default())
        .plan(&map, start, pose(3.0, 1.0, 0.0))
        .unwrap();
    let run = drive(&map, &path, start, 0.1, 60.0);
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert!(run.worst_cost < INSCRIBED, "cost {}", run.worst_cost);
    assert_limits(&run.commands);
}

#[test]
fn gives_up_when_boxed_in() {
    // 0.36 m square of free floor: too small for the tightest loop (5 cm radius) once the
    // robot radius is kept from every wall.
    let mut s = Sketch::new(2.0, 2.0, 100);
    s.rect(0.82, 0.82, 1.18, 1.18, 0);
    let map = s.costmap();
    let path = polyline(&[(1.0, 1.0), (1.5, 1.0)]);
    let planner = LocalPlanner::new(LocalParams::default());
    assert_eq!(
        planner.command(&map, pose(1.0, 1.0, 0.0), (0.0, 0.0), &path),
        None
    );
    assert_eq!(
        planner.command(&map, pose(1.0, 1.0, 0.0), (0.0, 0.0), &[]),
        None
    );
}

#[test]
fn drives_out_from_too_close_to_a_wall() {
    // The robot ends up 0.12 m from a wall (inside the 0.1445 m radius) facing along it; it
    // must still get a command that takes it along and away, never closer.
    let mut s = Sketch::new(4.0, 2.0, 0);
    s.rect(0.0, 0.0, 4.0, 0.5, 100);
    let map = s.costmap();
    let start = pose(1.0, 0.62, 0.0);
    assert!(map.cost_at(start.x, start.y).unwrap() >= INSCRIBED);
    let path = polyline(&[(1.0, 0.62), (1.3, 1.0), (3.0, 1.0)]);
    let run = drive(&map, &path, start, 0.1, 40.0);
    assert!(run.reached, "did not reach the goal in {:.1} s", run.time);
    assert_limits(&run.commands);
    assert!(run.worst_cost < LETHAL);
}
