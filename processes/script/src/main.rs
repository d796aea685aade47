//! `caravan-script`: publishes the launch file's timeline of commands (see the crate
//! documentation and docs/processes.md). Plumbing only: the timeline is `caravan_script`'s.

use caravan::{Error, Node, NodeIdentity, Trigger};
use caravan_schemas::Topic;
use caravan_script::field::Read;
use caravan_script::params::{Params, Plan};
use caravan_script::timeline::Timeline;
use std::process::ExitCode;

/// The script's rate when the launch file gives none.
const DEFAULT_RATE_HZ: f64 = 100.0;

fn main() -> ExitCode {
    caravan::node_main("caravan-script", setup, run)
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Plan, String> {
    if identity.on_override.is_some() {
        return Err(
            "key 'on': caravan-script steps at a rate, since its commands have times; give \
             `rate` instead"
                .into(),
        );
    }
    p.plan()
}

/// Publishes one message given as its bytes.
type Publish = Box<dyn Fn(&[u8]) -> Result<(), Error>>;

/// Reads every visible message of a topic, handing each to the callback.
type Drain = Box<dyn Fn(&mut dyn FnMut(&Read)) -> Result<(), Error>>;

fn unknown(type_name: &str) -> Error {
    Error::Config(format!(
        "message type '{type_name}' is not one of Caravan's"
    ))
}

/// A publisher of `topic`, whose messages are Caravan's type `type_name`.
fn publisher(node: &Node, topic: &str, type_name: &str) -> Result<Publish, Error> {
    caravan_schemas::with_message_type!(type_name, |T| {
        let port = node.publisher(&Topic::<T>::new(topic))?;
        let publish: Publish = Box::new(move |bytes: &[u8]| {
            if bytes.len() != size_of::<T>() {
                return Err(Error::Config(format!(
                    "a command's {} bytes are not one {} ({} bytes)",
                    bytes.len(),
                    caravan_schemas::type_name::<T>(),
                    size_of::<T>()
                )));
            }
            let mut loan = port.loan()?;
            // SAFETY: `bytes` is a whole value of `T` (built from its descriptor at setup), and
            // `T`, a message, is plain numbers and arrays of them, valid in any bit pattern.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    bytes.as_ptr(),
                    (&mut *loan as *mut T).cast::<u8>(),
                    bytes.len(),
                )
            };
            loan.send()
        });
        Ok(publish)
    })
    .unwrap_or_else(|| Err(unknown(type_name)))
}

/// A subscriber of `topic` (Caravan's type `type_name`) that hands out each message's bytes.
fn drain(node: &Node, topic: &str, type_name: &str) -> Result<Drain, Error> {
    caravan_schemas::with_message_type!(type_name, |T| {
        let port = node.subscriber(&Topic::<T>::new(topic))?;
        let drain: Drain = Box::new(move |each: &mut dyn FnMut(&Read)| {
            while let Some(msg) = port.receive()? {
                let base = (&*msg as *const T).cast::<u8>();
                each(&|offset, buf: &mut [u8]| {
                    assert!(
                        offset + buf.len() <= size_of::<T>(),
                        "a field of the message"
                    );
                    // SAFETY: within the message, at the bytes of one of its fields (the
                    // trigger's path was resolved against the type's layout).
                    unsafe {
                        std::ptr::copy_nonoverlapping(base.add(offset), buf.as_mut_ptr(), buf.len())
                    }
                });
            }
            Ok(())
        });
        Ok(drain)
    })
    .unwrap_or_else(|| Err(unknown(type_name)))
}

fn run(mut node: Node, plan: Plan) -> Result<(), Error> {
    // One publisher per topic, in the order the commands name them.
    let mut topics: Vec<&str> = Vec::new();
    let mut ports: Vec<Publish> = Vec::new();
    let mut port_of = Vec::new();
    for c in &plan.commands {
        let k = match topics.iter().position(|t| *t == c.topic) {
            Some(k) => k,
            None => {
                ports.push(publisher(&node, &c.topic, c.type_name)?);
                topics.push(&c.topic);
                topics.len() - 1
            }
        };
        port_of.push(k);
    }
    // One subscriber per watched topic, with the triggers that watch it.
    let mut watched: Vec<(&str, Drain, Vec<usize>)> = Vec::new();
    for (t, trigger) in plan.triggers.iter().enumerate() {
        match watched.iter_mut().find(|w| w.0 == trigger.topic) {
            Some(w) => w.2.push(t),
            None => watched.push((
                &trigger.topic,
                drain(&node, &trigger.topic, trigger.type_name)?,
                vec![t],
            )),
        }
    }
    let mut timeline = Timeline::new(plan.commands.iter().map(|c| c.when));
    let mut held = vec![false; plan.triggers.len()];
    let trigger = node.trigger(Trigger::every_hz(DEFAULT_RATE_HZ))?;
    node.run(trigger, |step| {
        // Every message that became visible since the last step: a trigger holds when any of
        // them crossed its threshold.
        held.fill(false);
        for (_, drain, triggers) in &watched {
            if !triggers.iter().any(|t| timeline.waits_on(*t)) {
                continue;
            }
            drain(&mut |read| {
                for &t in triggers {
                    let tr = &plan.triggers[t];
                    if tr.field.read(read).is_some_and(|v| tr.threshold.holds(v)) {
                        held[t] = true;
                    }
                }
            })?;
        }
        for i in timeline.step(step.now_ns(), |t| held[t]) {
            ports[port_of[i]](&plan.commands[i].bytes)?;
        }
        Ok(())
    })?;
    Ok(())
}
