//! The simulation loop of one physics step: actuator targets and firmware ticks, joint
//! torques and applied wrenches, the rapier step, joint readings, contact events. Time is
//! counted in whole nanoseconds so that firmware ticks on exact simulated times and two runs
//! with the same inputs agree bit for bit.

use super::applied_wrench::ActiveWrench;
use super::contacts::ContactMonitor;
use super::joint_state::{JointIo, Loads};
use super::rapier::prelude::*;
use super::rim::{Rims, StepHooks};
use super::scene::{self, Scene};
use crate::actuator::{Actuator, Target};
use crate::robot::{ContactPoint, Outputs, RobotBuild, RobotSetup, SimConfig};
use crate::spec::{Base, CmdVelFrame};
use crate::wrench::WrenchCommand;
use caravan_schemas::{Collision, Pose2D, Twist, Vector3, WheelSetpoint, WheelState};
use caravan_world::World;
use caravan_world::description::RobotDescription;

/// One robot's runtime state besides its rapier bodies.
struct RobotState {
    outputs: Outputs,
    /// Force–torque sensors: description joint index and its fixed impulse joint.
    sensors: Vec<(usize, ImpulseJointHandle)>,
    description: RobotDescription,
    /// Movable joints in description order (the robot's joint order on its topics).
    joints: Vec<JointIo>,
    /// The actuator of each entry of `joints`, if any.
    actuators: Vec<Option<Actuator>>,
    /// Entries of `joints` driven by `wheel_setpoint` (left, right).
    drive: Option<[usize; 2]>,
    base: Base,
    cmd_vel_frame: CmdVelFrame,
    cmd_vel: Twist,
    wrenches: Vec<ActiveWrench>,
}

/// Robots in a world, stepped at a fixed physics rate.
pub struct Simulation {
    scene: Scene,
    cfg: SimConfig,
    robots: Vec<RobotState>,
    loads: Loads,
    /// Wheels turned as rims, and their speeds.
    rims: Rims,
    contacts: ContactMonitor,
    events: Vec<Collision>,
    time_ns: u64,
}

impl Simulation {
    /// A simulation of the given robots. Inputs are not checked here; see [`crate::setup`].
    pub fn new(world: &World, builds: Vec<RobotBuild>, cfg: SimConfig) -> Result<Self, String> {
        let setups: Vec<&RobotSetup> = builds.iter().map(|b| &b.setup).collect();
        let mut scene = scene::build(world, &setups, &cfg)?;
        scene.physics.integration_parameters.dt = cfg.dt_ns as Real * 1e-9;
        let mut robots = Vec::with_capacity(builds.len());
        let mut rims = Rims::default();
        for (i, build) in builds.into_iter().enumerate() {
            let d = build.setup.description;
            let bodies = &scene.robots[i];
            let mut joints = Vec::new();
            let mut actuators = Vec::new();
            let mut index_of = vec![usize::MAX; d.joints.len()];
            let mut build_actuators = build.actuators;
            for j in d.movable_joints() {
                let body = bodies
                    .plan
                    .body_of_joint(j)
                    .expect("a movable joint has a body");
                let plan = bodies.plan.bodies[body].joint.as_ref().expect("joined");
                let mut io = JointIo::new(
                    j,
                    &d.joints[j],
                    bodies.bodies[plan.parent_body],
                    bodies.bodies[body],
                    plan.frame,
                );
                match bodies.joints[j] {
                    Some(scene::JointHandle::Multibody(h)) => io.multibody = Some(h),
                    Some(scene::JointHandle::Impulse(h)) => io.impulse = Some(h),
                    None => {}
                }
                if build.setup.is_rim(j) {
                    // Every link welded into the wheel's body turns with it.
                    let links = bodies.plan.bodies[body].links.iter().map(|(l, _)| *l);
                    let axis = super::shapes::vector(&d.joints[j].axis);
                    io.rim = Some(rims.add(i, links, axis));
                }
                io.read(&scene.physics.bodies, &scene.physics.multibody_joints);
                index_of[j] = joints.len();
                joints.push(io);
                actuators.push(build_actuators[j].take());
            }
            let spec = build.setup.spec;
            let sensors = build
                .setup
                .sensed
                .iter()
                .filter_map(|&j| match bodies.joints[j] {
                    Some(scene::JointHandle::Impulse(h)) => Some((j, h)),
                    _ => None,
                })
                .collect();
            let outputs = Outputs::of(spec, d, build.drive.is_some());
            robots.push(RobotState {
                outputs,
                sensors,
                description: d.clone(),
                joints,
                actuators,
                drive: build.drive.map(|[l, r]| [index_of[l], index_of[r]]),
                base: build.setup.spec.base,
                cmd_vel_frame: build.setup.spec.cmd_vel_frame,
                cmd_vel: Twist::default(),
                wrenches: Vec::new(),
            });
        }
        Ok(Self {
            scene,
            cfg,
            robots,
            loads: Loads::default(),
            rims,
            contacts: ContactMonitor::default(),
            events: Vec::new(),
            time_ns: 0,
        })
    }

