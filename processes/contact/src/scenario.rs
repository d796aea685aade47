//! The params the scenario's processes share: the arm (its URDF and surface radius), the depth
//! sensor, the push schedule and the estimator's settings, each a table of a process's params
//! with every key checked and named in errors.

use crate::arm_urdf::{ArmModel, from_description};
use crate::depth::Scanner;
use crate::identify::Settings;
use crate::push::PushSpec;
use nalgebra::Point2;
use serde::Deserialize;
use std::path::Path;

/// Topic of the person's hand: a `Pose2D` (x, y in the arm's plane; NaN while no hand is near).
pub const HAND_TOPIC: &str = "person/hand";
/// Topic of the depth sensor's scans.
pub const DEPTH_TOPIC: &str = "depth/scan";

/// `arm = { urdf = "robots/arm.urdf", link_radius = 0.05 }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmParams {
    /// The arm's URDF (see [`crate::arm_urdf`]), relative to the launch file.
    pub urdf: String,
    /// Half-width of the links' surface, m, > 0.
    #[serde(default = "link_radius")]
    pub link_radius: f64,
}

fn link_radius() -> f64 {
    0.05
}

impl ArmParams {
    /// Loads the URDF at `path` (the resolved `urdf`).
    pub fn load(&self, path: &Path) -> Result<ArmModel, String> {
        let d = caravan_world::description::load_description(path)
            .map_err(|e| format!("key 'arm.urdf': robot description {e}"))?;
        from_description(&d, self.link_radius).map_err(|e| format!("key 'arm': {e}"))
    }
}

/// `depth = { origin = [-1.0, -1.0], first_angle_deg = 0, fov_deg = 90, beams = 64, … }`:
/// the depth sensor, as the depth process simulates it and the perception reads its scans.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthParams {
    /// Where it sits in the arm's plane, m.
    #[serde(default = "origin")]
    pub origin: [f64; 2],
    #[serde(default)]
    pub first_angle_deg: f64,
    #[serde(default = "fov")]
    pub fov_deg: f64,
    #[serde(default = "beams")]
    pub beams: usize,
    #[serde(default = "max_range")]
    pub max_range_m: f64,
    #[serde(default = "range_sigma")]
    pub range_sigma_m: f64,
    /// Returns closer than this to the arm's surface are the arm's own, m ≥ 0.
    #[serde(default = "self_filter")]
    pub self_filter_m: f64,
}

fn origin() -> [f64; 2] {
    [-1.0, -1.0]
}
fn fov() -> f64 {
    90.0
}
fn beams() -> usize {
    64
}
fn max_range() -> f64 {
    4.0
}
fn range_sigma() -> f64 {
    0.005
}
fn self_filter() -> f64 {
    0.02
}

impl Default for DepthParams {
    fn default() -> Self {
        serde_json::from_str("{}").expect("every key has a default")
    }
}

impl DepthParams {
    pub fn scanner(&self) -> Result<Scanner, String> {
        let s = Scanner {
            origin: Point2::new(self.origin[0], self.origin[1]),
            first_angle: self.first_angle_deg.to_radians(),
            fov: self.fov_deg.to_radians(),
            beams: self.beams,
            max_range: self.max_range_m,
            range_sigma: self.range_sigma_m,
        };
        s.validate().map_err(|e| format!("key 'depth': {e}"))?;
        if !(self.origin.iter().all(|x| x.is_finite()) && self.self_filter_m >= 0.0) {
            return Err("key 'depth': 'origin' must be finite and 'self_filter_m' ≥ 0".into());
        }
        Ok(s)
    }
}

/// `push = { links = [3, 4], force_n = [90, 110], … }`: the scripted person's pushes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PushParams {
    /// Links that may be pushed, numbered from 1 as in the reference.
    #[serde(default = "links")]
    pub links: Vec<usize>,
    #[serde(default = "force")]
    pub force_n: [f64; 2],
    #[serde(default = "mu")]
    pub mu: f64,
    #[serde(default = "hand_radius")]
    pub hand_radius_m: f64,
    /// First push, s ≥ 0 (the arm settles into its pose before).
    #[serde(default = "start")]
    pub start_s: f64,
    /// How long each push lasts and the pause after it, s > 0.
    #[serde(default = "push_s")]
    pub push_s: f64,
    #[serde(default = "gap_s")]
    pub gap_s: f64,
}

