//! Topics between hosts. Each host says which topics its processes read (a `want` token per
//! topic, with its type and delivery contract); every other host then subscribes to that
//! topic on its own shared memory (creating the topic if no process made it yet, so nothing
//! its publishers send from then on is missed) and puts each message on zenoh, where the
//! reading host's bridge publishes it again, header untouched.
//!
//! The reading host's zenoh subscriber is declared before its `want`, and both travel in order
//! over one connection, so a host's first forwarded message already finds it: a topic's
//! messages reach a host from the moment its reader is known there (each reading host has a
//! subscriber of its own on the sending host, and [`caravan::Publisher::subscribers`] counts
//! it), as a subscriber on one host gets what is published after it came.
//!
//! Two threads per host, each with its own iceoryx2 node (ports stay on the thread that made
//! them): `outbound` finds the topics read here, and sends what other hosts read; `inbound`
//! publishes what arrives. A message whose source is a process of another host is never sent
//! on, so a topic published on several hosts does not loop.
//!
//! Contracts: messages of a lossless topic all arrive, in order per publisher (zenoh's
//! blocking congestion control over one TCP link, and a queue in the reading bridge that
//! never drops); but a publisher does not wait for a slow reader on another host, as it does
//! for one on its own: the reading bridge queues for it. Latest topics cross unchanged.

use super::keys::{self, Want};
use super::z;
use crate::run::driver::{discovery_interval, listen_until};
use anyhow::Result;
use caravan::Header;
use caravan::relay::{Inlet, Outlet};
use crossbeam::channel::{Receiver, RecvTimeoutError, Sender, unbounded};
use iceoryx2::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::handlers::FifoChannel;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

/// How long a thread waits before it looks at the stop flag again.
const POLL: Duration = Duration::from_millis(250);

/// What both threads share.
struct Ctx {
    session: zenoh::Session,
    group: String,
    host: String,
    iceoryx: iceoryx2::config::Config,
    running: AtomicBool,
    /// Node ids of processes on other hosts: their messages are not sent on.
    remote: Mutex<BTreeSet<u64>>,
    failed: Box<dyn Fn(String) + Send + Sync>,
}

/// A message from another host, for a topic read here.
struct Arrival {
    want: Want,
    /// The sending host.
    from: String,
    from_type: String,
    header: Header,
    wire: Vec<u8>,
}

/// What a relay thread runs.
type Body = Box<dyn FnOnce(&Ctx) -> Result<()> + Send>;

/// The running relay of one host.
pub struct Relay {
    ctx: Arc<Ctx>,
    threads: usize,
    /// One message per thread that ended.
    ended: Receiver<()>,
}

impl Relay {
    pub fn start(
        session: zenoh::Session,
        group: &str,
        host: &str,
        iceoryx: &iceoryx2::config::Config,
        remote: BTreeSet<u64>,
        failed: impl Fn(String) + Send + Sync + 'static,
    ) -> Result<Self> {
        let ctx = Arc::new(Ctx {
            session,
            group: group.to_string(),
            host: host.to_string(),
            iceoryx: iceoryx.clone(),
            running: AtomicBool::new(true),
            remote: Mutex::new(remote),
            failed: Box::new(failed),
        });
        let (tx, rx) = unbounded();
        let (ended_tx, ended) = unbounded();
        let spawn = |name: &str, body: Body| {
            let ctx = ctx.clone();
            let ended = ended_tx.clone();
            std::thread::Builder::new()
                .name(name.to_string())
                .spawn(move || {
                    if let Err(e) = body(&ctx) {
                        (ctx.failed)(format!("bridge of host '{}': {e:#}", ctx.host));
                    }
                    let _ = ended.send(());
                })
        };
        spawn("bridge-out", Box::new(move |ctx| outbound(ctx, tx)))?;
        spawn("bridge-in", Box::new(move |ctx| inbound(ctx, rx)))?;
        Ok(Self {
            ctx,
            threads: 2,
            ended,
        })
    }

    /// Stops both threads. One may be held up publishing to a lossless topic whose reader
    /// was killed; it is left behind after a few seconds rather than hanging the launcher.
    pub fn stop(self) {
        self.ctx.running.store(false, Ordering::Relaxed);
        let deadline = Instant::now() + Duration::from_secs(3);
        for _ in 0..self.threads {
            if self.ended.recv_deadline(deadline).is_err() {
                eprintln!("caravan: warning: a bridge thread did not stop within 3 s; leaving it");
                return;
            }
        }
    }
}

