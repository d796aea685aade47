//! The rapier world: a floor, the world file's obstacles as fixed colliders, and each robot's
//! bodies ([`crate::plan`]) with their colliders and joints.
//!
//! Frames follow REP 103 with z up; rapier's gravity points along −z. A body's frame is its
//! own link's frame, so a root body's pose is the robot's base_link pose.
//!
//! Each link's `<inertial>` rides on its first collider (mass properties in that collider's
//! frame), or on the body itself when the link has no collider; the link's other colliders
//! have no mass. A wheel ([`crate::plan::is_wheel`]) has two colliders. Its *tyre* is a ball
//! of the wheel's radius that touches only the floor: rapier's cylinder–box contacts put the
//! support point slightly off the wheel's lowest point, which on a flat floor pushes a robot
//! with idle motors steadily (about 0.06 m/s², in a direction that depends on the step
//! size), and a flat tread moves the load to its inner edge and shortens the track by a
//! wheel width. A ball touches a flat floor exactly below its centre, in the wheel's
//! mid-plane. Its *rim*, the cylinder of the wheel's true size, collides with everything but
//! the floor, so wheels hit walls and other robots where a real wheel would.
//!
//! No joint has a rapier motor: [`crate::actuator`] computes each joint's torque and the
//! simulation applies it to the child body and, reversed, to the parent, so a motor pushes
//! against the body it is bolted to.

use super::rapier::parry::query::intersection_test;
use super::rapier::prelude::*;
use super::shapes;
use crate::plan::RobotPlan;
use crate::robot::{Overlap, RobotSetup, SimConfig, StartPose};
use crate::spec::{Base, JointModel};
use caravan_world::description::{Geometry, RobotDescription};
use caravan_world::world::{self as world_file, FREE_FLOOR_FRICTION};
use caravan_world::{Obstacle, Shape, World};

/// What a collider belongs to, stored in its `user_data` so contacts can be classified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Floor,
    /// Index into [`World::obstacles`].
    Obstacle(usize),
    /// Link `link` of robot `robot`.
    Link {
        robot: usize,
        link: usize,
    },
}

impl Part {
    fn encode(self) -> u128 {
        match self {
            Part::Floor => 0,
            Part::Obstacle(i) => (1 << 64) | i as u128,
            Part::Link { robot, link } => (2 << 64) | ((robot as u128) << 32) | link as u128,
        }
    }

    pub fn decode(data: u128) -> Self {
        match data >> 64 {
            0 => Part::Floor,
            1 => Part::Obstacle(data as u64 as usize),
            _ => Part::Link {
                robot: (data >> 32) as u32 as usize,
                link: data as u32 as usize,
            },
        }
    }

    /// The robot this collider belongs to, if any.
    pub fn robot(self) -> Option<usize> {
        match self {
            Part::Link { robot, .. } => Some(robot),
            Part::Floor | Part::Obstacle(_) => None,
        }
    }
}

/// The contact filter of robots whose links must not touch each other (`self_collide =
/// false`, the default, as in Gazebo): a pair of colliders of the same robot makes no
/// contact. Only those robots' colliders ask for it (rapier's `FILTER_CONTACT_PAIRS`), so
/// other pairs never reach it.
pub struct NoSelfContacts;

impl PhysicsHooks for NoSelfContacts {
    fn filter_contact_pair(&self, c: &PairFilterContext) -> Option<SolverFlags> {
        let robot = |h: ColliderHandle| {
            c.colliders
                .get(h)
                .and_then(|col| Part::decode(col.user_data).robot())
        };
        match (robot(c.collider1), robot(c.collider2)) {
            (Some(a), Some(b)) if a == b => None,
            _ => Some(SolverFlags::default()),
        }
    }
}

/// Collision groups: who may touch whom.
mod groups {
    use super::super::rapier::prelude::{Group, InteractionGroups, InteractionTestMode};

