//! The reference scenarios: what the driver commands at each instant, and what an ideal IMU
//! reads in each phase. Every constant is a parameter with the reference's value as default.
//!
//! Frames: the world is z up; the IMU's axes are its link's. Specific force is the standard
//! one (+g up at rest); the paper plots it with the sign flipped.
//!
//! - **Tilt**: a platform (kinematic base) turns about the world x axis at `rate_deg_s` from
//!   `start_s` until it is `angle_deg` from level, then holds for `hold_s`. The IMU sits on
//!   the axis. f = g·(0, sin φ, cos φ), ω = (rate, 0, 0) during the ramp.
//! - **Lift**: a cube (floating base, the URDF's mass m) rests on the floor, is pushed up by
//!   `force_n` through its centre of mass from `push_from_s` to `push_to_s`, optionally
//!   braked by a smaller upward force for a while (`brake`), then falls freely.
//!   f = (0, 0, g), (0, 0, F/m), (0, 0, F_brake/m), then 0; ω = 0.
//! - **Rotation**: a platform (kinematic base) turns about the vertical axis through its
//!   origin at `rate_rad_s`; the IMU sits `radius_m` out along the platform's x axis.
//!   f = (−ω²r, 0, g) (the centripetal acceleration points to the axis), ω = (0, 0, rate).
//!
//! - **Allan**: a platform held still with the IMU's error model `imu_errors` on; the report
//!   reads the noise density and bias instability off the readings' Allan deviation.
//!
//! The kinematic platforms follow the commanded velocities exactly, so the readings measure
//! the IMU, not a controller's tracking.

use serde::Deserialize;

/// Gravity, m/s², the reference's value (physics uses the same by default).
pub const G: f64 = 9.81;

/// Readings within this long after a phase change are not scored, s: the reading whose
/// interval spans the change mixes two phases, and the contact of a resting body lets go
/// over a few steps.
pub const SETTLE_S: f64 = 0.05;

/// The lifted cube's rest is scored from this time, s. It starts touching the floor, and
/// rapier's soft contact lets it sink to its equilibrium and ring down over the first few
/// tenths of a second (errors up to 3.6e-2 m/s² before 0.3 s, below 1e-8 from 0.5 s).
pub const REST_FROM_S: f64 = 0.5;

