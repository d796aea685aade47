//! The planar arm's own dynamics: the joint torques τ = M(q)·q̈ + C(q, q̇)·q̇ that move its
//! links as they move, by the recursive Newton–Euler algorithm (a forward pass of the links'
//! accelerations, a backward pass of the forces between them). The joints turn about z and
//! gravity acts along −z, so gravity loads none of them.
//!
//! Why: the reference's method is static. It reads the external torques as what the
//! actuators hold against (τ_ext = −τ_act), which is exact only while the arm stands still.
//! A push moves the arm a little, and the position loops' correction still carries some of
//! its inertia 0.75 s later (0.016 N off at σ = 0 in the live group). The dynamic estimator
//! subtracts the arm's own dynamics: τ_ext = M(q)·q̈ + C(q, q̇)·q̇ − τ_act.

use crate::planar_arm::PlanarArm;
use caravan_world::description::RobotDescription;
use nalgebra::{Point2, Vector2};

/// One link's mass properties in the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkMass {
    /// kg, > 0.
    pub mass: f64,
    /// The centre of mass in the link's frame (origin on its joint, x along the link), m.
    pub com: Point2<f64>,
    /// Moment of inertia about the z axis through the centre of mass, kg·m².
    pub izz: f64,
}

/// The arm's links' mass properties, joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmDynamics {
    pub links: Vec<LinkMass>,
}

/// 2-D cross product (the z component).
fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `a` turned a quarter counter-clockwise: ω × a for ω along z, per unit ω.
fn perp(a: Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-a.y, a.x)
}