    const FLOOR: Group = Group::GROUP_1;
    const WORLD: Group = Group::GROUP_2;
    /// Every robot collider but wheels.
    const BODY: Group = Group::GROUP_3;
    const RIM: Group = Group::GROUP_4;
    const TYRE: Group = Group::GROUP_5;

    const fn g(member: Group, filter: Group) -> InteractionGroups {
        InteractionGroups::new(member, filter, InteractionTestMode::And)
    }

    pub const FLOOR_GROUPS: InteractionGroups = g(FLOOR, BODY.union(TYRE));
    pub const WORLD_GROUPS: InteractionGroups = g(WORLD, BODY.union(RIM));
    pub const BODY_GROUPS: InteractionGroups = g(BODY, FLOOR.union(WORLD).union(BODY).union(RIM));
    pub const RIM_GROUPS: InteractionGroups = g(RIM, WORLD.union(BODY).union(RIM));
    pub const TYRE_GROUPS: InteractionGroups = g(TYRE, FLOOR);
}

/// Natural frequency of contacts with fixed colliders (floor, walls), Hz; rapier's default
/// is 60. rapier sizes a contact's stiffness by the masses of the two bodies it joins, which
/// for a tyre is the 40 g wheel alone, not the 1.5 kg robot it carries through its joint. At
/// 60 Hz the tyres sink 1 mm into the floor: the rolling radius shrinks by 1.5 % (wheel
/// angles then overstate the distance travelled) and the chassis pitches by 0.6°. At 150 Hz
/// they sink 0.16 mm (0.24 %); stiffer contacts let a standing robot slowly drift in yaw.
pub const STATIC_CONTACT_HZ: Real = 150.0;

/// Height at which a lifted base is held above its normal standing height, m.
pub const LIFT_HEIGHT: f64 = 0.1;

/// Friction of a robot surface whose URDF gives no `<gazebo><mu1>`.
pub const DEFAULT_FRICTION: f64 = 0.5;

/// How a robot's joint is solved in rapier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointHandle {
    Impulse(ImpulseJointHandle),
    Multibody(MultibodyJointHandle),
}

/// One robot's rapier handles.
#[derive(Debug, Clone)]
pub struct RobotBodies {
    pub plan: RobotPlan,
    /// One per [`RobotPlan::bodies`]; the first is the base.
    pub bodies: Vec<RigidBodyHandle>,
    /// Per description joint: its rapier joint, for movable and sensed fixed joints.
    pub joints: Vec<Option<JointHandle>>,
    /// Colliders that can hit obstacles and other robots (everything but tyres).
    pub colliders: Vec<ColliderHandle>,
    /// Tyres, which touch only the floor.
    pub tyres: Vec<ColliderHandle>,
    /// Link index of the root link.
    pub root_link: usize,
}

impl RobotBodies {
    pub fn base(&self) -> RigidBodyHandle {
        self.bodies[0]
    }
}

/// The rapier state and the handles needed to drive and read it.
pub struct Scene {
    pub physics: PhysicsWorld,
    pub robots: Vec<RobotBodies>,
    /// Collider of each world obstacle, in [`World::obstacles`] order.
    pub obstacles: Vec<ColliderHandle>,
}

fn v(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as Real, y as Real, z as Real)
}

fn obstacle_collider(index: usize, o: &Obstacle, friction: f64) -> ColliderBuilder {
    let half_h = o.height / 2.0;
    let centre = v(o.center[0], o.center[1], half_h);
    let builder = match o.shape {
        Shape::Box { half_x, half_y } => {
            ColliderBuilder::cuboid(half_x as Real, half_y as Real, half_h as Real)
                .rotation(v(0.0, 0.0, o.yaw))
        }
        // rapier's cylinders stand along y; a quarter turn about x stands them along z.
        Shape::Cylinder { radius } => ColliderBuilder::cylinder(half_h as Real, radius as Real)
            .rotation(v(std::f64::consts::FRAC_PI_2, 0.0, 0.0)),
    };
    builder
        .translation(centre)
        .friction(friction as Real)
        .collision_groups(groups::WORLD_GROUPS)
        .user_data(Part::Obstacle(index).encode())
}

