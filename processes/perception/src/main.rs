//! `caravan-perception`: a robot's localisation, as a node.
//!
//! - `mode = "slam"` (the leader): laser-only SLAM. In: `robot/i/scan`. Out: `robot/i/pose`
//!   for every scan and `map` once a second; on exit the final map is saved in the run
//!   directory as `map.yaml` + `map.pgm` (ROS map_server format) for the run report.
//! - `mode = "odometry"` (a follower): dead reckoning from `robot/i/encoder_ticks`, in the map
//!   frame from the robot's known initial pose. Out: `robot/i/odometry` and `robot/i/pose`.
//!
//! `localisation = "ideal"` replaces the estimate on `robot/i/pose` by the true pose (from
//! `robot/i/pose_true`), for ablations; SLAM then still maps, from the true poses.

use caravan::{Error, Node, Trigger};
use caravan_perception::{Slam, SlamParams, WheelOdometry, map_file};
use caravan_schemas::{
    OccupancyGrid, Odometry, Pose2D, Pose3D, Quaternion, Twist, Vector3, topics,
};
use serde::Deserialize;
use std::process::ExitCode;

#[derive(
    Debug, Clone, Copy, Deserialize, serde::Serialize, schemars::JsonSchema, PartialEq, Eq,
)]
#[serde(rename_all = "lowercase")]
enum Mode {
    Slam,
    Odometry,
}

#[derive(
    Debug, Clone, Copy, Default, Deserialize, serde::Serialize, schemars::JsonSchema, PartialEq, Eq,
)]
#[serde(rename_all = "lowercase")]
enum Localisation {
    #[default]
    Estimated,
    Ideal,
}

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    /// What the node does: `slam` (the leader's laser SLAM) or `odometry` (a follower's wheel
    /// dead reckoning).
    mode: Mode,
    /// Index of the robot (topics `robot/<i>/…`); without `initial_pose`, one of the `world`
    /// file's robots (< its `[[start]]` poses).
    robot: usize,
    /// The robot's start pose [x, y, θ] in the map frame, m, m, rad, finite: SLAM's map origin
    /// is laid so that map and world frames agree, and odometry counts from it. Default: the
    /// `world` file's `[[start]]` pose of `robot`.
    initial_pose: Option<[f64; 3]>,
    /// The world file, relative to the launch file, whose `[[start]]` poses give `initial_pose`
    /// when it is not set (one of the two is required).
    world: Option<String>,
    /// `estimated`, or `ideal`: publish the true pose on `robot/<i>/pose` instead of the
    /// estimate (SLAM still builds its map, from the true poses; odometry still publishes its
    /// own estimate on `robot/<i>/odometry`).
    #[serde(default)]
    localisation: Localisation,
    /// Slam mode's parameters; checked only in slam mode.
    #[serde(default)]
    slam: SlamParams,
    /// Slam: how often the map is published, Hz, > 0.
    #[serde(default = "default_map_rate")]
    map_rate_hz: f64,
    /// Slam: base name (a plain file name, no `/`) of the map saved in the run directory on
    /// exit (`<name>.yaml`, `<name>.pgm`); `""` saves nothing. Nothing is saved outside
    /// `caravan launch`. The report reads only `map.yaml`.
    #[serde(default = "default_save_map")]
    save_map: String,
    /// The robot's URDF, relative to the launch file: odometry's wheel radius and separation.
    /// Required in odometry mode; in slam mode optional, but loaded and checked if given.
    urdf: Option<String>,
}

fn default_map_rate() -> f64 {
    1.0
}
fn default_save_map() -> String {
    "map".into()
}

impl Params {
    fn validate(&self) -> Result<(), String> {
        use caravan_world::limits::{MAX_WORLD_EXTENT_M, coordinate};
        for (k, v) in self.initial_pose.iter().flatten().enumerate() {
            coordinate(&format!("key 'initial_pose[{k}]'"), *v, MAX_WORLD_EXTENT_M)?;
        }
        // The map is written into the run directory, never beside or above it.
        let plain = self.save_map.is_empty()
            || (self.save_map != ".."
                && self.save_map != "."
                && !self.save_map.contains('/')
                && !self.save_map.contains('\0'));
        if !plain {
            return Err(format!(
                "key 'save_map': '{}' must be a plain file name (the map goes into the run \
                 directory) or \"\" for none",
                self.save_map
            ));
        }
        if !(self.map_rate_hz > 0.0 && self.map_rate_hz.is_finite()) {
            return Err(format!(
                "key 'map_rate_hz': must be positive, got {}",
                self.map_rate_hz
            ));
        }
        if self.mode == Mode::Slam {
            self.slam
                .validate()
                .map_err(|e| format!("key 'slam': {e}"))?;
        }
        Ok(())
    }

