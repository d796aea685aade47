//! Physical ranges of the scenarios' params ([`Scenario::validate`]): every number finite, of
//! its sign, and within what a real experiment of its kind has, so that a typo (`1e308`,
//! `1e-300`) is refused before the group starts (the driver's `setup` and the report's `new`
//! run under the launcher's check) with a message naming the key, in the style of the other
//! processes (`key 'hold_s': must be between 0.1 and 86400 s, got 1e308`), instead of a run
//! that never ends or a report of `inf`. Each bound's constant says why it is what it is.

use crate::scenario::{G, SETTLE_S, Scenario};
pub use caravan::range::{above, between, bound, shown};
use caravan_sensor::imu_errors::TriadErrors;

/// The longest time a scenario's key may name, s: a day. The reference's longest scenario
/// (the tilt) lasts 20 s; a day of simulated time at the scenarios' 1 kHz physics is 86.4
/// million steps, hours of wall time even in a release build, so a later time is a typo.
pub const MAX_TIME_S: f64 = 86_400.0;

/// The shortest a phase given by one duration key (`hold_s`, `brake.duration_s`) may last, s:
/// a phase is scored from [`SETTLE_S`] after it begins, so a shorter one leaves no reading to
/// score (the run then misses its targets whatever the IMU reads).
pub const MIN_PHASE_S: f64 = 2.0 * SETTLE_S;

/// The fastest turn, °/s: 2000 °/s is the largest full scale of MEMS gyroscopes (the
/// MPU-6050's ±2000 °/s); a real IMU turned faster saturates, so the scenario would test
/// nothing a real one can read.
pub const MAX_RATE_DEG_S: f64 = 2000.0;

/// The same in rad/s, rounded down (2000 °/s = 34.907 rad/s).
pub const MAX_RATE_RAD_S: f64 = 34.9;

/// The slowest tilt, °/s: 0.01 °/s (1.7e-4 rad/s) is still 170 times the reference's gyro
/// target of 1e-6 rad/s, and the steepest tilt (90°) then takes 2.5 h, within
/// [`MAX_TIME_S`]. A rate of 1e-300 °/s would ramp for ever.
pub const MIN_TILT_RATE_DEG_S: f64 = 0.01;

/// The slowest constant rotation, rad/s: 100 times the reference's gyro target of 1e-6 rad/s,
/// so the rate read is the rotation's, not the target's tolerance.
pub const MIN_TURN_RATE_RAD_S: f64 = 1e-4;

/// The largest specific force, m/s²: 16 g, the largest full scale of MEMS accelerometers (the
/// MPU-6050's ±16 g). It bounds the lift's forces (over the cube's mass) and the rotation's
/// centripetal acceleration ω²r.
pub const MAX_ACCEL_M_S2: f64 = 16.0 * G;

/// The farthest the IMU may sit from the rotation's axis, m: it rides on the platform's link,
/// and Caravan caps a part of a robot description at 100 m
/// (`caravan_world::limits::MAX_PART_SIZE_M`).
pub const MAX_RADIUS_M: f64 = caravan_world::limits::MAX_PART_SIZE_M;