/// Builds the scene: the world, then each robot in order.
pub fn build(world: &World, robots: &[&RobotSetup], cfg: &SimConfig) -> Result<Scene, String> {
    let mut physics = PhysicsWorld::new();
    physics.gravity = Vector::new(0.0, 0.0, -cfg.gravity as Real);
    // Recycled contact pairs keep stale distances; the contact monitor needs current ones,
    // and a small scene barely benefits from recycling.
    physics.integration_parameters.contact_recycling = false;
    physics.integration_parameters.num_solver_iterations = cfg.solver_iterations;
    physics
        .integration_parameters
        .static_contact_softness
        .natural_frequency = STATIC_CONTACT_HZ;

    // The floor: a slab whose top face is z = 0, a metre wider than the world on each side.
    let [sx, sy] = world.size;
    physics.insert_collider(
        ColliderBuilder::cuboid((sx / 2.0 + 1.0) as Real, (sy / 2.0 + 1.0) as Real, 0.05)
            .translation(v(sx / 2.0, sy / 2.0, -0.05))
            // Robot parts combine with `Min`: unless the world says, their own coefficients
            // decide their grip.
            .friction(world.friction.unwrap_or(FREE_FLOOR_FRICTION) as Real)
            .collision_groups(groups::FLOOR_GROUPS)
            .user_data(Part::Floor.encode()),
        None,
    );
    let obstacles = world
        .obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let mu = world.friction.unwrap_or(world_file::DEFAULT_FRICTION);
            physics.insert_collider(obstacle_collider(i, o, mu), None)
        })
        .collect();

    let mut out = Vec::with_capacity(robots.len());
    for (i, r) in robots.iter().enumerate() {
        out.push(add_robot(&mut physics, i, r)?);
    }
    Ok(Scene {
        physics,
        robots: out,
        obstacles,
    })
}

/// The base pose: a planar start stands a floating robot on its wheels (or, without wheels,
/// on its lowest point) and sits a fixed one at z = 0. Body poses are composed in rapier's
/// precision, as the solver will hold them.
fn base_pose(r: &RobotSetup, plan: &RobotPlan) -> Pose {
    let (x, y, yaw) = match r.pose {
        StartPose::Full(pose) => return shapes::pose(&pose),
        StartPose::Planar { x, y, yaw } => (x, y, yaw),
    };
    let z = if r.spec.base == Base::Fixed {
        0.0
    } else {
        standing_height(r.description, plan)
    } + if r.spec.lifted { LIFT_HEIGHT } else { 0.0 };
    Pose::from_parts(v(x, y, z), Rotation::from_rotation_z(yaw as Real))
}

/// Height of the base link above the floor when the robot stands at rest, m.
pub fn standing_height(d: &RobotDescription, plan: &RobotPlan) -> f64 {
    let rest = d.rest_poses();
    let mut wheel_bottom = f64::INFINITY;
    let mut lowest = f64::INFINITY;
    for (l, link) in d.links.iter().enumerate() {
        for c in &link.collisions {
            let pose = rest[l] * c.origin;
            let z = pose.translation.vector.z;
            if let (true, Geometry::Cylinder { radius, .. }) = (plan.wheels[l], &c.geometry) {
                wheel_bottom = wheel_bottom.min(z - radius);
            }
            lowest = lowest.min(shapes::lowest_point(&c.geometry, &pose));
        }
    }
    -if wheel_bottom.is_finite() {
        wheel_bottom
    } else if lowest.is_finite() {
        lowest
    } else {
        0.0
    }
}

