//! `caravan-contact-driver`: holds the arm in its working pose (`robot/0/joint_command`) and
//! plays the person: from `push.start_s` on, one push every `push.push_s + push.gap_s`, at a
//! random point of a link in `push.links`, inside the friction cone (`robot/0/wrench`, in the
//! link's frame), with the hand's position on `person/hand` for the depth sensor; a zero wrench
//! and a NaN hand end each push.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_contact::arm_urdf::ArmModel;
use caravan_contact::push::PushSpec;
use caravan_contact::scenario::{ArmParams, HAND_TOPIC, PushParams, pose_rad};
use caravan_schemas::{JointCommand, JointValue, Name, Pose2D, Topic, Vector3, Wrench, topics};
use caravan_sensor::noise::Gaussian;
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-contact-driver", setup, run)
}

/// The driver's rate when the launch file gives none.
const DEFAULT_RATE_HZ: f64 = 100.0;

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    arm: ArmParams,
    /// The working pose, one angle per joint, degrees.
    pose_deg: Vec<f64>,
    push: PushParams,
}

struct Ready {
    model: ArmModel,
    q: Vec<f64>,
    spec: PushSpec,
    push: PushParams,
    seed: u64,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    let model = p.arm.load(&identity.resolve_path(&p.arm.urdf))?;
    let q = pose_rad(&model, &p.pose_deg)?;
    // Its step, as `Node::trigger` takes it: the launch file's `rate`, or the default.
    let step_s = match &identity.rate_override {
        Some(rate) => caravan::parse_rate(rate)
            .map_err(|e| format!("its `rate`: {e}"))?
            .as_secs_f64(),
        None => 1.0 / DEFAULT_RATE_HZ,
    };
    let spec = p.push.spec(&model, &q, step_s)?;
    // Every push must find a point: refuse a pose whose pushed links are out of reach.
    if spec
        .sample(&model.arm.pose(&q), &mut Gaussian::new(0, 0))
        .is_none()
    {
        return Err("key 'pose_deg': no link in 'push.links' can be touched in this pose".into());
    }
    Ok(Ready {
        model,
        q,
        spec,
        push: p.push,
        seed: identity.node_seed(),
    })
}

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let joints = node.publisher(&topics::joint_command(0))?;
    let wrench = node.publisher(&topics::wrench(0))?;
    let hand = node.publisher(&Topic::<Pose2D>::new(HAND_TOPIC))?;
    let pose = r.model.arm.pose(&r.q);
    let mut g = Gaussian::new(r.seed, 0);
    let mut current: Option<(u64, usize)> = None;
    let trigger = node.trigger(Trigger::every_hz(DEFAULT_RATE_HZ))?;
    node.run(trigger, |step| {
        if step.index() == 0 {
            let mut cmd = caravan_schemas::placement_new::<JointCommand>();
            for (name, q) in r.model.joints.iter().zip(&r.q) {
                let _ = cmd.joints.push(JointValue {
                    name: Name::new(name),
                    position: *q,
                    velocity: 0.0,
                    effort: f64::NAN,
                });
            }
            joints.publish(&cmd)?;
        }
        let active = r.push.active(step.now().as_secs_f64());
        match (active, current) {
            (Some(k), Some((c, _))) if k == c => {}
            (Some(k), _) => {
                let p = r.spec.sample(&pose, &mut g).expect("checked at setup");
                wrench.publish(&Wrench {
                    link: Name::new(&r.model.links[p.link]),
                    frame: Wrench::LINK,
                    point: Vector3 {
                        x: p.local_point.x,
                        y: p.local_point.y,
                        z: 0.0,
                    },
                    force: Vector3 {
                        x: p.local_force.x,
                        y: p.local_force.y,
                        z: 0.0,
                    },
                    ..Wrench::default()
                })?;
                hand.publish(&Pose2D {
                    x: p.hand.center.x,
                    y: p.hand.center.y,
                    theta: 0.0,
                })?;
                current = Some((k, p.link));
            }
            (None, Some((_, link))) => {
                wrench.publish(&Wrench {
                    link: Name::new(&r.model.links[link]),
                    frame: Wrench::LINK,
                    ..Wrench::default()
                })?;
                hand.publish(&Pose2D {
                    x: f64::NAN,
                    y: f64::NAN,
                    theta: 0.0,
                })?;
                current = None;
            }
            (None, None) => {}
        }
        Ok(())
    })?;
    Ok(())
}
