//! `caravan-sensor`: the sensors of robot `robot` (params in `params.rs`).
//!
//! One node steps at 100 Hz and decimates: the IMU reads every step, the encoders every 2nd
//! (50 Hz), the laser every 10th (10 Hz), each by whole steps so periods stay exact in lockstep.
//!
//! In:  `robot/i/pose_true`, `robot/i/twist_true`, `robot/i/wheel_state` from physics, and
//!      `robot/j/pose_true` of the other robots (for the laser to see their chassis).
//! Out: `robot/i/encoder_ticks`, `robot/i/scan` (if `laser`), `robot/i/imu` (if `imu`).

use caravan::{Node, NodeIdentity, Subscriber, Topic, Trigger, parse_params, parse_rate};
use caravan_schemas::{EncoderTicks, Imu, LaserScan, Pose2D, Twist, WheelState, topics};
use caravan_sensor::encoders::encoder_ticks;
use caravan_sensor::imu::{BodyState, Mount, VirtualImu};
use caravan_sensor::laser::Laser;
use caravan_sensor::params::Params;
use caravan_sensor::schedule::{due, every_nth};
use caravan_sensor::sync::Pairer;
use std::fmt::Display;
use std::process::ExitCode;
use std::time::Duration;

const NODE_RATE_HZ: f64 = 100.0;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caravan-sensor: {e}");
            ExitCode::FAILURE
        }
    }
}

fn text(e: impl Display) -> String {
    e.to_string()
}

fn run() -> Result<(), String> {
    // Everything that can be wrong with the input is checked before the node joins the group.
    let identity = NodeIdentity::from_env().map_err(text)?;
    let node_name = identity.name.clone();
    let p: Params = parse_params(&node_name, &identity.params).map_err(text)?;
    let in_params = |e: &dyn Display| format!("params of node '{node_name}': {e}");
    p.validate().map_err(|e| in_params(&e))?;
    let world = caravan_world::load_world(&identity.resolve_path(&p.world))
        .map_err(|e| in_params(&format!("key 'world': world file {e}")))?;
    let robot = caravan_world::load_robot(&identity.resolve_path(&p.urdf))
        .map_err(|e| in_params(&format!("key 'urdf': robot description {e}")))?;
    let seed = identity.node_seed();

    // The launch file's `rate` overrides the default, as `Node::trigger` does; checked here so
    // a bad rate never joins the group.
    let period = match (&identity.rate_override, &identity.on_override) {
        (Some(rate), _) => {
            parse_rate(rate).map_err(|e| format!("node '{node_name}', its `rate`: {e}"))?
        }
        (None, Some(_)) => {
            return Err(format!(
                "node '{node_name}': caravan-sensor runs at a fixed rate; give it a `rate`, not `on`"
            ));
        }
        (None, None) => Duration::from_secs_f64(1.0 / NODE_RATE_HZ),
    };
    let encoder_every =
        every_nth(period, p.encoder_rate_hz, "encoder_rate_hz").map_err(|e| in_params(&e))?;
    let laser_every = if p.laser {
        every_nth(period, p.laser_rate_hz, "laser_rate_hz").map_err(|e| in_params(&e))?
    } else {
        1
    };

    let mut node = Node::new(identity).map_err(text)?;
    let i = p.robot;
    let sub_pose = |j: usize| node.subscriber(&Topic::<Pose2D>::new(&topics::pose_true(j)));
    let own_pose = sub_pose(i).map_err(text)?;
    let wheels = node
        .subscriber(&Topic::<WheelState>::new(&topics::wheel_state(i)))
        .map_err(text)?;
    let ticks_out = node
        .publisher(&Topic::<EncoderTicks>::new(&topics::encoder_ticks(i)))
        .map_err(text)?;

    // The laser sees the other robots at their latest true poses.
    let mut laser = p
        .laser
        .then(|| Laser::new(p.laser_config(), &world, &robot, seed));
    let others: Vec<Subscriber<Pose2D>> = if p.laser {
        (0..p.count)
            .filter(|&j| j != i)
            .map(sub_pose)
            .collect::<Result<_, _>>()
            .map_err(text)?
    } else {
        Vec::new()
    };
    let scan_out = if p.laser {
        Some(
            node.publisher(&Topic::<LaserScan>::new(&topics::scan(i)))
                .map_err(text)?,
        )
    } else {
        None
    };

    // The IMU needs pose and twist of the same instant; they come on two topics.
    let mount = Mount {
        offset: p.imu_offset.into(),
    };
    let mut imu = p.imu.then(|| VirtualImu::new(mount, p.imu_noise(), seed));
    let (twist_in, imu_out) = if p.imu {
        let twist_in = node
            .subscriber(&Topic::<Twist>::new(&topics::twist_true(i)))
            .map_err(text)?;
        let imu_out = node
            .publisher(&Topic::<Imu>::new(&topics::imu(i)))
            .map_err(text)?;
        (Some(twist_in), Some(imu_out))
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

    node.run(Trigger::Every(period), |step| {
        // Drain every input each step, so none overflows its queue between uses.
        while let Some(m) = own_pose.receive()? {
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
    })
    .map_err(text)?;
    Ok(())
}
