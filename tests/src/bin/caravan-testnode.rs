//! A node for integration tests. The first argument picks a behaviour; params come from the
//! environment as for any node.
//!
//! - `publish`: publishes `count` messages carrying `value` on `topic`, lossless.
//! - `stream`: once `topic` has `readers` subscribers (default 1), publishes `count` messages carrying `value` on
//!   it, lossless, one per step at the launch rate (default 100 Hz), then exits 0.
//! - `subscribe`: after `delay_ms`, receives `count` messages from `topic`, checks values and
//!   sequence numbers, prints `ready` once subscribed.
//! - `idle`: steps at the launch rate doing nothing.
//! - `steps`: steps `count` times at the launch rate, then exits 0.
//! - `params`: only parses its params (`gain: f64`, `name: String`).
//! - `lockstep-source` / `lockstep-sink`: see the lockstep protocol test.
//! - `lockstep-relay`: at 100 Hz, logs `now stamp` for each message of `topic` to `out`
//!   and publishes `count` messages (at least 1) on `<topic>/relayed`, carrying its time,
//!   one more at `burst_ms`.
//! - `lockstep-scheduled`: a `Trigger::Scheduled` node asking for steps at (k + 1)² × 10 ms
//!   for k < `count`, publishing on `topic` at each.
//! - `hang`: steps at 10 Hz and hangs in its step after `count` steps.
//! - `wrong-type`: after `count` ms, publishes `WheelSetpoint`s on `topic` (type-mismatch tests).
//! - `arm-commands`: the physics topics test's commands, see [`arm_commands`].
//! - `mute`: joins the group and sleeps forever without stepping (no status).
//! - `chaos`: at random steps (seeded by the group seed), SIGKILLs one of the live `victims`,
//!   `count` times in all, and appends `victim pid` for each kill to the file `out`.

use caravan::{Error, Node, Topic, Trigger};
use caravan_schemas::Pose2D;
use serde::Deserialize;
use std::io::Write;
use std::time::Duration;