fn add_robot(
    physics: &mut PhysicsWorld,
    index: usize,
    r: &RobotSetup,
) -> Result<RobotBodies, String> {
    let d = r.description;
    let plan = RobotPlan::with_sensed(d, &r.sensed);
    let multibody = r.spec.joint_model() == JointModel::Multibody;
    let with_kinematic = (0..d.joints.len()).any(|j| r.is_kinematic(j));
    let base = base_pose(r, &plan);
    let friction_of = |l: usize| d.links[l].friction.unwrap_or(DEFAULT_FRICTION);
    let self_filter = if r.spec.self_collide {
        ActiveHooks::empty()
    } else {
        ActiveHooks::FILTER_CONTACT_PAIRS
    };

    let mut bodies: Vec<RigidBodyHandle> = Vec::with_capacity(plan.bodies.len());
    let mut world_poses: Vec<Pose> = Vec::with_capacity(plan.bodies.len());
    let mut joints = vec![None; d.joints.len()];
    let mut colliders = Vec::new();
    let mut tyres = Vec::new();
    for body_plan in &plan.bodies {
        let (pose, builder) = match &body_plan.joint {
            None => {
                let builder = match (r.spec.base, r.spec.lifted) {
                    (Base::Fixed, _) | (Base::Floating, true) => RigidBodyBuilder::fixed(),
                    (Base::Kinematic, _) => RigidBodyBuilder::kinematic_velocity_based(),
                    (Base::Floating, false) => RigidBodyBuilder::dynamic(),
                };
                (base, builder)
            }
            Some(j) => (
                world_poses[j.parent_body] * shapes::pose(&r.start_frame(j.joint, &j.frame)),
                RigidBodyBuilder::dynamic(),
            ),
        };
        // Robots must never fall asleep: a sleeping robot would ignore its actuators.
        let handle = physics.insert_body(builder.pose(pose).can_sleep(false));
        let mut massless_links = Vec::new();
        for (link, link_pose) in &body_plan.links {
            let l = &d.links[*link];
            let part = Part::Link {
                robot: index,
                link: *link,
            };
            let extra = r.reflected_inertia_of(*link);
            let mut inertial = l.inertial.clone();
            if let (Some(i), Some((axis, j))) = (&mut inertial, extra) {
                i.inertia += shapes::axis_inertia(&i.origin, &axis, j);
            }
            let wheel = plan.wheels[*link];
            let fixed = r.spec.base == Base::Fixed && body_plan.joint.is_none();
            // A rim's contacts (its link's and any welded to it) take its surface speed
            // ([`super::rim`]).
            let hooks = if body_plan.joint.as_ref().is_some_and(|j| r.is_rim(j.joint)) {
                self_filter | ActiveHooks::MODIFY_SOLVER_CONTACTS
            } else {
                self_filter
            };
            // Several primitives on a link (a gear's rim and teeth) make one compound
            // collider: one broad-phase entry instead of one per part.
            if let Some(shape) = shapes::compound(&l.collisions, link_pose, fixed) {
                let mut builder = ColliderBuilder::new(shape)
                    .friction(friction_of(*link) as Real)
                    .friction_combine_rule(CoefficientCombineRule::Min)
                    .collision_groups(groups::BODY_GROUPS)
                    .active_hooks(hooks)
                    .user_data(part.encode());
                builder = match &inertial {
                    Some(i) => builder.mass_properties(shapes::mass_properties(
                        i,
                        &nalgebra::Isometry3::identity(),
                        link_pose,
                    )),
                    None => builder.density(0.0),
                };
                colliders.push(physics.insert_collider(builder, Some(handle)));
                continue;
            }
            for (k, c) in l.collisions.iter().enumerate() {
                let at = link_pose * c.origin;
                let shape = shapes::shape(&c.geometry, fixed)
                    .map_err(|e| format!("link '{}' of {}: {e}", l.name, d.file))?;
                let is_rim = wheel && matches!(c.geometry, Geometry::Cylinder { .. });
                let mut builder = ColliderBuilder::new(shape)
                    .position(shapes::collider_pose(&c.geometry, &at))
                    .friction(friction_of(*link) as Real)
                    .friction_combine_rule(CoefficientCombineRule::Min)
                    .collision_groups(if is_rim {
                        groups::RIM_GROUPS
                    } else {
                        groups::BODY_GROUPS
                    })
                    .active_hooks(hooks)
                    .user_data(part.encode());
                builder = match (&inertial, k) {
                    (Some(i), 0) => builder.mass_properties(shapes::mass_properties(
                        i,
                        &shapes::collider_iso(&c.geometry, &at),
                        link_pose,
                    )),
                    _ => builder.density(0.0),
                };
                colliders.push(physics.insert_collider(builder, Some(handle)));
                if is_rim && let Geometry::Cylinder { radius, .. } = c.geometry {
                    tyres.push(
                        physics.insert_collider(
                            // A ball needs no rotation; leaving it out keeps its frame the body's.
                            ColliderBuilder::ball(radius as Real)
                                .translation(shapes::vector(&at.translation.vector))
                                .density(0.0)
                                .friction(r.spec.wheel_friction as Real)
                                .friction_combine_rule(CoefficientCombineRule::Min)
                                .collision_groups(groups::TYRE_GROUPS)
                                .active_hooks(hooks & ActiveHooks::MODIFY_SOLVER_CONTACTS)
                                .user_data(part.encode()),
                            Some(handle),
                        ),
                    );
                }
            }
            if l.collisions.is_empty()
                && let Some(i) = inertial
            {
                massless_links.push((i, *link_pose));
            }
        }
        // Links without colliders still weigh: their mass goes on the body itself.
        if !massless_links.is_empty() {
            let mut props = MassProperties::default();
            for (i, link_pose) in &massless_links {
                props += shapes::mass_properties(i, link_pose, link_pose)
                    .transform_by(&shapes::pose(link_pose));
            }
            physics.bodies[handle].set_additional_mass_properties(props, true);
        }
        if let Some(j) = &body_plan.joint {
            let joint = &d.joints[j.joint];
            let parent = bodies[j.parent_body];
            let kinematic = r.is_kinematic(j.joint);
            // A rim is welded to its parent; the simulation turns the weld's frame.
            let mut generic = if r.is_rim(j.joint) {
                FixedJointBuilder::new()
                    .local_frame1(shapes::pose(&r.start_frame(j.joint, &j.frame)))
                    .contacts_enabled(false)
                    .into()
            } else {
                shapes::joint(joint, &j.frame)
            };
            if with_kinematic {
                // rapier cannot hold limits in a multibody with kinematic joints; the
                // actuators' targets are clamped to them (see `ActuatorSpec::Kinematic`).
                generic.limit_axes = JointAxesMask::empty();
            }
            if let Some(m) = r.spec.force_torque_softness
                && r.sensed.contains(&j.joint)
            {
                let _ = generic.set_softness(SpringCoefficients {
                    natural_frequency: m.natural_frequency_hz as Real,
                    damping_ratio: m.damping_ratio as Real,
                });
            }
            // A sensed fixed joint is an impulse joint even in a multibody: a multibody
            // holds its joints without forces to read.
            joints[j.joint] = Some(if multibody && joint.kind.is_movable() {
                let set = &mut physics.multibody_joints;
                let inserted = if kinematic {
                    set.insert_kinematic(parent, handle, generic, true)
                } else {
                    set.insert(parent, handle, generic, true)
                };
                JointHandle::Multibody(inserted.ok_or_else(|| {
                    format!(
                        "joint '{}' of {}: rapier refused it in a multibody",
                        joint.name, d.file
                    )
                })?)
            } else {
                JointHandle::Impulse(physics.impulse_joints.insert(parent, handle, generic, true))
            });
        }
        bodies.push(handle);
        world_poses.push(pose);
    }
    // rapier gives every angular degree of freedom of a multibody a default damping of
    // 0.1 N·m·s/rad, which slowed a 2.65 kg·m² bar's spin-up by 0.75 %. Joints here are
    // undamped, as impulse joints are; actuators apply the torques.
    for handle in joints.iter().flatten() {
        if let JointHandle::Multibody(h) = handle
            && let Some((mb, _)) = physics.multibody_joints.get_mut(*h)
        {
            mb.damping_mut().fill(0.0);
        }
    }
    start_joints(physics, r, &plan, &bodies, &joints, &world_poses);
    Ok(RobotBodies {
        plan,
        bodies,
        joints,
        colliders,
        tyres,
        root_link: d.root,
    })
}

