//! Wheel encoders: accumulated wheel angles (from physics) to accumulated tick counts.
//!
//! An incremental encoder counts whole ticks, so the count is the floor of the angle in ticks:
//! a wheel turned back by a hair below zero already reads −1, as a quadrature counter does
//! once it has seen the first falling edge. No noise or missed counts are modelled; the
//! quantisation itself is the sensor's error (2π/360 rad per tick at the default resolution).

use caravan_schemas::{EncoderTicks, WheelState};
use std::f64::consts::TAU;

/// Ticks counted for an accumulated wheel angle `angle_rad`: ⌊angle / 2π · ticks_per_rev⌋.
pub fn ticks(angle_rad: f64, ticks_per_rev: u32) -> i64 {
    // Dividing by 2π first keeps whole turns exact (2π / 2π is exactly 1).
    (angle_rad / TAU * f64::from(ticks_per_rev)).floor() as i64
}

/// The encoder message for a wheel state.
pub fn encoder_ticks(state: &WheelState, ticks_per_rev: u32) -> EncoderTicks {
    EncoderTicks {
        left: ticks(state.left_angle_rad, ticks_per_rev),
        right: ticks(state.right_angle_rad, ticks_per_rev),
        ticks_per_rev,
        _reserved: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn known_angles() {
        assert_eq!(ticks(0.0, 360), 0);
        assert_eq!(ticks(PI, 360), 180);
        assert_eq!(ticks(TAU, 360), 360);
        assert_eq!(ticks(10.0 * TAU, 360), 3600);
        assert_eq!(ticks(1f64.to_radians() * 0.999, 360), 0);
        assert_eq!(ticks(1f64.to_radians() * 1.001, 360), 1);
        assert_eq!(ticks(2.5, 1024), 407); // 2.5 / 2π · 1024 = 407.4
    }

    #[test]
    fn negative_angles_floor_toward_minus_infinity() {
        assert_eq!(ticks(-1e-9, 360), -1);
        assert_eq!(ticks(-PI, 360), -180);
        assert_eq!(ticks(-TAU, 360), -360);
        assert_eq!(ticks(-1f64.to_radians() * 1.5, 360), -2);
    }

    #[test]
    fn message_carries_both_wheels_and_the_resolution() {
        let state = WheelState {
            left_angle_rad: PI,
            right_angle_rad: -PI / 2.0,
            ..Default::default()
        };
        let m = encoder_ticks(&state, 360);
        assert_eq!((m.left, m.right, m.ticks_per_rev), (180, -90, 360));
    }
}
