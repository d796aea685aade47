//! The params the scenario's processes share: the arm (its URDF and surface radius), the depth
//! sensor, the push schedule and the estimator's settings, each a table of a process's params
//! with every key checked against its physical range ([`crate::range`]) and named in errors.

use crate::arm_urdf::{ArmModel, from_description};
use crate::depth::Scanner;
use crate::identify::Settings;
use crate::push::{PushSpec, holding_force_n};
use crate::range::{
    HAND_RADIUS_M, MAX_COORDINATE_M, MAX_DEPTH_NOISE_M, MAX_DEPTH_RANGE_M, MAX_LINK_RADIUS_M,
    MAX_MU, MAX_PUSH_N, MAX_TIME_S, MAX_TORQUE_NOISE_N_M, MIN_LINK_RADIUS_M, above, between, shown,
};
use nalgebra::Point2;
use serde::Deserialize;
use std::path::Path;

/// Topic of the person's hand: a `Pose2D` (x, y in the arm's plane; NaN while no hand is near).
pub const HAND_TOPIC: &str = "person/hand";
/// Topic of the depth sensor's scans.
pub const DEPTH_TOPIC: &str = "depth/scan";

/// `arm = { urdf = "robots/arm.urdf", link_radius = 0.05 }`.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ArmParams {
    /// The arm's URDF (see [`crate::arm_urdf`]), relative to the launch file.
    pub urdf: String,
    /// Half-width of the links' surface, m, 0.001 to 50.
    #[serde(default = "link_radius")]
    pub link_radius: f64,
}

fn link_radius() -> f64 {
    0.05
}

impl ArmParams {
    /// Checks `link_radius` and loads the URDF at `path` (the resolved `urdf`).
    pub fn load(&self, path: &Path) -> Result<ArmModel, String> {
        Ok(self.load_with_masses(path)?.0)
    }

    /// [`ArmParams::load`], and the links' mass properties for the dynamic estimator.
    pub fn load_with_masses(
        &self,
        path: &Path,
    ) -> Result<(ArmModel, Result<crate::arm_dynamics::ArmDynamics, String>), String> {
        let (lo, hi) = (MIN_LINK_RADIUS_M, MAX_LINK_RADIUS_M);
        between("arm.link_radius", self.link_radius, lo, hi, "m")?;
        let d = caravan_world::description::load_description(path)
            .map_err(|e| format!("key 'arm.urdf': robot description {e}"))?;
        let model =
            from_description(&d, self.link_radius).map_err(|e| format!("key 'arm': {e}"))?;
        let masses = crate::arm_dynamics::ArmDynamics::from_description(&d, &model.links)
            .map_err(|e| format!("key 'estimator.dynamics': {e}"));
        Ok((model, masses))
    }
}

/// `depth = { origin = [-1.0, -1.0], first_angle_deg = 0, fov_deg = 90, beams = 64, … }`:
/// the depth sensor, as the depth process simulates it and the perception reads its scans.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DepthParams {
    /// Where it sits in the arm's plane, m, each within ±10 km.
    #[serde(default = "origin")]
    pub origin: [f64; 2],
    /// Its first beam, degrees from +x, within ±360.
    #[serde(default)]
    pub first_angle_deg: f64,
    /// From the first beam to the last, degrees, in (0, 360].
    #[serde(default = "fov")]
    pub fov_deg: f64,
    /// 2 to a scan's capacity (`SCAN_MAX_BEAMS`).
    #[serde(default = "beams")]
    pub beams: usize,
    /// m, in (0, 100].
    #[serde(default = "max_range")]
    pub max_range_m: f64,
    /// m, 0 to 1.
    #[serde(default = "range_sigma")]
    pub range_sigma_m: f64,
    /// Returns closer than this to the arm's surface are the arm's own, m, 0 to 1.
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
        let (far, noise) = (MAX_COORDINATE_M, MAX_DEPTH_NOISE_M);
        for (k, x) in self.origin.iter().enumerate() {
            between(&format!("depth.origin[{k}]"), *x, -far, far, "m")?;
        }
        let angle = self.first_angle_deg;
        between("depth.first_angle_deg", angle, -360.0, 360.0, "°")?;
        above("depth.fov_deg", self.fov_deg, 0.0, 360.0, "°")?;
        let most = caravan_schemas::SCAN_MAX_BEAMS;
        if !(2..=most).contains(&self.beams) {
            return Err(format!(
                "key 'depth.beams': must be between 2 and {most} (a scan's capacity), got {}",
                self.beams
            ));
        }
        let range = self.max_range_m;
        above("depth.max_range_m", range, 0.0, MAX_DEPTH_RANGE_M, "m")?;
        between("depth.range_sigma_m", self.range_sigma_m, 0.0, noise, "m")?;
        between("depth.self_filter_m", self.self_filter_m, 0.0, noise, "m")?;
        let s = Scanner {
            origin: Point2::new(self.origin[0], self.origin[1]),
            first_angle: self.first_angle_deg.to_radians(),
            fov: self.fov_deg.to_radians(),
            beams: self.beams,
            max_range: self.max_range_m,
            range_sigma: self.range_sigma_m,
        };
        s.validate().map_err(|e| format!("key 'depth': {e}"))?;
        Ok(s)
    }
}

