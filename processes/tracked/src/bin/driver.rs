//! `caravan-tracked-driver`: the experiment's operator. It drives robot `robot` straight
//! ahead: `robot/i/cmd_vel` asks for `speed_m_s` from `start_s` until `stop_s`, then for a
//! stop. Params: `robot`, `speed_m_s` (default 0.3), `start_s` (0.5), `stop_s` (never).

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::{Twist, Vector3, topics};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-tracked-driver", setup, run)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    #[serde(default)]
    robot: usize,
    /// Forward speed asked for, m/s.
    #[serde(default = "speed")]
    speed_m_s: f64,
    /// When to start, s ≥ 0.
    #[serde(default = "start")]
    start_s: f64,
    /// When to ask for a stop, s > `start_s`.
    #[serde(default = "never")]
    stop_s: f64,
}

fn speed() -> f64 {
    0.3
}
fn start() -> f64 {
    0.5
}
fn never() -> f64 {
    f64::INFINITY
}

fn setup(p: Params, _: &NodeIdentity) -> Result<Params, String> {
    if !p.speed_m_s.is_finite() {
        return Err(format!(
            "key 'speed_m_s': must be a number, got {}",
            p.speed_m_s
        ));
    }
    if !(p.start_s.is_finite() && p.start_s >= 0.0 && p.stop_s > p.start_s) {
        return Err(format!(
            "keys 'start_s' < 'stop_s' (start ≥ 0) must hold, got {} and {}",
            p.start_s, p.stop_s
        ));
    }
    Ok(p)
}

fn run(mut node: Node, p: Params) -> Result<(), caravan::Error> {
    let cmd_vel = node.publisher(&topics::cmd_vel(p.robot))?;
    let trigger = node.trigger(Trigger::every_hz(50.0))?;
    node.run(trigger, |step| {
        let t = step.now().as_secs_f64();
        let v = if t >= p.start_s && t < p.stop_s {
            p.speed_m_s
        } else {
            0.0
        };
        cmd_vel.publish(&Twist {
            linear: Vector3 {
                x: v,
                ..Vector3::default()
            },
            ..Twist::default()
        })
    })?;
    Ok(())
}
