//! Reading a joint's position and speed from its two bodies, and applying a joint torque or
//! force to them. The same code serves impulse joints and multibody joints: positions come
//! from body poses through the joint frame, not from either solver's internal coordinates.

use super::rapier::prelude::*;
use super::shapes;
use crate::actuator::{JointReading, MotorSetting};
use caravan_world::description::{Joint, JointKind};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};

/// One movable joint as the simulation sees it.
#[derive(Debug, Clone)]
pub struct JointIo {
    /// Index in the description's joints.
    pub joint: usize,
    pub kind: JointKind,
    /// Parent and child bodies.
    pub body1: RigidBodyHandle,
    pub body2: RigidBodyHandle,
    /// The joint frame in the parent body frame (f64 for positions).
    pub frame: Isometry3<f64>,
    /// The axis in the child frame.
    pub axis: Vector3<f64>,
    /// The axis in the parent body frame, as rapier computes with it.
    axis1: Vector,
    /// The multibody joint, when the robot is a multibody: its generalized velocity is the
    /// joint speed (rapier does not keep the link bodies' velocities in step with it).
    pub multibody: Option<MultibodyJointHandle>,
    /// The impulse joint, when it is one (for a motor actuator).
    pub impulse: Option<ImpulseJointHandle>,
    /// A wheel turned as a rim ([`crate::spec::ActuatorSpec::Rim`]), its index in the
    /// simulation's [`super::rim::Rims`]: welded to its parent, its speed is the commanded one.
    pub rim: Option<usize>,
    /// Position and speed after the last step.
    pub reading: JointReading,
}

impl JointIo {
    pub fn new(
        joint: usize,
        j: &Joint,
        body1: RigidBodyHandle,
        body2: RigidBodyHandle,
        frame: Isometry3<f64>,
    ) -> Self {
        let axis1 = if frame.rotation == UnitQuaternion::identity() {
            shapes::vector(&j.axis)
        } else {
            shapes::vector(&(frame.rotation * j.axis))
        };
        Self {
            joint,
            kind: j.kind,
            body1,
            body2,
            frame,
            axis: j.axis,
            axis1,
            multibody: None,
            impulse: None,
            rim: None,
            reading: JointReading::default(),
        }
    }

    /// The rapier axis the joint moves along.
    fn motor_axis(&self) -> JointAxis {
        if self.kind == JointKind::Prismatic {
            JointAxis::LinX
        } else {
            JointAxis::AngX
        }
    }

