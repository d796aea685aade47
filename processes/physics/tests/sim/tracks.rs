//! What rows of overlapping wheels need: no contacts between a robot's own links, rapier's
//! velocity motors, kinematic joints or rims on the wheels, a world's own friction.

use caravan_physics::actuator::Target;
use caravan_physics::{Params, Simulation, load};
use std::path::Path;

fn sim(robot: serde_json::Value, dt_ns: u64) -> Simulation {
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({ "world": "empty.toml", "substeps": 1, "robots": [robot] }),
    )
    .unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    load(&params, &dir, dt_ns).unwrap()
}

/// Every wheel at `speed` rad/s.
fn spin(s: &mut Simulation, speed: f64) {
    let targets = vec![
        Target {
            velocity: speed,
            ..Target::default()
        };
        s.joints(0).count()
    ];
    s.set_targets(0, &targets);
}

/// The overlap robot on `joints` with `actuator` on every wheel, every wheel at 4 rad/s for
/// 5 s: it rolls level at the rim speed (4 rad/s × 5 cm: 0.2 m/s, so 0.4 m in the last 2 s).
fn rolls_at_rim_speed(joints: &str, actuator: &str) -> Simulation {
    let mut s = sim(
        serde_json::json!({ "urdf": "overlap.urdf", "joints": joints,
            "poses": [[1.0, 2.0, 0.0]], "actuators": [{ "type": actuator, "joints": ["*"] }] }),
        2_000_000,
    );
    spin(&mut s, 4.0);
    s.advance_to(3_000_000_000, u64::MAX);
    let x0 = s.pose(0).x;
    s.advance_to(5_000_000_000, u64::MAX);
    let moved = s.pose(0).x - x0;
    assert!((moved - 0.4).abs() < 0.02, "{actuator}: moved {moved} m");
    assert!(
        s.twist(0).angular.y.abs() < 0.05,
        "{joints} {actuator}: rolls level: {:?}",
        s.twist(0)
    );
    s
}

#[test]
fn overlapping_wheels_on_motors_roll_the_robot_at_their_rim_speed() {
    let s = rolls_at_rim_speed("impulse", "motor");
    for (name, _, speed, effort) in s.joints(0) {
        assert!((speed - 4.0).abs() < 0.05, "{name}: {speed} rad/s");
        assert!(
            effort.abs() <= 5.0,
            "{name}: {effort} N·m within the URDF's limit"
        );
    }
}

/// Contacts between one robot's own links: none by default, the overlapping rims' with
/// `self_collide = true`.
#[test]
fn a_robots_own_links_touch_only_with_self_collide() {
    for self_collide in [false, true] {
        let mut s = sim(
            serde_json::json!({ "urdf": "overlap.urdf", "joints": "impulse",
                "self_collide": self_collide, "contacts": true, "poses": [[1.0, 2.0, 0.0]] }),
            2_000_000,
        );
        s.advance_to(100_000_000, u64::MAX);
        let own = s
            .contact_points(0)
            .iter()
            .filter(|c| c.other_robot == 0)
            .count();
        assert_eq!(
            own > 0,
            self_collide,
            "{own} contacts between its own links"
        );
    }
}

#[test]
fn a_motor_holds_a_light_wheel_at_its_speed_with_a_long_step() {
    // A 40 g wheel on a fixed stand, 10 ms steps: an explicit speed loop strong enough to
    // drive a robot would ring; the motor is solved with the step.
    let mut s = sim(
        serde_json::json!({ "urdf": "overlap.urdf", "base": "fixed", "joints": "impulse",
            "poses": [[1.0, 2.0, 0.5, 0.0, 0.0, 0.0]],
            "actuators": [{ "type": "motor", "joints": ["*"], "damping": 1000.0 }] }),
        10_000_000,
    );
    spin(&mut s, 10.0);
    s.advance_to(1_000_000_000, u64::MAX);
    for (name, _, speed, effort) in s.joints(0) {
        assert!((speed - 10.0).abs() < 1e-3, "{name}: {speed}");
        assert!(
            effort.abs() < 0.1,
            "{name}: nothing to push against: {effort}"
        );
    }
    // Past the URDF's velocity limit the target is clamped to it.
    spin(&mut s, 50.0);
    s.advance_to(3_000_000_000, u64::MAX);
    let (_, _, speed, _) = s.joints(0).next().unwrap();
    assert!((speed - 20.0).abs() < 1e-3, "{speed}");
}

