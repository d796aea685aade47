//! The simulation loop of one physics step: firmware tick (when due), motor torques, rapier
//! step, wheel bookkeeping, contact events. Time is counted in whole nanoseconds so that the
//! firmware ticks on exact simulated times and two runs with the same inputs agree bit for bit.

use crate::contacts::ContactMonitor;
use crate::firmware::{FirmwareParams, SpeedPid};
use crate::motor::{self, MotorOutput, MotorParams};
use crate::scene::{self, Scene, SceneOptions};
use caravan_schemas::{Collision, Pose2D, Twist, Vector3, WheelSetpoint, WheelState};
use caravan_world::{RobotModel, World};
use rapier3d::prelude::*;

/// Everything that shapes the dynamics besides the world and the robot description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Physics step, ns.
    pub dt_ns: u64,
    pub motor: MotorParams,
    pub pid: FirmwareParams,
    pub wheel_friction: f64,
    /// Chassis held in the air, wheels spinning freely.
    pub lifted: bool,
}

impl SimConfig {
    /// Fitted defaults with physics step `dt_ns`.
    pub fn with_dt_ns(dt_ns: u64) -> Self {
        Self {
            dt_ns,
            motor: MotorParams::default(),
            pid: FirmwareParams::default(),
            wheel_friction: 1.0,
            lifted: false,
        }
    }
}

/// Per-robot drive state.
#[derive(Debug, Clone)]
struct Drive {
    setpoint: [f64; 2],
    pid: [SpeedPid; 2],
    /// Accumulated wheel angle relative to the chassis, rad.
    angle: [f64; 2],
    /// Angles at the last firmware tick, for the speed estimate.
    angle_at_tick: [f64; 2],
    /// Speed the firmware measured at its last tick, rad/s.
    measured: [f64; 2],
    /// Wheel speed relative to the chassis after the last step, rad/s.
    speed: [f64; 2],
    motor: [MotorOutput; 2],
}

/// N robots in a world, stepped at a fixed physics rate.
pub struct Simulation {
    scene: Scene,
    cfg: SimConfig,
    drives: Vec<Drive>,
    contacts: ContactMonitor,
    events: Vec<Collision>,
    time_ns: u64,
    last_tick_ns: Option<u64>,
    next_tick_ns: u64,
}

impl Simulation {
    /// A simulation of one robot per start pose. Poses are not checked here; see
    /// [`crate::setup`] for the checked entry point.
    pub fn new(world: &World, robot: &RobotModel, poses: &[[f64; 3]], cfg: SimConfig) -> Self {
        let options = SceneOptions {
            wheel_friction: cfg.wheel_friction,
            chassis_friction: 0.3,
            wheel_extra_inertia: cfg.motor.reflected_inertia(),
            lifted: cfg.lifted,
        };
        let mut scene = scene::build(world, robot, poses, &options);
        scene.physics.integration_parameters.dt = cfg.dt_ns as f32 * 1e-9;
        let pid = SpeedPid::new(&cfg.pid, cfg.motor.supply_v);
        let drive = Drive {
            setpoint: [0.0; 2],
            pid: [pid.clone(), pid],
            angle: [0.0; 2],
            angle_at_tick: [0.0; 2],
            measured: [0.0; 2],
            speed: [0.0; 2],
            motor: [MotorOutput::default(); 2],
        };
        Self {
            drives: vec![drive; poses.len()],
            scene,
            cfg,
            contacts: ContactMonitor::default(),
            events: Vec::new(),
            time_ns: 0,
            last_tick_ns: None,
            next_tick_ns: 0,
        }
    }

