//! Topics between hosts. Each host says which topics its processes read (a `want` token per
//! topic, with its type and delivery contract); every other host then subscribes to that
//! topic on its own shared memory (creating the topic if no process made it yet, so nothing
//! its publishers send from then on is missed) and puts each message on zenoh, where the
//! reading host's bridge publishes it again, header untouched.
//!
//! Each host's zenoh subscriber for everything sent to it is declared before any `want`, and
//! both travel in order over one connection, so a host's first forwarded message already
//! finds it: a topic's messages reach a host from the moment its reader is known there (each
//! reading host has a subscriber of its own on the sending host, and
//! [`caravan::Publisher::subscribers`] counts it), as a subscriber on one host gets what is
//! published after it came.
//!
//! Two threads per host, each with its own iceoryx2 node (ports stay on the thread that made
//! them): [`outbound`](super::outbound) finds the topics read here, and sends what other hosts
//! read; [`inbound`](super::inbound) publishes what arrives. A message whose source is a
//! process of another host is never sent on, so a topic published on several hosts does not
//! loop.
//!
//! Lockstep: the clock host's launcher runs the scheduler and records the whole group. Its
//! `record` token asks every host for every topic; the scheduler's `hello` / `done` and each
//! node's `grant` cross like any topic read on another host, and are held on arrival until
//! the data sent before them has arrived ([`super::causal`]), so a node never steps before
//! the messages it is meant to see are in, and the recording is the one a single host makes.
//!
//! Contracts: messages of a lossless topic all arrive, in order per publisher (zenoh's
//! blocking congestion control over one TCP link, and a queue in the reading bridge that
//! never drops); but a publisher does not wait for a slow reader on another host, as it does
//! for one on its own: the reading bridge queues for it. Latest topics cross unchanged.

use super::causal::Knowledge;
pub use super::context::RelayConfig;
use super::context::{Arrival, Ctx};
use super::keys::{self, Envelope};
use super::z;
use super::{inbound, outbound};
use anyhow::Result;
use caravan::network::LinkStats;
use crossbeam::channel::{Receiver, Sender, unbounded};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;

/// What a relay thread runs.
type Body = Box<dyn FnOnce(&Ctx) -> Result<()> + Send>;

/// The running relay of one host.
pub struct Relay {
    ctx: Arc<Ctx>,
    threads: usize,
    /// One message per thread that ended.
    ended: Receiver<()>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    /// Answers the other hosts' questions for this host's message types.
    _types: zenoh::query::Queryable<()>,
}

impl Relay {
    pub fn start(
        session: zenoh::Session,
        cfg: RelayConfig,
        failed: impl Fn(String) + Send + Sync + 'static,
    ) -> Result<Self> {
        let ctx = Arc::new(Ctx {
            session,
            remote: Mutex::new(cfg.remote.clone()),
            cfg,
            running: AtomicBool::new(true),
            own_nodes: Mutex::new(Vec::new()),
            knowledge: Mutex::new(Knowledge::default()),
            wants_handled: Mutex::new(BTreeMap::new()),
            reading: Mutex::new(BTreeMap::new()),
            network: Mutex::new(BTreeMap::new()),
            failed: Box::new(failed),
        });
        let (tx, rx) = unbounded();
        // Before any wish to read is said: what is sent here because of it finds a reader.
        let subscriber = receive_all(&ctx, tx.clone())?;
        let types = super::types::serve(&ctx)?;
        let (ended_tx, ended) = unbounded();
        let spawn = |name: &str, body: Body| {
            let ctx = ctx.clone();
            let ended = ended_tx.clone();
            std::thread::Builder::new()
                .name(name.to_string())
                .spawn(move || {
                    if let Err(e) = body(&ctx) {
                        (ctx.failed)(format!("bridge of host '{}': {e:#}", ctx.host()));
                    }
                    let _ = ended.send(());
                })
        };
        spawn("bridge-out", Box::new(move |ctx| outbound::run(ctx, tx)))?;
        spawn("bridge-in", Box::new(move |ctx| inbound::run(ctx, rx)))?;
        Ok(Self {
            ctx,
            threads: 2,
            ended,
            _subscriber: subscriber,
            _types: types,
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
                break;
            }
        }
        if let Err(e) = self.save_network() {
            eprintln!("caravan: warning: cannot save the network's statistics: {e:#}");
        }
    }

    fn save_network(&self) -> Result<()> {
        let stats: Vec<LinkStats> = self.ctx.network.lock().unwrap().values().cloned().collect();
        if stats.is_empty() {
            return Ok(());
        }
        let dir = &self.ctx.cfg.stats_dir;
        std::fs::create_dir_all(dir)?;
        let path = dir.join(format!("{}.json", self.ctx.host()));
        std::fs::write(&path, serde_json::to_vec(&stats)?)?;
        Ok(())
    }
}

/// Subscribes to every message other hosts send this one; they queue for the inbound thread.
fn receive_all(ctx: &Ctx, arrivals: Sender<Arrival>) -> Result<zenoh::pubsub::Subscriber<()>> {
    let prefix = keys::topic(ctx.group(), ctx.host(), "");
    z(ctx
        .session
        .declare_subscriber(format!("{prefix}**"))
        .callback(move |sample| {
            let Some(topic) = sample.key_expr().as_str().strip_prefix(&prefix) else {
                return;
            };
            let Some(envelope) = sample
                .attachment()
                .and_then(|a| Envelope::parse(&a.to_bytes()))
            else {
                return;
            };
            // Never blocks zenoh's receiving thread: the inbound thread queues.
            let _ = arrivals.send(Arrival::Message {
                topic: topic.to_string(),
                envelope,
                wire: sample.payload().to_bytes().into_owned(),
            });
        })
        .wait())
}
