//! The rapier world: a floor, the world file's obstacles as fixed colliders, and each robot as
//! a chassis body with two wheel bodies on revolute joints and a caster.
//!
//! Frames follow REP 103 with z up; rapier's gravity points along −z. A robot's chassis body
//! frame is its `base_link` (at axle height, midway between the wheels), so the body pose is
//! the robot pose. Wheel bodies keep the chassis orientation at rest, so their spin axis is
//! their local y, which is also rapier's cylinder axis.
//!
//! Each wheel has two colliders. Its *tyre* is a ball of the wheel's radius that touches only
//! the floor: rapier's cylinder–box contacts put the support point slightly off the wheel's
//! lowest point, which on a flat floor pushes a robot with idle motors steadily (about
//! 0.06 m/s², in a direction that depends on the step size), and a flat tread moves the load
//! to its inner edge and shortens the track by a wheel width. A ball touches a flat floor
//! exactly below its centre, in the wheel's mid-plane. Its *rim*, a cylinder of the wheel's
//! true size, collides with everything but the floor, so wheels hit walls and other robots
//! where a real wheel would.
//!
//! The wheel joints have no rapier motor: [`crate::motor`] computes the torque and the
//! simulation applies it to the wheel and, reversed, to the chassis, so the motor pushes
//! against the body it is bolted to.

use caravan_world::{Obstacle, ObstacleKind, RobotModel, Shape, World};
use rapier3d::parry::query::intersection_test;
use rapier3d::prelude::*;

/// What a collider belongs to, stored in its `user_data` so contacts can be classified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Floor,
    /// Index into [`World::obstacles`].
    Obstacle(usize),
    Chassis(usize),
    Wheel(usize),
    Caster(usize),
}

impl Part {
    fn encode(self) -> u128 {
        let (kind, index) = match self {
            Part::Floor => (0, 0),
            Part::Obstacle(i) => (1, i),
            Part::Chassis(i) => (2, i),
            Part::Wheel(i) => (3, i),
            Part::Caster(i) => (4, i),
        };
        (kind << 64) | index as u128
    }

    pub fn decode(data: u128) -> Self {
        let index = data as u64 as usize;
        match data >> 64 {
            0 => Part::Floor,
            1 => Part::Obstacle(index),
            2 => Part::Chassis(index),
            3 => Part::Wheel(index),
            _ => Part::Caster(index),
        }
    }

    /// The robot this collider belongs to, if any.
    pub fn robot(self) -> Option<usize> {
        match self {
            Part::Chassis(i) | Part::Wheel(i) | Part::Caster(i) => Some(i),
            Part::Floor | Part::Obstacle(_) => None,
        }
    }
}

/// Collision groups: who may touch whom.
mod groups {
    use rapier3d::prelude::{Group, InteractionGroups, InteractionTestMode};

    const FLOOR: Group = Group::GROUP_1;
    const WORLD: Group = Group::GROUP_2;
    /// Chassis and caster.
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

/// Surface and mounting choices that are not in the world file or the URDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneOptions {
    /// Coulomb friction coefficient of the wheels on the floor.
    pub wheel_friction: f64,
    /// Friction of the chassis against anything (it should rarely touch).
    pub chassis_friction: f64,
    /// Added to each wheel's inertia about its axle: the motor rotor seen through the gear.
    pub wheel_extra_inertia: f64,
    /// Hold the chassis fixed in the air so the wheels spin freely (bench test).
    pub lifted: bool,
}

/// Solver iterations (substeps of rapier's soft-TGS solver) per physics step. With rapier's
/// default of 4 and a 2 ms step, the light wheel (40 g) chatters between its joint and the
/// floor under the 1.4 kg chassis: its speed jitters by 0.06 rad/s rms about the rolling
/// speed. With 8 the jitter is 0.004 rad/s, as with 4 at a 1 ms step, for a third more
/// compute than 4 and two thirds less than halving the step.
pub const SOLVER_ITERATIONS: usize = 8;

/// Natural frequency of contacts with fixed colliders (floor, walls), Hz; rapier's default
/// is 60. rapier sizes a contact's stiffness by the masses of the two bodies it joins, which
/// for a tyre is the 40 g wheel alone, not the 1.5 kg robot it carries through its joint. At
/// 60 Hz the tyres sink 1 mm into the floor: the rolling radius shrinks by 1.5 % (wheel
/// angles then overstate the distance travelled) and the chassis pitches by 0.6°. At 150 Hz
/// they sink 0.16 mm (0.24 %); stiffer contacts let a standing robot slowly drift in yaw.
pub const STATIC_CONTACT_HZ: f32 = 150.0;

