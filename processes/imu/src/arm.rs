//! The arm: an IMU on a link away from the axis it turns about, where the reference's
//! scenarios have it on the axis (the tilt, the spin-up) or on a platform turned as one body
//! (the rotation). A two-link arm on a fixed base, both joints kinematic: the elbow bends to
//! `elbow_deg` at its URDF velocity limit, then the shoulder turns the whole arm steadily
//! at `rate_rad_s` about its vertical axis. The IMU rides on the forearm, `imu_x_m` along it
//! from the elbow, so that the forearm's origin and centre of mass are both off the axis.
//!
//! With L the elbow's distance from the shoulder axis, β the elbow angle, ω the shoulder rate
//! and d the IMU's offset, the IMU moves on a circle of radius |(L + d·cos β, d·sin β)| and,
//! in the forearm's frame (turned β from the upper arm's), reads
//! - bending (elbow at ωₑ about the still elbow): f = (−ωₑ²·d, 0, g), ω = (0, 0, ωₑ);
//! - turning: f = (−ω²·(L·cos β + d), ω²·L·sin β, g), ω = (0, 0, ω);
//! - at rest before and between: f = (0, 0, g), ω = 0.

use crate::range::{between, bound, shown};
use crate::scenario::{Expect, G, Phase, SETTLE_S, Scenario};
use caravan_world::description::RobotDescription;
use serde::Deserialize;

/// What the arm's readings depend on besides the scenario's keys, from its description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmGeometry {
    /// The elbow's distance from the shoulder's axis, m.
    pub upper_m: f64,
    /// The elbow's bending rate: its `<limit velocity>`, rad/s.
    pub elbow_rate_rad_s: f64,
}

impl ArmGeometry {
    /// Reads joints `shoulder` and `elbow` of `d`: both about the vertical axis, the elbow a
    /// child of the shoulder's link, with a velocity limit. The error names the key.
    pub fn from_description(
        d: &RobotDescription,
        shoulder: &str,
        elbow: &str,
    ) -> Result<Self, String> {
        let find = |key: &str, name: &str| {
            d.joint(name).ok_or_else(|| {
                format!(
                    "key '{key}': robot description {} has no joint '{name}'",
                    d.file
                )
            })
        };
        let (s, e) = (find("shoulder", shoulder)?, find("elbow", elbow)?);
        let (s, e) = (&d.joints[s], &d.joints[e]);
        // The readings below assume both joints turn counter-clockwise about +z from
        // unturned origins, and the elbow on the upper arm's x axis.
        for (key, j) in [("shoulder", s), ("elbow", e)] {
            let up = (j.origin.rotation * j.axis.normalize()).z;
            if !j.kind.is_movable() || (up - 1.0).abs() > 1e-9 || j.origin.rotation.angle() > 1e-9 {
                return Err(format!(
                    "key '{key}': joint '{}' of {} must turn about +z (axis 0 0 1), its origin \
                     unturned",
                    j.name, d.file
                ));
            }
        }
        let o = e.origin.translation.vector;
        if e.parent != s.child || o.y.abs() > 1e-9 || o.x <= 0.0 {
            return Err(format!(
                "key 'elbow': joint '{}' of {} must sit on the shoulder's link at (L, 0, z), \
                 L > 0",
                e.name, d.file
            ));
        }
        Ok(Self {
            upper_m: o.x,
            elbow_rate_rad_s: e.limits.velocity,
        })
    }
}

/// The arm's keys: `scenario = "arm"` and these.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Arm {
    /// The arm's description (relative to the launch file).
    #[serde(default = "arm_urdf")]
    pub urdf: String,
    /// The shoulder's joint: vertical, at the base.
    #[serde(default = "arm_shoulder")]
    pub shoulder: String,
    /// The elbow's joint: vertical, on the shoulder's link; it bends at its URDF velocity
    /// limit.
    #[serde(default = "arm_elbow")]
    pub elbow: String,
    /// The shoulder's turn rate, rad/s, 1e-4 to 34.9 either way, ω²r at most 16 g.
    #[serde(default = "arm_rate")]
    pub rate_rad_s: f64,
    /// The elbow's bend, degrees, −180 to 180 (0: the arm straight).
    #[serde(default = "arm_elbow_deg")]
    pub elbow_deg: f64,
    /// The IMU's distance from the elbow along the forearm, m, 0 to 100 (the sensor's
    /// `imu_offset` x).
    #[serde(default = "arm_imu_x")]
    pub imu_x_m: f64,
    /// When the elbow starts bending, s, 0.1 to 86 400.
    #[serde(default = "arm_bend_from")]
    pub bend_from_s: f64,
    /// When the shoulder starts turning, s: after the bend, ≤ 86 400.
    #[serde(default = "arm_spin_from")]
    pub spin_from_s: f64,
    /// End of the run, s, > `spin_from_s`, ≤ 86 400.
    #[serde(default = "arm_end")]
    pub end_s: f64,
}

