//! One robot's sensors between their inputs and outputs, step by step: what the sensor node
//! does with each message it drains, and what it publishes at each step.
//!
//! Each step the node feeds in, in this order: on a link, the force readings and the link's
//! states; on the base, its true poses and twists, then pairs them for the IMU; the other
//! robots' latest poses and the latest wheel state. Then it takes the outputs: encoder ticks
//! on every `encoder_every`-th step (once a wheel state came), a scan on every
//! `laser_every`-th step (once the sensors' own pose is known) and the IMU's reading when a new
//! one is ready. The noise streams draw in that order, so a run is reproducible from its seed.

use crate::attach::link_state;
use crate::encoders::encoder_ticks;
use crate::force_accel::ForceAccelerometer;
use crate::imu::{BodyState, Mount, Reading, VirtualImu};
use crate::laser::Laser;
use crate::params::{Accelerometer, Params};
use crate::schedule::due;
use crate::sync::Pairer;
use caravan_schemas::{
    EncoderTicks, ForceTorques, Imu, LaserScan, LinkStates, Pose2D, Twist, WheelState,
};
use caravan_world::{RobotModel, World};
use std::time::Duration;

/// How many unpaired poses or twists wait for their partner (16 steps of physics).
const PAIRING_CAPACITY: usize = 16;

/// A robot's laser, encoders and IMU, with what they last received.
pub struct SensorSuite {
    /// The link the sensors ride on; `None`: the base.
    link: Option<String>,
    ticks_per_rev: u32,
    encoder_every: u64,
    laser_every: u64,
    laser: Option<Laser>,
    /// The robots whose chassis the laser sees, by index.
    others: Vec<usize>,
    imu: Option<VirtualImu>,
    force_accel: Option<ForceAccelerometer>,
    /// The base's poses and twists, paired by stamp for the IMU.
    pairer: Pairer<Pose2D, Twist>,
    /// The sensors' latest planar pose (the base's or the link's).
    own: Option<Pose2D>,
    /// The latest pose of each of `others`.
    other_poses: Vec<Option<Pose2D>>,
    /// The other robots' poses known at a scan (a buffer kept between scans).
    visible: Vec<Pose2D>,
    wheel: Option<WheelState>,
    /// The IMU's newest reading not yet published.
    fresh_imu: Option<Reading>,
    /// Whether the silence of the link's states was reported.
    warned_silent: bool,
}

impl SensorSuite {
    /// The sensors `p` asks for, in `world`: the laser sees the other robots' chassis if the
    /// robot's description `robot` is known. Encoders read every `encoder_every`-th step and
    /// the laser every `laser_every`-th (both ≥ 1); `seed` seeds the noise streams.
    pub fn new(
        p: &Params,
        world: &World,
        robot: Option<&RobotModel>,
        seed: u64,
        encoder_every: u64,
        laser_every: u64,
    ) -> Self {
        let laser = p.laser.then(|| match robot {
            Some(robot) => Laser::new(p.laser_config(), world, robot, seed),
            None => Laser::world_only(p.laser_config(), world, seed),
        });
        let others: Vec<usize> = if p.laser && robot.is_some() {
            (0..p.count).filter(|&j| j != p.robot).collect()
        } else {
            Vec::new()
        };
        let mount = Mount {
            offset: p.imu_offset.into(),
        };
        let imu = p.imu.then(|| {
            let imu = VirtualImu::new(mount, p.imu_noise(), seed);
            match &p.imu_errors {
                Some(e) => imu.with_errors(e),
                None => imu,
            }
        });
        let force_accel = (p.imu && p.imu_accelerometer == Accelerometer::ForceSensor)
            .then(|| ForceAccelerometer::new(&p.imu_force_joint, p.imu_test_mass_kg));
        Self {
            link: p.link.clone(),
            ticks_per_rev: p.ticks_per_rev,
            encoder_every,
            laser_every,
            laser,
            other_poses: vec![None; others.len()],
            visible: Vec::with_capacity(others.len()),
            others,
            imu,
            force_accel,
            pairer: Pairer::new(PAIRING_CAPACITY),
            own: None,
            wheel: None,
            fresh_imu: None,
            warned_silent: false,
        }
    }

    /// The robots whose true poses the laser needs, by index; feed them to
    /// [`SensorSuite::other_pose`] in this order.
    pub fn others(&self) -> &[usize] {
        &self.others
    }

    /// Whether the accelerometer reads a force sensor: feed [`SensorSuite::forces`].
    pub fn reads_forces(&self) -> bool {
        self.force_accel.is_some()
    }