/// Height at which a lifted chassis is held above its normal standing height, m.
pub const LIFT_HEIGHT: f64 = 0.1;

/// Handles of one robot's bodies and colliders.
#[derive(Debug, Clone)]
pub struct RobotBodies {
    pub chassis: RigidBodyHandle,
    /// Left then right.
    pub wheels: [RigidBodyHandle; 2],
    /// Chassis box, caster, left wheel rim, right wheel rim: what can hit obstacles and
    /// other robots.
    pub colliders: [ColliderHandle; 4],
    /// Left and right tyres, which touch only the floor.
    pub tyres: [ColliderHandle; 2],
}

/// The rapier state and the handles needed to drive and read it.
pub struct Scene {
    pub physics: PhysicsWorld,
    pub robots: Vec<RobotBodies>,
    /// Collider of each world obstacle, in [`World::obstacles`] order.
    pub obstacles: Vec<ColliderHandle>,
}

fn v(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as f32, y as f32, z as f32)
}

fn obstacle_collider(index: usize, o: &Obstacle) -> ColliderBuilder {
    let half_h = o.height / 2.0;
    let centre = v(o.center[0], o.center[1], half_h);
    let builder = match o.shape {
        Shape::Box { half_x, half_y } => {
            ColliderBuilder::cuboid(half_x as f32, half_y as f32, half_h as f32)
                .rotation(v(0.0, 0.0, o.yaw))
        }
        // rapier's cylinders stand along y; a quarter turn about x stands them along z.
        Shape::Cylinder { radius } => ColliderBuilder::cylinder(half_h as f32, radius as f32)
            .rotation(v(std::f64::consts::FRAC_PI_2, 0.0, 0.0)),
    };
    builder
        .translation(centre)
        .friction(0.5)
        .collision_groups(groups::WORLD_GROUPS)
        .user_data(Part::Obstacle(index).encode())
}

/// Builds the scene with one robot per start pose `[x, y, theta]`.
pub fn build(world: &World, robot: &RobotModel, poses: &[[f64; 3]], opt: &SceneOptions) -> Scene {
    let mut physics = PhysicsWorld::new();
    physics.gravity = Vector::new(0.0, 0.0, -9.81);
    // Recycled contact pairs keep stale distances; the contact monitor needs current ones,
    // and a small scene barely benefits from recycling.
    physics.integration_parameters.contact_recycling = false;
    physics.integration_parameters.num_solver_iterations = SOLVER_ITERATIONS;
    physics
        .integration_parameters
        .static_contact_softness
        .natural_frequency = STATIC_CONTACT_HZ;

    // The floor: a slab whose top face is z = 0, a metre wider than the world on each side.
    let [sx, sy] = world.size;
    physics.insert_collider(
        ColliderBuilder::cuboid((sx / 2.0 + 1.0) as f32, (sy / 2.0 + 1.0) as f32, 0.05)
            .translation(v(sx / 2.0, sy / 2.0, -0.05))
            // Robot parts combine with `Min`, so their own coefficients decide their grip.
            .friction(10.0)
            .collision_groups(groups::FLOOR_GROUPS)
            .user_data(Part::Floor.encode()),
        None,
    );
    let obstacles = world
        .obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| physics.insert_collider(obstacle_collider(i, o), None))
        .collect();

    let robots = poses
        .iter()
        .enumerate()
        .map(|(i, pose)| add_robot(&mut physics, i, robot, *pose, opt))
        .collect();
    Scene {
        physics,
        robots,
        obstacles,
    }
}

fn mass_props(mass: f64, inertia: [f64; 3]) -> MassProperties {
    MassProperties::new(
        Vector::ZERO,
        mass as f32,
        v(inertia[0], inertia[1], inertia[2]),
    )
}

