//! `caravan-sensor`: the sensors of robot `robot` (params in `params.rs`).
//!
//! One node steps at 100 Hz and decimates: the IMU reads every step, the encoders every 2nd
//! (50 Hz), the laser every 10th (10 Hz), each by whole steps so periods stay exact in lockstep.
//!
//! In:  `robot/i/pose_true`, `robot/i/twist_true`, `robot/i/wheel_state` from physics, and
//!      `robot/j/pose_true` of the other robots (for the laser to see their chassis); with
//!      `link`, `robot/i/link_states` instead of pose and twist (see `attach.rs`).
//! Out: `robot/i/encoder_ticks`, `robot/i/scan` (if `laser`), `robot/i/imu` (if `imu`).
//!
//! What the sensors do with each input and when they publish is the library's `SensorSuite`
//! (`suite.rs`); this file opens the ports and drains them into it each step.

use caravan::{Node, NodeIdentity, Subscriber, Trigger, parse_rate};
use caravan_schemas::{Pose2D, topics};
use caravan_sensor::attach::{check_force_joint, check_link};
use caravan_sensor::params::Accelerometer;
use caravan_sensor::params::Params;
use caravan_sensor::schedule::every_nth;
use caravan_sensor::suite::SensorSuite;
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
    world.check_robot(&p.world, p.robot)?;
    identity.serves_robot(p.robot);
    let urdf = identity.resolve_path(&p.urdf);
    let robot = match &p.link {
        // Without `link` the sensors ride on a wheeled robot's base: a description that is
        // not one may well be a robot whose link was meant.
        None => Some(caravan_world::load_robot(&urdf).map_err(|e| {
            format!(
                "key 'urdf': robot description {e} (without `link` the sensors ride on the \
                 base of a wheeled robot; on another robot, give `link`, the link they ride on)"
            )
        })?),
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

    let mut suite = SensorSuite::new(&p, &world, robot.as_ref(), seed, encoder_every, laser_every);
    // The laser sees the other robots at their latest true poses, if it knows their shape.
    let others: Vec<Subscriber<Pose2D>> = suite
        .others()
        .iter()
        .map(|&j| sub_pose(j))
        .collect::<Result<_, _>>()?;
    let scan_out = if p.laser {
        Some(node.publisher(&topics::scan(i))?)
    } else {
        None
    };

    // The IMU needs pose and twist of the same instant; they come on two topics. The
    // force-sensor accelerometer pairs force readings with link states by stamp.
    let forces_in = if suite.reads_forces() {
        Some(node.subscriber(&topics::force_torque(i))?)
    } else {
        None
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

    node.run(Trigger::Every(period), |step| {
        // Drain every input each step, so none overflows its queue between uses.
        if let (Some(links_in), Some(link)) = (&links_in, &p.link) {
            if suite.link_silent(step.now()) {
                eprintln!(
                    "caravan-sensor: no state of link '{link}' on robot/{i}/link_states after \
                     1 s; give physics `link_states = true` for robot {i}"
                );
            }
            if let Some(forces_in) = &forces_in {
                while let Some(m) = forces_in.receive()? {
                    suite.forces(m.header().stamp_ns, &m);
                }
            }
            while let Some(m) = links_in.receive()? {
                suite.link_states(m.header().stamp_ns, &m);
            }
        }
        while let Some(m) = own_pose
            .as_ref()
            .map(|s| s.receive())
            .transpose()?
            .flatten()
        {
            suite.pose(m.header().stamp_ns, *m);
        }
        if let Some(twist_in) = &twist_in {
            while let Some(m) = twist_in.receive()? {
                suite.twist(m.header().stamp_ns, *m);
            }
        }
        suite.pair_imu();
        for (k, sub) in others.iter().enumerate() {
            if let Some(m) = sub.latest()? {
                suite.other_pose(k, *m);
            }
        }
        if let Some(m) = wheels.latest()? {
            suite.wheel(*m);
        }

        if let Some(ticks) = suite.encoder_ticks(step.index()) {
            ticks_out.publish(&ticks)?;
        }
        if let Some(out) = &scan_out
            && suite.scan_due(step.index())
        {
            let mut scan = out.loan()?;
            suite.scan(&mut scan);
            scan.send()?;
        }
        if let (Some(out), Some(imu)) = (&imu_out, suite.imu_message()) {
            out.publish(&imu)?;
        }
        Ok(())
    })?;
    Ok(())
}
