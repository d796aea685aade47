//! Motor step responses and their settling time: how the motor and PID constants were fitted.
//!
//! # Target
//! The reference robot's wheel speed, stepped from rest to a set-point, settles in 0.5 s with
//! the wheels free and in 2.5 s with the robot on the floor. Caravan's target is each ± 15 %.
//!
//! # Measurement
//! The signal is the wheel speed the firmware measures (angle change over each 20 ms control
//! period), the quantity the Arduino would log. The settling time is the time from the step
//! to the last such sample outside the band of ± 5 % of the set-point ([`BAND`]); the record
//! must end inside the band. "Free" holds the chassis fixed 0.1 m in the air; "on the floor"
//! lets the robot drive off in a straight line.
//!
//! # Chosen constants (the defaults of [`MotorParams`] and [`FirmwareParams`])
//! | constant | value |
//! |---|---|
//! | supply | 6 V |
//! | armature resistance R | 20 Ω |
//! | k_t = k_e | 0.01 N·m/A = V·s/rad |
//! | gear ratio N | 30 |
//! | rotor inertia | 2·10⁻⁷ kg·m² (1.8·10⁻⁴ at the wheel) |
//! | gearbox friction at the wheel | viscous 10⁻⁵ N·m·s/rad, Coulomb 2·10⁻³ N·m |
//! | PID | kp = 0.22 V/(rad/s), ki = 2.3 V/rad, kd = 0, 50 Hz |
//!
//! That is a small 6 V gear motor: 20 rad/s (190 rpm) at the wheel without load, a stall
//! torque of 0.09 N·m per wheel, 1.0 V to hold 3 rad/s. The wheel with its reflected rotor
//! has 2.7·10⁻⁴ kg·m² about its axle; on the floor each wheel also accelerates half of the
//! 1.5 kg robot, m/2·r² = 3.4·10⁻³ kg·m², 13.5 times more. With the electrical damping
//! N²·k_t·k_e/R = 4.5·10⁻³ N·m·s/rad the mechanical time constant is 0.06 s free and 0.8 s on
//! the floor. Against the free wheel the PI loop is overdamped and its integral gain sets
//! the settling time; against the loaded wheel it is underdamped (ζ ≈ 0.35) and the settling
//! time grows with the inertia. So one set of constants gives both 0.5 s and 2.5 s, and the
//! loaded response overshoots by about a third, as a Ziegler–Nichols tuning tends to. It is
//! the "slow actuator" the paper's authors blamed.
//!
//! # How they were fitted
//! 1. A one-wheel model (J·dω/dt = motor torque, the same 50 Hz incremental PID) was
//!    grid-searched with supply, N and k fixed: R ∈ 2…40 Ω, rotor inertia 2·10⁻⁷…4·10⁻⁶,
//!    kp ∈ 0.1…1.6, ki ∈ 0.5…16, keeping combinations with 0.5 ± 0.06 s free and 2.5 s
//!    loaded, then the one least sensitive to ± 20 % inertia (R = 20 Ω, 2·10⁻⁷ kg·m²).
//! 2. In this simulation kp ∈ 0.18…0.22 and ki ∈ 2.0…2.6 were scanned with set-points 1.5, 3
//!    and 5 rad/s, and the pair in the middle of both bands kept.
//!
//! # Measured (2 ms physics step, the default)
//! | step | free | on the floor |
//! |---|---|---|
//! | 0 → 3 rad/s | 0.50 s, no overshoot (90 % at 0.38 s) | 2.48 s, peak 4.0 rad/s |
//! | 0 → 1.5 and 0 → 5 rad/s | 0.48–0.52 s | 2.48–2.50 s |
//!
//! The same at a 1 ms step. The settling time of an underdamped response jumps by half an
//! oscillation period when a peak crosses the band edge (kp = 0.18 gives 3.4 s at 1.5 rad/s),
//! so retuning should check several set-points.

use crate::convoy::ConvoyConfig;
#[cfg(doc)]
use crate::{firmware::FirmwareParams, motor::MotorParams};
use caravan_schemas::WheelSetpoint;
use caravan_world::World;
use caravan_world::description::RobotDescription;

/// The settling band: within ±5 % of the set-point.
pub const BAND: f64 = 0.05;

/// A wheel-speed record: (time since the step, s; speed, rad/s).
pub type Samples = Vec<(f64, f64)>;

/// Time after which every sample stays within `band`·|target| of `target`; `None` if the
/// last sample is still outside.
pub fn settling_time(samples: &[(f64, f64)], target: f64, band: f64) -> Option<f64> {
    let tol = band * target.abs();
    let last = samples.last()?;
    if (last.1 - target).abs() > tol {
        return None;
    }
    let outside = samples.iter().rposition(|&(_, w)| (w - target).abs() > tol);
    Some(outside.map_or(0.0, |k| samples[k].0))
}

/// A floor with nothing on it, for bench tests.
pub fn empty_world() -> World {
    World {
        name: "empty".into(),
        size: [10.0, 10.0],
        obstacles: Vec::new(),
        friction: None,
        surveys: Vec::new(),
        starts: Vec::new(),
        goals: Vec::new(),
    }
}

/// Steps both wheels of one robot from rest to `setpoint` rad/s and records the left
/// wheel's speed as the firmware measures it (every control period) for `duration` s.
/// `cfg.lifted` chooses wheels free (chassis held in the air) or the robot on the floor.
pub fn record_step(
    robot: &RobotDescription,
    cfg: ConvoyConfig,
    setpoint: f64,
    duration: f64,
) -> Samples {
    let mut sim = crate::convoy::simulation(&empty_world(), robot, &[[5.0, 5.0, 0.0]], cfg);
    // Let the robot settle onto its wheels before the step.
    let settle_ns = 500_000_000;
    sim.advance_to(settle_ns, u64::MAX);
    sim.set_setpoint(
        0,
        &WheelSetpoint {
            left_rad_s: setpoint,
            right_rad_s: setpoint,
        },
    );
    let period = cfg.pid.period_ns();
    let start = sim.time_ns();
    let mut samples = Vec::new();
    let mut t = start;
    while t < start + (duration * 1e9) as u64 {
        t += period;
        sim.advance_to(t, u64::MAX);
        samples.push((
            (sim.time_ns() - start) as f64 * 1e-9,
            sim.measured_speeds(0)[0],
        ));
    }
    samples
}
