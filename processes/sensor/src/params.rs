//! The sensor node's params (the launch file's `params` table) and their checks.
//!
//! ```toml
//! params = { robot = 0, count = 5, world = "worlds/lab.toml", laser = true }
//! ```
//!
//! Laser defaults are the Hokuyo URG-04LX-UG01's datasheet values (see
//! `shared/reference/convoy.md`); the encoder resolution (360 ticks/rev) and the IMU noise
//! figures are Caravan's documented choices, since the reference does not give them.

use crate::imu::ImuNoise;
use crate::laser::LaserConfig;
use serde::Deserialize;

/// Unknown keys are rejected by `caravan::parse_params`, which names them.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
pub struct Params {
    /// Index i of the robot this instance belongs to (topics `robot/i/...`), < `count`; with a
    /// `world` that lists `[[start]]` poses, one of its robots (< their number).
    pub robot: usize,
    /// Robots in the group, ≥ 1; the laser sees the chassis of robots 0 … count−1 other than
    /// `robot`. Keep it equal to physics' `count`.
    pub count: usize,
    /// World file (walls, boxes, cylinders), relative to the launch file; non-empty.
    pub world: String,
    /// Robot description, for the chassis boxes of the other robots and base_link's height;
    /// non-empty.
    #[serde(default = "default_urdf")]
    pub urdf: String,
    /// The link the laser and the IMU ride on, a link of `urdf`, read from
    /// `robot/i/link_states` (give physics `link_states = true` for this robot). Default: the
    /// base, from `robot/i/pose_true` and `robot/i/twist_true`. A link the URDF lacks is
    /// refused (exit 2) naming the links it has, and no state of the link within 1 s is warned
    /// about on stderr. On a link of a robot that is not a wheeled robot the laser sees the
    /// world but no other robots. The IMU reads once per `link_states` message, so at the
    /// physics node's rate: for a reading every physics step, run physics with `substeps = 1`
    /// at the rate wanted.
    #[serde(default)]
    pub link: Option<String>,

    /// Whether this robot carries the laser scanner (the leader does).
    #[serde(default)]
    pub laser: bool,
    /// Scans per second, Hz, > 0, dividing the node rate.
    #[serde(default = "default_laser_rate")]
    pub laser_rate_hz: f64,
    /// Field of view, degrees (the code's one non-SI unit), (0, 360], centred on the robot's x
    /// axis.
    #[serde(default = "default_laser_fov")]
    pub laser_fov_deg: f64,
    /// Readings per scan, 2 … 1081, spread evenly over the field from its first to its last
    /// edge: 682 over 240° gives the datasheet's 0.352° step.
    #[serde(default = "default_laser_beams")]
    pub laser_beams: usize,
    /// Lower end of the valid range, m, ≥ 0.
    #[serde(default = "default_laser_range_min")]
    pub laser_range_min: f64,
    /// Upper end of the valid range, m, > `laser_range_min`.
    #[serde(default = "default_laser_range_max")]
    pub laser_range_max: f64,
    /// Scanner position ahead of its link's origin (base_link by default), m, finite, along the
    /// link's x axis; give the SLAM node the same value as `slam.laser_x_offset_m`.
    #[serde(default)]
    pub laser_x_offset: f64,
    /// Scanner height above its link's origin, m, finite. Obstacles lower than the scan plane
    /// are not seen, as with a real planar scanner.
    #[serde(default)]
    pub laser_z_offset: f64,
    /// Range noise on the laser (datasheet accuracy, see `laser.rs`).
    #[serde(default = "yes")]
    pub noise: bool,

    /// Encoder resolution, ticks per wheel revolution, ≥ 1.
    #[serde(default = "default_ticks")]
    pub ticks_per_rev: u32,
    /// Encoder readings per second, Hz, > 0, dividing the node rate (the Arduino's 50 Hz loop).
    #[serde(default = "default_encoder_rate")]
    pub encoder_rate_hz: f64,