impl ArmDynamics {
    /// The links `links` (names, joint order) of `d`: each needs an `<inertial>` (a turned
    /// one is turned into the link's frame; the planar model keeps its izz). A link fixed to
    /// one of them (the tip frame) must carry no mass, which this model would leave out.
    pub fn from_description(d: &RobotDescription, links: &[String]) -> Result<Self, String> {
        let links_named = links;
        let links = links
            .iter()
            .map(|name| {
                let link = d
                    .link(name)
                    .map(|l| &d.links[l])
                    .ok_or_else(|| format!("{}: no link '{name}'", d.file))?;
                let i = link.inertial.as_ref().ok_or_else(|| {
                    format!(
                        "{}: link '{name}' has no <inertial>; the dynamic estimator needs \
                         its mass",
                        d.file
                    )
                })?;
                let c = i.origin.translation.vector;
                let izz = (i.origin.rotation.to_rotation_matrix().matrix()
                    * i.inertia
                    * i.origin.rotation.to_rotation_matrix().matrix().transpose())[(2, 2)];
                if !(i.mass.is_finite() && i.mass > 0.0 && izz.is_finite() && izz >= 0.0) {
                    return Err(format!(
                        "{}: link '{name}' needs a positive mass and izz",
                        d.file
                    ));
                }
                Ok(LinkMass {
                    mass: i.mass,
                    com: Point2::new(c.x, c.y),
                    izz,
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        let in_chain = |l: usize| links_named.iter().any(|n| *n == d.links[l].name);
        if let Some(j) = d.joints.iter().find(|j| {
            j.kind == caravan_world::description::JointKind::Fixed
                && in_chain(j.parent)
                && d.links[j.child].inertial.is_some()
        }) {
            return Err(format!(
                "{}: link '{}' is fixed to the arm and has an <inertial>; the dynamic \
                 estimator models only the joints' own links",
                d.file, d.links[j.child].name
            ));
        }
        Ok(Self { links })
    }

    /// The joint torques (N·m) that give `arm` the joint accelerations `qdd` (rad/s²) at
    /// angles `q` (rad) and speeds `qd` (rad/s): M(q)·q̈ + C(q, q̇)·q̇.
    pub fn torques(&self, arm: &PlanarArm, q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
        let pose = arm.pose(q);
        let n = arm.links();
        // Forward: each link's angular rate and acceleration, its centre's acceleration, and
        // the acceleration of the next joint (the link's far end).
        let (mut w, mut a) = (0.0, 0.0);
        let mut joint_acc = Vector2::zeros();
        let mut alphas = Vec::with_capacity(n);
        let mut com_acc = Vec::with_capacity(n);
        let mut com_at = Vec::with_capacity(n);
        for i in 0..n {
            w += qd[i];
            a += qdd[i];
            let frame = &pose.frames[i];
            let c = frame * self.links[i].com - pose.joints[i];
            com_acc.push(joint_acc + a * perp(c) - w * w * c);
            com_at.push(c);
            alphas.push(a);
            let end = frame.rotation * Vector2::new(arm.lengths[i], 0.0);
            joint_acc += a * perp(end) - w * w * end;
        }
        // Backward: the force and moment (about the joint) each link takes from its parent.
        let mut tau = vec![0.0; n];
        let (mut f, mut moment) = (Vector2::zeros(), 0.0);
        for i in (0..n).rev() {
            let link = &self.links[i];
            let inertial = link.mass * com_acc[i];
            // The child's force acts at joint i + 1, the link's far end.
            let end = pose.frames[i].rotation * Vector2::new(arm.lengths[i], 0.0);
            moment = link.izz * alphas[i] + cross(com_at[i], inertial) + moment + cross(end, f);
            f += inertial;
            tau[i] = moment;
        }
        tau
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn arm() -> (PlanarArm, ArmDynamics) {
        let arm = PlanarArm::new(Point2::new(0.1, -0.2), vec![0.4, 0.35, 0.3], 0.05).unwrap();
        let link = |mass: f64, x: f64, izz: f64| LinkMass {
            mass,
            com: Point2::new(x, 0.01),
            izz,
        };
        let dynamics = ArmDynamics {
            links: vec![
                link(4.0, 0.2, 0.06),
                link(3.5, 0.15, 0.04),
                link(3.0, 0.1, 0.02),
            ],
        };
        (arm, dynamics)
    }

    /// M(q) from the links' Jacobians: Σ m·Jᵥᵀ·Jᵥ + izz·J_ωᵀ·J_ω.
    fn mass_matrix(arm: &PlanarArm, d: &ArmDynamics, q: &[f64]) -> DMatrix<f64> {
        let pose = arm.pose(q);
        let n = q.len();
        let mut m = DMatrix::zeros(n, n);
        for (i, link) in d.links.iter().enumerate() {
            let c = pose.frames[i] * link.com;
            let jv: Vec<Vector2<f64>> = (0..n)
                .map(|j| {
                    if j <= i {
                        perp(c - pose.joints[j])
                    } else {
                        Vector2::zeros()
                    }
                })
                .collect();
            for r in 0..n {
                for s in 0..n {
                    let jw = f64::from(r <= i && s <= i);
                    m[(r, s)] += link.mass * jv[r].dot(&jv[s]) + link.izz * jw;
                }
            }
        }
        m
    }

    #[test]
    fn at_rest_the_torques_are_the_mass_matrix_times_the_accelerations() {
        let (arm, d) = arm();
        let q = [0.3, -0.8, 1.1];
        let qdd = [0.7, -1.3, 2.0];
        let tau = d.torques(&arm, &q, &[0.0; 3], &qdd);
        let expected = mass_matrix(&arm, &d, &q) * nalgebra::DVector::from_row_slice(&qdd);
        for k in 0..3 {
            assert!(
                (tau[k] - expected[k]).abs() < 1e-12,
                "{tau:?} vs {expected}"
            );
        }
    }

    #[test]
    fn the_velocity_terms_are_those_of_the_lagrangian() {
        // C(q, q̇)·q̇ = Ṁ·q̇ − ½·∂(q̇ᵀ·M·q̇)/∂q, by central differences of M.
        let (arm, d) = arm();
        let q = [0.3, -0.8, 1.1];
        let qd = [1.2, -0.5, 0.9];
        let tau = d.torques(&arm, &q, &qd, &[0.0; 3]);
        let h = 1e-6;
        let at = |s: f64, dir: &[f64]| -> Vec<f64> {
            q.iter().zip(dir).map(|(a, b)| a + s * b).collect()
        };
        let v = nalgebra::DVector::from_row_slice(&qd);
        let m_dot =
            (mass_matrix(&arm, &d, &at(h, &qd)) - mass_matrix(&arm, &d, &at(-h, &qd))) / (2.0 * h);
        let mut expected = &m_dot * &v;
        for k in 0..3 {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            let energy = |s: f64| (v.transpose() * mass_matrix(&arm, &d, &at(s, &e)) * &v)[0];
            expected[k] -= 0.5 * (energy(h) - energy(-h)) / (2.0 * h);
        }
        for k in 0..3 {
            assert!((tau[k] - expected[k]).abs() < 1e-7, "{tau:?} vs {expected}");
        }
    }
}
