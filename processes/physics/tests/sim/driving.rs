use crate::common::{geometry, room, run_for, sim};
use caravan_schemas::WheelSetpoint;
use caravan_world::kinematics::wheel_speeds;

fn command(v: f64, omega: f64) -> WheelSetpoint {
    let (r, l) = geometry();
    let (left, right) = wheel_speeds(v, omega, r, l);
    WheelSetpoint {
        left_rad_s: left,
        right_rad_s: right,
    }
}

#[test]
fn drives_straight_at_the_commanded_speed() {
    let mut s = sim(&room(None), &[[0.5, 2.0, 0.0]]);
    s.set_setpoint(0, &command(0.2, 0.0));
    run_for(&mut s, 4.0); // past the step response
    let a = s.pose(0);
    run_for(&mut s, 2.0);
    let b = s.pose(0);
    let speed = (b.x - a.x) / 2.0;
    assert!((speed - 0.2).abs() < 0.01, "speed {speed} m/s");
    assert!((b.y - 2.0).abs() < 0.02, "drifted sideways to y = {}", b.y);
    assert!(b.theta.abs() < 0.05, "heading {}", b.theta);
    let twist = s.twist(0);
    assert!((twist.linear.x - 0.2).abs() < 0.02, "{twist:?}");
}

#[test]
fn turns_left_with_positive_yaw_rate() {
    let mut s = sim(&room(None), &[[2.0, 2.0, 0.0]]);
    s.set_setpoint(0, &command(0.1, 1.0));
    run_for(&mut s, 4.0);
    let a = s.pose(0);
    run_for(&mut s, 1.0);
    let b = s.pose(0);
    let yaw_rate = (b.theta - a.theta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    assert!((yaw_rate - 1.0).abs() < 0.05, "yaw rate {yaw_rate} rad/s");
    assert!(s.twist(0).angular.z > 0.8, "{:?}", s.twist(0));
    // Turning on a circle of radius v/ω = 0.1 m: the robot stays near its start.
    assert!((b.x - 2.0).hypot(b.y - 2.0) < 0.3, "{b:?}");
}

#[test]
fn wheel_state_reports_angles_speeds_and_voltages() {
    let mut s = sim(&room(None), &[[0.5, 2.0, 0.0]]);
    let before = s.wheel_state(0);
    assert_eq!(before.left_voltage, 0.0);
    s.set_setpoint(0, &command(0.2, 0.0));
    run_for(&mut s, 4.0);
    let w = s.wheel_state(0);
    assert!((w.left_rad_s - 2.985).abs() < 0.15 && (w.right_rad_s - 2.985).abs() < 0.15);
    assert!(w.left_voltage > 0.5 && w.left_voltage < 6.0, "{w:?}");
    // Rolling without slip: the wheel turned as far as the robot travelled.
    let (r, _) = geometry();
    let travelled = s.pose(0).x - 0.5;
    assert!(
        (w.left_angle_rad * r - travelled).abs() < 0.02,
        "{w:?} vs {travelled} m"
    );
}

#[test]
fn holds_still_without_setpoints() {
    let mut s = sim(&room(None), &[[1.0, 1.0, 0.5]]);
    run_for(&mut s, 2.0);
    let p = s.pose(0);
    assert!(
        (p.x - 1.0).abs() < 1e-3 && (p.y - 1.0).abs() < 1e-3,
        "{p:?}"
    );
    assert!((p.theta - 0.5).abs() < 1e-3, "{p:?}");
}
