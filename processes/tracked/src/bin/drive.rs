//! `caravan-tracked-drive`: the tracked robot's differential-drive controller (see
//! `caravan_tracked::diff_drive`). Every step it takes the latest `robot/i/cmd_vel` (forward
//! speed and turn rate, body frame), limits it, and sends every wheel joint of a side the
//! same speed on `robot/i/joint_command`, with the flippers' angle; it integrates wheel
//! odometry from `robot/i/joint_states` onto `robot/i/odometry`. The flippers go from the
//! robot's start pose (in line) to `flipper_angle_rad`, then to the angles asked on
//! `robot/i/flipper_command`, at no more than their joints' speed limit
//! (`caravan_tracked::flippers`). Params: `robot`, `count`, `urdf`, `flipper_angle_rad`,
//! `limits` (see the crate docs; each number's range is in `caravan_tracked::params` and
//! docs/tracked.md). Give it `rate = "50Hz"`.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::{
    JointCommand, JointState, JointValue, Name, Odometry, Quaternion, Twist, Vector3, topics,
};
use caravan_tracked::diff_drive::{DiffDrive, DriveLimits, WheelOdometry, circumscribed_radius};
use caravan_tracked::flippers::{FlipperRamp, flipper_command};
use caravan_tracked::urdf::flipper_joints;
use caravan_world::description::{JointKind, load_description};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-tracked-drive", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    /// The robot's index: one of the group's `count` robots.
    #[serde(default)]
    robot: usize,
    /// The robots the physics simulates (default 1, the scenario's one robot), 1 to
    /// `caravan_tracked::params::MAX_ROBOTS`: a node cannot see the physics' params, so this
    /// is what `robot` is checked against.
    #[serde(default = "one")]
    count: usize,
    /// Its description: continuous joints named `left_…` and `right_…` are the sides' wheels;
    /// revolute joints named `…flipper_joint` the flippers.
    urdf: String,
    /// The flippers' angle until the operator asks for another, rad above the main track's
    /// line (positive raises their tips; default 30°).
    #[serde(default = "flipper_rest")]
    flipper_angle_rad: f64,
    #[serde(default)]
    limits: DriveLimits,
}

fn one() -> usize {
    1
}

fn flipper_rest() -> f64 {
    caravan_tracked::urdf::FLIPPER_ANGLE_DEG.to_radians()
}

struct Ready {
    robot: usize,
    limits: DriveLimits,
    left: Vec<String>,
    right: Vec<String>,
    /// Each flipper joint's name and its target's ramp.
    flippers: Vec<(String, FlipperRamp)>,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    caravan_tracked::params::robot_index(p.robot, p.count)?;
    identity.serves_robot(p.robot);
    caravan_tracked::params::FLIPPER_ANGLE_RAD.check("flipper_angle_rad", p.flipper_angle_rad)?;
    let radius_given = p.limits.wheel_radius_m != 0.0;
    let d = load_description(&identity.resolve_path(&p.urdf))
        .map_err(|e| format!("key 'urdf': robot description {e}"))?;
    let named = |kind: JointKind, test: &dyn Fn(&str) -> bool| -> Vec<String> {
        d.joints
            .iter()
            .filter(|j| j.kind == kind && test(&j.name))
            .map(|j| j.name.clone())
            .collect()
    };
    let left = named(JointKind::Continuous, &|n| n.starts_with("left_"));
    let right = named(JointKind::Continuous, &|n| n.starts_with("right_"));
    if left.is_empty() || right.is_empty() {
        return Err(format!(
            "key 'urdf': {} has no continuous joints named left_… and right_… (the wheels)",
            d.file
        ));
    }
    let mut flippers = Vec::new();
    for name in flipper_joints() {
        // Fixed flippers (`caravan-tracked-urdf --flipper-angle`) have nothing to move.
        let Some(j) = d.joint(&name).map(|j| &d.joints[j]) else {
            continue;
        };
        if j.kind != JointKind::Revolute {
            continue;
        }
        let l = j.limits;
        if !(l.lower <= p.flipper_angle_rad && p.flipper_angle_rad <= l.upper) {
            return Err(format!(
                "key 'flipper_angle_rad': {} is outside {}'s range [{}, {}] rad",
                p.flipper_angle_rad, j.name, l.lower, l.upper
            ));
        }
        // From the pose the robot starts in (the URDF's zero) to the asked angle.
        let mut ramp = FlipperRamp::at(0.0, l.velocity, [l.lower, l.upper]);
        ramp.goal_rad = p.flipper_angle_rad;
        flippers.push((j.name.clone(), ramp));
    }
    let mut limits = p.limits;
    if limits.wheel_radius_m == 0.0 {
        let first = d.joint(&left[0]).map(|j| d.joints[j].child);
        limits.wheel_radius_m = first.map_or(0.0, |c| circumscribed_radius(&d.links[c]));
    }
    limits
        .validate()
        .and_then(|()| {
            // The slowest wheel: the physics holds each at its joint's velocity limit.
            let slowest = left
                .iter()
                .chain(&right)
                .filter_map(|n| d.joint(n).map(|j| d.joints[j].limits.velocity))
                .fold(f64::INFINITY, f64::min);
            limits.check_wheel_speed(slowest, &d.file, radius_given)
        })
        .map_err(|e| e.replace("key '", "key 'limits."))?;
    Ok(Ready {
        robot: p.robot,
        limits,
        left,
        right,
        flippers,
    })
}

