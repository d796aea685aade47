//! Wheels turned as rims ([`crate::spec::ActuatorSpec::Rim`]). A rim is welded to its
//! parent and the simulation turns the weld's frame, so the wheel's geometry turns while its
//! body moves only with its parent. Its contacts are then given the speed the wheel's surface
//! has at each contact point, `ω · axis × (p − centre)`:
//!
//! - along the contact plane as rapier's `tangent_velocity` (a conveyor belt's speed), and
//! - along the normal as a change of the contact's distance by that speed over the step (a
//!   tooth turning into a stair's edge closes the gap as fast as it turns).
//!
//! That is what rapier's kinematic joint gives the contacts, without the joint's degree of
//! freedom: the multibody's mass matrix, which rapier assembles densely over every link's
//! Jacobian, keeps only the robot's other joints. One difference: where the normal motion
//! would close the gap within the step, rapier sees a penetration and pushes out over a few
//! steps (at most its corrective speed), where the kinematic joint's velocity is resolved at
//! once; a tooth pressing an edge is a little softer. The geometry's turn takes effect because
//! rapier runs every multibody's forward kinematics at the start of each step, from the joints'
//! frames.

use super::rapier::prelude::*;
use super::scene::{NoSelfContacts, Part};

/// One turning wheel: its speed and its axis in its body's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Rim {
    /// rad/s, as last commanded.
    speed: Real,
    /// Unit axis in the wheel body's frame (the joint's axis; the body's frame is the wheel
    /// link's, its centre on the axis).
    axis: Vector,
}

/// The rims of every robot: each rim once, and which links (by robot) belong to it: the
/// wheel's link and any welded to it.
#[derive(Debug, Clone, Default)]
pub struct Rims {
    rims: Vec<Rim>,
    links: Vec<Vec<Option<usize>>>,
}

impl Rims {
    /// Adds a rim of robot `robot` made of `links`, turning about `axis` (its body's frame);
    /// returns its index for [`Self::set_speed`].
    pub fn add(
        &mut self,
        robot: usize,
        links: impl IntoIterator<Item = usize>,
        axis: Vector,
    ) -> usize {
        let rim = self.rims.len();
        self.rims.push(Rim { speed: 0.0, axis });
        if self.links.len() <= robot {
            self.links.resize(robot + 1, Vec::new());
        }
        let of_robot = &mut self.links[robot];
        for link in links {
            if of_robot.len() <= link {
                of_robot.resize(link + 1, None);
            }
            of_robot[link] = Some(rim);
        }
        rim
    }

    /// Sets the speed of rim `rim` (from [`Self::add`]), rad/s.
    pub fn set_speed(&mut self, rim: usize, speed: f64) {
        self.rims[rim].speed = speed as Real;
    }

    /// The spin of link `link` of robot `robot` relative to its body, in the body's frame
    /// (rad/s about the axis); `None` for a link that is not part of a rim.
    pub fn spin(&self, robot: usize, link: usize) -> Option<Vector> {
        let rim = self.of(Part::Link { robot, link })?;
        Some(rim.axis * rim.speed)
    }

    fn of(&self, part: Part) -> Option<Rim> {
        let Part::Link { robot, link } = part else {
            return None;
        };
        let rim = (*self.links.get(robot)?.get(link)?)?;
        Some(self.rims[rim])
    }
}

/// A rim in contact: its speed, and its axis and centre (world frame).
#[derive(Clone, Copy)]
struct Turning {
    speed: Real,
    axis: Vector,
    centre: Vector,
}

impl Turning {
    /// The surface's velocity at world point `at`.
    fn velocity_at(&self, at: Vector) -> Vector {
        self.axis.cross(at - self.centre) * self.speed
    }
}

/// The hooks of one physics step: no contacts within a robot that asks for none
/// ([`NoSelfContacts`]), and each rim's surface speed on its contacts.
pub struct StepHooks<'a> {
    pub rims: &'a Rims,
    /// The step, s.
    pub dt: Real,
}

impl StepHooks<'_> {
    fn turning(&self, c: &ContactModificationContext, collider: ColliderHandle) -> Option<Turning> {
        let col = c.colliders.get(collider)?;
        let rim = self.rims.of(Part::decode(col.user_data))?;
        let body = c.bodies.get(col.parent()?)?;
        Some(Turning {
            speed: rim.speed,
            axis: *body.rotation() * rim.axis,
            centre: body.translation(),
        })
    }
}

impl PhysicsHooks for StepHooks<'_> {
    fn filter_contact_pair(&self, c: &PairFilterContext) -> Option<SolverFlags> {
        NoSelfContacts.filter_contact_pair(c)
    }

    fn modify_solver_contacts(&self, c: &mut ContactModificationContext) {
        let first = self.turning(c, c.collider1);
        let second = self.turning(c, c.collider2);
        let dt = self.dt;
        let Some(m) = c.rigid_mut() else {
            return;
        };
        // The normal points from the first collider to the second.
        let n = *m.normal;
        for sc in m.solver_contacts.iter_mut() {
            // The solver drives (v1 − v2)·t + tangent_velocity·t to zero: a first surface
            // moving at v adds v, a second one −v.
            if let Some(t) = first {
                let v = t.velocity_at(sc.anchor1);
                let along = v.dot(n);
                sc.tangent_velocity += v - n * along;
                sc.dist -= along * dt;
            }
            if let Some(t) = second {
                let v = t.velocity_at(sc.anchor2);
                let along = v.dot(n);
                sc.tangent_velocity -= v - n * along;
                sc.dist += along * dt;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rim_surface_moves_across_its_axis_at_radius_times_speed() {
        let t = Turning {
            speed: 2.0,
            axis: Vector::new(0.0, 1.0, 0.0),
            centre: Vector::new(1.0, 0.0, 0.5),
        };
        // The lowest point of a wheel turning about +y moves toward −x: on the ground, the
        // wheel drives toward +x.
        let v = t.velocity_at(Vector::new(1.0, 0.0, 0.0));
        assert!((v - Vector::new(-1.0, 0.0, 0.0)).length() < 1e-6, "{v:?}");
    }

    #[test]
    fn rims_are_found_by_robot_and_link_only() {
        let mut rims = Rims::default();
        let rim = rims.add(1, [3], Vector::new(0.0, 1.0, 0.0));
        rims.set_speed(rim, 4.0);
        assert_eq!(
            rims.of(Part::Link { robot: 1, link: 3 }).unwrap().speed,
            4.0
        );
        assert_eq!(rims.spin(1, 3), Some(Vector::new(0.0, 4.0, 0.0)));
        assert!(rims.of(Part::Link { robot: 0, link: 3 }).is_none());
        assert!(rims.of(Part::Link { robot: 1, link: 9 }).is_none());
        assert!(rims.of(Part::Floor).is_none());
    }
}