impl Scenario {
    /// Checks the values serde cannot: each key's range (above) and the order of the times;
    /// the error names the key. The lift's forces are bounded by the cube's mass, read from its
    /// description: [`Scenario::validate_forces`].
    pub fn validate(&self) -> Result<(), String> {
        let time = |key: &str, v: f64| between(key, v, 0.0, MAX_TIME_S, "s");
        let phase = |key: &str, v: f64| between(key, v, MIN_PHASE_S, MAX_TIME_S, "s");
        match *self {
            Scenario::Tilt {
                rate_deg_s,
                angle_deg,
                start_s,
                hold_s,
            } => {
                between(
                    "rate_deg_s",
                    rate_deg_s,
                    MIN_TILT_RATE_DEG_S,
                    MAX_RATE_DEG_S,
                    "°/s",
                )?;
                above("angle_deg", angle_deg, 0.0, 90.0, "°")?;
                time("start_s", start_s)?;
                phase("hold_s", hold_s)?;
            }
            Scenario::Lift {
                force_n,
                push_from_s,
                push_to_s,
                fall_end_s,
                brake,
                ..
            } => {
                // At most 16 g on the cube: `validate_forces`, once its mass is known.
                positive("force_n", force_n)?;
                above("push_from_s", push_from_s, 0.0, MAX_TIME_S, "s")?;
                time("push_to_s", push_to_s)?;
                if let Some(b) = brake {
                    positive("brake.force_n", b.force_n)?;
                    phase("brake.duration_s", b.duration_s)?;
                }
                time("fall_end_s", fall_end_s)?;
                let fall_from = self.fall_from_s();
                if !(push_to_s > push_from_s && fall_end_s > fall_from) {
                    return Err(format!(
                        "keys 'push_from_s' < 'push_to_s' < 'fall_end_s' (after the brake) \
                         must hold, got {push_from_s}, {push_to_s}, {fall_end_s} (fall from \
                         {fall_from})"
                    ));
                }
            }
            Scenario::Rotation {
                rate_rad_s,
                radius_m,
                from_s,
                end_s,
            } => {
                turn_rate(rate_rad_s)?;
                let rate = rate_rad_s.abs();
                between("radius_m", radius_m, 0.0, MAX_RADIUS_M, "m")?;
                let centripetal = rate * rate * radius_m;
                if centripetal > MAX_ACCEL_M_S2 {
                    return Err(format!(
                        "keys 'rate_rad_s' and 'radius_m': the centripetal acceleration ω²r = \
                         {} m/s² must be at most {} m/s² (16 g, an accelerometer's full \
                         scale), got ω = {} rad/s and r = {} m",
                        bound(centripetal),
                        bound(MAX_ACCEL_M_S2),
                        shown(rate_rad_s),
                        shown(radius_m)
                    ));
                }
                time("from_s", from_s)?;
                time("end_s", end_s)?;
                if end_s <= from_s {
                    return Err(format!(
                        "keys 'from_s' < 'end_s' must hold, got {from_s}, {end_s}"
                    ));
                }
            }
            Scenario::Allan { ref imu_errors } => {
                imu_errors
                    .validate()
                    .map_err(|e| format!("key 'imu_errors': {e}"))?;
                triad_within_full_scale("accel", &imu_errors.accel, MAX_ACCEL_M_S2, "m/s²")?;
                triad_within_full_scale("gyro", &imu_errors.gyro, MAX_RATE_RAD_S, "rad/s")?;
                if imu_errors.accel.noise_density <= 0.0 || imu_errors.gyro.noise_density <= 0.0 {
                    return Err(
                        "key 'imu_errors': the Allan check needs a noise_density > 0 \
                                on both triads"
                            .into(),
                    );
                }
            }
            Scenario::Arm(crate::arm::Arm {
                rate_rad_s,
                elbow_deg,
                imu_x_m,
                bend_from_s,
                spin_from_s,
                end_s,
                ..
            }) => {
                turn_rate(rate_rad_s)?;
                between("elbow_deg", elbow_deg, -180.0, 180.0, "°")?;
                between("imu_x_m", imu_x_m, 0.0, MAX_RADIUS_M, "m")?;
                phase("bend_from_s", bend_from_s)?;
                time("spin_from_s", spin_from_s)?;
                time("end_s", end_s)?;
                if !(spin_from_s > bend_from_s && end_s > spin_from_s) {
                    return Err(format!(
                        "keys 'bend_from_s' < 'spin_from_s' < 'end_s' must hold, got \
                         {bend_from_s}, {spin_from_s}, {end_s}"
                    ));
                }
            }
            Scenario::SpinUp { start_s, end_s, .. } => {
                time("start_s", start_s)?;
                time("end_s", end_s)?;
                if end_s <= start_s {
                    return Err(format!(
                        "keys 'start_s' < 'end_s' must hold, got {start_s}, {end_s}"
                    ));
                }
            }
        }
        Ok(())
    }