fn arm_urdf() -> String {
    "robots/arm.urdf".into()
}
fn arm_shoulder() -> String {
    "shoulder".into()
}
fn arm_elbow() -> String {
    "elbow".into()
}
fn arm_rate() -> f64 {
    1.2
}
fn arm_elbow_deg() -> f64 {
    60.0
}
fn arm_imu_x() -> f64 {
    0.2
}
fn arm_bend_from() -> f64 {
    0.5
}
fn arm_spin_from() -> f64 {
    2.0
}
fn arm_end() -> f64 {
    4.0
}

impl Arm {
    /// The arm's keys and geometry, checked together, if `s` is the arm; `load` reads the
    /// description its `urdf` names (the driver and the report resolve the path their way).
    pub fn load(
        s: &Scenario,
        load: impl FnOnce(&str) -> Result<RobotDescription, String>,
    ) -> Result<Option<(Self, ArmGeometry)>, String> {
        let Scenario::Arm(arm) = s else {
            return Ok(None);
        };
        let g = ArmGeometry::from_description(&load(&arm.urdf)?, &arm.shoulder, &arm.elbow)?;
        arm.validate(&g)?;
        Ok(Some((arm.clone(), g)))
    }

    /// When the elbow has bent, s.
    pub fn bent_s(&self, g: &ArmGeometry) -> f64 {
        self.bend_from_s + self.elbow_deg.abs().to_radians() / g.elbow_rate_rad_s
    }

    /// The checks that need the arm's description: a bending rate, the bend done before the
    /// turn, and at most 16 g on the IMU.
    pub fn validate(&self, g: &ArmGeometry) -> Result<(), String> {
        let max_rate = crate::range::MAX_RATE_RAD_S;
        between(
            "urdf",
            g.elbow_rate_rad_s,
            crate::range::MIN_TURN_RATE_RAD_S,
            max_rate,
            "rad/s (the elbow's <limit velocity>)",
        )?;
        let bent = self.bent_s(g);
        if bent + SETTLE_S > self.spin_from_s {
            return Err(format!(
                "key 'spin_from_s': the elbow bends until {} s at its {} rad/s, so the turn \
                 may start at {} s at the earliest, got {}",
                bound(bent),
                bound(g.elbow_rate_rad_s),
                bound(bent + SETTLE_S),
                shown(self.spin_from_s)
            ));
        }
        let bending = g.elbow_rate_rad_s.powi(2) * self.imu_x_m;
        if bending > crate::range::MAX_ACCEL_M_S2 {
            return Err(format!(
                "keys 'imu_x_m' and 'urdf': the IMU's centripetal acceleration while the elbow \
                 bends, ωₑ²d = {} m/s², must be at most {} m/s² (16 g)",
                bound(bending),
                bound(crate::range::MAX_ACCEL_M_S2)
            ));
        }
        let radius = self.radius_m(g);
        let centripetal = self.rate_rad_s.powi(2) * radius;
        if centripetal > crate::range::MAX_ACCEL_M_S2 {
            return Err(format!(
                "keys 'rate_rad_s' and 'imu_x_m': the IMU's centripetal acceleration ω²r = {} \
                 m/s² must be at most {} m/s² (16 g, an accelerometer's full scale)",
                bound(centripetal),
                bound(crate::range::MAX_ACCEL_M_S2)
            ));
        }
        Ok(())
    }

    /// The IMU's distance from the shoulder axis once bent, m.
    pub fn radius_m(&self, g: &ArmGeometry) -> f64 {
        let b = self.elbow_deg.to_radians();
        (g.upper_m + self.imu_x_m * b.cos()).hypot(self.imu_x_m * b.sin())
    }