#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(tag = "scenario", rename_all = "snake_case", deny_unknown_fields)]
pub enum Scenario {
    /// Static tilt: a platform turned about x from level to `angle_deg` at `rate_deg_s`, then
    /// held.
    Tilt {
        /// Tilt rate, °/s, 0.01 to 2000 (the ranges and why: [`crate::range`]).
        #[serde(default = "tilt_rate")]
        rate_deg_s: f64,
        /// Final tilt, degrees, in (0, 90].
        #[serde(default = "tilt_angle")]
        angle_deg: f64,
        /// Start of the ramp, s, 0 to 86 400.
        #[serde(default = "tilt_start")]
        start_s: f64,
        /// Hold after the ramp, s, 0.1 to 86 400.
        #[serde(default = "tilt_hold")]
        hold_s: f64,
    },
    /// Lift and free fall: a cube at rest, pushed up by `force_n` from `push_from_s` to
    /// `push_to_s` (optionally braked), then released.
    Lift {
        /// The cube's description, for its mass (relative to the launch file).
        #[serde(default = "lift_urdf")]
        urdf: String,
        /// Upward force, N, > 0 and at most 16 g on the cube's mass.
        #[serde(default = "lift_force")]
        force_n: f64,
        /// Push interval, s: 0 < from < to ≤ 86 400.
        #[serde(default = "lift_from")]
        push_from_s: f64,
        /// End of the push, s, after `push_from_s`, ≤ 86 400.
        #[serde(default = "lift_to")]
        push_to_s: f64,
        /// A braking phase after the push (none by default, as in the reference's lift).
        #[serde(default)]
        brake: Option<Brake>,
        /// Free fall scored until this time, s (before the cube lands), after the push and
        /// the brake, ≤ 86 400.
        #[serde(default = "lift_fall_end")]
        fall_end_s: f64,
    },
    /// Constant rotation: the IMU `radius_m` from a vertical axis turning at `rate_rad_s`.
    Rotation {
        /// Turn rate, rad/s, 1e-4 to 34.9 (2000 °/s) either way.
        #[serde(default = "rotation_rate")]
        rate_rad_s: f64,
        /// IMU distance from the axis, m, 0 to 100 (the sensor's `imu_offset` x), with
        /// ω²r at most 16 g.
        #[serde(default = "rotation_radius")]
        radius_m: f64,
        /// Scored from this time to `end_s`, s: 0 ≤ from < end ≤ 86 400.
        #[serde(default = "rotation_from")]
        from_s: f64,
        /// End of the scored interval, s, after `from_s`, ≤ 86 400.
        #[serde(default = "rotation_end")]
        end_s: f64,
    },
    /// An IMU on the forearm of a two-link arm turned about its shoulder (see [`crate::arm`]).
    Arm(crate::arm::Arm),
    /// A still platform with the IMU's error model on: the report reads the noise density and
    /// bias instability back off the Allan deviation.
    Allan {
        /// The sensor's error model, as its `imu_errors` param (the configured values the
        /// report recovers); each term at most its triad's full scale (16 g, 2000 °/s).
        imu_errors: caravan_sensor::imu_errors::ImuErrors,
    },
    /// Spin-up: a bar driven to ω by a motor of maximum torque M, one row of the reference's
    /// table.
    SpinUp {
        /// The bar and its motor, one row of the reference's table: the joint's
        /// `<limit effort>` is the motor's maximum torque M, its `<limit velocity>` the rate
        /// ω, the bar's inertia about the joint axis I.
        #[serde(default = "spin_up_urdf")]
        urdf: String,
        /// The bar's joint.
        #[serde(default = "spin_up_joint")]
        joint: String,
        /// When the motor is switched on, s, 0 to 86 400.
        #[serde(default = "spin_up_start")]
        start_s: f64,
        /// End of the run, s, > `start_s`, ≤ 86 400.
        #[serde(default = "spin_up_end")]
        end_s: f64,
    },
}

/// A braking phase: an upward force smaller than the weight, so the rising cube slows down.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Brake {
    /// Upward force, N, > 0 and at most 16 g on the cube's mass.
    pub force_n: f64,
    /// How long, s, 0.1 to 86 400 (scored from 0.05 s after it begins).
    pub duration_s: f64,
}

fn spin_up_urdf() -> String {
    "robots/spinup_row1.urdf".into()
}
fn spin_up_joint() -> String {
    "bar_joint".into()
}
fn spin_up_start() -> f64 {
    0.5
}
fn spin_up_end() -> f64 {
    1.5
}

fn tilt_rate() -> f64 {
    3.0
}
fn tilt_angle() -> f64 {
    45.0
}
fn tilt_start() -> f64 {
    2.0
}
fn tilt_hold() -> f64 {
    3.0
}
fn lift_urdf() -> String {
    "robots/cube.urdf".into()
}
fn lift_force() -> f64 {
    54.05
}
fn lift_from() -> f64 {
    2.5
}
fn lift_to() -> f64 {
    5.0
}
fn lift_fall_end() -> f64 {
    6.0
}
fn rotation_rate() -> f64 {
    std::f64::consts::FRAC_PI_4
}
fn rotation_radius() -> f64 {
    0.75
}
fn rotation_from() -> f64 {
    0.5
}
fn rotation_end() -> f64 {
    5.0
}

