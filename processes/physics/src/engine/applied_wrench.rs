//! Applied wrenches: a force (and a torque) acting at a point on a named link for a while,
//! such as a person's push or a lifting force. The point is fixed on the link from the
//! moment the command arrives; the force keeps its direction in the world, or turns with the
//! link, as the command's frame says.

use super::joint_state::Loads;
use super::rapier::prelude::*;
use super::shapes;
use crate::plan::RobotPlan;
use crate::wrench::WrenchCommand;
use caravan_world::description::RobotDescription;
use nalgebra::{Point3, Vector3};

/// A wrench acting now.
#[derive(Debug, Clone)]
pub struct ActiveWrench {
    pub link: usize,
    body: RigidBodyHandle,
    /// Application point in the body frame.
    point: Vector,
    /// Force and torque in the world frame, or in the body frame when `turns`.
    force: Vector,
    torque: Vector,
    turns: bool,
    /// End of the wrench, ns; `None`: until replaced.
    pub until_ns: Option<u64>,
}

impl ActiveWrench {
    pub fn start(
        w: &WrenchCommand,
        d: &RobotDescription,
        plan: &RobotPlan,
        handles: &[RigidBodyHandle],
        bodies: &RigidBodySet,
        now_ns: u64,
    ) -> Result<Self, String> {
        let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
        let valid = finite(&w.point)
            && finite(&w.force)
            && finite(&w.torque)
            && w.duration_s.is_finite()
            && w.duration_s >= 0.0;
        if !valid {
            return Err(format!(
                "wrench on '{}': point, force, torque and duration must be finite (duration ≥ 0)",
                w.link
            ));
        }
        let link = d
            .link(&w.link)
            .ok_or_else(|| format!("wrench: robot '{}' has no link named '{}'", d.name, w.link))?;
        let (b, in_body) = plan.link_body[link];
        let body = handles[b];
        let body_pose = bodies[body].position();
        let p = Vector3::from(w.point);
        let (point, force, torque) = if w.in_link_frame {
            let r = in_body.rotation;
            (
                shapes::vector(&in_body.transform_point(&Point3::from(p)).coords),
                shapes::vector(&(r * Vector3::from(w.force))),
                shapes::vector(&(r * Vector3::from(w.torque))),
            )
        } else {
            let world = shapes::vector(&p);
            (
                body_pose.inverse_transform_point(world),
                shapes::vector(&Vector3::from(w.force)),
                shapes::vector(&Vector3::from(w.torque)),
            )
        };
        Ok(Self {
            link,
            body,
            point,
            force,
            torque,
            turns: w.in_link_frame,
            until_ns: (w.duration_s > 0.0).then(|| now_ns + (w.duration_s * 1e9).round() as u64),
        })
    }

    /// Queues this step's force and torque.
    pub fn push(&self, bodies: &RigidBodySet, loads: &mut Loads) {
        let pose = bodies[self.body].position();
        let at = pose.transform_point(self.point);
        let (f, t) = if self.turns {
            (pose.rotation * self.force, pose.rotation * self.torque)
        } else {
            (self.force, self.torque)
        };
        loads.wrench(self.body, f, at, t);
    }
}
