//! The receiving side of a host's relay: publishes what other hosts send here on this host's
//! shared memory, header untouched. Lockstep control messages wait until what was sent before
//! them has arrived ([`super::causal`]); they leave in the order they came.

use super::causal::{Knowledge, Received};
use super::context::{Arrival, Ctx, POLL, is_control};
use super::keys::Envelope;
use anyhow::Result;
use caravan::relay::Inlet;
use crossbeam::channel::{Receiver, RecvTimeoutError};
use iceoryx2::prelude::ipc;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::time::{Duration, Instant};

/// A control message held until what was sent before it is in.
struct Held {
    topic: String,
    envelope: Envelope,
    knowledge: Knowledge,
    wire: Vec<u8>,
    since: Instant,
}

/// After this long, a held message waits for something that was lost (or counted wrong): the
/// run could no longer be the single-host one, so the group fails.
const HELD_TOO_LONG: Duration = Duration::from_secs(20);

struct Inbound<'a> {
    ctx: &'a Ctx,
    iox: iceoryx2::node::Node<ipc::Service>,
    inlets: BTreeMap<String, Box<dyn Inlet>>,
    /// Topics whose messages cannot be published here (the failure was said once).
    refused: BTreeSet<String>,
}

pub(super) fn run(ctx: &Ctx, arrivals: Receiver<Arrival>) -> Result<()> {
    let mut inbound = Inbound {
        iox: ctx.iox_node()?,
        ctx,
        inlets: BTreeMap::new(),
        refused: BTreeSet::new(),
    };
    let mut got = Received::default();
    let mut held: VecDeque<Held> = VecDeque::new();
    let mut failed = false;
    while ctx.is_running() {
        match arrivals.recv_timeout(POLL) {
            Ok(Arrival::Message {
                topic,
                mut envelope,
                wire,
            }) => match envelope.knowledge.take() {
                Some(knowledge) => {
                    ctx.knowledge.lock().unwrap().merge(&knowledge);
                    held.push_back(Held {
                        topic,
                        envelope,
                        knowledge,
                        wire,
                        since: Instant::now(),
                    });
                }
                None => {
                    let from = envelope.host.clone();
                    inbound.deliver(&topic, &envelope, &wire)?;
                    inbound.measure(&envelope);
                    *got.messages.entry(from).or_default() += 1;
                }
            },
            Ok(Arrival::Handled) | Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return Ok(()),
        }
        if held.is_empty() {
            continue;
        }
        got.wants = ctx.wants_handled.lock().unwrap().clone();
        while let Some(front) = held.front() {
            if !front.knowledge.is_met(ctx.host(), &got) {
                if !failed && front.since.elapsed() > HELD_TOO_LONG {
                    failed = true;
                    (ctx.failed)(format!(
                        "bridge of host '{}': a lockstep message on '{}' from host '{}' waited {HELD_TOO_LONG:?} for what was sent before it, which never came (it needs {}; this host has {:?})",
                        ctx.host(),
                        front.topic,
                        front.envelope.host,
                        front.knowledge.encode(),
                        got
                    ));
                }
                break;
            }
            let h = held.pop_front().expect("a held message");
            inbound.deliver(&h.topic, &h.envelope, &h.wire)?;
        }
    }
    Ok(())
}

impl Inbound<'_> {
    /// Notes how long a message took from its publisher's send to its publication here. The
    /// two wall clocks are two machines' (one in tests): a message that seems to arrive before
    /// it was sent says the clocks disagree, and counts as 0. An announcement (no send time)
    /// is not a message.
    fn measure(&self, envelope: &Envelope) {
        let sent = envelope.header.send_wall_ns;
        if sent == 0 {
            return;
        }
        let latency = caravan::wall_clock_ns().saturating_sub(sent);
        let mut network = self.ctx.network.lock().unwrap();
        network
            .entry(envelope.host.clone())
            .or_insert_with(|| caravan::network::LinkStats {
                from: envelope.host.clone(),
                to: self.ctx.host().to_string(),
                ..Default::default()
            })
            .record(Some(latency));
    }

    /// Publishes one message here; an empty one only makes its topic.
    fn deliver(&mut self, topic: &str, envelope: &Envelope, wire: &[u8]) -> Result<()> {
        let ctx = self.ctx;
        if self.refused.contains(topic) {
            return Ok(());
        }
        let read_as = ctx.reading.lock().unwrap().get(topic).cloned();
        if let Some(read_as) = read_as.filter(|t| *t != envelope.type_name) {
            self.refused.insert(topic.to_string());
            (ctx.failed)(format!(
                "topic '{topic}': host '{}' publishes it as {}, but processes of host '{}' read it as {read_as}; publisher and subscribers of a topic must use one message type",
                envelope.host,
                envelope.type_name,
                ctx.host()
            ));
            return Ok(());
        }
        if !self.inlets.contains_key(topic) {
            // The sending host knows the type even when no process of this host uses it.
            let inlet = super::types::learn(ctx, &envelope.type_name).and_then(|()| {
                Ok(caravan::relay::open_inlet(
                    &self.iox,
                    topic,
                    &envelope.type_name,
                    envelope.delivery,
                )?)
            });
            match inlet {
                Ok(inlet) => {
                    self.inlets.insert(topic.to_string(), inlet);
                }
                Err(e) => {
                    self.refused.insert(topic.to_string());
                    (ctx.failed)(format!(
                        "topic '{topic}': host '{}' sends it, but host '{}' cannot publish it: {e}",
                        envelope.host,
                        ctx.host()
                    ));
                    return Ok(());
                }
            }
        }
        if wire.is_empty() {
            return Ok(());
        }
        if !is_control(topic) {
            // Its node runs elsewhere: what it publishes here is not sent back.
            ctx.remote.lock().unwrap().insert(envelope.header.source_id);
        }
        self.inlets[topic].publish(&envelope.header, wire)?;
        Ok(())
    }
}
