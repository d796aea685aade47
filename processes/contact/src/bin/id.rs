//! `caravan-contact-id`: the perception process. On every `robot/0/joint_states` (the torque
//! sensors' rate) it takes the joints' external torques (minus the actuators' efforts, plus the
//! sensors' noise `estimator.torque_sigma`), the depth sensor's latest scan without the arm's
//! own returns, identifies the contact and publishes it on `robot/0/contact_estimate`. With
//! `estimator.dynamics` it first subtracts the arm's own dynamics from the torques
//! (`caravan_contact::arm_dynamics`).

use caravan::{Node, NodeIdentity, Trigger};
use caravan_contact::arm_dynamics::ArmDynamics;
use caravan_contact::arm_urdf::ArmModel;
use caravan_contact::depth::{Scanner, self_filter};
use caravan_contact::identify::{NoForce, PointSource, Settings, identify};
use caravan_contact::joints;
use caravan_contact::messages::{ContactEstimate, contact_estimate};
use caravan_contact::scenario::{ArmParams, DEPTH_TOPIC, DepthParams, EstimatorParams};
use caravan_schemas::{LaserScan, Name, Topic, Vector3, topics};
use caravan_sensor::noise::Gaussian;
use nalgebra::Point2;
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-contact-id", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    arm: ArmParams,
    #[serde(default)]
    depth: DepthParams,
    estimator: EstimatorParams,
}

struct Ready {
    model: ArmModel,
    /// The links' masses, when the estimator subtracts the arm's dynamics.
    dynamics: Option<ArmDynamics>,
    scanner: Scanner,
    self_filter_m: f64,
    settings: Settings,
    seed: u64,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    let (model, masses) = p
        .arm
        .load_with_masses(&identity.resolve_path(&p.arm.urdf))?;
    Ok(Ready {
        model,
        dynamics: if p.estimator.dynamics {
            Some(masses?)
        } else {
            None
        },
        scanner: p.depth.scanner()?,
        self_filter_m: p.depth.self_filter_m,
        settings: p.estimator.settings()?,
        seed: identity.node_seed(),
    })
}

const NAN3: Vector3 = Vector3 {
    x: f64::NAN,
    y: f64::NAN,
    z: f64::NAN,
};

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let states = node.subscriber(&topics::joint_states(0))?;
    let scans = node.subscriber(&Topic::<LaserScan>::new(DEPTH_TOPIC))?;
    let out = node.publisher(&contact_estimate(0))?;
    let mut noise = Gaussian::new(r.seed, 0);
    let mut ranges: Vec<f64> = Vec::new();
    // The last joint reading and its stamp (ns), for the joint accelerations.
    let mut last: Option<(u64, joints::Reading)> = None;
    let trigger = node.trigger(Trigger::on(topics::joint_states(0).name()))?;
    node.run(trigger, |_| {
        if let Some(scan) = scans.latest()? {
            ranges = scan.ranges[..scan.beam_count as usize]
                .iter()
                .map(|r| *r as f64)
                .collect();
        }
        while let Some(m) = states.receive()? {
            let Some(now) = joints::read_all(&m, &r.model.joints) else {
                continue;
            };
            let stamp = m.header().stamp_ns;
            // The external torque is what the actuator holds against, less (dynamic) what
            // moves the arm over the step that ended at this reading.
            let own = match (&r.dynamics, &last) {
                (Some(d), Some((t0, before))) if stamp > *t0 => {
                    own_torques(d, &r.model, before, &now, stamp - t0)
                }
                _ => vec![0.0; now.efforts.len()],
            };
            let tau: Vec<f64> = now
                .efforts
                .iter()
                .zip(&own)
                .map(|(e, own)| own - e + noise.sample(r.settings.torque_sigma))
                .collect();
            let q = now.angles.clone();
            last = Some((stamp, now));
            let pose = r.model.arm.pose(&q);
            let depth: Vec<Point2<f64>> =
                self_filter(&r.scanner.points(&ranges), &pose.contours, r.self_filter_m);
            let v2 = |x: f64, y: f64| Vector3 { x, y, z: 0.0 };
            let estimate = match identify(&pose, &tau, &depth, &r.settings) {
                Ok(e) => ContactEstimate {
                    link: Name::new(&r.model.links[e.link]),
                    status: match e.source {
                        Some(PointSource::Line) => ContactEstimate::FOUND,
                        Some(PointSource::Depth) => ContactEstimate::POINT_FROM_OTHER_SENSOR,
                        None => ContactEstimate::NO_POINT,
                    },
                    first_candidate: e.candidates.k_min as u32 + 1,
                    last_candidate: e.candidates.k_max as u32 + 1,
                    _reserved: 0,
                    point: e.point.map_or(NAN3, |p| v2(p.x, p.y)),
                    force: v2(e.force.x, e.force.y),
                },
                Err(why) => ContactEstimate {
                    status: if why == NoForce::NoContact {
                        ContactEstimate::NO_CONTACT
                    } else {
                        ContactEstimate::NO_SOLUTION
                    },
                    point: NAN3,
                    force: NAN3,
                    ..ContactEstimate::default()
                },
            };
            out.publish(&estimate)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// The torques the arm's own motion took over the step from `before` to `now`, `dt_ns`
/// apart: M(q)·q̈ + C(q, q̇)·q̇ at the step's start, q̈ the change of the joint speeds over
/// it, as physics' semi-implicit step turns the torques of a step into the speeds at its
/// end.
fn own_torques(
    d: &ArmDynamics,
    model: &ArmModel,
    before: &joints::Reading,
    now: &joints::Reading,
    dt_ns: u64,
) -> Vec<f64> {
    let dt = dt_ns as f64 * 1e-9;
    let qdd: Vec<f64> = now
        .speeds
        .iter()
        .zip(&before.speeds)
        .map(|(v1, v0)| (v1 - v0) / dt)
        .collect();
    d.torques(&model.arm, &before.angles, &before.speeds, &qdd)
}
