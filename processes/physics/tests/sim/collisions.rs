use crate::common::{room, run_for, sim};
use caravan_schemas::{Collision, WheelSetpoint};

fn drive(speed: f64) -> WheelSetpoint {
    WheelSetpoint {
        left_rad_s: speed,
        right_rad_s: speed,
    }
}

fn started(robot: u32, other_robot: i32) -> Collision {
    Collision {
        robot,
        other_robot,
        started: 1,
        _reserved: 0,
    }
}

#[test]
fn driving_into_a_wall_starts_and_backing_off_ends_a_collision() {
    // Wall face at x = 1.475; the chassis front is 0.08 m ahead of base_link.
    let mut s = sim(&room(Some(1.5)), &[[0.8, 2.0, 0.0]]);
    s.set_setpoint(0, &drive(3.0));
    run_for(&mut s, 5.0);
    let events = s.take_collisions();
    assert_eq!(events.first(), Some(&started(0, -1)), "{events:?}");
    assert_eq!(s.touching(), vec![(0, -1)]);
    s.set_setpoint(0, &drive(-3.0));
    run_for(&mut s, 3.0);
    let events = s.take_collisions();
    assert!(
        events
            .iter()
            .any(|c| c.started == 0 && c.robot == 0 && c.other_robot == -1),
        "{events:?}"
    );
    assert!(s.touching().is_empty());
}

#[test]
fn robots_standing_apart_do_not_collide() {
    let mut s = sim(
        &room(Some(3.5)),
        &[[1.0, 1.0, 0.0], [1.5, 1.0, 0.0], [1.0, 2.0, 1.5]],
    );
    run_for(&mut s, 2.0);
    assert!(s.take_collisions().is_empty());
    assert!(s.touching().is_empty());
}

#[test]
fn a_robot_driving_into_another_collides_with_it() {
    let mut s = sim(&room(None), &[[1.0, 2.0, 0.0], [1.6, 2.0, 0.0]]);
    s.set_setpoint(0, &drive(3.0));
    run_for(&mut s, 4.0);
    let events = s.take_collisions();
    assert!(events.contains(&started(0, 1)), "{events:?}");
    assert!(events.contains(&started(1, 0)), "{events:?}");
    assert!(!events.iter().any(|c| c.other_robot == -1), "{events:?}");
}