fn add_robot(
    physics: &mut PhysicsWorld,
    index: usize,
    m: &RobotModel,
    [x, y, theta]: [f64; 3],
    opt: &SceneOptions,
) -> RobotBodies {
    let z = m.base_height() + if opt.lifted { LIFT_HEIGHT } else { 0.0 };
    let base = Pose::from_parts(v(x, y, z), Rotation::from_rotation_z(theta as f32));
    let chassis_body = if opt.lifted {
        RigidBodyBuilder::fixed()
    } else {
        RigidBodyBuilder::dynamic()
    };
    // Robots must never fall asleep: a sleeping robot would ignore its motor torques.
    let chassis = physics.insert_body(chassis_body.pose(base).can_sleep(false));

    // The URDF's chassis inertial and collision origins coincide for the convoy robot;
    // RobotModel exposes the collision one, so the chassis mass sits at the box centre.
    let [cx, cy, cz] = m.chassis_center;
    let [hx, hy, hz] = m.chassis_half_extents;
    let chassis_collider = physics.insert_collider(
        ColliderBuilder::cuboid(hx as f32, hy as f32, hz as f32)
            .translation(v(cx, cy, cz))
            .mass_properties(mass_props(m.chassis.mass, m.chassis.inertia))
            .friction(opt.chassis_friction as f32)
            .friction_combine_rule(CoefficientCombineRule::Min)
            .collision_groups(groups::BODY_GROUPS)
            .user_data(Part::Chassis(index).encode()),
        Some(chassis),
    );
    // The caster is a frictionless ball: it carries weight but never steers or brakes.
    let [kx, ky, kz] = m.caster.position;
    let caster_collider = physics.insert_collider(
        ColliderBuilder::ball(m.caster_radius as f32)
            .translation(v(kx, ky, kz))
            .mass_properties(mass_props(m.caster.mass, m.caster.inertia))
            .friction(0.0)
            .friction_combine_rule(CoefficientCombineRule::Min)
            .collision_groups(groups::BODY_GROUPS)
            .user_data(Part::Caster(index).encode()),
        Some(chassis),
    );

    let mut wheels = [chassis; 2];
    let mut rims = [chassis_collider; 2];
    let mut tyres = [chassis_collider; 2];
    for (side, wheel) in m.wheels.iter().enumerate() {
        let offset = v(wheel.position[0], wheel.position[1], wheel.position[2]);
        let pose = Pose::from_parts(base.transform_point(offset), base.rotation);
        let body = physics.insert_body(RigidBodyBuilder::dynamic().pose(pose).can_sleep(false));
        let [ixx, iyy, izz] = wheel.inertia;
        rims[side] = physics.insert_collider(
            ColliderBuilder::cylinder((m.wheel_width / 2.0) as f32, m.wheel_radius as f32)
                .mass_properties(mass_props(
                    wheel.mass,
                    [ixx, iyy + opt.wheel_extra_inertia, izz],
                ))
                .friction(0.5)
                .friction_combine_rule(CoefficientCombineRule::Min)
                .collision_groups(groups::RIM_GROUPS)
                .user_data(Part::Wheel(index).encode()),
            Some(body),
        );
        tyres[side] = physics.insert_collider(
            ColliderBuilder::ball(m.wheel_radius as f32)
                .density(0.0)
                .friction(opt.wheel_friction as f32)
                .friction_combine_rule(CoefficientCombineRule::Min)
                .collision_groups(groups::TYRE_GROUPS)
                .user_data(Part::Wheel(index).encode()),
            Some(body),
        );
        // The wheel overlaps the chassis box; contacts between the joined bodies are off.
        let joint = RevoluteJointBuilder::new(Vector::Y)
            .local_anchor1(offset)
            .local_anchor2(Vector::ZERO)
            .contacts_enabled(false);
        physics.impulse_joints.insert(chassis, body, joint, true);
        wheels[side] = body;
    }
    RobotBodies {
        chassis,
        wheels,
        colliders: [chassis_collider, caster_collider, rims[0], rims[1]],
        tyres,
    }
}

/// Why a start pose cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum Overlap {
    /// Robot `robot` overlaps world obstacle `obstacle`.
    Obstacle { robot: usize, obstacle: usize },
    /// Robots `robot` and `other` overlap.
    Robot { robot: usize, other: usize },
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

/// "wall", "box" or "cylinder", for messages.
pub fn kind_name(kind: ObstacleKind) -> &'static str {
    match kind {
        ObstacleKind::Wall => "wall",
        ObstacleKind::Box => "box",
        ObstacleKind::Cylinder => "cylinder",
    }
}