    /// The joint's rapier data, impulse or multibody.
    fn data_mut<'a>(
        &self,
        impulse: &'a mut ImpulseJointSet,
        multibody: &'a mut MultibodyJointSet,
    ) -> Option<&'a mut GenericJoint> {
        if let Some(h) = self.impulse {
            return impulse.get_mut(h, true).map(|j| &mut j.data);
        }
        let (mb, id) = multibody.get_mut(self.multibody?)?;
        mb.link_mut(id).map(|l| &mut l.joint.data)
    }

    /// Sets rapier's motor: a velocity motor, or a servo pulling to a position (on a
    /// multibody joint, its implicit spring: [`Self::set_spring`]).
    pub fn set_motor(
        &self,
        impulse: &mut ImpulseJointSet,
        multibody: &mut MultibodyJointSet,
        m: MotorSetting,
    ) {
        if m.stiffness > 0.0 && self.multibody.is_some() {
            self.set_spring(multibody, m);
            return;
        }
        let axis = self.motor_axis();
        let Some(data) = self.data_mut(impulse, multibody) else {
            return;
        };
        let data = data.set_motor_model(axis, MotorModel::ForceBased);
        let data = if m.stiffness > 0.0 {
            data.set_motor(
                axis,
                m.position as Real,
                m.velocity as Real,
                m.stiffness as Real,
                m.damping as Real,
            )
        } else {
            data.set_motor_velocity(axis, m.velocity as Real, m.damping as Real)
        };
        let _ = data.set_motor_max_force(axis, m.max_effort as Real);
    }

    /// A servo on a multibody joint: rapier's implicit joint spring and damper, which (unlike
    /// a motor) needs no constraint, so it works beside kinematic joints and its effort can
    /// be read. The damper pulls toward rest, so the spring's rest leads the target by
    /// `damping·ω*/stiffness` (the damper's pull toward the target speed), and stays within
    /// `max_effort/stiffness` of the joint: the effort bound, exact while the joint is still.
    fn set_spring(&self, multibody: &mut MultibodyJointSet, m: MotorSetting) {
        let Some((mb, id)) = self.multibody.and_then(|h| multibody.get_mut(h)) else {
            return;
        };
        let axis = self.motor_axis() as usize;
        let Some(link) = mb.link_mut(id) else {
            return;
        };
        // rapier's own coordinate, the one its spring acts on.
        let q = link.joint.coords()[axis] as f64;
        let reach = m.max_effort / m.stiffness;
        let lead = m.damping * m.velocity / m.stiffness;
        let rest = q + (m.position + lead - q).clamp(-reach, reach);
        link.joint
            .set_spring(axis, m.stiffness as Real, rest as Real);
        let dof = link.assembly_id();
        mb.damping_mut()[dof] = m.damping as Real;
    }

    /// Moves a kinematic multibody joint at `speed` (rad/s or m/s) over the next step: its
    /// generalized velocity, which the solver leaves alone.
    pub fn set_kinematic_velocity(&self, multibody: &mut MultibodyJointSet, speed: f64) {
        let Some((mb, id)) = self.multibody.and_then(|h| multibody.get_mut(h)) else {
            return;
        };
        let Some(dof) = mb.link(id).map(|l| l.assembly_id()) else {
            return;
        };
        mb.generalized_velocity_mut()[dof] = speed as Real;
    }

    /// Turns a rim at `speed` (rad/s) over the next step: its weld's frame is set to where
    /// the wheel will be, and its contacts take that speed ([`super::rim`]).
    pub fn turn_rim(
        &mut self,
        impulse: &mut ImpulseJointSet,
        multibody: &mut MultibodyJointSet,
        speed: f64,
        dt: f64,
    ) {
        self.reading.velocity = speed;
        let angle = self.reading.position + speed * dt;
        let axis = nalgebra::Unit::new_normalize(self.axis);
        let turned = self.frame * UnitQuaternion::from_axis_angle(&axis, angle);
        if let Some(data) = self.data_mut(impulse, multibody) {
            data.set_local_frame1(shapes::pose(&turned));
        }
    }

    /// The effort rapier's motor applied over the last step, N·m or N: its last substep's
    /// impulse times the substeps, over the step.
    pub fn motor_effort(
        &self,
        impulse: &mut ImpulseJointSet,
        multibody: &mut MultibodyJointSet,
        per_second: f64,
    ) -> f64 {
        let axis = self.motor_axis() as usize;
        if let Some((mb, id)) = self.multibody.and_then(|h| multibody.get(h))
            && let Some(link) = mb.link(id)
            && link.joint.spring(axis).0 > 0.0
        {
            // The spring and damper's force at the state after the step.
            let (k, rest) = link.joint.spring(axis);
            let q = link.joint.coords()[axis];
            let d = mb.damping()[link.assembly_id()] as f64;
            return (k * (rest - q)) as f64 - d * self.reading.velocity;
        }
        self.data_mut(impulse, multibody)
            // rapier's motor impulse acts against the joint's positive direction.
            .map_or(0.0, |d| -d.motors[axis].impulse as f64 * per_second)
    }

    /// The joint axis in the world frame.
    pub fn world_axis(&self, bodies: &RigidBodySet) -> Vector {
        *bodies[self.body1].rotation() * self.axis1
    }

    /// Reads position and speed from the bodies; revolute and continuous joints count turns.
    pub fn read(&mut self, bodies: &RigidBodySet, multibodies: &MultibodyJointSet) {
        let (b1, b2) = (&bodies[self.body1], &bodies[self.body2]);
        let axis_w = self.world_axis(bodies);
        let joint_w = shapes::isometry(b1.position()) * self.frame;
        let child = shapes::isometry(b2.position());
        let generalized = self.multibody.and_then(|h| {
            let (mb, link) = multibodies.get(h)?;
            mb.joint_velocity(mb.link(link)?)
                .iter()
                .next()
                .map(|v| *v as f64)
        });
        self.reading = match self.kind {
            JointKind::Prismatic => {
                let p = child.translation.vector;
                let offset = joint_w.inverse_transform_point(&p.into()).coords;
                let at = shapes::vector(&p);
                JointReading {
                    position: offset.dot(&self.axis),
                    velocity: generalized.unwrap_or_else(|| {
                        (b2.velocity_at_point(at) - b1.velocity_at_point(at)).dot(axis_w) as f64
                    }),
                }
            }
            _ => {
                let q = joint_w.rotation.inverse() * child.rotation;
                let angle = 2.0 * q.imag().dot(&self.axis).atan2(q.w);
                // Turns are counted (for a revolute joint whose limits pass ±π too), so a
                // target beyond π is reached, not chased round.
                let previous = self.reading.position;
                let position = previous + wrap(angle - wrap(previous));
                // A rim's bodies move as one: its speed is the one it was turned at.
                let velocity = if self.rim.is_some() {
                    self.reading.velocity
                } else {
                    generalized.unwrap_or_else(|| (b2.angvel() - b1.angvel()).dot(axis_w) as f64)
                };
                JointReading { position, velocity }
            }
        };
    }

    /// Queues torque (or force) `effort` on the child and its reaction on the parent.
    pub fn push(&self, bodies: &RigidBodySet, effort: f64, loads: &mut Loads) {
        let axis_w = self.world_axis(bodies);
        match self.kind {
            JointKind::Prismatic => {
                let at = bodies[self.body2].translation();
                loads.force(self.body2, axis_w, effort, at);
                loads.force(self.body1, axis_w, -effort, at);
            }
            _ => {
                loads.torque(self.body2, axis_w, effort);
                loads.torque(self.body1, axis_w, -effort);
            }
        }
    }
}

