//! `caravan-sensor`: the sensors of robot `robot` (params in `params.rs`).
//!
//! One node steps at 100 Hz and decimates: the IMU reads every step, the encoders every 2nd
//! (50 Hz), the laser every 10th (10 Hz), each by whole steps so periods stay exact in lockstep.
//!
//! In:  `robot/i/pose_true`, `robot/i/twist_true`, `robot/i/wheel_state` from physics, and
//!      `robot/j/pose_true` of the other robots (for the laser to see their chassis); with
//!      `link`, `robot/i/link_states` instead of pose and twist (see `attach.rs`).
//! Out: `robot/i/encoder_ticks`, `robot/i/scan` (if `laser`), `robot/i/imu` (if `imu`).

use caravan::{Node, NodeIdentity, Subscriber, Trigger, parse_rate};
use caravan_schemas::{Pose2D, Twist, WheelState, topics};
use caravan_sensor::attach::{check_force_joint, check_link, link_state};
use caravan_sensor::encoders::encoder_ticks;
use caravan_sensor::force_accel::ForceAccelerometer;
use caravan_sensor::imu::{BodyState, Mount, VirtualImu};
use caravan_sensor::laser::Laser;
use caravan_sensor::params::Accelerometer;
use caravan_sensor::params::Params;
use caravan_sensor::schedule::{due, every_nth};
use caravan_sensor::sync::Pairer;
use std::process::ExitCode;
use std::time::Duration;

const NODE_RATE_HZ: f64 = 100.0;

fn main() -> ExitCode {
    caravan::node_main("caravan-sensor", setup, run)
}

/// Everything the sensors need, loaded and checked before the node joins the group.
struct Ready {
    p: Params,
    world: caravan_world::World,
    /// The wheeled-robot view of the description: required on the base, optional on a link
    /// (the laser then sees no other robots).
    robot: Option<caravan_world::RobotModel>,
    seed: u64,
    period: Duration,
    encoder_every: u64,
    laser_every: u64,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    p.validate().map_err(|e| e.to_string())?;
    let world = caravan_world::load_world(&identity.resolve_path(&p.world))
        .map_err(|e| format!("key 'world': world file {e}"))?;
    let urdf = identity.resolve_path(&p.urdf);
    let robot = match &p.link {
        None => Some(
            caravan_world::load_robot(&urdf)
                .map_err(|e| format!("key 'urdf': robot description {e}"))?,
        ),
        Some(link) => {
            let d = caravan_world::description::load_description(&urdf)
                .map_err(|e| format!("key 'urdf': robot description {e}"))?;
            check_link(&d, link)?;
            if p.imu_accelerometer == Accelerometer::ForceSensor {
                check_force_joint(&d, &p.imu_force_joint)?;
            }
            caravan_world::RobotModel::from_description(&d).ok()
        }
    };
    // The launch file's `rate` overrides the default, as `Node::trigger` does.
    let period = match (&identity.rate_override, &identity.on_override) {
        (Some(rate), _) => parse_rate(rate).map_err(|e| format!("its `rate`: {e}"))?,
        (None, Some(_)) => {
            return Err("caravan-sensor runs at a fixed rate; give it a `rate`, not `on`".into());
        }
        (None, None) => Duration::from_secs_f64(1.0 / NODE_RATE_HZ),
    };
    let encoder_every =
        every_nth(period, p.encoder_rate_hz, "encoder_rate_hz").map_err(|e| e.to_string())?;
    let laser_every = if p.laser {
        every_nth(period, p.laser_rate_hz, "laser_rate_hz").map_err(|e| e.to_string())?
    } else {
        1
    };
    Ok(Ready {
        seed: identity.node_seed(),
        p,
        world,
        robot,
        period,
        encoder_every,
        laser_every,
    })
}