    /// A lift's forces against the cube's mass `mass_kg` (its description's): each at most
    /// [`MAX_ACCEL_M_S2`]·m, so the IMU reads at most 16 g. Nothing to check for the other
    /// scenarios.
    pub fn validate_forces(&self, mass_kg: f64) -> Result<(), String> {
        let Scenario::Lift { force_n, brake, .. } = *self else {
            return Ok(());
        };
        if !(mass_kg.is_finite() && mass_kg > 0.0) {
            return Err(format!(
                "key 'urdf': the lifted body needs a mass, its description gives {mass_kg} kg"
            ));
        }
        let max = MAX_ACCEL_M_S2 * mass_kg;
        let unit = format!("N (16 g on the {} kg of 'urdf')", bound(mass_kg));
        above("force_n", force_n, 0.0, max, &unit)?;
        if let Some(b) = brake {
            above("brake.force_n", b.force_n, 0.0, max, &unit)?;
        }
        Ok(())
    }
}

/// Each error term of a triad of the Allan check's `imu_errors` at most the triad's full scale
/// `full` (in `unit`, per √Hz or √s as the term goes): a term that large saturates the
/// sensor, and datasheets give values orders of magnitude below it. The sensor's own check
/// gives the signs and the correlation times; a scale factor is kept within ±100 %.
fn triad_within_full_scale(
    triad: &str,
    t: &TriadErrors,
    full: f64,
    unit: &str,
) -> Result<(), String> {
    for (key, v, per) in [
        ("noise_density", t.noise_density, "/√Hz"),
        ("bias_instability", t.bias_instability, ""),
        ("random_walk", t.random_walk, "/√s"),
        ("quantum", t.quantum, ""),
    ] {
        let key = format!("imu_errors.{triad}.{key}");
        between(&key, v, 0.0, full, &format!("{unit}{per}"))?;
    }
    let key = format!("imu_errors.{triad}.scale_factor");
    above(&key, t.scale_factor, -1.0, 1.0, "")?;
    Ok(())
}

// The slowest tilt to 90° ends within a scenario's longest time, and the rate ranges are ranges.
const _: () = assert!(90.0 / MIN_TILT_RATE_DEG_S <= MAX_TIME_S);
const _: () = assert!(MIN_TURN_RATE_RAD_S < MAX_RATE_RAD_S);

/// A constant turn's rate (key `rate_rad_s`), either way.
fn turn_rate(rate_rad_s: f64) -> Result<(), String> {
    let rate = rate_rad_s.abs();
    if rate.is_finite() && (MIN_TURN_RATE_RAD_S..=MAX_RATE_RAD_S).contains(&rate) {
        return Ok(());
    }
    Err(format!(
        "key 'rate_rad_s': must be between {} and {} rad/s either way (2000 °/s, a \
         gyroscope's full scale), got {}",
        bound(MIN_TURN_RATE_RAD_S),
        bound(MAX_RATE_RAD_S),
        shown(rate_rad_s)
    ))
}