fn iox_node(ctx: &Ctx) -> Result<iceoryx2::node::Node<ipc::Service>> {
    NodeBuilder::new()
        .config(&ctx.iceoryx)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("bridge node: {e:?}"))
}

/// A topic another host reads, as this host sends it to that host.
struct Outgoing {
    outlet: Box<dyn Outlet>,
    listener: iceoryx2::port::listener::Listener<ipc::Service>,
    publisher: zenoh::pubsub::Publisher<'static>,
    type_name: String,
}

/// Outgoing topics by (topic, reading host).
type Sending = BTreeMap<(String, String), Outgoing>;

/// A topic read here, as this host asks for it.
struct Reading {
    _token: zenoh::liveliness::LivelinessToken,
    _subscriber: zenoh::pubsub::Subscriber<()>,
}

fn outbound(ctx: &Ctx, arrivals: Sender<Arrival>) -> Result<()> {
    let iox = iox_node(ctx)?;
    let wants = z(ctx
        .session
        .liveliness()
        .declare_subscriber(format!("{}/want/**", keys::root(&ctx.group)))
        .history(true)
        .with(FifoChannel::new(1024))
        .wait())?;
    let mut sending = Sending::new();
    let mut reading: BTreeMap<String, Reading> = BTreeMap::new();
    let started = Instant::now();
    let mut pending = Vec::new();
    while ctx.running.load(Ordering::Relaxed) {
        for sample in pending.drain(..) {
            remote_want(ctx, &iox, &mut sending, sample);
        }
        discover(ctx, &iox, &mut reading, &arrivals)?;
        let next_discovery = Instant::now() + discovery_interval(started);
        let listeners: Vec<_> = sending.values().map(|o| &o.listener).collect();
        listen_until(
            &listeners,
            next_discovery,
            SignalHandlingMode::Disabled,
            || {
                send(ctx, &sending)?;
                while let Ok(Some(sample)) = wants.try_recv() {
                    pending.push(sample);
                }
                Ok(!pending.is_empty() || !ctx.running.load(Ordering::Relaxed))
            },
        )?;
    }
    Ok(())
}

/// Puts every waiting message of the topics other hosts read on zenoh.
fn send(ctx: &Ctx, sending: &Sending) -> Result<()> {
    for o in sending.values() {
        let mut failure = None;
        o.outlet.drain(&mut |header, wire| {
            if failure.is_some() || ctx.remote.lock().unwrap().contains(&header.source_id) {
                return;
            }
            let attachment = keys::attachment(&header, &o.type_name, &ctx.host);
            if let Err(e) = o.publisher.put(wire).attachment(attachment).wait() {
                failure = Some(e);
            }
        })?;
        if let Some(e) = failure {
            anyhow::bail!("topic '{}': cannot send: {e}", o.outlet.topic());
        }
    }
    Ok(())
}

/// A host starts or stops reading a topic.
fn remote_want(
    ctx: &Ctx,
    iox: &iceoryx2::node::Node<ipc::Service>,
    sending: &mut Sending,
    sample: zenoh::sample::Sample,
) {
    let Some(want) = Want::parse(&ctx.group, sample.key_expr().as_str()) else {
        return;
    };
    if want.host == ctx.host {
        return;
    }
    let key = (want.topic.clone(), want.host.clone());
    if sample.kind() == SampleKind::Delete {
        // Unread, a lossless outlet would fill and hold up the publishers here.
        sending.remove(&key);
        return;
    }
    if sending.contains_key(&key) {
        return;
    }
    match outgoing(ctx, iox, &want) {
        Ok(o) => {
            sending.insert(key, o);
        }
        Err(e) => (ctx.failed)(format!(
            "topic '{}': host '{}' reads it as {}, but host '{}' cannot send it so: {e:#}",
            want.topic, want.host, want.type_name, ctx.host
        )),
    }
}

