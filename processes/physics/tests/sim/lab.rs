//! The lab world keeps the convoy's start corridor and the goal route free.

use crate::common::launch_dir;
use caravan_physics::Params;
use caravan_world::load_world;

const ROUTE: [[f64; 2]; 5] = [[2.2, 1.0], [5.0, 1.1], [5.6, 3.0], [3.4, 3.8], [1.4, 3.0]];

#[test]
fn goal_route_keeps_045_m_from_obstacles() {
    let world = load_world(&launch_dir().join("worlds/lab.toml")).unwrap();
    for leg in ROUTE.windows(2) {
        let (a, b) = (leg[0], leg[1]);
        for k in 0..=200 {
            let t = k as f64 / 200.0;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let c = world.clearance(p);
            assert!(c >= 0.45, "clearance {c} m at {p:?} on {a:?} → {b:?}");
        }
    }
}

#[test]
fn start_corridor_is_free() {
    let world = load_world(&launch_dir().join("worlds/lab.toml")).unwrap();
    for i in 0..=300 {
        for j in 0..=10 {
            let p = [0.6 + i as f64 * 0.01, 0.75 + j as f64 * 0.05];
            assert!(
                world.clearance(p) > 0.15,
                "{p:?} is too close to an obstacle"
            );
        }
    }
}

#[test]
fn the_convoy_starts_in_the_lab() {
    let params = Params::one_kind("worlds/lab.toml", "robots/convoy_bot.urdf", 5);
    let sim = caravan_physics::load(&params, &launch_dir(), 2_000_000).unwrap();
    assert_eq!(sim.robot_count(), 5);
    assert!((sim.pose(4).x - 0.6).abs() < 1e-6);
}