/// An angle in (−π, π].
fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let w = a - tau * (a / tau).round();
    if w <= -std::f64::consts::PI {
        w + tau
    } else {
        w
    }
}

/// Torques and forces for this step, summed per body before they reach rapier. Torques about
/// the same axis add as numbers first, so a chassis carrying two motors gets one torque of
/// their summed magnitudes.
#[derive(Debug, Default)]
pub struct Loads {
    torques: Vec<(RigidBodyHandle, Vector, f64)>,
    forces: Vec<(RigidBodyHandle, Vector, Vector)>,
}

impl Loads {
    pub fn torque(&mut self, body: RigidBodyHandle, axis: Vector, magnitude: f64) {
        match self
            .torques
            .iter_mut()
            .find(|(b, a, _)| *b == body && *a == axis)
        {
            Some((_, _, m)) => *m += magnitude,
            None => self.torques.push((body, axis, magnitude)),
        }
    }

    pub fn force(&mut self, body: RigidBodyHandle, axis: Vector, magnitude: f64, at: Vector) {
        self.forces.push((body, axis * magnitude as Real, at));
    }

    /// A force `f` (world frame) at world point `at` and a free torque `t`.
    pub fn wrench(&mut self, body: RigidBodyHandle, f: Vector, at: Vector, t: Vector) {
        self.forces.push((body, f, at));
        if t != Vector::ZERO {
            let n = t.length();
            self.torques.push((body, t / n, n as f64));
        }
    }

    /// Hands everything to rapier and empties the queue.
    pub fn apply(&mut self, bodies: &mut RigidBodySet) {
        for (body, axis, m) in self.torques.drain(..) {
            bodies[body].add_torque(axis * m as Real, true);
        }
        for (body, f, at) in self.forces.drain(..) {
            bodies[body].add_force_at_point(f, at, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::wrap;

    #[test]
    fn wrap_keeps_angles_in_half_open_range() {
        let pi = std::f64::consts::PI;
        assert!((wrap(3.0 * pi) - pi).abs() < 1e-12);
        assert!((wrap(-pi) - pi).abs() < 1e-12);
        assert!((wrap(0.5) - 0.5).abs() < 1e-15);
    }
}