#[derive(Deserialize, schemars::JsonSchema, Default)]
#[serde(default)]
struct Params {
    topic: String,
    count: u64,
    value: f64,
    out: String,
    gain: f64,
    name: String,
    /// `chaos`: the processes it may kill.
    victims: Vec<String>,
    /// `subscribe`: how long to wait before subscribing, ms.
    delay_ms: u64,
    /// `stream`: the subscribers to wait for (0 counts as 1).
    readers: usize,
    /// `lockstep-relay`: the time of its step (ms) that sends one message more, 0 for none.
    burst_ms: u64,
}

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_default();
    if caravan::check_only() {
        // The launcher's check before the group starts: only the params can be checked here.
        let checked = caravan::NodeIdentity::from_env()
            .and_then(|id| caravan::parse_params::<Params>(&id.name, &id.params));
        if let Err(e) = checked {
            eprintln!("caravan-testnode {mode}: {e}");
            std::process::exit(2);
        }
        return;
    }
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
        "stream" => {
            let publisher = node.publisher(&Topic::<Pose2D>::lossless(&p.topic))?;
            let count = p.count;
            node.run(node.trigger(Trigger::every_hz(100.0))?, |step| {
                // A lossless stream needs its reader first: what is sent to nobody is gone.
                if publisher.subscribers() < p.readers.max(1) {
                    return Ok(());
                }
                let seq = publisher.sequence() + 1;
                publisher.publish(&Pose2D {
                    x: p.value,
                    y: seq as f64,
                    theta: 0.0,
                })?;
                if seq >= count {
                    step.stop();
                }
                Ok(())
            })?;
        }
        "subscribe" => subscribe(&mut node, &p)?,
        "idle" => {
            node.run(Trigger::every_hz(10.0), |_| Ok(()))?;
        }
        "steps" => {
            let count = p.count;
            node.run(Trigger::every_hz(10.0), |step| {
                if step.index() + 1 >= count {
                    step.stop();
                }
                Ok(())
            })?;
        }
        "params" => {}
        "chaos" => chaos(&mut node, &p)?,
        "mute" => loop {
            // Joins the group but never steps, so it never publishes a status.
            std::thread::sleep(std::time::Duration::from_secs(3600));
        },
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
        "lockstep-scheduled" => {
            // Asks for steps at (k + 1)² × 10 ms, k = 0 … count − 1, publishing at each.
            let publisher = node.publisher(&Topic::<Pose2D>::new(&p.topic))?;
            let count = p.count;
            node.run(Trigger::Scheduled, |step| {
                publisher.publish(&Pose2D::default())?;
                let k = step.index();
                if k < count {
                    step.wake_at(Duration::from_millis((k + 1) * (k + 1) * 10));
                }
                Ok(())
            })?;
        }
        "lockstep-relay" => {
            let subscriber = node.subscriber(&Topic::<Pose2D>::new(&p.topic))?;
            let relayed = node.publisher(&Topic::<Pose2D>::new(&format!("{}/relayed", p.topic)))?;
            let mut log = std::fs::File::create(&p.out).map_err(|e| Error::Step(e.to_string()))?;
            node.run(Trigger::every_hz(100.0), |step| {
                while let Some(msg) = subscriber.receive()? {
                    writeln!(log, "{} {}", step.now_ns(), msg.header().stamp_ns)
                        .map_err(|e| Error::Step(e.to_string()))?;
                }
                let extra = (p.burst_ms > 0 && step.now().as_millis() == p.burst_ms as u128) as u64;
                for _ in 0..p.count.max(1) + extra {
                    relayed.publish(&Pose2D {
                        x: step.now().as_secs_f64(),
                        ..Default::default()
                    })?;
                }
                Ok(())
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
        "arm-commands" => arm_commands(&mut node)?,
        other => return Err(Error::Step(format!("unknown mode '{other}'"))),
    }
    Ok(())
}

fn subscribe(node: &mut Node, p: &Params) -> Result<(), Error> {
    std::thread::sleep(Duration::from_millis(p.delay_ms));
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

/// Commands for the physics topics test, by simulated time: from 0.5 s robot 0's joints
/// `upper_joint`, `fore_joint`, `hand_joint` to positions 0.2, −0.2, 0 rad and robot 2 (a
/// kinematic base) to 0.5 m/s along x; at 2 s robot 2 back to (3, 2, 1) m (`set_pose`), where it
/// flies on; at 3 s a 10 N downward force on robot 0's `hand`, 0.3 m along the link, for 1 s.
fn arm_commands(node: &mut Node) -> Result<(), Error> {
    use caravan_schemas::{
        JointCommand, JointValue, Name, Pose3D, Quaternion, Twist, Vector3, Wrench, topics,
    };
    let joints = node.publisher(&topics::joint_command(0))?;
    let set_pose = node.publisher(&topics::set_pose(2))?;
    let mut moved = false;
    let wrench = node.publisher(&topics::wrench(0))?;
    let cmd_vel = node.publisher(&topics::cmd_vel(2))?;
    let mut pushed = false;
    node.run(Trigger::every_hz(10.0), |step| {
        let t = step.now().as_secs_f64();
        if t >= 0.5 {
            let mut cmd = caravan_schemas::placement_new::<JointCommand>();
            for (name, position) in [
                ("upper_joint", 0.2),
                ("fore_joint", -0.2),
                ("hand_joint", 0.0),
            ] {
                let value = JointValue {
                    name: Name::new(name),
                    position,
                    velocity: 0.0,
                    effort: f64::NAN,
                };
                let _ = cmd.joints.push(value);
            }
            joints.publish(&cmd)?;
            let mut v = Twist::default();
            v.linear.x = 0.5;
            cmd_vel.publish(&v)?;
        }
        if t >= 2.0 && !moved {
            moved = true;
            set_pose.publish(&Pose3D {
                position: Vector3 {
                    x: 3.0,
                    y: 2.0,
                    z: 1.0,
                },
                orientation: Quaternion {
                    w: 1.0,
                    ..Quaternion::default()
                },
            })?;
        }
        if t >= 3.0 && !pushed {
            pushed = true;
            wrench.publish(&Wrench {
                link: Name::new("hand"),
                frame: Wrench::LINK,
                point: Vector3 {
                    x: 0.3,
                    y: 0.0,
                    z: 0.0,
                },
                force: Vector3 {
                    x: 0.0,
                    y: 0.0,
                    z: -10.0,
                },
                duration_s: 1.0,
                ..Wrench::default()
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

fn chaos(node: &mut Node, p: &Params) -> Result<(), Error> {
    use iceoryx2::node::NodeView;
    let config = match &node.identity().iceoryx_config {
        Some(path) => caravan::group::load_config(path)?,
        None => caravan::group::config(&node.identity().group)?,
    };
    // A small xorshift stream: reproducible kill steps without another dependency.
    let mut state = node.identity().node_seed() | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut kills = 0;
    let out = p.out.clone();
    let victims = p.victims.clone();
    node.run(Trigger::every_hz(10.0), |_| {
        if kills >= p.count || next() % 10 != 0 {
            return Ok(());
        }
        let victim = &victims[(next() % victims.len() as u64) as usize];
        let mut pid = None;
        let _ = iceoryx2::node::Node::<iceoryx2::prelude::ipc::Service>::list(&config, |state| {
            if let iceoryx2::node::NodeState::Alive(view) = state
                && let Some(details) = view.details()
                && details.name().to_string() == *victim
            {
                pid = Some(details.process_id().value());
            }
            iceoryx2::prelude::CallbackProgression::Continue
        });
        // A victim that is restarting is not there: try again at a later step.
        if let Some(pid) = pid {
            // SAFETY: kill(2) on a process of the group under test.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            kills += 1;
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&out)
                .map_err(|e| Error::Input(format!("{out}: {e}")))?;
            let _ = writeln!(f, "{victim} {pid}");
        }
        Ok(())
    })?;
    Ok(())
}