/// `push = { links = [3, 4], force_n = [90, 110], … }`: the scripted person's pushes.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PushParams {
    /// Links that may be pushed, numbered from 1 as in the reference.
    #[serde(default = "links")]
    pub links: Vec<usize>,
    /// [min, max] magnitude, N: 0 < min ≤ max ≤ 1000, and max within what the joints hold.
    #[serde(default = "force")]
    pub force_n: [f64; 2],
    /// 0 to 5.
    #[serde(default = "mu")]
    pub mu: f64,
    /// m, 0.001 to 1.
    #[serde(default = "hand_radius")]
    pub hand_radius_m: f64,
    /// First push, s, 0 to 86 400 (the arm settles into its pose before).
    #[serde(default = "start")]
    pub start_s: f64,
    /// How long each push lasts, s: from one step of the driver to 86 400.
    #[serde(default = "push_s")]
    pub push_s: f64,
    /// The pause after each push, s: from one step of the driver to 86 400.
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
    /// The pushes on `model` held in its working pose `q` (rad), every key in its range; a
    /// push and a pause last at least `step_s`, the driver's step (it would miss a shorter
    /// one's start or end).
    pub fn spec(&self, model: &ArmModel, q: &[f64], step_s: f64) -> Result<PushSpec, String> {
        if self.links.contains(&0) {
            return Err("key 'push.links': links are numbered from 1".into());
        }
        let [lo, hi] = self.force_n;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi && hi <= MAX_PUSH_N) {
            return Err(format!(
                "key 'push.force_n': [min, max] must hold 0 < min ≤ max ≤ {MAX_PUSH_N} N (a \
                 person's hardest push), got [{}, {}]",
                shown(lo),
                shown(hi)
            ));
        }
        between("push.mu", self.mu, 0.0, MAX_MU, "")?;
        let [h_lo, h_hi] = HAND_RADIUS_M;
        between("push.hand_radius_m", self.hand_radius_m, h_lo, h_hi, "m")?;
        between("push.start_s", self.start_s, 0.0, MAX_TIME_S, "s")?;
        let step = "s (a step of the driver at least)";
        between("push.push_s", self.push_s, step_s, MAX_TIME_S, step)?;
        between("push.gap_s", self.gap_s, step_s, MAX_TIME_S, step)?;
        let spec = PushSpec {
            links: self.links.iter().map(|l| l - 1).collect(),
            force_n: (lo, hi),
            mu: self.mu,
            hand_radius: self.hand_radius_m,
        };
        spec.validate(&model.arm)
            .map_err(|e| format!("key 'push': {e}"))?;
        let efforts: Vec<f64> = model.limits.iter().map(|l| l.effort).collect();
        let (hold, joint, lever) = holding_force_n(&model.arm.pose(q), &efforts, &spec.links);
        if hi > hold {
            return Err(format!(
                "key 'push.force_n': at most {hold:.1} N in this pose, got {}: joint '{}' \
                 holds {} N·m (its <limit effort>) and a push on links {:?} acts up to \
                 {lever:.3} m from it; a harder push moves the arm",
                shown(hi),
                model.joints[joint],
                efforts[joint],
                self.links
            ));
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
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EstimatorParams {
    /// The torque sensors' noise, N·m, 0 to 20: added to every reading, and the thresholds
    /// scale with it.
    #[serde(default)]
    pub torque_sigma: f64,
    /// Below this a joint is unloaded whatever the noise, N·m, 0 to 20: the position loops'
    /// residual torque, up to about 0.1 N·m 0.75 s after a push ends.
    #[serde(default = "floor")]
    pub torque_floor: f64,
    /// 0 to 5.
    #[serde(default = "mu")]
    pub mu: f64,
    /// Subtract the arm's own dynamics from the torques before identifying
    /// ([`crate::arm_dynamics`]): τ_ext = M(q)·q̈ + C(q, q̇)·q̇ − τ_act, q̈ from successive
    /// joint speeds. Off: the reference's static method, τ_ext = −τ_act.
    #[serde(default)]
    pub dynamics: bool,
}

fn floor() -> f64 {
    0.2
}

impl EstimatorParams {
    pub fn settings(&self) -> Result<Settings, String> {
        let (sigma, floor, noise) = (self.torque_sigma, self.torque_floor, MAX_TORQUE_NOISE_N_M);
        between("estimator.torque_sigma", sigma, 0.0, noise, "N·m")?;
        between("estimator.torque_floor", floor, 0.0, noise, "N·m")?;
        between("estimator.mu", self.mu, 0.0, MAX_MU, "")?;
        Ok(Settings {
            mu: self.mu,
            torque_sigma: self.torque_sigma,
            torque_floor: self.torque_floor,
            ..Settings::default()
        })
    }
}

/// The working pose, degrees → radians, one angle per joint, each within ±360° and its
/// joint's `<limit>` (the position loops hold no angle beyond it).
pub fn pose_rad(model: &ArmModel, pose_deg: &[f64]) -> Result<Vec<f64>, String> {
    if pose_deg.len() != model.arm.links() || pose_deg.iter().any(|a| !a.is_finite()) {
        return Err(format!(
            "key 'pose_deg': {} finite angles expected (one per joint), got {:?}",
            model.arm.links(),
            pose_deg
        ));
    }
    for ((a, limits), joint) in pose_deg.iter().zip(&model.limits).zip(&model.joints) {
        let lo = limits.lower.to_degrees().max(-360.0);
        let hi = limits.upper.to_degrees().min(360.0);
        if !(lo..=hi).contains(a) {
            return Err(format!(
                "key 'pose_deg': joint '{joint}' must be between {lo:.2}° and {hi:.2}° (its \
                 <limit>, and one turn), got {}°",
                shown(*a)
            ));
        }
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
        assert!(d.scanner().unwrap_err().contains("'depth.beams'"));
        let e: EstimatorParams = serde_json::from_str(r#"{"torque_sigma": -1}"#).unwrap();
        assert!(e.settings().unwrap_err().contains("torque_sigma"));
    }
}
