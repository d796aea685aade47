use crate::common::{room, run_for, sim};
use caravan_schemas::WheelSetpoint;

/// Same inputs, same outputs, bit for bit: no wall clock, no randomness.
#[test]
fn two_runs_agree_bit_for_bit() {
    let run = || {
        let mut s = sim(&room(Some(2.5)), &[[1.0, 2.0, 0.0], [1.0, 1.0, 0.3]]);
        let mut trace = Vec::new();
        for k in 0..30u32 {
            let sp = WheelSetpoint {
                left_rad_s: 2.0 + (k % 7) as f64 * 0.3,
                right_rad_s: 3.0 - (k % 5) as f64 * 0.2,
            };
            s.set_setpoint(k as usize % 2, &sp);
            run_for(&mut s, 0.1);
            for i in 0..2 {
                let p = s.pose(i);
                let w = s.wheel_state(i);
                trace.extend(
                    [p.x, p.y, p.theta, w.left_angle_rad, w.right_voltage].map(f64::to_bits),
                );
            }
            trace.extend(s.take_collisions().iter().map(|c| c.started as u64));
        }
        trace
    };
    assert_eq!(run(), run());
}