    pub fn robot_count(&self) -> usize {
        self.robots.len()
    }

    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Simulated time, ns.
    pub fn time_ns(&self) -> u64 {
        self.time_ns
    }

    /// What robot `i` publishes.
    pub fn outputs(&self, i: usize) -> Outputs {
        self.robots[i].outputs
    }

    pub fn description(&self, i: usize) -> &RobotDescription {
        &self.robots[i].description
    }

    /// Sets robot `i`'s wheel-speed set-points (rad/s); held until the next call. A
    /// non-finite value counts as zero, so a faulty publisher cannot poison the solver.
    pub fn set_setpoint(&mut self, i: usize, sp: &WheelSetpoint) {
        let clean = |x: f64| if x.is_finite() { x } else { 0.0 };
        let r = &mut self.robots[i];
        let Some(drive) = r.drive else { return };
        for (k, speed) in drive.into_iter().zip([sp.left_rad_s, sp.right_rad_s]) {
            if let Some(a) = &mut r.actuators[k] {
                a.target.velocity = clean(speed);
            }
        }
    }

    /// Updates robot `i`'s joint targets, in joint order; NaN fields leave a target as it was.
    pub fn set_targets(&mut self, i: usize, targets: &[Target]) {
        for (a, t) in self.robots[i].actuators.iter_mut().zip(targets) {
            if let Some(a) = a {
                a.target.merge(*t);
            }
        }
    }

    /// Sets a kinematic robot's velocity command; ignored for other bases.
    pub fn set_cmd_vel(&mut self, i: usize, cmd: &Twist) {
        self.robots[i].cmd_vel = *cmd;
    }