    /// The scored phases: at rest, bending, bent and still, turning.
    pub fn phases(&self, g: &ArmGeometry) -> Vec<Phase> {
        let still = Expect::Vector([0.0, 0.0, G]);
        let (b, w, we) = (
            self.elbow_deg.to_radians(),
            self.rate_rad_s,
            g.elbow_rate_rad_s * self.elbow_deg.signum(),
        );
        let (l, d) = (g.upper_m, self.imu_x_m);
        let bent = self.bent_s(g);
        let phase = |name, from_s, to_s, accel, gyro| Phase {
            name,
            from_s,
            to_s,
            accel,
            gyro,
        };
        vec![
            phase("rest", SETTLE_S, self.bend_from_s, still, [0.0; 3]),
            // The last step of the bend may be shorter; its reading is not scored.
            phase(
                "bending",
                self.bend_from_s + SETTLE_S,
                bent - SETTLE_S,
                Expect::Vector([-we * we * d, 0.0, G]),
                [0.0, 0.0, we],
            ),
            phase("bent", bent + SETTLE_S, self.spin_from_s, still, [0.0; 3]),
            phase(
                "turning",
                self.spin_from_s + SETTLE_S,
                self.end_s,
                Expect::Vector([-w * w * (l * b.cos() + d), w * w * l * b.sin(), G]),
                [0.0, 0.0, w],
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation2, Vector2};

    fn arm() -> Arm {
        let s: Scenario = serde_json::from_value(serde_json::json!({ "scenario": "arm" })).unwrap();
        s.validate().unwrap();
        let Scenario::Arm(a) = s else { panic!() };
        a
    }

    const GEOMETRY: ArmGeometry = ArmGeometry {
        upper_m: 0.45,
        elbow_rate_rad_s: 1.0,
    };

    #[test]
    fn the_turning_reading_is_the_centripetal_acceleration_in_the_forearms_frame() {
        let a = arm();
        a.validate(&GEOMETRY).unwrap();
        let turning = &a.phases(&GEOMETRY)[3];
        let Expect::Vector(f) = turning.accel else {
            panic!()
        };
        // The IMU's position in the upper arm's frame; its acceleration −ω²·p, seen from the
        // forearm (turned β).
        let b = a.elbow_deg.to_radians();
        let p = Vector2::new(0.45, 0.0) + Rotation2::new(b) * Vector2::new(a.imu_x_m, 0.0);
        let in_forearm = Rotation2::new(-b) * (-a.rate_rad_s.powi(2) * p);
        assert!((f[0] - in_forearm.x).abs() < 1e-12 && (f[1] - in_forearm.y).abs() < 1e-12);
        assert!((p.norm() - a.radius_m(&GEOMETRY)).abs() < 1e-12);
        // Off the axis and tangential in the sensor's frame: what the arm is for.
        assert!(f[1].abs() > 0.1);
    }

    #[test]
    fn only_the_arm_the_readings_assume_is_taken() {
        let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../launch/imu/robots/arm.urdf");
        let text = std::fs::read_to_string(shipped).unwrap();
        let parse = |t: &str| {
            let d = caravan_world::description::parse(t, "arm.urdf", std::path::Path::new("."))
                .unwrap();
            ArmGeometry::from_description(&d, "shoulder", "elbow")
        };
        assert_eq!(parse(&text).unwrap(), GEOMETRY);
        // Turning clockwise flips the gyro's sign and the tangential reading.
        let down = text.replacen("<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 0 -1\"/>", 1);
        assert!(parse(&down).unwrap_err().contains("'shoulder'"));
        // An elbow off the upper arm's x axis changes the lever the readings assume.
        let aside = text.replace("<origin xyz=\"0.45 0 0\"/>", "<origin xyz=\"0.45 0.1 0\"/>");
        assert!(parse(&aside).unwrap_err().contains("'elbow'"));
        // Bending at 30 rad/s swings the IMU 0.2 m out at 180 m/s², past 16 g.
        let mut a = arm();
        a.imu_x_m = 0.2;
        let fast = ArmGeometry {
            elbow_rate_rad_s: 30.0,
            ..GEOMETRY
        };
        assert!(a.validate(&fast).unwrap_err().contains("bends"));
    }

    #[test]
    fn the_turn_must_wait_for_the_bend() {
        let mut a = arm();
        a.spin_from_s = a.bent_s(&GEOMETRY);
        assert!(a.validate(&GEOMETRY).unwrap_err().contains("'spin_from_s'"));
        a.spin_from_s = 3.0;
        a.rate_rad_s = 30.0;
        assert!(a.validate(&GEOMETRY).unwrap_err().contains("16 g"));
    }
}
