//! Where the laser and the IMU ride: robot `i`'s base, read from `robot/i/pose_true` and
//! `robot/i/twist_true` (a wheeled robot on the floor), or a named link of any robot, read
//! from `robot/i/link_states` (physics publishes it for a robot with `link_states = true`).

use crate::imu::BodyState;
use caravan_schemas::{LinkStates, Pose2D};
use caravan_world::description::RobotDescription;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Checks that robot description `d` has the link the sensors ride on (key `link`); the error
/// names the file and the links there are.
pub fn check_link(d: &RobotDescription, link: &str) -> Result<(), String> {
    if d.link(link).is_some() {
        return Ok(());
    }
    let links: Vec<&str> = d.links.iter().map(|l| l.name.as_str()).collect();
    Err(format!(
        "key 'link' = \"{link}\": robot description {} has no link named '{link}' (links: {})",
        d.file,
        links.join(", ")
    ))
}

/// Checks that the force-sensor accelerometer's joint exists in `d` and is fixed (key
/// `imu_force_joint`).
pub fn check_force_joint(d: &RobotDescription, joint: &str) -> Result<(), String> {
    match d.joint(joint).map(|j| &d.joints[j]) {
        Some(j) if j.kind == caravan_world::description::JointKind::Fixed => Ok(()),
        Some(_) => Err(format!(
            "key 'imu_force_joint' = \"{joint}\": joint '{joint}' of {} moves; the test mass \
             hangs on a fixed joint with a force–torque sensor",
            d.file
        )),
        None => Err(format!(
            "key 'imu_force_joint' = \"{joint}\": robot description {} has no joint named \
             '{joint}'",
            d.file
        )),
    }
}

/// The state of link `name` in a `link_states` message stamped `stamp_ns`, with the link's
/// planar pose (x, y, yaw) for the laser and its height above the floor.
pub fn link_state(
    stamp_ns: u64,
    states: &LinkStates,
    name: &str,
) -> Option<(BodyState, Pose2D, f64)> {
    let s = states.get(name)?;
    let (p, q) = (&s.pose.position, &s.pose.orientation);
    let orientation = UnitQuaternion::from_quaternion(Quaternion::new(q.w, q.x, q.y, q.z));
    let v = |m: &caravan_schemas::Vector3| Vector3::new(m.x, m.y, m.z);
    let body = BodyState {
        stamp_ns,
        orientation,
        velocity: v(&s.twist.linear),
        angular_velocity: v(&s.twist.angular),
    };
    let planar = Pose2D {
        x: p.x,
        y: p.y,
        theta: s.pose.orientation.yaw(),
    };
    Some((body, planar, p.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{LinkState, Pose3D, Quaternion as MsgQuaternion, Twist};

    #[test]
    fn the_force_joint_must_exist_and_be_fixed() {
        let urdf = r#"<robot name="r"><link name="a"/>
  <link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="c"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="fixed" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="hinge" type="continuous"><parent link="a"/><child link="c"/><axis xyz="0 0 1"/></joint>
</robot>"#;
        let d =
            caravan_world::description::parse(urdf, "r.urdf", std::path::Path::new(".")).unwrap();
        assert!(check_force_joint(&d, "fixed").is_ok());
        assert!(
            check_force_joint(&d, "hinge")
                .unwrap_err()
                .contains("moves")
        );
        let e = check_force_joint(&d, "wrist").unwrap_err();
        assert!(
            e.contains("'imu_force_joint'") && e.contains("no joint named"),
            "{e}"
        );
    }

    #[test]
    fn a_link_state_becomes_a_body_state_and_a_planar_pose() {
        let mut states = caravan_schemas::placement_new::<LinkStates>();
        let mut twist = Twist::default();
        twist.angular.z = 0.5;
        let pose = Pose3D {
            position: caravan_schemas::Vector3 {
                x: 1.0,
                y: 2.0,
                z: 0.3,
            },
            orientation: MsgQuaternion::from_yaw(0.7),
        };
        states
            .links
            .push(LinkState::new("hand", pose, twist))
            .unwrap();
        let (body, planar, z) = link_state(42, &states, "hand").unwrap();
        assert_eq!((planar.x, planar.y, z, body.stamp_ns), (1.0, 2.0, 0.3, 42));
        assert!((planar.theta - 0.7).abs() < 1e-12);
        assert!((body.orientation.euler_angles().2 - 0.7).abs() < 1e-12);
        assert_eq!(body.angular_velocity.z, 0.5);
        assert!(link_state(42, &states, "foot").is_none());
    }
}