    /// The start pose: `initial_pose`, else the world file's start of this robot.
    fn initial(&self, identity: &caravan::NodeIdentity) -> Result<Pose2D, String> {
        let [x, y, theta] = match (self.initial_pose, &self.world) {
            (Some(pose), _) => pose,
            (None, Some(file)) => {
                let world = caravan_world::load_world(&identity.resolve_path(file))
                    .map_err(|e| format!("key 'world': world file {e}"))?;
                // A world that lists [[start]] poses names its robots: this one is among them.
                world.check_robot(file, self.robot)?;
                *world.starts.get(self.robot).ok_or_else(|| {
                    format!(
                        "key 'initial_pose': not given, and world file {file} has no [[start]] \
                         pose for robot {}",
                        self.robot
                    )
                })?
            }
            (None, None) => {
                return Err(
                    "key 'initial_pose': give the start pose [x, y, theta], or a 'world' \
                            file whose [[start]] poses include this robot"
                        .into(),
                );
            }
        };
        Ok(Pose2D { x, y, theta })
    }
}

/// Wheel radius and separation, m, from the URDF.
struct Wheels {
    radius_m: f64,
    separation_m: f64,
}

fn main() -> ExitCode {
    caravan::node_main(
        "caravan-perception",
        |p: Params, identity| {
            p.validate()?;
            identity.serves_robot(p.robot);
            let initial = p.initial(identity)?;
            let wheels = match (&p.urdf, p.mode) {
                (Some(urdf), _) => {
                    let robot = caravan_world::load_robot(&identity.resolve_path(urdf))
                        .map_err(|e| format!("key 'urdf': robot description {e}"))?;
                    Some(Wheels {
                        radius_m: robot.wheel_radius,
                        separation_m: robot.wheel_separation(),
                    })
                }
                (None, Mode::Odometry) => {
                    return Err("key 'urdf': odometry needs the robot's URDF (its wheel radius and separation)".into());
                }
                (None, Mode::Slam) => None,
            };
            Ok((p, initial, wheels))
        },
        |node, (p, initial, wheels)| match (p.mode, wheels) {
            (Mode::Odometry, Some(wheels)) => odometry(node, &p, initial, &wheels),
            _ => slam(node, &p, initial),
        },
    )
}

fn slam(mut node: Node, p: &Params, initial: Pose2D) -> Result<(), Error> {
    let i = p.robot;
    let mut slam = Slam::new(p.slam.clone(), initial).map_err(|message| Error::Params {
        node: node.name().to_string(),
        message: format!("key 'slam': {message}"),
    })?;
    let scan_topic = topics::scan(i);
    let scans = node.subscriber(&scan_topic)?;
    let truth = match p.localisation {
        Localisation::Ideal => Some(node.subscriber(&topics::pose_true(i))?),
        Localisation::Estimated => None,
    };
    let pose_pub = node.publisher(&topics::pose(i))?;
    let map_pub = node.publisher(&topics::map())?;
    let map_period = 1.0 / p.map_rate_hz;
    let mut next_map = 0.0;
    node.run(Trigger::on(scan_topic.name()), |step| {
        let Some(scan) = scans.latest()? else {
            return Ok(());
        };
        let pose = match &truth {
            Some(sub) => match sub.latest()? {
                Some(t) => slam.update_with_pose(&scan, *t),
                None => return Ok(()),
            },
            None => slam.update(&scan),
        };
        pose_pub.publish(&pose)?;
        let now = step.now().as_secs_f64();
        if now >= next_map {
            next_map = now + map_period;
            let mut map = map_pub.loan()?;
            slam.write_grid(&mut map);
            map.send()?;
        }
        Ok(())
    })?;
    if let (Some(dir), false) = (&node.identity().run_dir, p.save_map.is_empty()) {
        let mut grid = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
        slam.write_grid(&mut grid);
        if let Err(e) = map_file::save_map(&grid, &dir.join(&p.save_map)) {
            eprintln!("caravan-perception: cannot save the map: {e}");
        }
    }
    Ok(())
}

fn odometry(mut node: Node, p: &Params, initial: Pose2D, wheels: &Wheels) -> Result<(), Error> {
    let i = p.robot;
    let ticks_topic = topics::encoder_ticks(i);
    let ticks = node.subscriber(&ticks_topic)?;
    let truth = match p.localisation {
        Localisation::Ideal => Some(node.subscriber(&topics::pose_true(i))?),
        Localisation::Estimated => None,
    };
    let odom_pub = node.publisher(&topics::odometry(i))?;
    let pose_pub = node.publisher(&topics::pose(i))?;
    let mut odometry = WheelOdometry::new(initial, wheels.radius_m, wheels.separation_m);
    node.run(Trigger::on(ticks_topic.name()), |_| {
        while let Some(msg) = ticks.receive()? {
            let t = msg.header().stamp_ns as f64 * 1e-9;
            let Some(estimate) = odometry.update(t, &msg) else {
                continue;
            };
            odom_pub.publish(&odometry_message(estimate.pose, estimate.v, estimate.omega))?;
            let pose = match &truth {
                Some(sub) => match sub.latest()? {
                    Some(t) => *t,
                    None => continue,
                },
                None => estimate.pose,
            };
            pose_pub.publish(&pose)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// nav_msgs/Odometry for a planar pose and body velocity; covariances are not estimated.
fn odometry_message(pose: Pose2D, v: f64, omega: f64) -> Odometry {
    Odometry {
        pose: Pose3D {
            position: Vector3 {
                x: pose.x,
                y: pose.y,
                z: 0.0,
            },
            orientation: Quaternion::from_yaw(pose.theta),
        },
        pose_covariance: [0.0; 36],
        twist: Twist::planar(v, omega),
        twist_covariance: [0.0; 36],
    }
}