    pub fn robot_count(&self) -> usize {
        self.drives.len()
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

    /// Sets robot `i`'s wheel-speed set-points (rad/s); held until the next call. A
    /// non-finite value counts as zero, so a faulty publisher cannot poison the solver.
    pub fn set_setpoint(&mut self, i: usize, sp: &WheelSetpoint) {
        let clean = |x: f64| if x.is_finite() { x } else { 0.0 };
        self.drives[i].setpoint = [clean(sp.left_rad_s), clean(sp.right_rad_s)];
    }

    /// Advances by one physics step.
    pub fn step(&mut self) {
        let dt = self.cfg.dt_ns as f64 * 1e-9;
        if self.time_ns >= self.next_tick_ns {
            self.firmware_tick();
        }
        for (i, drive) in self.drives.iter_mut().enumerate() {
            let bodies = &self.scene.robots[i];
            let axle = axle(&self.scene.physics.bodies[bodies.chassis]);
            for side in 0..2 {
                let out =
                    motor::torque(&self.cfg.motor, drive.pid[side].output(), drive.speed[side]);
                drive.motor[side] = out;
                let t = axle * out.torque as f32;
                let wheel = &mut self.scene.physics.bodies[bodies.wheels[side]];
                wheel.reset_torques(false);
                wheel.add_torque(t, true);
            }
            let chassis = &mut self.scene.physics.bodies[bodies.chassis];
            chassis.reset_torques(false);
            let reaction = drive.motor[0].torque + drive.motor[1].torque;
            chassis.add_torque(axle * -(reaction as f32), true);
        }
        self.scene.physics.step();
        self.time_ns += self.cfg.dt_ns;
        for (i, drive) in self.drives.iter_mut().enumerate() {
            let speeds = relative_speeds(&self.scene, i);
            drive.speed = speeds;
            for (angle, speed) in drive.angle.iter_mut().zip(speeds) {
                *angle += speed * dt;
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

    /// The firmware of every robot: measure speeds over the last period, update the PIDs.
    fn firmware_tick(&mut self) {
        let elapsed = self.last_tick_ns.map(|t| (self.time_ns - t) as f64 * 1e-9);
        for d in &mut self.drives {
            for side in 0..2 {
                d.measured[side] = match elapsed {
                    Some(e) if e > 0.0 => (d.angle[side] - d.angle_at_tick[side]) / e,
                    _ => 0.0,
                };
                d.angle_at_tick[side] = d.angle[side];
                d.pid[side].update(d.setpoint[side], d.measured[side]);
            }
        }
        self.last_tick_ns = Some(self.time_ns);
        self.next_tick_ns += self.cfg.pid.period_ns();
    }

    /// Ground-truth pose of robot `i`'s base_link in the map frame.
    pub fn pose(&self, i: usize) -> Pose2D {
        let body = &self.scene.physics.bodies[self.scene.robots[i].chassis];
        let p = body.translation();
        Pose2D {
            x: p.x as f64,
            y: p.y as f64,
            theta: yaw(body.rotation()),
        }
    }

    /// Height of robot `i`'s base_link above the floor, m (for tests and diagnostics).
    pub fn base_height(&self, i: usize) -> f64 {
        let body = &self.scene.physics.bodies[self.scene.robots[i].chassis];
        body.translation().z as f64
    }

    /// Ground-truth velocity of robot `i`: base_link's linear velocity and the chassis'
    /// angular velocity, both in the map frame.
    pub fn twist(&self, i: usize) -> Twist {
        let body = &self.scene.physics.bodies[self.scene.robots[i].chassis];
        let lin = body.velocity_at_point(body.translation());
        let ang = body.angvel();
        let v3 = |v: Vector| Vector3 {
            x: v.x as f64,
            y: v.y as f64,
            z: v.z as f64,
        };
        Twist {
            linear: v3(lin),
            angular: v3(ang),
        }
    }

    /// Robot `i`'s wheels: accumulated angles, speeds relative to the chassis, voltages.
    pub fn wheel_state(&self, i: usize) -> WheelState {
        let d = &self.drives[i];
        WheelState {
            left_angle_rad: d.angle[0],
            right_angle_rad: d.angle[1],
            left_rad_s: d.speed[0],
            right_rad_s: d.speed[1],
            left_voltage: d.motor[0].voltage,
            right_voltage: d.motor[1].voltage,
        }
    }

    /// Wheel speeds (left, right) the firmware measured at its last tick, rad/s.
    pub fn measured_speeds(&self, i: usize) -> [f64; 2] {
        self.drives[i].measured
    }

    /// Contact events since the last call, in the order they happened.
    pub fn take_collisions(&mut self) -> Vec<Collision> {
        std::mem::take(&mut self.events)
    }

    /// Pairs (robot, other robot or −1) touching now.
    pub fn touching(&self) -> Vec<(u32, i32)> {
        self.contacts.touching().collect()
    }
}

/// The wheel axle direction (the chassis' y axis) in the world frame.
fn axle(chassis: &RigidBody) -> Vector {
    *chassis.rotation() * Vector::Y
}

/// Wheel speeds relative to the chassis about the axle, rad/s; positive rolls forward.
fn relative_speeds(scene: &Scene, i: usize) -> [f64; 2] {
    let bodies = &scene.physics.bodies;
    let r = &scene.robots[i];
    let chassis = &bodies[r.chassis];
    let axle = axle(chassis);
    r.wheels
        .map(|w| (bodies[w].angvel() - chassis.angvel()).dot(axle) as f64)
}

/// Yaw (rotation about z) of a unit quaternion, rad.
fn yaw(q: &Rotation) -> f64 {
    let (x, y, z, w) = (q.x as f64, q.y as f64, q.z as f64, q.w as f64);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}
