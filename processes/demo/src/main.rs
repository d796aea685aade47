//! Demo nodes: `caravan-demo ROLE`, with ROLE one of
//! - `ping`: counts up at its rate and publishes the count on `demo/ping`;
//! - `pong`: on each `demo/ping`, publishes the value times `gain` on `demo/pong`;
//! - `sum`: at its rate, adds the latest `demo/pong` to a running total on `demo/sum`;
//! - `noise`: at its rate, publishes seeded random numbers on `demo/noise`;
//! - `crash`: steps `steps` times, then exits with status 3 (for restart tests);
//! - `source`: at its rate, publishes a count on the lossless topic `topic`;
//! - `sink`: at its rate, receives every message of the lossless topic `topic` (its status
//!   counts sequence gaps). Sources and sinks make the reliability soak.
//! - `clock`: at its rate (100 Hz), publishes the wall clock (CLOCK_REALTIME, s) as `x` on
//!   `demo/clock`: a receiver on the same machine measures a path's latency as its own clock
//!   minus `x` (the ROS 2 bridge's, `tests/python/ros2_latency.py`).

use caravan::{Error, Node, Topic, Trigger};
use caravan_schemas::Pose2D;
use rand::{Rng, SeedableRng};
use serde::Deserialize;

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
struct Params {
    /// `pong`: factor applied to each value.
    gain: f64,
    /// `crash`: steps before exiting (0 behaves as 1).
    steps: u64,
    /// `source`, `sink`: the topic.
    topic: String,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            gain: 2.0,
            steps: 5,
            topic: "demo/stream".into(),
        }
    }
}

fn topic(name: &str) -> Topic<Pose2D> {
    Topic::new(name)
}

const ROLES: [&str; 8] = [
    "ping", "pong", "sum", "noise", "crash", "source", "sink", "clock",
];

fn main() -> std::process::ExitCode {
    let role = std::env::args().nth(1).unwrap_or_default();
    caravan::node_main(
        &format!("caravan-demo {role}"),
        |p: Params, _| {
            if ROLES.contains(&role.as_str()) {
                Ok(p)
            } else {
                Err(format!(
                    "unknown role '{role}'; expected ping, pong, sum, noise, crash, source, sink or clock"
                ))
            }
        },
        |node, p| run(&role, node, p),
    )
}

fn run(role: &str, mut node: Node, p: Params) -> Result<(), Error> {
    match role {
        "ping" => count_up(&mut node, &topic("demo/ping"), 10.0)?,
        "pong" => {
            let input = node.subscriber(&topic("demo/ping"))?;
            let out = node.publisher(&topic("demo/pong"))?;
            node.run(Trigger::on("demo/ping"), |_| {
                while let Some(msg) = input.receive()? {
                    out.publish(&Pose2D {
                        x: msg.x * p.gain,
                        ..*msg
                    })?;
                }
                Ok(())
            })?;
        }
        "sum" => {
            let input = node.subscriber(&topic("demo/pong"))?;
            let out = node.publisher(&topic("demo/sum"))?;
            let mut total = 0.0;
            node.run(Trigger::every_hz(20.0), |_| {
                if let Some(msg) = input.latest()? {
                    total += msg.x;
                }
                out.publish(&Pose2D {
                    x: total,
                    y: 0.0,
                    theta: 0.0,
                })
            })?;
        }
        "noise" => {
            let out = node.publisher(&topic("demo/noise"))?;
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(node.identity().node_seed());
            node.run(Trigger::every_hz(7.0), |_| {
                out.publish(&Pose2D {
                    x: rng.random(),
                    y: rng.random(),
                    theta: 0.0,
                })
            })?;
        }
        "clock" => {
            let out = node.publisher(&topic("demo/clock"))?;
            node.run(Trigger::every_hz(100.0), |_| {
                let wall = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .unwrap_or_default();
                out.publish(&Pose2D {
                    x: wall.as_secs_f64(),
                    y: 0.0,
                    theta: 0.0,
                })
            })?;
        }
        "source" => count_up(&mut node, &Topic::lossless(&p.topic), 100.0)?,
        "sink" => {
            let input = node.subscriber(&Topic::<Pose2D>::lossless(&p.topic))?;
            node.run(Trigger::every_hz(100.0), |_| {
                while input.receive()?.is_some() {}
                Ok(())
            })?;
        }
        "crash" => {
            node.run(Trigger::every_hz(10.0), |step| {
                if step.index() + 1 >= p.steps {
                    step.stop();
                }
                Ok(())
            })?;
            // Leave the group cleanly first, then fail the way the restart tests expect.
            drop(node);
            std::process::exit(3);
        }
        _ => {}
    }
    Ok(())
}

/// Publishes the step count on `topic`, `hz` times a second (the launch file's rate wins).
fn count_up(node: &mut Node, topic: &Topic<Pose2D>, hz: f64) -> Result<(), Error> {
    let out = node.publisher(topic)?;
    node.run(Trigger::every_hz(hz), |step| {
        out.publish(&Pose2D {
            x: step.index() as f64,
            y: 0.0,
            theta: 0.0,
        })
    })?;
    Ok(())
}