    /// Whether to report, once, that no state of the link has come by `now` (the group's
    /// time): true the first time it is a second or more and the link's pose is still
    /// unknown (physics does not publish this robot's link states, or not this link).
    pub fn link_silent(&mut self, now: Duration) -> bool {
        if self.link.is_none() || self.own.is_some() || self.warned_silent {
            return false;
        }
        if now >= Duration::from_secs(1) {
            self.warned_silent = true;
            return true;
        }
        false
    }

    /// Takes a `force_torque` message stamped `stamp_ns`, for the force-sensor accelerometer.
    pub fn forces(&mut self, stamp_ns: u64, m: &ForceTorques) {
        if let Some(fa) = self.force_accel.as_mut() {
            fa.push(stamp_ns, m);
        }
    }

    /// Takes a `link_states` message stamped `stamp_ns`: the link's pose for the laser (and
    /// its height for the scan plane), and its motion for the IMU. Take this step's forces
    /// first, so that the force reading of the same instant is there.
    pub fn link_states(&mut self, stamp_ns: u64, m: &LinkStates) {
        let Some(link) = &self.link else {
            return;
        };
        let Some((body, planar, z)) = link_state(stamp_ns, m, link) else {
            return;
        };
        self.own = Some(planar);
        if let Some(laser) = self.laser.as_mut() {
            laser.set_mount_height(z);
        }
        let force = self
            .force_accel
            .as_ref()
            .and_then(|f| f.specific_force(stamp_ns));
        if let Some(r) = self
            .imu
            .as_mut()
            .and_then(|imu| imu.update_with(&body, force))
        {
            self.fresh_imu = Some(r);
        }
    }

    /// Takes the base's true pose stamped `stamp_ns`.
    pub fn pose(&mut self, stamp_ns: u64, pose: Pose2D) {
        self.own = Some(pose);
        if self.imu.is_some() {
            self.pairer.push_a(stamp_ns, pose);
        }
    }

    /// Takes the base's true twist stamped `stamp_ns`.
    pub fn twist(&mut self, stamp_ns: u64, twist: Twist) {
        self.pairer.push_b(stamp_ns, twist);
    }

    /// Feeds the IMU every pose and twist of the same instant received so far, in time order.
    pub fn pair_imu(&mut self) {
        if let Some(imu) = self.imu.as_mut() {
            while let Some((stamp, pose, twist)) = self.pairer.pop() {
                if let Some(r) = imu.update(&BodyState::planar(stamp, &pose, &twist)) {
                    self.fresh_imu = Some(r);
                }
            }
        }
    }

    /// Takes the latest pose of robot `others()[k]`.
    pub fn other_pose(&mut self, k: usize, pose: Pose2D) {
        self.other_poses[k] = Some(pose);
    }

    /// Takes the latest wheel state.
    pub fn wheel(&mut self, state: WheelState) {
        self.wheel = Some(state);
    }

    /// The encoder ticks to publish at step `index` (0 for the first), if any.
    pub fn encoder_ticks(&self, index: u64) -> Option<EncoderTicks> {
        if !due(index, self.encoder_every) {
            return None;
        }
        self.wheel
            .as_ref()
            .map(|w| encoder_ticks(w, self.ticks_per_rev))
    }

    /// Whether step `index` (0 for the first) scans: call [`SensorSuite::scan`].
    pub fn scan_due(&self, index: u64) -> bool {
        self.laser.is_some() && self.own.is_some() && due(index, self.laser_every)
    }

    /// Writes a scan from the own pose, seeing the other robots whose poses came, into `out`
    /// (a loaned message, filled in place: a scan is ~8.7 KB). Call it when
    /// [`SensorSuite::scan_due`]; with no laser or no pose yet it leaves `out` as it is.
    pub fn scan(&mut self, out: &mut LaserScan) {
        let (Some(laser), Some(own)) = (self.laser.as_mut(), &self.own) else {
            return;
        };
        self.visible.clear();
        self.visible.extend(self.other_poses.iter().flatten());
        laser.scan(own, &self.visible, out);
    }

    /// The IMU message of the newest reading since the last call, if any.
    pub fn imu_message(&mut self) -> Option<Imu> {
        let fresh = self.fresh_imu.take();
        match (&self.imu, fresh) {
            (Some(imu), Some(r)) => Some(imu.message(&r)),
            _ => None,
        }
    }
}

#[cfg(test)]
#[path = "suite_tests.rs"]
mod tests;