/// What a scenario's driver does at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Angular velocity of the kinematic platform, world frame, rad/s.
    Turn([f64; 3]),
    /// Command the bar's joint to its velocity limit ω (the motor then gives its maximum
    /// torque until ω is reached).
    Spin,
    /// Start an upward push of `force_n` for `duration_s` (sent once; it replaces the last).
    Push { force_n: f64, duration_s: f64 },
    /// The arm's joints: the elbow to its bend (rad) from when it starts bending, and the
    /// shoulder at its rate (rad/s) from when it turns.
    Arm {
        elbow_rad: Option<f64>,
        shoulder_rad_s: Option<f64>,
    },
    /// Nothing to send.
    Idle,
}

/// The ideal accelerometer reading of a phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expect {
    /// Specific force, sensor frame, m/s².
    Vector([f64; 3]),
    /// Only the magnitude, m/s²: during the tilt ramp the reading turns with the platform,
    /// and the instant the ramp began is known to a physics step only.
    Norm(f64),
}

/// One phase: its time window and the ideal reading in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    pub name: &'static str,
    pub from_s: f64,
    pub to_s: f64,
    pub accel: Expect,
    /// Angular rate, sensor frame, rad/s.
    pub gyro: [f64; 3],
}

impl Scenario {
    /// The scenario's name.
    pub fn name(&self) -> &'static str {
        match self {
            Scenario::Tilt { .. } => "tilt",
            Scenario::Lift { .. } => "lift",
            Scenario::Rotation { .. } => "rotation",
            Scenario::SpinUp { .. } => "spinup",
            Scenario::Arm(_) => "arm",
            Scenario::Allan { .. } => "allan",
        }
    }

    /// End of the ramp of a tilt, s.
    fn ramp_end(&self) -> f64 {
        match *self {
            Scenario::Tilt {
                rate_deg_s,
                angle_deg,
                start_s,
                ..
            } => start_s + angle_deg / rate_deg_s,
            _ => 0.0,
        }
    }

    /// The pushes of a lift, in time order: (start s, upward force N, duration s).
    fn pushes(&self) -> Vec<(f64, f64, f64)> {
        match *self {
            Scenario::Lift {
                force_n,
                push_from_s,
                push_to_s,
                brake,
                ..
            } => std::iter::once((push_from_s, force_n, push_to_s - push_from_s))
                .chain(brake.map(|b| (push_to_s, b.force_n, b.duration_s)))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// When a lift's free fall begins, s.
    pub(crate) fn fall_from_s(&self) -> f64 {
        self.pushes().last().map_or(0.0, |&(from, _, d)| from + d)
    }

    /// How long a run must last to cover every phase, s.
    pub fn duration_s(&self) -> f64 {
        match *self {
            Scenario::Tilt { hold_s, .. } => self.ramp_end() + hold_s,
            Scenario::Lift { fall_end_s, .. } => fall_end_s,
            Scenario::Rotation { end_s, .. }
            | Scenario::SpinUp { end_s, .. }
            | Scenario::Arm(crate::arm::Arm { end_s, .. }) => end_s,
            // As long as the group runs.
            Scenario::Allan { .. } => f64::INFINITY,
        }
    }

    /// What the driver sends at time `t_s`; `pushed` says how many pushes it has sent.
    pub fn command(&self, t_s: f64, pushed: usize) -> Command {
        match *self {
            Scenario::Tilt {
                rate_deg_s,
                start_s,
                ..
            } => {
                let on = t_s >= start_s && t_s < self.ramp_end();
                Command::Turn([if on { rate_deg_s.to_radians() } else { 0.0 }, 0.0, 0.0])
            }
            Scenario::Lift { .. } => match self.pushes().get(pushed) {
                Some(&(from_s, force_n, duration_s)) if t_s >= from_s => Command::Push {
                    force_n,
                    duration_s,
                },
                _ => Command::Idle,
            },
            Scenario::Rotation { rate_rad_s, .. } => Command::Turn([0.0, 0.0, rate_rad_s]),
            Scenario::SpinUp { start_s, .. } if t_s >= start_s => Command::Spin,
            Scenario::SpinUp { .. } | Scenario::Allan { .. } => Command::Idle,
            Scenario::Arm(crate::arm::Arm {
                rate_rad_s,
                elbow_deg,
                bend_from_s,
                spin_from_s,
                ..
            }) => Command::Arm {
                elbow_rad: (t_s >= bend_from_s).then(|| elbow_deg.to_radians()),
                shoulder_rad_s: (t_s >= spin_from_s).then_some(rate_rad_s),
            },
        }
    }

    /// The scored phases, in time order; none for the spin-up, which is timed instead (see
    /// [`crate::spin_up`]), and the arm, whose phases depend on its description
    /// ([`crate::arm::Arm::phases`]). `mass_kg` is the lifted cube's (unused otherwise).
    pub fn phases(&self, mass_kg: f64) -> Vec<Phase> {
        let level = Expect::Vector([0.0, 0.0, G]);
        let phase = |name, from_s, to_s, accel, gyro| Phase {
            name,
            from_s,
            to_s,
            accel,
            gyro,
        };
        match *self {
            Scenario::Tilt {
                rate_deg_s,
                angle_deg,
                start_s,
                ..
            } => {
                let end = self.ramp_end();
                let phi = angle_deg.to_radians();
                vec![
                    phase("level", SETTLE_S, start_s, level, [0.0; 3]),
                    phase(
                        "ramp",
                        start_s + SETTLE_S,
                        end,
                        Expect::Norm(G),
                        [rate_deg_s.to_radians(), 0.0, 0.0],
                    ),
                    phase(
                        "held",
                        end + SETTLE_S,
                        self.duration_s(),
                        Expect::Vector([0.0, G * phi.sin(), G * phi.cos()]),
                        [0.0; 3],
                    ),
                ]
            }
            Scenario::Lift {
                push_from_s,
                fall_end_s,
                ..
            } => {
                let mut phases = vec![phase("rest", REST_FROM_S, push_from_s, level, [0.0; 3])];
                for (k, (from_s, force_n, duration_s)) in self.pushes().into_iter().enumerate() {
                    phases.push(phase(
                        if k == 0 { "pushed" } else { "braking" },
                        from_s + SETTLE_S,
                        from_s + duration_s,
                        Expect::Vector([0.0, 0.0, force_n / mass_kg]),
                        [0.0; 3],
                    ));
                }
                phases.push(phase(
                    "free fall",
                    self.fall_from_s() + SETTLE_S,
                    fall_end_s,
                    Expect::Vector([0.0; 3]),
                    [0.0; 3],
                ));
                phases
            }
            Scenario::Rotation {
                rate_rad_s,
                radius_m,
                from_s,
                end_s,
            } => vec![phase(
                "turning",
                from_s,
                end_s,
                Expect::Vector([-rate_rad_s * rate_rad_s * radius_m, 0.0, G]),
                [0.0, 0.0, rate_rad_s],
            )],
            Scenario::SpinUp { .. } | Scenario::Allan { .. } | Scenario::Arm(_) => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilt() -> Scenario {
        serde_json::from_value(serde_json::json!({ "scenario": "tilt" })).unwrap()
    }

    #[test]
    fn the_tilt_turns_for_angle_over_rate_then_holds_at_the_reference_values() {
        let s = tilt();
        assert_eq!(s.duration_s(), 2.0 + 15.0 + 3.0);
        assert_eq!(s.command(1.99, 0), Command::Turn([0.0; 3]));
        assert_eq!(
            s.command(2.0, 0),
            Command::Turn([3f64.to_radians(), 0.0, 0.0])
        );
        assert_eq!(s.command(17.0, 0), Command::Turn([0.0; 3]));
        let held = &s.phases(0.0)[2];
        let Expect::Vector(f) = held.accel else {
            panic!()
        };
        // The reference: two axes read 9.81·cos 45° = 6.937 m/s².
        assert!((f[1] - 6.937).abs() < 5e-4 && (f[2] - 6.937).abs() < 5e-4);
        assert!((s.phases(0.0)[1].gyro[0] - 0.05236).abs() < 1e-5);
    }

    #[test]
    fn the_lift_pushes_once_and_reads_force_over_mass() {
        let s: Scenario =
            serde_json::from_value(serde_json::json!({ "scenario": "lift" })).unwrap();
        assert_eq!(s.command(2.4, 0), Command::Idle);
        assert_eq!(
            s.command(2.5, 0),
            Command::Push {
                force_n: 54.05,
                duration_s: 2.5
            }
        );
        assert_eq!(s.command(2.6, 1), Command::Idle);
        assert_eq!(s.command(5.5, 1), Command::Idle);
        let pushed = &s.phases(5.0)[1];
        // The reference: 10.81 m/s² (1.10 g) while pushed.
        assert_eq!(pushed.accel, Expect::Vector([0.0, 0.0, 54.05 / 5.0]));
    }

    #[test]
    fn a_brake_follows_the_push_and_delays_the_fall() {
        let s: Scenario = serde_json::from_value(serde_json::json!({ "scenario": "lift",
            "brake": { "force_n": 34.05, "duration_s": 0.8 }, "fall_end_s": 6.5 }))
        .unwrap();
        s.validate().unwrap();
        assert_eq!(s.command(4.99, 1), Command::Idle);
        assert_eq!(
            s.command(5.0, 1),
            Command::Push {
                force_n: 34.05,
                duration_s: 0.8
            }
        );
        assert_eq!(s.command(5.5, 2), Command::Idle);
        let names: Vec<_> = s.phases(5.0).iter().map(|p| p.name).collect();
        assert_eq!(names, ["rest", "pushed", "braking", "free fall"]);
        let braking = &s.phases(5.0)[2];
        assert_eq!(braking.accel, Expect::Vector([0.0, 0.0, 34.05 / 5.0]));
        assert_eq!(s.phases(5.0)[3].from_s, 5.8 + SETTLE_S);
        // The fall must still be scored after the brake.
        let late: Scenario = serde_json::from_value(serde_json::json!({ "scenario": "lift",
            "brake": { "force_n": 34.05, "duration_s": 1.5 } }))
        .unwrap();
        assert!(late.validate().unwrap_err().contains("'fall_end_s'"));
    }

    #[test]
    fn the_rotation_reads_the_centripetal_acceleration_inwards() {
        let s: Scenario =
            serde_json::from_value(serde_json::json!({ "scenario": "rotation" })).unwrap();
        let Expect::Vector(f) = s.phases(0.0)[0].accel else {
            panic!()
        };
        // The reference: radial 0.4626 m/s² (ω²r), gyro Z π/4 = 0.7854 rad/s.
        assert!((f[0] + 0.4626).abs() < 1e-4 && f[2] == G);
        assert_eq!(s.phases(0.0)[0].gyro[2], std::f64::consts::FRAC_PI_4);
    }

    #[test]
    fn the_allan_check_needs_white_noise_on_both_triads() {
        let allan = |gyro_nd: f64| {
            serde_json::from_value::<Scenario>(serde_json::json!({ "scenario": "allan",
                "imu_errors": { "accel": { "noise_density": 1e-3 },
                                "gyro": { "noise_density": gyro_nd } } }))
            .unwrap()
            .validate()
        };
        assert!(allan(1e-4).is_ok());
        assert!(allan(0.0).unwrap_err().contains("noise_density"));
        assert!(allan(-1.0).unwrap_err().contains("'imu_errors'"));
    }

    #[test]
    fn bad_values_name_their_key() {
        let bad: Scenario =
            serde_json::from_value(serde_json::json!({ "scenario": "tilt", "angle_deg": 120.0 }))
                .unwrap();
        assert!(bad.validate().unwrap_err().contains("'angle_deg'"));
        let unknown = serde_json::from_value::<Scenario>(
            serde_json::json!({ "scenario": "tilt", "angel_deg": 10.0 }),
        );
        assert!(unknown.unwrap_err().to_string().contains("angel_deg"));
    }
}