    /// Whether this robot publishes an IMU.
    #[serde(default = "yes")]
    pub imu: bool,
    /// IMU position in the link it rides on (base_link by default), m, finite. The sensor's
    /// axes are that link's; for a turned sensor, ride on a fixed child link whose joint's
    /// `rpy` turns it (`imu_link`), which physics' `link_states` reports in its own frame.
    #[serde(default)]
    pub imu_offset: [f64; 3],
    /// White noise on the IMU readings (off: ideal readings, as in the reference study).
    #[serde(default)]
    pub imu_noise: bool,
    /// 1-σ accelerometer noise per axis, m/s², ≥ 0, also reported as the message covariance.
    /// The defaults of the three are an MPU-6050-class part at 100 Hz: accelerometer ≈ 400
    /// µg/√Hz, gyroscope ≈ 0.005 °/s/√Hz over 50 Hz.
    #[serde(default = "default_accel_stddev")]
    pub imu_accel_stddev: f64,
    /// 1-σ gyroscope noise per axis, rad/s, ≥ 0.
    #[serde(default = "default_gyro_stddev")]
    pub imu_gyro_stddev: f64,
    /// 1-σ orientation noise per axis, rad, ≥ 0.
    #[serde(default = "default_orientation_stddev")]
    pub imu_orientation_stddev: f64,
    /// A datasheet error model on top of the white noise: per triad (`accel`, `gyro`) noise
    /// density, bias instability, rate random walk, scale factor and quantisation, and the
    /// flicker bias's `bias_correlation_s` (see `imu_errors.rs`). Applies whatever
    /// `imu_noise` says.
    #[serde(default)]
    pub imu_errors: Option<crate::imu_errors::ImuErrors>,
    /// The accelerometer's design: `finite_difference` of the sensor's velocity (the
    /// reference's, default) or `force_sensor`, a test mass of `imu_test_mass_kg` held by the
    /// force–torque sensor on fixed joint `imu_force_joint` (give physics
    /// `force_torque = [that joint]`, and `link` the test mass's link), a = F/m.
    #[serde(default)]
    pub imu_accelerometer: Accelerometer,
    /// The fixed joint of `urdf` whose force–torque sensor holds the test mass
    /// (`imu_accelerometer = "force_sensor"`).
    #[serde(default = "default_force_joint")]
    pub imu_force_joint: String,
    /// The test mass of the force-sensor accelerometer, kg, > 0.
    #[serde(default = "default_test_mass")]
    pub imu_test_mass_kg: f64,
}

/// The accelerometer's design.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Accelerometer {
    #[default]
    FiniteDifference,
    ForceSensor,
}

fn default_force_joint() -> String {
    "accel_joint".into()
}
fn default_test_mass() -> f64 {
    1.0
}

fn default_urdf() -> String {
    "robots/convoy_bot.urdf".into()
}
fn default_laser_rate() -> f64 {
    10.0
}
fn default_laser_fov() -> f64 {
    240.0
}
fn default_laser_beams() -> usize {
    682
}
fn default_laser_range_min() -> f64 {
    0.02
}
fn default_laser_range_max() -> f64 {
    5.6
}
fn yes() -> bool {
    true
}
fn default_ticks() -> u32 {
    360
}
fn default_encoder_rate() -> f64 {
    50.0
}
fn default_accel_stddev() -> f64 {
    0.03
}
fn default_gyro_stddev() -> f64 {
    6e-4
}
fn default_orientation_stddev() -> f64 {
    0.01
}

/// A param that parses but makes no sense; names the key.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    pub key: &'static str,
    pub message: String,
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "key '{}': {}", self.key, self.message)
    }
}

fn check(ok: bool, key: &'static str, message: impl FnOnce() -> String) -> Result<(), ParamError> {
    if ok {
        Ok(())
    } else {
        Err(ParamError {
            key,
            message: message(),
        })
    }
}

fn positive(v: f64, key: &'static str) -> Result<(), ParamError> {
    check(v.is_finite() && v > 0.0, key, || {
        format!("must be a positive number, got {v}")
    })
}