fn outgoing(ctx: &Ctx, iox: &iceoryx2::node::Node<ipc::Service>, want: &Want) -> Result<Outgoing> {
    let outlet = caravan::relay::open_outlet(iox, &want.topic, &want.type_name, want.delivery())?;
    let listener = caravan::tap::open_listener(iox, &want.topic)?;
    let publisher = z(ctx
        .session
        .declare_publisher(keys::topic(&ctx.group, &want.host, &want.topic))
        .congestion_control(CongestionControl::Block)
        .express(true)
        .wait())?;
    Ok(Outgoing {
        outlet,
        listener,
        publisher,
        type_name: want.type_name.clone(),
    })
}

/// Finds the topics this host's processes read, and asks the other hosts for them.
fn discover(
    ctx: &Ctx,
    iox: &iceoryx2::node::Node<ipc::Service>,
    reading: &mut BTreeMap<String, Reading>,
    arrivals: &Sender<Arrival>,
) -> Result<()> {
    let me = std::process::id() as i64;
    let mut read_now = BTreeSet::new();
    for topic in caravan::tap::list_topics(&ctx.iceoryx, false)? {
        // The topic may vanish between listing and opening.
        let Ok(ports) = caravan::tap::topic_ports(iox, &topic.name, &topic.type_name) else {
            continue;
        };
        // Ports of this launcher (recorder, bridge) read for others, not for a process.
        let readers = ports
            .subscribers
            .iter()
            .filter(|id| {
                id.pid::<ipc::Service>()
                    .map_or(true, |p| p.value() as i64 != me)
            })
            .count();
        if readers == 0 {
            continue;
        }
        read_now.insert(topic.name.clone());
        if reading.contains_key(&topic.name) {
            continue;
        }
        let want = Want {
            host: ctx.host.clone(),
            type_name: topic.type_name.clone(),
            lossless: ports.lossless,
            depth: ports.depth,
            topic: topic.name.clone(),
        };
        let subscriber = {
            let want = want.clone();
            let arrivals = arrivals.clone();
            z(ctx
                .session
                .declare_subscriber(keys::topic(&ctx.group, &ctx.host, &topic.name))
                .callback(move |sample| {
                    let Some(attachment) = sample.attachment().map(|a| a.to_bytes()) else {
                        return;
                    };
                    let Some((header, from_type, from)) = keys::parse_attachment(&attachment)
                    else {
                        return;
                    };
                    // Never blocks zenoh's receiving thread: the inbound thread queues.
                    let _ = arrivals.send(Arrival {
                        want: want.clone(),
                        from: from.to_string(),
                        from_type: from_type.to_string(),
                        header,
                        wire: sample.payload().to_bytes().into_owned(),
                    });
                })
                .wait())?
        };
        let token = z(ctx
            .session
            .liveliness()
            .declare_token(want.key(&ctx.group))
            .wait())?;
        reading.insert(
            topic.name.clone(),
            Reading {
                _token: token,
                _subscriber: subscriber,
            },
        );
    }
    reading.retain(|topic, _| read_now.contains(topic));
    Ok(())
}

fn inbound(ctx: &Ctx, arrivals: Receiver<Arrival>) -> Result<()> {
    let iox = iox_node(ctx)?;
    let mut inlets: BTreeMap<String, Box<dyn Inlet>> = BTreeMap::new();
    let mut refused = BTreeSet::new();
    while ctx.running.load(Ordering::Relaxed) {
        let a = match arrivals.recv_timeout(POLL) {
            Ok(a) => a,
            Err(RecvTimeoutError::Timeout) if ctx.running.load(Ordering::Relaxed) => continue,
            Err(_) => return Ok(()),
        };
        let topic = &a.want.topic;
        if a.from_type != a.want.type_name {
            if refused.insert(topic.clone()) {
                (ctx.failed)(format!(
                    "topic '{topic}': host '{}' publishes it as {}, but processes of host '{}' read it as {}; publisher and subscribers of a topic must use one message type",
                    a.from, a.from_type, ctx.host, a.want.type_name
                ));
            }
            continue;
        }
        ctx.remote.lock().unwrap().insert(a.header.source_id);
        if !inlets.contains_key(topic) {
            let inlet =
                caravan::relay::open_inlet(&iox, topic, &a.want.type_name, a.want.delivery())?;
            inlets.insert(topic.clone(), inlet);
        }
        inlets[topic].publish(&a.header, &a.wire)?;
    }
    Ok(())
}
