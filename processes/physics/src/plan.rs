//! Which links ride on which rigid body. Links joined by fixed joints are welded into one
//! body (as Gazebo lumps them), so a fixed joint costs the solver nothing and cannot flex;
//! every movable joint starts a new body. Bodies are listed depth-first from the root, each
//! after its parent, which is also the order they are inserted into rapier.

use caravan_world::description::{Geometry, JointKind, RobotDescription};
use nalgebra::Isometry3;

/// A movable (or sensed fixed) joint between two bodies.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPlan {
    /// Index into [`RobotDescription::joints`].
    pub joint: usize,
    /// Index of the parent body in [`RobotPlan::bodies`].
    pub parent_body: usize,
    /// The joint frame (the child link frame at joint position 0) in the parent body frame.
    pub frame: Isometry3<f64>,
}

/// One rigid body: the link it is named after, the links welded to it, and its joint.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPlan {
    /// Links carried, with their pose in the body frame; the first is the body's own link
    /// (pose identity).
    pub links: Vec<(usize, Isometry3<f64>)>,
    /// The joint to the parent body; `None` for the root body.
    pub joint: Option<JointPlan>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RobotPlan {
    pub bodies: Vec<BodyPlan>,
    /// For each link: its body and its pose in that body's frame.
    pub link_body: Vec<(usize, Isometry3<f64>)>,
    /// For each link: whether it is a wheel (see [`is_wheel`]).
    pub wheels: Vec<bool>,
}

impl RobotPlan {
    pub fn new(d: &RobotDescription) -> Self {
        Self::with_sensed(d, &[])
    }

    /// As [`RobotPlan::new`], except that the fixed joints in `sensed` (description joint
    /// indices) are not welded: their child starts a body of its own, held by a fixed
    /// joint whose constraint force can be read (a force–torque sensor).
    pub fn with_sensed(d: &RobotDescription, sensed: &[usize]) -> Self {
        let mut bodies = Vec::new();
        add_body(d, d.root, None, sensed, &mut bodies);
        let mut link_body = vec![(0, Isometry3::identity()); d.links.len()];
        for (b, body) in bodies.iter().enumerate() {
            for (link, pose) in &body.links {
                link_body[*link] = (b, *pose);
            }
        }
        let wheels = (0..d.links.len()).map(|l| is_wheel(d, l)).collect();
        RobotPlan {
            bodies,
            link_body,
            wheels,
        }
    }

    /// The body a movable joint moves (its child body).
    pub fn body_of_joint(&self, joint: usize) -> Option<usize> {
        self.bodies
            .iter()
            .position(|b| b.joint.as_ref().is_some_and(|j| j.joint == joint))
    }
}

fn add_body(
    d: &RobotDescription,
    link: usize,
    joint: Option<JointPlan>,
    sensed: &[usize],
    bodies: &mut Vec<BodyPlan>,
) {
    let welded = |j: usize| d.joints[j].kind == JointKind::Fixed && !sensed.contains(&j);
    let index = bodies.len();
    let mut links = vec![(link, Isometry3::identity())];
    let mut i = 0;
    while i < links.len() {
        let (l, pose) = links[i];
        for j in d.child_joints(l) {
            if welded(j) {
                let joint = &d.joints[j];
                links.push((joint.child, pose * joint.origin));
            }
        }
        i += 1;
    }
    bodies.push(BodyPlan {
        links: links.clone(),
        joint,
    });
    for (l, pose) in links {
        for j in d.child_joints(l) {
            if !welded(j) {
                let plan = JointPlan {
                    joint: j,
                    parent_body: index,
                    frame: pose * d.joints[j].origin,
                };
                add_body(d, d.joints[j].child, Some(plan), sensed, bodies);
            }
        }
    }
}

/// A wheel is a link on a continuous joint with a cylinder about the joint axis. It touches
/// the floor through a ball of the cylinder's radius (see [`crate::scene`]).
pub fn is_wheel(d: &RobotDescription, link: usize) -> bool {
    let Some(j) = d.parent_joint(link) else {
        return false;
    };
    let joint = &d.joints[j];
    joint.kind == JointKind::Continuous
        && d.links[link].collisions.iter().any(|c| {
            matches!(c.geometry, Geometry::Cylinder { .. })
                && (c.origin.rotation * nalgebra::Vector3::z())
                    .cross(&joint.axis)
                    .norm()
                    < 1e-6
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_convoy_robot_is_three_bodies_with_the_caster_welded() {
        let d = caravan_world::description::load_description(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../launch/convoy/robots/convoy_bot.urdf"),
        )
        .unwrap();
        let plan = RobotPlan::new(&d);
        assert_eq!(plan.bodies.len(), 3);
        let names: Vec<&str> = plan.bodies[0]
            .links
            .iter()
            .map(|(l, _)| d.links[*l].name.as_str())
            .collect();
        assert_eq!(names, ["base_link", "caster"]);
        assert_eq!(d.links[plan.bodies[1].links[0].0].name, "left_wheel");
        assert_eq!(plan.wheels.iter().filter(|w| **w).count(), 2);
        let caster = d.link("caster").unwrap();
        assert_eq!(plan.link_body[caster].0, 0);
        assert!((plan.link_body[caster].1.translation.vector.z + 0.047).abs() < 1e-12);
    }
}