/// Mean position of the named joints in a joint-state message, rad.
fn mean_angle(state: &JointState, names: &[String]) -> f64 {
    let sum: f64 = names
        .iter()
        .filter_map(|n| state.get(n).map(|j| j.position))
        .sum();
    sum / names.len() as f64
}

fn run(mut node: Node, mut r: Ready) -> Result<(), caravan::Error> {
    let cmd_vel = node.subscriber(&topics::cmd_vel(r.robot))?;
    let flipper_cmd = node.subscriber(&flipper_command(r.robot))?;
    let joint_states = node.subscriber(&topics::joint_states(r.robot))?;
    let command = node.publisher(&topics::joint_command(r.robot))?;
    let odometry = node.publisher(&topics::odometry(r.robot))?;
    let trigger = node.trigger(Trigger::every_hz(50.0))?;
    let (mut drive, mut odom) = (DiffDrive::default(), WheelOdometry::default());
    let mut last_s = None;
    node.run(trigger, |step| {
        let now_s = step.now().as_secs_f64();
        let dt = last_s.map_or(0.0, |t| now_s - t);
        last_s = Some(now_s);
        let (v, w) = cmd_vel
            .latest()?
            .map_or((0.0, 0.0), |m| (m.linear.x, m.angular.z));
        let (left, right) = drive.update(&r.limits, v, w, dt);
        let mut cmd = caravan_schemas::placement_new::<JointCommand>();
        let wheels = r
            .left
            .iter()
            .map(|n| (n, left))
            .chain(r.right.iter().map(|n| (n, right)));
        for (name, speed) in wheels {
            let _ = cmd.joints.push(JointValue {
                name: Name::new(name),
                position: f64::NAN,
                velocity: speed,
                effort: f64::NAN,
            });
        }
        if let Some(asked) = flipper_cmd.latest()? {
            for (name, ramp) in &mut r.flippers {
                let goal = asked
                    .joints
                    .as_slice()
                    .iter()
                    .find(|j| j.name.as_str() == name);
                if let Some(goal) = goal.filter(|j| j.position.is_finite()) {
                    ramp.goal_rad = goal.position;
                }
            }
        }
        for (name, ramp) in &mut r.flippers {
            let (position, velocity) = ramp.update(dt);
            let _ = cmd.joints.push(JointValue {
                name: Name::new(name),
                position,
                velocity,
                effort: f64::NAN,
            });
        }
        command.publish(&cmd)?;
        if let Some(state) = joint_states.latest()? {
            let (l, rr) = (mean_angle(&state, &r.left), mean_angle(&state, &r.right));
            odom.update(&r.limits, l, rr, dt);
            let mut out = Odometry::default();
            out.pose.position = Vector3 {
                x: odom.x_m,
                y: odom.y_m,
                z: 0.0,
            };
            out.pose.orientation = Quaternion::from_yaw(odom.yaw_rad);
            out.twist = Twist {
                linear: Vector3 {
                    x: odom.v_m_s,
                    ..Vector3::default()
                },
                angular: Vector3 {
                    z: odom.w_rad_s,
                    ..Vector3::default()
                },
            };
            odometry.publish(&out)?;
        }
        Ok(())
    })?;
    Ok(())
}
