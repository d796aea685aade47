//! `caravan-contact-depth`: the sparse depth sensor. Each step it casts its beams at the arm
//! (from `robot/0/joint_states`) and the person's hand (`person/hand`, a disc of
//! `hand_radius_m`) and publishes the ranges on `depth/scan` as a `LaserScan`.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_contact::arm_urdf::ArmModel;
use caravan_contact::depth::{Disc, Scanner};
use caravan_contact::joints;
use caravan_contact::range::{HAND_RADIUS_M, between};
use caravan_contact::scenario::{ArmParams, DEPTH_TOPIC, DepthParams, HAND_TOPIC};
use caravan_schemas::{LaserScan, Pose2D, Topic, topics};
use caravan_sensor::noise::Gaussian;
use nalgebra::Point2;
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-contact-depth", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    arm: ArmParams,
    #[serde(default)]
    depth: DepthParams,
    /// The hand's radius, m, 0.001 to 1 (the driver's `push.hand_radius_m`).
    hand_radius_m: f64,
}

struct Ready {
    model: ArmModel,
    scanner: Scanner,
    hand_radius: f64,
    seed: u64,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    let model = p.arm.load(&identity.resolve_path(&p.arm.urdf))?;
    let scanner = p.depth.scanner()?;
    let [lo, hi] = HAND_RADIUS_M;
    between("hand_radius_m", p.hand_radius_m, lo, hi, "m")?;
    Ok(Ready {
        model,
        scanner,
        hand_radius: p.hand_radius_m,
        seed: identity.node_seed(),
    })
}

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let states = node.subscriber(&topics::joint_states(0))?;
    let hands = node.subscriber(&Topic::<Pose2D>::new(HAND_TOPIC))?;
    let out = node.publisher(&Topic::<LaserScan>::new(DEPTH_TOPIC))?;
    let mut noise = Gaussian::new(r.seed, 0);
    let (mut q, mut hand) = (None, None);
    let trigger = node.trigger(Trigger::every_hz(20.0))?;
    let period = trigger.period().map_or(0.0, |p| p.as_secs_f32());
    node.run(trigger, |_| {
        if let Some(m) = states.latest()? {
            q = joints::read(&m, &r.model.joints).map(|(q, _)| q);
        }
        if let Some(h) = hands.latest()? {
            hand = (h.x.is_finite() && h.y.is_finite()).then(|| Disc {
                center: Point2::new(h.x, h.y),
                radius: r.hand_radius,
            });
        }
        let Some(q) = &q else {
            return Ok(());
        };
        let pose = r.model.arm.pose(q);
        let ranges = r.scanner.scan(&pose.contours, hand.as_slice(), &mut noise);
        let mut scan = LaserScan {
            angle_min: r.scanner.first_angle as f32,
            angle_max: (r.scanner.first_angle + r.scanner.fov) as f32,
            angle_increment: r.scanner.increment() as f32,
            scan_time: period,
            range_min: 0.0,
            range_max: r.scanner.max_range as f32,
            beam_count: ranges.len() as u32,
            ..LaserScan::default()
        };
        for (slot, range) in scan.ranges.iter_mut().zip(&ranges) {
            *slot = *range as f32;
        }
        out.publish(&scan)?;
        Ok(())
    })?;
    Ok(())
}
