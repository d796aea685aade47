//! Setup's second step: each robot's start pose, its kind's own or else the world file's
//! `[[start]]` poses in robot order, on the world's floor.

use super::SetupError;
use crate::robot::StartPose;
use crate::spec::RobotSpec;
use caravan_world::World;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use std::path::Path;

/// Where one robot starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Start {
    /// The key it comes from, for messages (`poses[3]`, `robots[1].poses[0]`), also when the
    /// pose is the world's.
    pub key: String,
    /// `[x, y, yaw]` or `[x, y, z, roll, pitch, yaw]`.
    pub given: Vec<f64>,
}

impl Start {
    pub fn pose(&self) -> StartPose {
        match *self.given {
            [x, y, yaw] => StartPose::Planar { x, y, yaw },
            [x, y, z, roll, pitch, yaw] => StartPose::Full(Isometry3::new(
                Vector3::new(x, y, z),
                UnitQuaternion::from_euler_angles(roll, pitch, yaw).scaled_axis(),
            )),
            _ => unreachable!("validated: 3 or 6 numbers"),
        }
    }
}

/// The start of every robot of `kinds` (each its keys' prefix and its spec), in robot order,
/// in `world` (read from `world_path`).
pub fn place<'a>(
    world: &World,
    world_path: &Path,
    kinds: impl IntoIterator<Item = (&'a str, &'a RobotSpec)>,
) -> Result<Vec<Start>, SetupError> {
    let kinds: Vec<_> = kinds.into_iter().collect();
    let total: usize = kinds.iter().map(|(_, s)| s.count).sum();
    let mut starts: Vec<Start> = Vec::with_capacity(total);
    for (key, spec) in kinds {
        for n in 0..spec.count {
            let given = match spec.poses.get(n) {
                Some(p) => p.clone(),
                None => {
                    let start = world.starts.get(starts.len()).ok_or_else(|| {
                        SetupError(format!(
                            "key '{key}poses': not given, and world file {} has {} [[start]] \
                             pose(s) for {total} robot(s); give one pose per robot in either",
                            world_path.display(),
                            world.starts.len(),
                        ))
                    })?;
                    start.to_vec()
                }
            };
            let key = format!("{key}poses[{n}]");
            starts.push(Start { key, given });
        }
    }
    for (g, Start { key, given: p }) in starts.iter().enumerate() {
        let (x, y) = (p[0], p[1]);
        if !(0.0..=world.size[0]).contains(&x) || !(0.0..=world.size[1]).contains(&y) {
            return Err(SetupError(format!(
                "key '{key}' = {p:?}: robot {g} would start off the floor of world '{}' \
                 ({}), which spans x ∈ [0, {}] and y ∈ [0, {}] m",
                world.name,
                world_path.display(),
                world.size[0],
                world.size[1]
            )));
        }
    }
    Ok(starts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world(starts: Vec<[f64; 3]>) -> World {
        World {
            name: "w".into(),
            size: [4.0, 3.0],
            obstacles: Vec::new(),
            friction: None,
            surveys: Vec::new(),
            starts,
            goals: Vec::new(),
        }
    }

    fn spec(v: serde_json::Value) -> RobotSpec {
        serde_json::from_value(v).unwrap()
    }

    fn starts(w: &World, kinds: &[(&str, &RobotSpec)]) -> Result<Vec<Start>, String> {
        place(w, Path::new("w.toml"), kinds.iter().copied()).map_err(|e| e.0)
    }

    #[test]
    fn a_kind_without_poses_takes_the_worlds_starts_in_robot_order() {
        let w = world(vec![[1.0, 1.0, 0.0], [2.0, 1.0, 0.5], [3.0, 1.0, 1.0]]);
        let own = spec(serde_json::json!({ "urdf": "a.urdf",
            "poses": [[0.5, 2.0, 1.0, 0.0, 0.0, 0.0]] }));
        let world_s = spec(serde_json::json!({ "urdf": "b.urdf", "count": 2 }));
        let s = starts(&w, &[("robots[0].", &own), ("robots[1].", &world_s)]).unwrap();
        let keys: Vec<_> = s.iter().map(|s| s.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "robots[0].poses[0]",
                "robots[1].poses[0]",
                "robots[1].poses[1]"
            ]
        );
        // Robot 1 is the world's second start: robot 0 took the first place in order.
        assert_eq!(
            s[1].pose(),
            StartPose::Planar {
                x: 2.0,
                y: 1.0,
                yaw: 0.5
            }
        );
        assert!(matches!(s[0].pose(), StartPose::Full(p) if p.translation.z == 1.0));
    }

    #[test]
    fn too_few_starts_and_poses_off_the_floor_name_the_key() {
        let w = world(vec![[1.0, 1.0, 0.0]]);
        let two = spec(serde_json::json!({ "urdf": "a.urdf", "count": 2 }));
        let e = starts(&w, &[("", &two)]).unwrap_err();
        assert!(
            e.starts_with("key 'poses': not given") && e.contains("1 [[start]] pose(s) for 2"),
            "{e}"
        );
        let off = spec(serde_json::json!({ "urdf": "a.urdf", "poses": [[1.0, 3.5, 0.0]] }));
        let e = starts(&w, &[("robots[0].", &off)]).unwrap_err();
        assert!(
            e.starts_with("key 'robots[0].poses[0]' = [1.0, 3.5, 0.0]")
                && e.contains("off the floor"),
            "{e}"
        );
    }
}