#[test]
fn kinematic_wheels_roll_a_multibody_at_their_rim_speed_and_no_faster_than_the_limit() {
    let mut s = rolls_at_rim_speed("multibody", "kinematic");
    for (name, _, speed, effort) in s.joints(0) {
        // Exactly the target, whatever the load: the solver leaves the joint alone.
        assert!((speed - 4.0).abs() < 1e-4, "{name}: {speed} rad/s");
        assert_eq!(effort, 0.0, "{name}");
    }
    spin(&mut s, 50.0);
    s.advance_to(5_100_000_000, u64::MAX);
    let (_, _, speed, _) = s.joints(0).next().unwrap();
    assert!(
        (speed - 20.0).abs() < 1e-4,
        "clamped to the URDF's 20 rad/s: {speed}"
    );
}

#[test]
fn rims_roll_a_multibody_at_their_rim_speed_and_report_their_turn() {
    let mut s = rolls_at_rim_speed("multibody", "rim");
    for (name, position, speed, effort) in s.joints(0) {
        // Turned exactly: 4 rad/s for 5 s, whatever the load.
        assert!((speed - 4.0).abs() < 1e-9, "{name}: {speed} rad/s");
        assert!((position - 20.0).abs() < 0.01, "{name}: {position} rad");
        assert_eq!(effort, 0.0, "{name}");
    }
    // The wheel's link spins in `link_states`, though its body does not.
    let wheel = s.description(0).link("left_a").unwrap();
    let (_, twist) = &s.link_states(0)[wheel];
    assert!((twist.angular.y - 4.0).abs() < 0.05, "{twist:?}");
    // Backwards, and clamped to the URDF's 20 rad/s like a kinematic joint.
    spin(&mut s, -50.0);
    let x0 = s.pose(0).x;
    s.advance_to(6_000_000_000, u64::MAX);
    let (_, _, speed, _) = s.joints(0).next().unwrap();
    assert_eq!(speed, -20.0);
    assert!(s.pose(0).x < x0 - 0.3, "rolled back to {}", s.pose(0).x);
}

/// A robot standing on its wheels: its contact points carry its weight (2.6 kg × 9.81 m/s²)
/// and lie on the floor, whatever turns its wheels and whether a wheel is one shape or a
/// compound: a rim and a tooth, whose contacts rapier's solver merges into clusters
/// (`geared.urdf`), or whose one manifold, the tooth's, it solves as it is, its points in
/// the tooth's frame (`spiked.urdf`).
#[test]
fn wheel_contacts_carry_the_robots_weight_on_the_floor() {
    for (urdf, joints, actuator) in [
        ("overlap.urdf", "impulse", "motor"),
        ("overlap.urdf", "multibody", "kinematic"),
        ("overlap.urdf", "multibody", "rim"),
        ("geared.urdf", "multibody", "kinematic"),
        ("geared.urdf", "multibody", "rim"),
        ("spiked.urdf", "multibody", "rim"),
    ] {
        let mut s = sim(
            serde_json::json!({ "urdf": urdf, "joints": joints, "contacts": true,
                "poses": [[1.0, 2.0, 0.0]], "actuators": [{ "type": actuator, "joints": ["*"] }] }),
            2_000_000,
        );
        s.advance_to(2_000_000_000, u64::MAX);
        let points = s.contact_points(0);
        let total: f64 = points.iter().map(|c| c.normal_force).sum();
        assert!(
            (total - 2.6 * 9.81).abs() < 0.05 * 2.6 * 9.81,
            "{urdf} {joints} {actuator}: {} points carry {total} N",
            points.len()
        );
        for c in points.iter().filter(|c| c.normal_force > 0.0) {
            assert!(c.point[2].abs() < 0.003, "{urdf} {actuator}: {c:?}");
        }
    }
}