fn run(mut node: Node, ready: Ready) -> Result<(), caravan::Error> {
    let Ready {
        p,
        world,
        robot,
        seed,
        period,
        encoder_every,
        laser_every,
    } = ready;
    let i = p.robot;
    let sub_pose = |j: usize| node.subscriber(&topics::pose_true(j));
    // On a link, the sensors' pose comes from link_states instead.
    let own_pose = match p.link {
        None => Some(sub_pose(i)?),
        Some(_) => None,
    };
    let wheels = node.subscriber(&topics::wheel_state(i))?;
    let ticks_out = node.publisher(&topics::encoder_ticks(i))?;

    // The laser sees the other robots at their latest true poses, if it knows their shape.
    let mut laser = p.laser.then(|| match &robot {
        Some(robot) => Laser::new(p.laser_config(), &world, robot, seed),
        None => Laser::world_only(p.laser_config(), &world, seed),
    });
    let others: Vec<Subscriber<Pose2D>> = if p.laser && robot.is_some() {
        (0..p.count)
            .filter(|&j| j != i)
            .map(sub_pose)
            .collect::<Result<_, _>>()?
    } else {
        Vec::new()
    };
    let scan_out = if p.laser {
        Some(node.publisher(&topics::scan(i))?)
    } else {
        None
    };

    // The IMU needs pose and twist of the same instant; they come on two topics.
    let mount = Mount {
        offset: p.imu_offset.into(),
    };
    let mut imu = p.imu.then(|| {
        let imu = VirtualImu::new(mount, p.imu_noise(), seed);
        match &p.imu_errors {
            Some(e) => imu.with_errors(e),
            None => imu,
        }
    });
    // The force-sensor accelerometer pairs force readings with link states by stamp.
    let mut force_accel = (p.imu && p.imu_accelerometer == Accelerometer::ForceSensor)
        .then(|| ForceAccelerometer::new(&p.imu_force_joint, p.imu_test_mass_kg));
    let forces_in = match force_accel {
        Some(_) => Some(node.subscriber(&topics::force_torque(i))?),
        None => None,
    };
    let links_in = match &p.link {
        Some(_) => Some(node.subscriber(&topics::link_states(i))?),
        None => None,
    };
    let (twist_in, imu_out) = if p.imu {
        let twist_in = match links_in {
            None => Some(node.subscriber(&topics::twist_true(i))?),
            Some(_) => None,
        };
        let imu_out = node.publisher(&topics::imu(i))?;
        (twist_in, Some(imu_out))
    } else {
        (None, None)
    };

    eprintln!(
        "caravan-sensor: robot {i} of {}: encoders {} ticks/rev at {} Hz; laser {}; imu {}",
        p.count,
        p.ticks_per_rev,
        p.encoder_rate_hz,
        if p.laser {
            format!(
                "{} beams at {} Hz, noise {}",
                p.laser_beams, p.laser_rate_hz, p.noise
            )
        } else {
            "off".into()
        },
        if p.imu {
            format!("on, noise {}", p.imu_noise)
        } else {
            "off".into()
        },
    );

    let mut pairer = Pairer::<Pose2D, Twist>::new(16);
    let mut own: Option<Pose2D> = None;
    let mut other_poses: Vec<Option<Pose2D>> = vec![None; others.len()];
    let mut visible: Vec<Pose2D> = Vec::with_capacity(others.len());
    let mut wheel: Option<WheelState> = None;
    let mut fresh_imu = None;
    let mut warned_silent = false;

    node.run(Trigger::Every(period), |step| {
        // Drain every input each step, so none overflows its queue between uses.
        if let (Some(links_in), Some(link)) = (&links_in, &p.link) {
            // Nothing after a second: physics does not publish this robot's link states, or
            // not this link. Say so once rather than stay silent.
            if own.is_none() && !warned_silent && step.now() >= Duration::from_secs(1) {
                warned_silent = true;
                eprintln!(
                    "caravan-sensor: no state of link '{link}' on robot/{i}/link_states after \
                     1 s; give physics `link_states = true` for robot {i}"
                );
            }
            if let (Some(fa), Some(forces_in)) = (force_accel.as_mut(), &forces_in) {
                while let Some(m) = forces_in.receive()? {
                    fa.push(m.header().stamp_ns, &m);
                }
            }
            while let Some(m) = links_in.receive()? {
                let stamp_ns = m.header().stamp_ns;
                let Some((body, planar, z)) = link_state(stamp_ns, &m, link) else {
                    continue;
                };
                own = Some(planar);
                if let Some(laser) = laser.as_mut() {
                    laser.set_mount_height(z);
                }
                let force = force_accel
                    .as_ref()
                    .and_then(|f| f.specific_force(stamp_ns));
                if let Some(r) = imu.as_mut().and_then(|imu| imu.update_with(&body, force)) {
                    fresh_imu = Some(r);
                }
            }
        }
        while let Some(m) = own_pose
            .as_ref()
            .map(|s| s.receive())
            .transpose()?
            .flatten()
        {
            own = Some(*m);
            if imu.is_some() {
                pairer.push_a(m.header().stamp_ns, *m);
            }
        }
        if let Some(twist_in) = &twist_in {
            while let Some(m) = twist_in.receive()? {
                pairer.push_b(m.header().stamp_ns, *m);
            }
        }
        if let Some(imu) = imu.as_mut() {
            while let Some((stamp, pose, twist)) = pairer.pop() {
                if let Some(r) = imu.update(&BodyState::planar(stamp, &pose, &twist)) {
                    fresh_imu = Some(r);
                }
            }
        }
        for (sub, slot) in others.iter().zip(other_poses.iter_mut()) {
            if let Some(m) = sub.latest()? {
                *slot = Some(*m);
            }
        }
        if let Some(m) = wheels.latest()? {
            wheel = Some(*m);
        }

        if due(step.index(), encoder_every)
            && let Some(w) = &wheel
        {
            ticks_out.publish(&encoder_ticks(w, p.ticks_per_rev))?;
        }
        if let (Some(laser), Some(out), Some(own)) = (laser.as_mut(), &scan_out, &own)
            && due(step.index(), laser_every)
        {
            visible.clear();
            visible.extend(other_poses.iter().flatten());
            // Filled in place in shared memory: a scan is ~8.7 KB.
            let mut scan = out.loan()?;
            laser.scan(own, &visible, &mut scan);
            scan.send()?;
        }
        if let (Some(imu), Some(out), Some(r)) = (&imu, &imu_out, fresh_imu.take()) {
            out.publish(&imu.message(&r))?;
        }
        Ok(())
    })?;
    Ok(())
}
