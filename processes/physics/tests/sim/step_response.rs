//! The reference's motor step responses: 0 → 3 rad/s settles into the ±5 % band in
//! 0.5 s ± 15 % with the wheels free and in 2.5 s ± 15 % with the robot on the floor.

use crate::common::{config, convoy_bot};
use caravan_physics::step_response::{BAND, record_step, settling_time};

fn settling(lifted: bool, setpoint: f64, duration: f64) -> f64 {
    let cfg = caravan_physics::convoy::ConvoyConfig { lifted, ..config() };
    let samples = record_step(&convoy_bot(), cfg, setpoint, duration);
    settling_time(&samples, setpoint, BAND)
        .unwrap_or_else(|| panic!("never settled (lifted = {lifted}): {samples:?}"))
}

#[test]
fn wheels_free_settle_in_half_a_second() {
    let t = settling(true, 3.0, 2.0);
    assert!((0.425..=0.575).contains(&t), "settling time {t} s");
}

#[test]
fn robot_on_the_floor_settles_in_two_and_a_half_seconds() {
    let t = settling(false, 3.0, 5.0);
    assert!((2.125..=2.875).contains(&t), "settling time {t} s");
}