fn non_negative(v: f64, key: &'static str) -> Result<(), ParamError> {
    check(v.is_finite() && v >= 0.0, key, || {
        format!("must be zero or positive, got {v}")
    })
}

impl Params {
    /// Checks the values serde cannot: ranges, orderings and the robot index.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(self.count >= 1, "count", || {
            "must be at least 1 (the robots in the group)".into()
        })?;
        check(self.robot < self.count, "robot", || {
            format!(
                "robot index {} is not below count = {} (robots are numbered 0..{})",
                self.robot, self.count, self.count
            )
        })?;
        check(!self.world.trim().is_empty(), "world", || {
            "must name a world file".into()
        })?;
        check(!self.urdf.trim().is_empty(), "urdf", || {
            "must name a URDF file".into()
        })?;
        positive(self.laser_rate_hz, "laser_rate_hz")?;
        check(
            self.laser_fov_deg.is_finite()
                && self.laser_fov_deg > 0.0
                && self.laser_fov_deg <= 360.0,
            "laser_fov_deg",
            || format!("must be in (0, 360] degrees, got {}", self.laser_fov_deg),
        )?;
        check(
            (2..=caravan_schemas::SCAN_MAX_BEAMS).contains(&self.laser_beams),
            "laser_beams",
            || {
                format!(
                    "must be between 2 and {} (a scan's capacity), got {}",
                    caravan_schemas::SCAN_MAX_BEAMS,
                    self.laser_beams
                )
            },
        )?;
        non_negative(self.laser_range_min, "laser_range_min")?;
        check(
            self.laser_range_max.is_finite() && self.laser_range_max > self.laser_range_min,
            "laser_range_max",
            || {
                format!(
                    "must be greater than laser_range_min ({}), got {}",
                    self.laser_range_min, self.laser_range_max
                )
            },
        )?;
        check(self.laser_x_offset.is_finite(), "laser_x_offset", || {
            format!("must be a finite number, got {}", self.laser_x_offset)
        })?;
        check(self.laser_z_offset.is_finite(), "laser_z_offset", || {
            format!("must be a finite number, got {}", self.laser_z_offset)
        })?;
        check(self.ticks_per_rev >= 1, "ticks_per_rev", || {
            "must be at least 1".into()
        })?;
        positive(self.encoder_rate_hz, "encoder_rate_hz")?;
        check(
            self.imu_offset.iter().all(|v| v.is_finite()),
            "imu_offset",
            || format!("must be three finite numbers, got {:?}", self.imu_offset),
        )?;
        non_negative(self.imu_accel_stddev, "imu_accel_stddev")?;
        non_negative(self.imu_gyro_stddev, "imu_gyro_stddev")?;
        non_negative(self.imu_orientation_stddev, "imu_orientation_stddev")?;
        if self.imu_accelerometer == Accelerometer::ForceSensor {
            positive(self.imu_test_mass_kg, "imu_test_mass_kg")?;
            check(self.link.is_some(), "imu_accelerometer", || {
                "the force-sensor design reads its states from link_states: give `link`, the \
                 test mass's link"
                    .into()
            })?;
        }
        if let Some(e) = &self.imu_errors {
            e.validate().map_err(|message| ParamError {
                key: "imu_errors",
                message,
            })?;
        }
        Ok(())
    }

    /// The scanner's settings (call after [`Params::validate`]).
    pub fn laser_config(&self) -> LaserConfig {
        let fov = self.laser_fov_deg.to_radians();
        LaserConfig {
            angle_min: -fov / 2.0,
            angle_increment: fov / (self.laser_beams - 1) as f64,
            beams: self.laser_beams,
            range_min: self.laser_range_min,
            range_max: self.laser_range_max,
            scan_time: 1.0 / self.laser_rate_hz,
            x_offset: self.laser_x_offset,
            z_offset: self.laser_z_offset,
            noise: self.noise,
        }
    }

    /// The IMU's noise model (call after [`Params::validate`]).
    pub fn imu_noise(&self) -> ImuNoise {
        ImuNoise {
            enabled: self.imu_noise,
            accel_stddev: self.imu_accel_stddev,
            gyro_stddev: self.imu_gyro_stddev,
            orientation_stddev: self.imu_orientation_stddev,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse(v: serde_json::Value) -> Result<Params, String> {
        let p: Params = caravan::parse_params("sensor", &v).map_err(|e| e.to_string())?;
        p.validate().map_err(|e| e.to_string())?;
        Ok(p)
    }

    #[test]
    fn defaults_are_the_datasheet_values() {
        let p = parse(json!({"robot": 0, "count": 5, "world": "w.toml"})).unwrap();
        assert!(!p.laser && p.noise && p.imu && !p.imu_noise);
        assert_eq!(p.urdf, "robots/convoy_bot.urdf");
        assert_eq!(p.ticks_per_rev, 360);
        let c = p.laser_config();
        assert_eq!(c.beams, 682);
        assert!((c.angle_increment.to_degrees() - 0.352).abs() < 5e-4);
        assert!((c.angle_min + 120f64.to_radians()).abs() < 1e-12);
        assert!((c.scan_time - 0.1).abs() < 1e-12);
        assert_eq!((c.range_min, c.range_max), (0.02, 5.6));
    }

    #[test]
    fn robot_index_must_be_below_count() {
        let e = parse(json!({"robot": 5, "count": 5, "world": "w.toml"})).unwrap_err();
        assert!(e.contains("key 'robot'") && e.contains("count = 5"), "{e}");
    }

    #[test]
    fn bad_laser_settings_name_the_key() {
        let base = json!({"robot": 0, "count": 1, "world": "w.toml"});
        let with = |key: &str, v: serde_json::Value| {
            let mut p = base.clone();
            p[key] = v;
            parse(p).unwrap_err()
        };
        let e = with("laser_range_max", json!(0.01));
        assert!(
            e.contains("'laser_range_max'") && e.contains("laser_range_min"),
            "{e}"
        );
        assert!(with("laser_beams", json!(5000)).contains("'laser_beams'"));
        assert!(with("laser_beams", json!(1)).contains("'laser_beams'"));
        assert!(with("laser_fov_deg", json!(400.0)).contains("'laser_fov_deg'"));
        assert!(with("laser_rate_hz", json!(0.0)).contains("'laser_rate_hz'"));
        assert!(with("laser_range_min", json!(-1.0)).contains("'laser_range_min'"));
        assert!(with("ticks_per_rev", json!(0)).contains("'ticks_per_rev'"));
        assert!(with("imu_gyro_stddev", json!(-1.0)).contains("'imu_gyro_stddev'"));
        let e = with("imu_errors", json!({"gyro": {"noise_density": -1.0}}));
        assert!(
            e.contains("key 'imu_errors'") && e.contains("'gyro.noise_density'"),
            "{e}"
        );
        let e = with("imu_errors", json!({"gyro": {"bias_instabilty": 1e-5}}));
        assert!(e.contains("bias_instabilty"), "{e}");
        let e = with("imu_accelerometer", json!("force_sensor"));
        assert!(
            e.contains("key 'imu_accelerometer'") && e.contains("`link`"),
            "{e}"
        );
        assert!(with("imu_accelerometer", json!("spring")).contains("imu_accelerometer"));
    }

    #[test]
    fn unknown_and_mistyped_keys_are_named() {
        let e = parse(json!({"robot": 0, "count": 1, "world": "w", "lazer": true})).unwrap_err();
        assert!(e.contains("'lazer'"), "{e}");
        let e = parse(json!({"robot": 0, "count": 1, "world": "w", "laser": "yes"})).unwrap_err();
        assert!(e.contains("'laser'"), "{e}");
        let e = parse(json!({"count": 1, "world": "w"})).unwrap_err();
        assert!(e.contains("robot"), "{e}");
    }
}