/// Gives each joint its initial state (`initial_positions`, `initial_velocities`). The bodies
/// already stand at the initial positions; a multibody's generalized coordinates and speeds
/// are set to match (a rim's weld frame was turned instead). An impulse-joint robot's bodies
/// get the velocities the joints' speeds give them, carried out from its resting root.
fn start_joints(
    physics: &mut PhysicsWorld,
    r: &RobotSetup,
    plan: &RobotPlan,
    bodies: &[RigidBodyHandle],
    joints: &[Option<JointHandle>],
    world_poses: &[Pose],
) {
    let mut impulse_speeds = false;
    for (j, handle) in joints.iter().enumerate() {
        let (q, v) = r.start_of(j);
        match handle {
            Some(JointHandle::Multibody(h)) if (q, v) != (0.0, 0.0) && !r.is_rim(j) => {
                let (mb, id) = physics.multibody_joints.get_mut(*h).expect("inserted");
                let dof = mb.link(id).expect("inserted").assembly_id();
                let mut displacement = vec![0.0; mb.ndofs()];
                displacement[dof] = q as Real;
                mb.apply_displacements(&displacement);
                mb.generalized_velocity_mut()[dof] = v as Real;
            }
            Some(JointHandle::Impulse(_)) => impulse_speeds |= v != 0.0,
            _ => {}
        }
    }
    if !impulse_speeds {
        return;
    }
    let d = r.description;
    let poses: Vec<_> = (plan.link_body.iter())
        .map(|(b, in_body)| shapes::isometry(&world_poses[*b]) * in_body)
        .collect();
    let twists =
        crate::link_twists::link_twists(d, &poses, Default::default(), |j| r.start_of(j).1);
    for (b, body_plan) in plan.bodies.iter().enumerate().skip(1) {
        let (link, body) = (body_plan.links[0].0, &mut physics.bodies[bodies[b]]);
        body.recompute_mass_properties_from_colliders(&physics.colliders);
        let com = shapes::isometry(body.position())
            * nalgebra::Point3::from(shapes::vector_f64(body.local_center_of_mass()));
        let t = twists[link];
        let v = t.linear
            + t.angular
                .cross(&(com.coords - poses[link].translation.vector));
        body.set_linvel(shapes::vector(&v), true);
        body.set_angvel(shapes::vector(&t.angular), true);
    }
}

/// The first robot that, at its start pose, overlaps an obstacle or another robot (floor
/// contacts excepted).
pub fn first_overlap(scene: &Scene) -> Option<Overlap> {
    let colliders = &scene.physics.colliders;
    let overlaps = |a: ColliderHandle, b: ColliderHandle| {
        let (ca, cb) = (&colliders[a], &colliders[b]);
        intersection_test(ca.position(), ca.shape(), cb.position(), cb.shape())
            .map(|hit| hit.intersecting)
            .unwrap_or(false)
    };
    for (i, r) in scene.robots.iter().enumerate() {
        for &part in &r.colliders {
            if let Some(obstacle) = scene.obstacles.iter().position(|&o| overlaps(part, o)) {
                return Some(Overlap::Obstacle { robot: i, obstacle });
            }
            for (j, other) in scene.robots.iter().enumerate().skip(i + 1) {
                if other.colliders.iter().any(|&o| overlaps(part, o)) {
                    return Some(Overlap::Robot { robot: i, other: j });
                }
            }
        }
    }
    None
}