fn links() -> Vec<usize> {
    vec![3, 4]
}
fn force() -> [f64; 2] {
    [90.0, 110.0]
}
fn mu() -> f64 {
    0.5
}
fn hand_radius() -> f64 {
    0.04
}
fn start() -> f64 {
    1.0
}
fn push_s() -> f64 {
    2.0
}
fn gap_s() -> f64 {
    1.0
}

impl PushParams {
    pub fn spec(&self, model: &ArmModel) -> Result<PushSpec, String> {
        if self.links.contains(&0) {
            return Err("key 'push.links': links are numbered from 1".into());
        }
        let spec = PushSpec {
            links: self.links.iter().map(|l| l - 1).collect(),
            force_n: (self.force_n[0], self.force_n[1]),
            mu: self.mu,
            hand_radius: self.hand_radius_m,
        };
        spec.validate(&model.arm)
            .map_err(|e| format!("key 'push': {e}"))?;
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !(self.start_s.is_finite() && self.start_s >= 0.0 && ok(self.push_s) && ok(self.gap_s)) {
            return Err("key 'push': 'start_s' ≥ 0, 'push_s' > 0 and 'gap_s' > 0 must hold".into());
        }
        Ok(spec)
    }

    /// The push under way at `t_s` (its index) or `None` before the first and in pauses.
    pub fn active(&self, t_s: f64) -> Option<u64> {
        if t_s < self.start_s {
            return None;
        }
        let cycle = self.push_s + self.gap_s;
        let k = ((t_s - self.start_s) / cycle).floor();
        (t_s - self.start_s - k * cycle < self.push_s).then_some(k as u64)
    }
}

/// `estimator = { torque_sigma = 0.1, torque_floor = 0.2, mu = 0.5 }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorParams {
    /// The torque sensors' noise, N·m ≥ 0: added to every reading, and the thresholds scale
    /// with it.
    #[serde(default)]
    pub torque_sigma: f64,
    /// Below this a joint is unloaded whatever the noise, N·m ≥ 0: the position loops'
    /// residual torque, up to about 0.1 N·m 0.75 s after a push ends.
    #[serde(default = "floor")]
    pub torque_floor: f64,
    #[serde(default = "mu")]
    pub mu: f64,
}

fn floor() -> f64 {
    0.2
}

impl EstimatorParams {
    pub fn settings(&self) -> Result<Settings, String> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !(ok(self.torque_sigma) && ok(self.torque_floor) && ok(self.mu)) {
            return Err(
                "key 'estimator': 'torque_sigma', 'torque_floor' and 'mu' must be ≥ 0".into(),
            );
        }
        Ok(Settings {
            mu: self.mu,
            torque_sigma: self.torque_sigma,
            torque_floor: self.torque_floor,
            ..Settings::default()
        })
    }
}

/// The working pose, degrees → radians, one angle per joint.
pub fn pose_rad(model: &ArmModel, pose_deg: &[f64]) -> Result<Vec<f64>, String> {
    if pose_deg.len() != model.arm.links() || pose_deg.iter().any(|a| !a.is_finite()) {
        return Err(format!(
            "key 'pose_deg': {} finite angles expected (one per joint), got {:?}",
            model.arm.links(),
            pose_deg
        ));
    }
    Ok(pose_deg.iter().map(|a| a.to_radians()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_alternate_with_pauses_after_the_start() {
        let p: PushParams =
            serde_json::from_str(r#"{"start_s": 1.0, "push_s": 2.0, "gap_s": 1.0}"#).unwrap();
        assert_eq!(p.active(0.5), None);
        assert_eq!(p.active(1.0), Some(0));
        assert_eq!(p.active(2.99), Some(0));
        assert_eq!(p.active(3.5), None);
        assert_eq!(p.active(4.0), Some(1));
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        assert!(serde_json::from_str::<DepthParams>(r#"{"beam": 3}"#).is_err());
        let d: DepthParams = serde_json::from_str(r#"{"beams": 1}"#).unwrap();
        assert!(d.scanner().unwrap_err().contains("'depth'"));
        let e: EstimatorParams = serde_json::from_str(r#"{"torque_sigma": -1}"#).unwrap();
        assert!(e.settings().unwrap_err().contains("torque_sigma"));
    }
}
