//! Every link's twist at the instant its pose is reported, from the kinematic tree: the root
//! link's twist and each joint's speed after the step, carried out to the children.
//!
//! Why not each link body's own velocity, as rapier keeps it: a multibody link's body velocity
//! is computed at the start of the step's last substep (the step's start, with one substep),
//! from the configuration before it, and not again after the positions move (rapier 0.36, `integrate_multibody_positions`). A link
//! turning steadily about an axis away from its centre of mass then reports its centre's
//! velocity of one step earlier with the new pose: a point on the axis moves outward at about
//! ω²·r·dt, and an IMU differencing such velocities reads a false tangential force of about
//! ω³·r·dt/8. The joints' generalized speeds are the state after the step, so the twists
//! carried out from them describe the same instant as the poses.
//!
//! With `ω_p`, `v_p` the parent's angular velocity and origin velocity, `o` a link's origin
//! (the joint's position: URDF puts the child's frame at the joint) and `a` the joint axis in
//! the world (URDF gives it in the joint frame, the child's), a joint of speed `q̇` gives its
//! child
//! - `ω = ω_p + a·q̇` (revolute, continuous) or `ω_p` (prismatic, fixed);
//! - `v = v_p + ω_p × (o − o_p) + a·q̇` (the last term for prismatic joints only).

use caravan_world::description::{JointKind, RobotDescription};
use nalgebra::{Isometry3, Vector3};

/// A link's twist, world frame: the velocity of its origin (m/s) and its angular velocity
/// (rad/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LinkTwist {
    pub linear: Vector3<f64>,
    pub angular: Vector3<f64>,
}

/// The twists of every link of `d`, in description order, from every link's world pose
/// (`poses`, description order), the root link's twist and `speed(j)`, joint `j`'s speed
/// (rad/s or m/s; never asked for fixed joints). A link the root does not reach keeps a zero
/// twist (descriptions are trees, so there is none).
pub fn link_twists(
    d: &RobotDescription,
    poses: &[Isometry3<f64>],
    root: LinkTwist,
    speed: impl Fn(usize) -> f64,
) -> Vec<LinkTwist> {
    let mut twists = vec![LinkTwist::default(); d.links.len()];
    twists[d.root] = root;
    let mut open = vec![d.root];
    while let Some(parent) = open.pop() {
        let p = twists[parent];
        let from = poses[parent].translation.vector;
        for j in d.child_joints(parent) {
            let joint = &d.joints[j];
            let to = poses[joint.child].translation.vector;
            let mut twist = LinkTwist {
                linear: p.linear + p.angular.cross(&(to - from)),
                angular: p.angular,
            };
            let axis = || poses[joint.child].rotation * joint.axis.normalize();
            match joint.kind {
                JointKind::Revolute | JointKind::Continuous => {
                    twist.angular += axis() * speed(j);
                }
                JointKind::Prismatic => twist.linear += axis() * speed(j),
                JointKind::Fixed => {}
            }
            twists[joint.child] = twist;
            open.push(joint.child);
        }
    }
    twists
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_world::description::parse;
    use nalgebra::{Translation3, UnitQuaternion};

    /// A base, an upper arm turning about z at the base, a forearm turning about z at 0.45 m
    /// and sliding a hand along its x axis from 0.3 m, and a tool fixed 0.1 m above the hand.
    const ARM: &str = r#"<robot name="arm">
  <link name="base"/>
  <link name="upper"/>
  <link name="fore"/>
  <link name="hand"/>
  <link name="tool"/>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/></joint>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.45 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="slide" type="prismatic"><parent link="fore"/><child link="hand"/>
    <origin xyz="0.3 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="mount" type="fixed"><parent link="hand"/><child link="tool"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>"#;

    /// Link poses of the arm at shoulder angle `a`, elbow angle `b` and slide `s`, in
    /// description order.
    fn poses(a: f64, b: f64, s: f64) -> Vec<Isometry3<f64>> {
        let rz = |t: f64| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), t);
        let at = |x: f64, y: f64, z: f64, r: UnitQuaternion<f64>| {
            Isometry3::from_parts(Translation3::new(x, y, z), r)
        };
        let base = Isometry3::identity();
        let upper = base * at(0.0, 0.0, 0.2, rz(a));
        let fore = upper * at(0.45, 0.0, 0.0, rz(b));
        let hand = fore * at(0.3 + s, 0.0, 0.0, rz(0.0));
        let tool = hand * at(0.0, 0.0, 0.1, rz(0.0));
        vec![base, upper, fore, hand, tool]
    }

    #[test]
    fn twists_are_the_time_derivatives_of_the_poses() {
        let d = parse(ARM, "arm.urdf", std::path::Path::new(".")).unwrap();
        let names: Vec<&str> = d.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["base", "upper", "fore", "hand", "tool"]);
        // Joint rates, and the configuration at t as a function of time.
        let (wa, wb, vs) = (1.2, -0.7, 0.25);
        let at = |t: f64| poses(0.3 + wa * t, -0.4 + wb * t, 0.05 + vs * t);
        let speeds = [wa, wb, vs];
        let twists = link_twists(&d, &at(0.0), LinkTwist::default(), |j| speeds[j]);
        // Central differences of the analytic poses, to round-off (h = 1e-6 s).
        let h = 1e-6;
        let (before, after) = (at(-h), at(h));
        for (k, name) in names.iter().enumerate() {
            let v = (after[k].translation.vector - before[k].translation.vector) / (2.0 * h);
            // The rotation vector by atan2 (an acos of the scalar part loses half the digits
            // of so small a turn).
            let dq = after[k].rotation * before[k].rotation.inverse();
            let n = dq.imag().norm();
            let w = dq.imag() * (2.0 * n.atan2(dq.w) / n.max(f64::MIN_POSITIVE)) / (2.0 * h);
            assert!((twists[k].linear - v).norm() < 1e-8, "{name}: {twists:?}");
            assert!((twists[k].angular - w).norm() < 1e-8, "{name}: {twists:?}");
        }
        // The tool turns with the forearm at wa + wb, and the upper arm's origin, on the
        // shoulder's axis, stands still.
        assert!((twists[4].angular.z - (wa + wb)).abs() < 1e-12);
        assert_eq!(twists[1].linear, Vector3::zeros());
    }

    #[test]
    fn a_moving_root_carries_its_twist_to_every_link() {
        let d = parse(ARM, "arm.urdf", std::path::Path::new(".")).unwrap();
        let root = LinkTwist {
            linear: Vector3::new(0.5, 0.0, 0.0),
            angular: Vector3::new(0.0, 0.0, 2.0),
        };
        let twists = link_twists(&d, &poses(0.0, 0.0, 0.0), root, |_| 0.0);
        // Rigid: every origin moves at v + ω × r, r from the base's origin.
        for (k, pose) in poses(0.0, 0.0, 0.0).iter().enumerate() {
            let expected = root.linear + root.angular.cross(&pose.translation.vector);
            assert!((twists[k].linear - expected).norm() < 1e-12);
            assert_eq!(twists[k].angular, root.angular);
        }
    }
}
