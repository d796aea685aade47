//! The sending side of a host's relay: finds the topics this host's processes read and asks
//! the other hosts for them (`want` tokens), and sends what the other hosts read, or record.
//!
//! Lockstep control messages (a node's hello and step reports, the clock host's grants) are
//! taken first and sent last, each with what this host knows was sent ([`super::causal`]):
//! every message published before them is on its way by then. A node's hello is sent only
//! after this host has looked for the topics the node opened, so the wishes to read them are
//! said, and counted, before the node can be granted a step.

use super::context::{Arrival, Ctx, is_control};
use super::keys::{self, Envelope, Want};
use super::z;
use anyhow::Result;
use caravan::discovery::{discovery_interval, listen_until, services_changed};
use caravan::relay::Outlet;
use caravan::{Delivery, Header};
use crossbeam::channel::Sender;
use iceoryx2::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;
use zenoh::Wait;
use zenoh::handlers::FifoChannel;
use zenoh::qos::CongestionControl;
use zenoh::sample::{Sample, SampleKind};

/// A topic another host reads or records, as this host sends it to that host.
struct Outgoing {
    outlet: Box<dyn Outlet>,
    listener: iceoryx2::port::listener::Listener<ipc::Service>,
    publisher: zenoh::pubsub::Publisher<'static>,
    type_name: String,
    delivery: Delivery,
}

/// A control message taken from its topic, to be sent after the data before it.
struct Control {
    key: (String, String),
    header: Header,
    wire: Vec<u8>,
}

struct Outbound<'a> {
    ctx: &'a Ctx,
    iox: iceoryx2::node::Node<ipc::Service>,
    /// Outgoing topics by (topic, receiving host).
    sending: BTreeMap<(String, String), Outgoing>,
    /// Topics read here, with the token that says so.
    reading: BTreeMap<String, zenoh::liveliness::LivelinessToken>,
    /// Hosts that record the whole group: every topic goes to them.
    recorders: BTreeSet<String>,
    arrivals: Sender<Arrival>,
    /// When the services last changed as of the last listing of topics.
    services: Option<std::time::SystemTime>,
    /// The topics as last listed, and those of them held open to read their ports: a look
    /// for topics lists and opens services only after one was made or removed, so it does
    /// not hold up the messages this thread forwards.
    topics: Vec<caravan::tap::TopicInfo>,
    watched: BTreeMap<String, caravan::tap::TopicWatch>,
}

pub(super) fn run(ctx: &Ctx, arrivals: Sender<Arrival>) -> Result<()> {
    let root = keys::root(ctx.group());
    let watch = |what: &str| {
        z(ctx
            .session
            .liveliness()
            .declare_subscriber(format!("{root}/{what}"))
            .history(true)
            .with(FifoChannel::new(1024))
            .wait())
    };
    let wants = watch("want/**")?;
    let records = watch("record/*")?;
    let mut out = Outbound {
        iox: ctx.iox_node()?,
        ctx,
        sending: BTreeMap::new(),
        reading: BTreeMap::new(),
        recorders: BTreeSet::new(),
        arrivals,
        services: None,
        topics: Vec::new(),
        watched: BTreeMap::new(),
    };
    let _record = match &ctx.cfg.clock_host {
        Some(clock) if clock == ctx.host() => Some(out.declare(keys::record(ctx.group(), clock))?),
        _ => None,
    };
    let started = Instant::now();
    let mut samples = Vec::new();
    let mut control = Vec::new();
    while ctx.is_running() {
        for sample in samples.drain(..) {
            out.on_sample(sample)?;
        }
        out.discover()?;
        let next_discovery = Instant::now() + discovery_interval(started);
        loop {
            let listeners: Vec<_> = out.sending.values().map(|o| &o.listener).collect();
            let woken = listen_until::<anyhow::Error, _>(
                &listeners,
                next_discovery,
                SignalHandlingMode::Disabled,
                || {
                    out.take_control(&mut control)?;
                    // Reports and grants go at once, without leaving the wait (whose set-up
                    // costs a system call per topic); a hello, or a new topic, needs a look
                    // for topics first, outside it.
                    if control.is_empty() || out.must_discover(&control) {
                        out.send_data()?;
                    } else {
                        out.send_taken(&mut control)?;
                    }
                    for subscriber in [&wants, &records] {
                        while let Ok(Some(sample)) = subscriber.try_recv() {
                            samples.push(sample);
                        }
                    }
                    Ok(!control.is_empty() || !samples.is_empty() || !ctx.is_running())
                },
            )?;
            drop(listeners);
            if !control.is_empty() {
                out.discover()?;
                out.send_taken(&mut control)?;
            }
            if !woken || !samples.is_empty() || !ctx.is_running() {
                break;
            }
        }
    }
    Ok(())
}