    /// Moves a kinematic robot at once so that its base link stands at `pose` (map frame),
    /// every body of the robot by the same rigid motion, and stops it (velocities and the
    /// velocity command zero): a new episode's start without restarting the group. Ignored
    /// for other bases, which the solver owns.
    pub fn set_pose(&mut self, i: usize, pose: &caravan_schemas::Pose3D) {
        if self.robots[i].base != Base::Kinematic {
            return;
        }
        let (p, q) = (&pose.position, &pose.orientation);
        let target = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(p.x, p.y, p.z),
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q.w, q.x, q.y, q.z,
            )),
        );
        let rb = &self.scene.robots[i];
        let bodies = &mut self.scene.physics.bodies;
        let motion = super::shapes::pose(&target) * bodies[rb.base()].position().inverse();
        for &handle in &rb.bodies {
            let body = &mut bodies[handle];
            body.set_position(motion * *body.position(), true);
            body.set_linvel(Vector::ZERO, true);
            body.set_angvel(Vector::ZERO, true);
        }
        self.robots[i].cmd_vel = Twist::default();
    }

    /// Starts a wrench on robot `i`; replaces the one acting on the same link. Errors name
    /// an unknown link.
    pub fn apply_wrench(&mut self, i: usize, w: &WrenchCommand) -> Result<(), String> {
        let r = &mut self.robots[i];
        let bodies = &self.scene.robots[i];
        let active = ActiveWrench::start(
            w,
            &r.description,
            &bodies.plan,
            &bodies.bodies,
            &self.scene.physics.bodies,
            self.time_ns,
        )?;
        r.wrenches.retain(|a| a.link != active.link);
        r.wrenches.push(active);
        Ok(())
    }

    /// Advances by one physics step.
    pub fn step(&mut self) {
        let dt = self.cfg.dt_ns as f64 * 1e-9;
        let physics = &mut self.scene.physics;
        let bodies = &mut physics.bodies;
        for (r, rb) in self.robots.iter_mut().zip(&self.scene.robots) {
            for a in r.actuators.iter_mut().flatten() {
                a.firmware_tick(self.time_ns);
            }
            for h in &rb.bodies {
                let b = &mut bodies[*h];
                b.reset_torques(false);
                b.reset_forces(false);
            }
            for (io, a) in r.joints.iter_mut().zip(&mut r.actuators) {
                if let Some(a) = a {
                    if let Some(motor) = a.motor() {
                        let joints = &mut physics.impulse_joints;
                        io.set_motor(joints, &mut physics.multibody_joints, motor);
                        continue;
                    }
                    if let Some(speed) = a.kinematic_velocity(io.reading, dt) {
                        if let Some(rim) = io.rim {
                            let joints = &mut physics.impulse_joints;
                            io.turn_rim(joints, &mut physics.multibody_joints, speed, dt);
                            self.rims.set_speed(rim, speed);
                        } else {
                            io.set_kinematic_velocity(&mut physics.multibody_joints, speed);
                        }
                        continue;
                    }
                    let tau = a.torque(io.reading, dt);
                    io.push(bodies, tau, &mut self.loads);
                }
            }
            r.wrenches
                .retain(|w| w.until_ns.is_none_or(|t| self.time_ns < t));
            for w in &r.wrenches {
                w.push(bodies, &mut self.loads);
            }
            if r.base == Base::Kinematic {
                drive_kinematic(&mut bodies[rb.base()], &r.cmd_vel, r.cmd_vel_frame);
            }
        }
        self.loads.apply(bodies);
        let hooks = StepHooks {
            rims: &self.rims,
            dt: dt as Real,
        };
        self.scene.physics.step_with_events(&hooks, &());
        self.time_ns += self.cfg.dt_ns;
        let physics = &mut self.scene.physics;
        let per_second = physics.integration_parameters.num_solver_iterations as f64 / dt;
        for r in &mut self.robots {
            for (io, a) in r.joints.iter_mut().zip(&mut r.actuators) {
                io.read(&physics.bodies, &physics.multibody_joints);
                if let Some(a) = a {
                    a.after_step(io.reading.velocity, dt);
                    if a.motor().is_some() {
                        let joints = &mut physics.impulse_joints;
                        a.effort =
                            io.motor_effort(joints, &mut physics.multibody_joints, per_second);
                    }
                }
            }
        }
        self.contacts.update(&self.scene, &mut self.events);
    }

    /// Steps until the next step would pass `t_ns`, at most `max_steps` times; returns the
    /// number of steps taken.
    pub fn advance_to(&mut self, t_ns: u64, max_steps: u64) -> u64 {
        let mut n = 0;
        while n < max_steps && self.time_ns + self.cfg.dt_ns <= t_ns {
            self.step();
            n += 1;
        }
        n
    }

    fn base(&self, i: usize) -> &RigidBody {
        &self.scene.physics.bodies[self.scene.robots[i].base()]
    }

    /// Ground-truth pose of robot `i`'s base link in the map frame.
    pub fn pose(&self, i: usize) -> Pose2D {
        let body = self.base(i);
        let p = body.translation();
        Pose2D {
            x: p.x as f64,
            y: p.y as f64,
            theta: yaw(body.rotation()),
        }
    }

    /// Height of robot `i`'s base link above the floor, m (for tests and diagnostics).
    pub fn base_height(&self, i: usize) -> f64 {
        self.base(i).translation().z as f64
    }

    /// Ground-truth velocity of robot `i`: the base link origin's linear velocity and the
    /// base's angular velocity, both in the map frame.
    pub fn twist(&self, i: usize) -> Twist {
        let body = self.base(i);
        match self.free_root_velocity(i) {
            // A free multibody root: its velocity after the step, as `link_states` gives it.
            Some(v) => twist_from(twist_at(body, v, &super::shapes::isometry(body.position()))),
            None => twist_of(body.velocity_at_point(body.translation()), body.angvel()),
        }
    }

    /// Robot `i`'s joints in joint order: (name, position, velocity, effort).
    pub fn joints(&self, i: usize) -> impl Iterator<Item = (&str, f64, f64, f64)> + '_ {
        let r = &self.robots[i];
        r.joints.iter().zip(&r.actuators).map(|(io, a)| {
            (
                r.description.joints[io.joint].name.as_str(),
                io.reading.position,
                io.reading.velocity,
                a.as_ref().map_or(0.0, |a| a.effort),
            )
        })
    }

    /// Pose (world frame) and twist of every link of robot `i`, in description order. The
    /// twists are carried out from the root's along the tree by the joints' speeds after the
    /// step ([`crate::link_twists`]), so each is the velocity of the link's origin at the
    /// instant of its pose.
    pub fn link_states(&self, i: usize) -> Vec<(caravan_schemas::Pose3D, Twist)> {
        let rb = &self.scene.robots[i];
        let r = &self.robots[i];
        let bodies = &self.scene.physics.bodies;
        let poses: Vec<Pose> = rb
            .plan
            .link_body
            .iter()
            .map(|(b, in_body)| *bodies[rb.bodies[*b]].position() * super::shapes::pose(in_body))
            .collect();
        let exact: Vec<nalgebra::Isometry3<f64>> =
            poses.iter().map(super::shapes::isometry).collect();
        let d = &r.description;
        let mut speeds = vec![0.0; d.joints.len()];
        for io in &r.joints {
            speeds[io.joint] = io.reading.velocity;
        }
        let root = self.root_twist(i, &exact[d.root]);
        let twists = crate::link_twists::link_twists(d, &exact, root, |j| speeds[j]);
        poses
            .iter()
            .zip(twists)
            .map(|(pose, twist)| (pose3d(pose), twist_from(twist)))
            .collect()
    }

    /// The twist of robot `i`'s root link, whose pose is `root`. A free multibody root's
    /// velocity is its generalized one, the state after the step (rapier leaves the root
    /// body's as it was at the start of the step's last substep); any other root's is its
    /// body's.
    fn root_twist(
        &self,
        i: usize,
        root: &nalgebra::Isometry3<f64>,
    ) -> crate::link_twists::LinkTwist {
        let body = self.base(i);
        let velocity = self
            .free_root_velocity(i)
            .unwrap_or((body.linvel(), body.angvel()));
        twist_at(body, velocity, root)
    }

    /// The velocity of robot `i`'s centre of mass and its angular velocity after the step, if
    /// its root is a free multibody root: its generalized velocity.
    fn free_root_velocity(&self, i: usize) -> Option<(Vector, Vector)> {
        let multibodies = &self.scene.physics.multibody_joints;
        let id = multibodies.rigid_body_link(self.scene.robots[i].base())?;
        let mb = multibodies.get_multibody(id.multibody)?;
        let link = mb.link(id.id).filter(|l| l.is_root())?;
        let speeds = mb.joint_velocity(link);
        let v =
            (speeds.len() == 6).then(|| link.joint.jacobian_mul_coordinates(speeds.as_slice()))?;
        Some((v.linvel, v.angvel))
    }

    /// Pose (map frame) and twist (map frame) of robot `i`'s root link.
    pub fn ground_truth(&self, i: usize) -> (caravan_schemas::Pose3D, Twist) {
        let in_body = &self.scene.robots[i].plan.link_body[self.robots[i].description.root].1;
        let pose = *self.base(i).position() * super::shapes::pose(in_body);
        let twist = self.root_twist(i, &super::shapes::isometry(&pose));
        (pose3d(&pose), twist_from(twist))
    }

    /// Robot `i`'s wheels: angles, speeds relative to the chassis, voltages. Zero for a robot
    /// without a differential drive on DC motors.
    pub fn wheel_state(&self, i: usize) -> WheelState {
        let r = &self.robots[i];
        let motor = |k: usize| r.actuators[k].as_ref().and_then(|a| a.dc_motor());
        let Some((Some(l), Some(rt))) = r.drive.map(|[a, b]| (motor(a), motor(b))) else {
            return WheelState::default();
        };
        WheelState {
            left_angle_rad: l.angle,
            right_angle_rad: rt.angle,
            left_rad_s: l.speed,
            right_rad_s: rt.speed,
            left_voltage: l.output.voltage,
            right_voltage: rt.output.voltage,
        }
    }

    /// Wheel speeds (left, right) the firmware measured at its last tick, rad/s.
    pub fn measured_speeds(&self, i: usize) -> [f64; 2] {
        let r = &self.robots[i];
        let m = |k: usize| {
            r.actuators[k]
                .as_ref()
                .and_then(|a| a.dc_motor())
                .map_or(0.0, |m| m.measured)
        };
        r.drive.map_or([0.0; 2], |[a, b]| [m(a), m(b)])
    }

    /// Contact events since the last call, in the order they happened.
    pub fn take_collisions(&mut self) -> Vec<Collision> {
        std::mem::take(&mut self.events)
    }

    /// Pairs (robot, other robot or −1) touching now.
    /// Robot `i`'s force–torque sensors after the last step: the joint's name and the force
    /// (N) and torque (N·m) the parent exerts on the child through it, in the child link's
    /// frame, about the child link's origin.
    pub fn force_torque(&self, i: usize) -> Vec<(&str, [f64; 3], [f64; 3])> {
        let r = &self.robots[i];
        let physics = &self.scene.physics;
        // rapier writes back the impulses of the last of its solver substeps, as applied to
        // the parent; and the angular ones about the child's centre of mass.
        let per_second = -(physics.integration_parameters.num_solver_iterations as f64)
            / (self.cfg.dt_ns as f64 * 1e-9);
        r.sensors
            .iter()
            .filter_map(|&(j, h)| {
                let joint = physics.impulse_joints.get(h)?;
                let child = &physics.bodies[joint.body2()];
                let imp = joint.impulses;
                let force = Vector::new(imp[0], imp[1], imp[2]) * per_second as Real;
                let about_com = Vector::new(imp[3], imp[4], imp[5]) * per_second as Real;
                let com = child
                    .position()
                    .inverse_transform_point(child.center_of_mass());
                let torque = about_com + com.cross(force);
                let a = |v: Vector| [v.x as f64, v.y as f64, v.z as f64];
                Some((r.description.joints[j].name.as_str(), a(force), a(torque)))
            })
            .collect()
    }

    /// The first robot that, at its start pose, overlaps an obstacle or another robot.
    pub fn first_overlap(&self) -> Option<crate::robot::Overlap> {
        scene::first_overlap(&self.scene)
    }

    pub fn touching(&self) -> Vec<(u32, i32)> {
        self.contacts.touching().collect()
    }

    /// Contact points of robot `i`'s links after the last step.
    pub fn contact_points(&self, i: usize) -> Vec<ContactPoint> {
        super::contacts::points(&self.scene, i, self.cfg.dt_ns as f64 * 1e-9)
    }
}