/// A force's sign, before its bound is known.
fn positive(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "key '{key}': must be a positive number of newtons, got {}",
            shown(v)
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(v: serde_json::Value) -> Scenario {
        serde_json::from_value(v).unwrap()
    }

    fn refused(v: serde_json::Value) -> String {
        scenario(v).validate().unwrap_err()
    }

    #[test]
    fn the_reference_defaults_are_in_range() {
        for name in ["tilt", "lift", "rotation", "spin_up", "arm"] {
            let s = scenario(serde_json::json!({ "scenario": name }));
            s.validate().unwrap();
            s.validate_forces(5.0).unwrap();
        }
    }

    #[test]
    fn a_hold_of_1e308_s_is_refused() {
        let e = refused(serde_json::json!({ "scenario": "tilt", "hold_s": 1e308 }));
        assert_eq!(
            e,
            "key 'hold_s': must be between 0.1 and 86400 s, got 1e308"
        );
    }

    #[test]
    fn a_tilt_rate_of_1e_300_deg_s_is_refused() {
        let e = refused(serde_json::json!({ "scenario": "tilt", "rate_deg_s": 1e-300 }));
        assert!(
            e.starts_with("key 'rate_deg_s': must be between 0.01 and 2000 °/s"),
            "{e}"
        );
        let e = refused(serde_json::json!({ "scenario": "tilt", "rate_deg_s": 2001.0 }));
        assert!(e.starts_with("key 'rate_deg_s'"), "{e}");
    }

    #[test]
    fn a_rotation_radius_of_1e308_m_is_refused() {
        let e = refused(serde_json::json!({ "scenario": "rotation", "radius_m": 1e308 }));
        assert!(
            e.starts_with("key 'radius_m': must be between 0 and 100 m"),
            "{e}"
        );
        // Within 100 m, but 30 rad/s at 1 m is 92 g.
        let e = refused(
            serde_json::json!({ "scenario": "rotation", "rate_rad_s": -30.0,
            "radius_m": 1.0 }),
        );
        assert!(
            e.contains("'rate_rad_s' and 'radius_m'") && e.contains("900 m/s²"),
            "{e}"
        );
        let e = refused(serde_json::json!({ "scenario": "rotation", "rate_rad_s": 1e-300 }));
        assert!(e.starts_with("key 'rate_rad_s'"), "{e}");
        // Either way round.
        scenario(serde_json::json!({ "scenario": "rotation", "rate_rad_s": -0.5 }))
            .validate()
            .unwrap();
    }

    #[test]
    fn times_past_a_day_and_phases_shorter_than_their_settling_are_refused() {
        for (v, key) in [
            (
                serde_json::json!({ "scenario": "tilt", "start_s": 1e6 }),
                "'start_s'",
            ),
            (
                serde_json::json!({ "scenario": "tilt", "hold_s": 0.05 }),
                "'hold_s'",
            ),
            (
                serde_json::json!({ "scenario": "lift", "fall_end_s": 1e308 }),
                "'fall_end_s'",
            ),
            (
                serde_json::json!({ "scenario": "lift", "brake": { "force_n": 1.0,
                    "duration_s": 1e-300 } }),
                "'brake.duration_s'",
            ),
            (
                serde_json::json!({ "scenario": "rotation", "end_s": 1e9 }),
                "'end_s'",
            ),
            (
                serde_json::json!({ "scenario": "spin_up", "end_s": f64::MAX }),
                "'end_s'",
            ),
        ] {
            let e = refused(v.clone());
            assert!(e.starts_with(&format!("key {key}")), "{v}: {e}");
        }
    }

    #[test]
    fn the_lifts_forces_are_at_most_16_g_on_the_cubes_mass() {
        let lift = scenario(serde_json::json!({ "scenario": "lift", "force_n": 1e308,
            "brake": { "force_n": 800.0, "duration_s": 0.5 }, "fall_end_s": 6.0 }));
        lift.validate().unwrap();
        let e = lift.validate_forces(5.0).unwrap_err();
        assert!(
            e.starts_with("key 'force_n': must be above 0 and at most 784.8 N (16 g on the 5 kg"),
            "{e}"
        );
        let brake = scenario(serde_json::json!({ "scenario": "lift",
            "brake": { "force_n": 800.0, "duration_s": 0.5 }, "fall_end_s": 6.0 }));
        let e = brake.validate_forces(5.0).unwrap_err();
        assert!(e.starts_with("key 'brake.force_n'"), "{e}");
        assert!(brake.validate_forces(0.0).unwrap_err().contains("'urdf'"));
        let e = refused(serde_json::json!({ "scenario": "lift", "force_n": -1.0 }));
        assert!(e.starts_with("key 'force_n': must be a positive"), "{e}");
    }

    #[test]
    fn the_allan_error_model_stays_within_each_triads_full_scale() {
        let allan = |accel: serde_json::Value| {
            scenario(serde_json::json!({ "scenario": "allan",
                "imu_errors": { "accel": accel, "gyro": { "noise_density": 8.7e-5 } } }))
            .validate()
        };
        allan(serde_json::json!({ "noise_density": 3.9e-3, "bias_instability": 4e-3 })).unwrap();
        for (accel, key) in [
            (
                serde_json::json!({ "noise_density": 1e308 }),
                "noise_density",
            ),
            (
                serde_json::json!({ "noise_density": 1e-3, "random_walk": 1e3 }),
                "random_walk",
            ),
            (
                serde_json::json!({ "noise_density": 1e-3, "scale_factor": 5.0 }),
                "scale_factor",
            ),
        ] {
            let e = allan(accel).unwrap_err();
            assert!(
                e.starts_with(&format!("key 'imu_errors.accel.{key}'")),
                "{e}"
            );
        }
    }

    #[test]
    fn the_bounds_hold_together() {
        assert!(MAX_RATE_RAD_S <= MAX_RATE_DEG_S.to_radians());
        assert_eq!(MAX_RADIUS_M, 100.0);
    }
}