impl Outbound<'_> {
    /// Declares a liveliness token that asks for messages, and counts it.
    fn declare(&self, key: String) -> Result<zenoh::liveliness::LivelinessToken> {
        let token = z(self.ctx.session.liveliness().declare_token(key).wait())?;
        let me = self.ctx.host().to_string();
        *self
            .ctx
            .knowledge
            .lock()
            .unwrap()
            .wants
            .entry(me)
            .or_default() += 1;
        Ok(token)
    }

    /// Another host starts or stops reading a topic, or recording the group.
    fn on_sample(&mut self, sample: Sample) -> Result<()> {
        let key = sample.key_expr().as_str();
        let put = sample.kind() == SampleKind::Put;
        let host = if let Some(want) = Want::parse(self.ctx.group(), key) {
            if want.host == self.ctx.host() {
                return Ok(());
            }
            let k = (want.topic.clone(), want.host.clone());
            if !put {
                // Unread, a lossless outlet would fill and hold up the publishers here; but a
                // host that records the group still gets the topic.
                if !self.recorders.contains(&want.host) || is_control(&want.topic) {
                    self.sending.remove(&k);
                }
                return Ok(());
            }
            if is_control(&want.topic) && !self.sends_control(&want) {
                // Counted all the same: the wish was seen and acted on.
            } else if !self.sending.contains_key(&k)
                && let Err(e) = self.open(&want.topic, &want.host, &want.type_name, want.delivery())
            {
                (self.ctx.failed)(format!(
                    "topic '{}': host '{}' reads it as {}, but host '{}' cannot send it so: {e:#}",
                    want.topic,
                    want.host,
                    want.type_name,
                    self.ctx.host()
                ));
            }
            want.host
        } else if key.starts_with(&keys::record(self.ctx.group(), "")) {
            let host = keys::last(key).to_string();
            if host == self.ctx.host() || !put {
                return Ok(());
            }
            self.recorders.insert(host.clone());
            self.discover()?;
            host
        } else {
            // Another version's key: nothing this one can act on.
            return Ok(());
        };
        *self
            .ctx
            .wants_handled
            .lock()
            .unwrap()
            .entry(host)
            .or_default() += 1;
        let _ = self.arrivals.send(Arrival::Handled);
        Ok(())
    }

    /// Whether this host sends a lockstep control topic to the host that asks: hellos and
    /// reports go only to the clock host, grants only come from it. A control message that
    /// arrived here is thus never sent on, whoever else reads it.
    fn sends_control(&self, want: &Want) -> bool {
        let Some(clock) = &self.ctx.cfg.clock_host else {
            return false;
        };
        let to_clock = [
            caravan::schemas::lockstep::HELLO,
            caravan::schemas::lockstep::DONE,
        ]
        .contains(&want.topic.as_str());
        if to_clock {
            want.host == *clock && self.ctx.host() != clock
        } else {
            self.ctx.host() == clock
        }
    }

    /// Whether this host may send control messages: a follower waits until it sends the clock
    /// host every topic, so the clock host knows them all before a node is stepped.
    fn control_ready(&self) -> bool {
        match &self.ctx.cfg.clock_host {
            Some(clock) if clock != self.ctx.host() => self.recorders.contains(clock),
            _ => true,
        }
    }

    /// Starts sending `topic` to `host`, and tells it the topic is coming (an empty message),
    /// so the topic exists there before anything that follows.
    fn open(&mut self, topic: &str, host: &str, type_name: &str, delivery: Delivery) -> Result<()> {
        // The reading host knows the type even when this host's publisher has not started.
        super::types::learn(self.ctx, type_name)?;
        let outlet = caravan::relay::open_outlet(&self.iox, topic, type_name, delivery)?;
        let listener = caravan::tap::open_listener(&self.iox, topic)?;
        let publisher = z(self
            .ctx
            .session
            .declare_publisher(keys::topic(self.ctx.group(), host, topic))
            .congestion_control(CongestionControl::Block)
            .express(true)
            .wait())?;
        let o = Outgoing {
            outlet,
            listener,
            publisher,
            type_name: type_name.to_string(),
            delivery,
        };
        self.put(&o, host, Header::default(), Vec::new(), false)?;
        self.sending
            .insert((topic.to_string(), host.to_string()), o);
        Ok(())
    }

    /// Puts one message on zenoh; a data message is counted.
    fn put(
        &self,
        o: &Outgoing,
        to: &str,
        header: Header,
        wire: Vec<u8>,
        control: bool,
    ) -> Result<()> {
        let envelope = Envelope {
            header,
            type_name: o.type_name.clone(),
            host: self.ctx.host().to_string(),
            delivery: o.delivery,
            knowledge: control.then(|| self.ctx.knowledge.lock().unwrap().clone()),
        };
        if let Err(e) = o.publisher.put(wire).attachment(envelope.to_bytes()).wait() {
            anyhow::bail!("topic '{}': cannot send: {e}", o.outlet.topic());
        }
        if !control {
            let me = self.ctx.host().to_string();
            let mut knowledge = self.ctx.knowledge.lock().unwrap();
            *knowledge.sent.entry((me, to.to_string())).or_default() += 1;
        }
        Ok(())
    }

    /// Takes the waiting control messages.
    fn take_control(&self, into: &mut Vec<Control>) -> Result<()> {
        if !self.control_ready() {
            // Left in their topics until the clock host's record token is handled.
            return Ok(());
        }
        for (key, o) in self.sending.iter().filter(|(k, _)| is_control(&k.0)) {
            o.outlet.drain(&mut |header, wire| {
                into.push(Control {
                    key: key.clone(),
                    header,
                    wire,
                })
            })?;
        }
        Ok(())
    }

    /// Puts every waiting data message of the topics other hosts read on zenoh.
    fn send_data(&self) -> Result<()> {
        for ((_, to), o) in self.sending.iter().filter(|(k, _)| !is_control(&k.0)) {
            let mut result = Ok(());
            o.outlet.drain(&mut |header, wire| {
                if result.is_ok() && !self.ctx.remote.lock().unwrap().contains(&header.source_id) {
                    result = self.put(o, to, header, wire, false);
                }
            })?;
            result?;
        }
        Ok(())
    }

    /// Whether topics must be looked for before `control` goes: it holds a hello, or a topic
    /// was made or removed since the last look.
    fn must_discover(&self, control: &[Control]) -> bool {
        let hello = control
            .iter()
            .any(|c| c.key.0 == caravan::schemas::lockstep::HELLO);
        hello || services_changed(&self.ctx.cfg.iceoryx) != self.services
    }

    /// Sends the data waiting, then `control`: every message published before it is on its
    /// way first.
    fn send_taken(&self, control: &mut Vec<Control>) -> Result<()> {
        self.send_data()?;
        for c in control.drain(..) {
            if let Some(o) = self.sending.get(&c.key) {
                self.put(o, &c.key.1, c.header, c.wire, true)?;
            }
        }
        Ok(())
    }

    /// Finds the topics this host's processes read, and asks the other hosts for them; and
    /// sends every topic to the hosts that record the group.
    fn discover(&mut self) -> Result<()> {
        let ctx = self.ctx;
        let lockstep = ctx.cfg.clock_host.is_some();
        let me = std::process::id() as i64;
        let changed = services_changed(&ctx.cfg.iceoryx);
        if changed.is_none() || changed != self.services {
            // Read before listing: a change during the listing is listed next time.
            self.services = changed;
            self.topics = caravan::tap::list_topics(&ctx.cfg.iceoryx, lockstep)?;
            self.topics
                .retain(|t| !t.name.starts_with("caravan/") || is_control(&t.name));
            // Opened again: a topic may have been removed and made again, of another type.
            self.watched.clear();
        }
        let mut read_now = BTreeSet::new();
        for topic in self.topics.clone() {
            let control = is_control(&topic.name);
            if !self.watched.contains_key(&topic.name) {
                match caravan::tap::watch_topic(&self.iox, &topic.name, &topic.type_name) {
                    Ok(watch) => {
                        self.watched.insert(topic.name.clone(), watch);
                    }
                    // The topic may vanish between listing and opening, or be busy: as it
                    // was, until the next look (a wish to read withdrawn and said again would
                    // count twice).
                    Err(_) => {
                        if self.reading.contains_key(&topic.name) {
                            read_now.insert(topic.name.clone());
                        }
                        continue;
                    }
                }
            }
            let ports = self.watched[&topic.name].ports();
            // Ports of this launcher (recorder, bridge) read for others, not for a process;
            // but its scheduler reads the nodes' reports.
            let readers = ports
                .subscribers
                .iter()
                .filter(|id| match control {
                    true => !ctx.is_own(id),
                    false => id
                        .pid::<ipc::Service>()
                        .map_or(true, |p| p.value() as i64 != me),
                })
                .count();
            if readers > 0 {
                read_now.insert(topic.name.clone());
                if !self.reading.contains_key(&topic.name) {
                    let want = Want {
                        host: ctx.host().to_string(),
                        type_name: topic.type_name.clone(),
                        lossless: ports.lossless,
                        depth: ports.depth,
                        topic: topic.name.clone(),
                    };
                    // Known before the first message can come.
                    ctx.reading
                        .lock()
                        .unwrap()
                        .insert(topic.name.clone(), topic.type_name.clone());
                    let token = self.declare(want.key(ctx.group()))?;
                    self.reading.insert(topic.name.clone(), token);
                }
            }
            let used_here = ports
                .publishers
                .iter()
                .chain(&ports.subscribers)
                .any(|id| !ctx.is_own(id));
            if control || !used_here {
                continue;
            }
            let delivery = if ports.lossless {
                Delivery::Lossless { depth: ports.depth }
            } else {
                Delivery::Latest { depth: ports.depth }
            };
            for host in self.recorders.clone() {
                if !self
                    .sending
                    .contains_key(&(topic.name.clone(), host.clone()))
                    && let Err(e) = self.open(&topic.name, &host, &topic.type_name, delivery)
                {
                    (ctx.failed)(format!(
                        "topic '{}': host '{}' records the group, but host '{}' cannot send it the topic: {e:#}",
                        topic.name,
                        host,
                        ctx.host()
                    ));
                }
            }
        }
        self.reading.retain(|topic, _| read_now.contains(topic));
        ctx.reading
            .lock()
            .unwrap()
            .retain(|topic, _| read_now.contains(topic));
        Ok(())
    }
}