fn v3(v: Vector) -> Vector3 {
    Vector3 {
        x: v.x as f64,
        y: v.y as f64,
        z: v.z as f64,
    }
}

/// A rapier pose as a message's.
fn pose3d(pose: &Pose) -> caravan_schemas::Pose3D {
    let q = pose.rotation;
    caravan_schemas::Pose3D {
        position: v3(pose.translation),
        orientation: caravan_schemas::Quaternion {
            x: q.x as f64,
            y: q.y as f64,
            z: q.z as f64,
            w: q.w as f64,
        },
    }
}

/// A link's twist (f64) as a message's.
fn twist_from(t: crate::link_twists::LinkTwist) -> Twist {
    let v = |v: nalgebra::Vector3<f64>| Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    Twist {
        linear: v(t.linear),
        angular: v(t.angular),
    }
}

/// The twist at `at` of `body` moving with `(linvel, angvel)`: its centre of mass's velocity
/// and its angular velocity. The centre is placed from the body's pose, not rapier's cached
/// world centre, which its last substep may not have updated.
fn twist_at(
    body: &RigidBody,
    (linvel, angvel): (Vector, Vector),
    at: &nalgebra::Isometry3<f64>,
) -> crate::link_twists::LinkTwist {
    let f64v = super::shapes::vector_f64;
    let com = super::shapes::isometry(body.position())
        * nalgebra::Point3::from(f64v(body.local_center_of_mass()));
    let angular = f64v(angvel);
    crate::link_twists::LinkTwist {
        linear: f64v(linvel) + angular.cross(&(at.translation.vector - com.coords)),
        angular,
    }
}

fn twist_of(linear: Vector, angular: Vector) -> Twist {
    Twist {
        linear: v3(linear),
        angular: v3(angular),
    }
}

/// Sets a kinematic base's velocities from a command in the body or world frame.
fn drive_kinematic(body: &mut RigidBody, cmd: &Twist, frame: CmdVelFrame) {
    let clean = |x: f64| if x.is_finite() { x as Real } else { 0.0 };
    let lin = Vector::new(
        clean(cmd.linear.x),
        clean(cmd.linear.y),
        clean(cmd.linear.z),
    );
    let ang = Vector::new(
        clean(cmd.angular.x),
        clean(cmd.angular.y),
        clean(cmd.angular.z),
    );
    let (lin, ang) = match frame {
        CmdVelFrame::World => (lin, ang),
        CmdVelFrame::Body => (*body.rotation() * lin, *body.rotation() * ang),
    };
    body.set_linvel(lin, true);
    body.set_angvel(ang, true);
}

/// Yaw (rotation about z) of a unit quaternion, rad.
fn yaw(q: &Rotation) -> f64 {
    let (x, y, z, w) = (q.x as f64, q.y as f64, q.z as f64, q.w as f64);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}
