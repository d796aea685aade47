//! A node for integration tests. The first argument picks a behaviour; params come from the
//! environment as for any node.
//!
//! - `publish`: publishes `count` messages carrying `value` on `topic`, lossless.
//! - `subscribe`: receives `count` messages from `topic`, checks values and sequence numbers,
//!   prints `ready` once subscribed.
//! - `idle`: steps at the launch rate doing nothing.
//! - `params`: only parses its params (`gain: f64`, `name: String`).
//! - `lockstep-source` / `lockstep-sink`: see the lockstep protocol test.
//! - `hang`: steps at 10 Hz and hangs in its step after `count` steps.
//! - `wrong-type`: after `count` ms, publishes `WheelSetpoint`s on `topic` (type-mismatch tests).

use caravan::{Error, Node, Topic, Trigger};
use caravan_schemas::Pose2D;
use serde::Deserialize;
use std::io::Write;

#[derive(Deserialize, Default)]
#[serde(default)]
struct Params {
    topic: String,
    count: u64,
    value: f64,
    out: String,
    gain: f64,
    name: String,
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_default();
    if let Err(e) = run(&mode) {
        eprintln!("caravan-testnode {mode}: {e}");
        std::process::exit(1);
    }
}

fn run(mode: &str) -> Result<(), Error> {
    let mut node = Node::from_env()?;
    let p: Params = node.params()?;
    match mode {
        "publish" => {
            let publisher = node.publisher(&Topic::<Pose2D>::lossless(&p.topic))?;
            let ack_topic = format!("{}/ack", p.topic);
            let ack = node.subscriber(&Topic::<Pose2D>::new(&ack_topic))?;
            publisher.publish(&Pose2D {
                x: p.value,
                y: 1.0,
                theta: 0.0,
            })?;
            // iceoryx2 connects a subscriber when it first receives; wait for that before
            // filling its queue, as a lossless stream needs a connected reader.
            node.run(Trigger::on(&ack_topic), |step| {
                if ack.receive()?.is_some() {
                    step.stop();
                }
                Ok(())
            })?;
            for i in 2..=p.count {
                publisher.publish(&Pose2D {
                    x: p.value,
                    y: i as f64,
                    theta: 0.0,
                })?;
            }
        }
        "subscribe" => subscribe(&mut node, &p)?,
        "idle" => {
            node.run(Trigger::every_hz(10.0), |_| Ok(()))?;
        }
        "params" => {}
        "lockstep-source" => {
            let publisher = node.publisher(&Topic::<Pose2D>::new(&p.topic))?;
            node.run(Trigger::every_hz(10.0), |step| {
                publisher.publish(&Pose2D {
                    x: step.now().as_secs_f64(),
                    y: 0.0,
                    theta: 0.0,
                })
            })?;
        }
        "lockstep-sink" => {
            let subscriber = node.subscriber(&Topic::<Pose2D>::new(&p.topic))?;
            let mut log = std::fs::File::create(&p.out).map_err(|e| Error::Step(e.to_string()))?;
            node.run(Trigger::on(&p.topic), |step| {
                while let Some(msg) = subscriber.receive()? {
                    writeln!(log, "{} {}", step.now_ns(), msg.header().stamp_ns)
                        .map_err(|e| Error::Step(e.to_string()))?;
                }
                Ok(())
            })?;
        }
        "hang" => {
            let count = p.count;
            node.run(Trigger::every_hz(10.0), |step| {
                if step.index() >= count {
                    // Simulates a node stuck in its computation (a deadlock, an endless loop).
                    loop {
                        std::thread::park();
                    }
                }
                Ok(())
            })?;
        }
        "wrong-type" => {
            // Join late, as a plug-in would, so the group's own publisher owns the topic.
            std::thread::sleep(std::time::Duration::from_millis(p.count));
            let publisher =
                node.publisher(&Topic::<caravan_schemas::WheelSetpoint>::new(&p.topic))?;
            node.run(Trigger::every_hz(10.0), |_| {
                publisher.publish(&Default::default())
            })?;
        }
        other => return Err(Error::Step(format!("unknown mode '{other}'"))),
    }
    Ok(())
}

fn subscribe(node: &mut Node, p: &Params) -> Result<(), Error> {
    let subscriber = node.subscriber(&Topic::<Pose2D>::lossless(&p.topic))?;
    let ack = node.publisher(&Topic::<Pose2D>::new(&format!("{}/ack", p.topic)))?;
    println!("ready");
    std::io::stdout().flush().ok();
    let mut expected_seq = 1;
    let count = p.count;
    let value = p.value;
    node.run(Trigger::on(&p.topic), |step| {
        while let Some(msg) = subscriber.receive()? {
            if msg.x != value {
                return Err(Error::Step(format!(
                    "foreign message: value {} instead of {value}",
                    msg.x
                )));
            }
            if msg.header().seq != expected_seq || msg.y as u64 != expected_seq {
                return Err(Error::Step(format!(
                    "gap: seq {} after {}",
                    msg.header().seq,
                    expected_seq - 1
                )));
            }
            if expected_seq == 1 {
                ack.publish(&Pose2D::default())?;
            }
            expected_seq += 1;
            if expected_seq > count {
                step.stop();
                break;
            }
        }
        Ok(())
    })?;
    println!(
        "received {} missed {}",
        expected_seq - 1,
        subscriber.missed()
    );
    Ok(())
}
