//! State a node shares with its ports, and the iceoryx2 plumbing they have in common.

use crate::Error;
use caravan_schemas::{Header, Message};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// Node-wide state, shared (single-threaded) by the node and its publishers and subscribers.
pub(crate) struct Shared {
    pub iox: iceoryx2::node::Node<ipc::Service>,
    pub node_hash: u64,
    /// Simulated time of the current step, ns.
    pub now_ns: Cell<u64>,
    /// In lockstep, a message stamped t is visible from t + tick_ns on; 0 in realtime.
    pub tick_ns: Cell<u64>,
    pub lockstep: bool,
    /// Topic hashes published to since the last report, each with a bit for each step of the
    /// grant that did (bit j: its step j), for the lockstep scheduler.
    pub published: RefCell<Vec<(u64, u32)>>,
    /// Which step of its grant the node is taking (0 for the first), lockstep only.
    pub step_of_grant: Cell<u32>,
    /// A step published more than one message to one topic since the last report: a grant
    /// of several periods ends there (its readers' buffers hold one message per step ahead).
    pub burst: Cell<bool>,
    /// Messages lost by all subscribers (sequence gaps).
    pub missed: Cell<u64>,
    /// Wake-up listeners by topic, created with the first subscriber of each topic so that
    /// messages published before the step loop starts still wake it.
    pub listeners: RefCell<Vec<(String, Rc<Listener<ipc::Service>>)>>,
    /// The emulated network around this node (links into its host, its CPU slowdown);
    /// `None` when there is nothing to emulate.
    pub net: Option<crate::network::NodeNet>,
    /// Earliest time a message held by a subscriber becomes visible (simulated ns in
    /// lockstep, wall-clock ns in realtime); `u64::MAX` when none is held.
    pub next_arrival_ns: Cell<u64>,
    /// Whether a step is running (outside one: a node's set-up, its last status).
    pub in_step: Cell<bool>,
    /// The stepping thread's CPU time when the current step started, ns, for compute
    /// budgets; `None` outside a step or when this step's CPU clock is not read (always read
    /// with a CPU slowdown in lockstep, see `stats.rs`).
    pub step_cpu_started_ns: Cell<Option<u64>>,
    /// Counts what may put a message a step can see into a subscriber's port: a step's start
    /// and each message the node sends (it may read its own topic). In lockstep every message
    /// of the group's nodes that a step can see is in before the step starts, so a subscriber
    /// that found its port empty at this count does not look again (each look walks
    /// iceoryx2's publisher slots). A message from outside the group (`caravan topic pub`,
    /// `caravan play`) comes when it comes: a step that looked before it sees it at the next.
    pub arrivals: Cell<u64>,
    /// What the node told the lockstep scheduler it touches (see [`Ports`]).
    pub ports: RefCell<Ports>,
}

/// The topics a node reads and publishes, as the lockstep scheduler learns them: it steps
/// a node early, beside nodes finishing an earlier time, only when they share no topic.
#[derive(Default)]
pub(crate) struct Ports {
    pub inputs: Vec<u64>,
    pub outputs: Vec<u64>,
    /// The smallest buffer depth of the topics in `outputs`; 0 while there are none.
    pub output_depth: usize,
    /// The node joined the schedule: a port opened from now on breaks its declaration.
    pub joined: bool,
    /// The lists are not the whole truth: a port opened after joining, an injector (it may
    /// publish anywhere), emulated links (messages wake it between ticks) or a CPU slowdown
    /// (messages stamped after the granted time).
    pub undeclared: bool,
}

impl Ports {
    fn add(list: &mut Vec<u64>, topic_hash: u64) {
        if !list.contains(&topic_hash) {
            list.push(topic_hash);
        }
    }

    pub fn input(&mut self, topic_hash: u64) {
        // Every node publishes its status, so a reader of it shares a topic with all of them.
        self.undeclared |= is_status(topic_hash);
        self.undeclared |= self.joined && !self.inputs.contains(&topic_hash);
        Self::add(&mut self.inputs, topic_hash);
    }

    /// A publisher of the topic hashed `topic_hash`, whose subscribers hold `depth` messages.
    pub fn output(&mut self, topic_hash: u64, depth: usize) {
        // Every node publishes its status; the recorder keeps it out of the file and the
        // report reads only the latest, so it does not order nodes.
        if is_status(topic_hash) {
            return;
        }
        self.undeclared |= self.joined && !self.outputs.contains(&topic_hash);
        Self::add(&mut self.outputs, topic_hash);
        self.output_depth = match self.output_depth {
            0 => depth,
            d => d.min(depth),
        };
    }
}

/// Whether `topic_hash` names the `status` topic every node publishes.
fn is_status(topic_hash: u64) -> bool {
    topic_hash == caravan_schemas::topics::status().name_hash()
}

impl Shared {
    /// The host's CPU slowdown when it stamps this node's messages (lockstep only): each
    /// message is then later by the step's CPU time so far times it, so every step's CPU
    /// clock is read (`stats.rs`).
    pub fn stamping_slowdown(&self) -> Option<f64> {
        self.net
            .as_ref()
            .and_then(|n| n.slowdown)
            .filter(|_| self.lockstep)
    }

    /// After a message on the topic hashed `topic_hash` was sent: in lockstep the scheduler
    /// learns of it with the step's report (and wakes the topic's triggered nodes); in
    /// realtime `notifier` wakes them.
    pub fn sent(&self, topic_hash: u64, notifier: &Notifier<ipc::Service>) {
        self.arrivals.set(self.arrivals.get() + 1);
        if self.lockstep {
            // Outside a step (a node's set-up, its last status) nothing is ahead of anyone: the
            // message marks no step, and is no burst.
            let bit = if self.in_step.get() {
                1u32.checked_shl(self.step_of_grant.get()).unwrap_or(0)
            } else {
                0
            };
            let mut list = self.published.borrow_mut();
            match list.iter_mut().find(|(t, _)| *t == topic_hash) {
                Some((_, steps)) => {
                    if *steps & bit != 0 {
                        self.burst.set(true);
                    }
                    *steps |= bit;
                }
                None => list.push((topic_hash, bit)),
            }
        } else {
            wake(notifier);
        }
    }

    /// The wake-up listener of `topic`, created on first use.
    pub fn listener(&self, topic: &str) -> Result<Rc<Listener<ipc::Service>>, Error> {
        let mut listeners = self.listeners.borrow_mut();
        if let Some((_, l)) = listeners.iter().find(|(t, _)| t == topic) {
            return Ok(l.clone());
        }
        let l = Rc::new(listener(&self.iox, topic)?);
        listeners.push((topic.to_string(), l.clone()));
        Ok(l)
    }

    pub fn is_visible(&self, header: &Header) -> bool {
        !self.lockstep || header.stamp_ns + self.tick_ns.get() <= self.now_ns.get()
    }
}

pub(crate) fn service_name(topic: &str) -> Result<ServiceName, Error> {
    ServiceName::new(topic).map_err(|e| Error::topic(topic, format!("not a valid name: {e:?}")))
}

/// The builder of a topic's publish-subscribe service: its payload and Caravan's header.
fn pubsub_builder<T: Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &ServiceName,
) -> iceoryx2::service::builder::publish_subscribe::Builder<T, Header, ipc::Service> {
    iox.service_builder(name)
        .publish_subscribe::<T>()
        .user_header::<Header>()
}

/// A new topic's service made with `delivery`'s contract: latest-value topics overwrite the
/// oldest message, lossless ones make publishers wait; subscribers hold `depth` messages.
pub(crate) fn with_contract<P, H>(
    builder: iceoryx2::service::builder::publish_subscribe::Builder<P, H, ipc::Service>,
    delivery: crate::Delivery,
) -> iceoryx2::service::builder::publish_subscribe::Builder<P, H, ipc::Service>
where
    P: core::fmt::Debug + IceoryxSend + ?Sized,
    H: core::fmt::Debug + ZeroCopySend,
{
    let depth = delivery.depth();
    builder
        .enable_safe_overflow(!delivery.is_lossless())
        .subscriber_max_buffer_size(depth)
        .subscriber_max_borrowed_samples(depth.max(8))
        .history_size(0)
}

/// A publisher's behaviour when a subscriber's buffer is full: wait on a lossless topic,
/// drop the oldest on a latest-value one.
pub(crate) fn backpressure(lossless: bool) -> BackpressureStrategy {
    if lossless {
        BackpressureStrategy::RetryUntilDelivered
    } else {
        BackpressureStrategy::DiscardData
    }
}

/// The publish-subscribe builder of a topic, as [`open_pubsub`] hands it to its `shape`.
pub(crate) type PubSubBuilder<T> =
    iceoryx2::service::builder::publish_subscribe::Builder<T, Header, ipc::Service>;

/// Opens (or creates) the publish-subscribe service of a topic with its delivery contract, the
/// builder first given to `shape` (to size the service: a value `shape` sets is also what an
/// existing service must at least support).
pub(crate) fn open_pubsub<T: Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    delivery: crate::Delivery,
    shape: impl Fn(PubSubBuilder<T>) -> PubSubBuilder<T>,
) -> Result<PubSubFactory<ipc::Service, T, Header>, Error> {
    use iceoryx2::service::builder::publish_subscribe::{
        PublishSubscribeOpenError as Open, PublishSubscribeOpenOrCreateError as Either,
    };
    let name = service_name(topic)?;
    crate::types::register_type::<T>(iox.config()).map_err(|e| Error::topic(topic, e))?;
    repairing_hung(
        iox,
        || shape(with_contract(pubsub_builder::<T>(iox, &name), delivery)).open_or_create(),
        |e| matches!(e, Either::PublishSubscribeOpenError(Open::HangsInCreation)),
    )
    .map_err(|e| {
        Error::topic(
            topic,
            format!(
                "cannot open as {} ({:?}); another process uses this topic with a different \
                     message type or delivery contract",
                caravan_schemas::type_name::<T>(),
                e
            ),
        )
    })
}

/// The event builder of a topic, as [`open_event`] hands it to its `shape`.
pub(crate) type EventBuilder = iceoryx2::service::builder::event::Builder<ipc::Service>;

/// Opens (or creates) a topic's event service, its builder first given to `shape` (to size
/// it); a value `shape` sets is also what an existing service must at least support.
pub(crate) fn open_event(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    shape: impl Fn(EventBuilder) -> EventBuilder,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, Error> {
    use iceoryx2::service::builder::event::{
        EventOpenError as Open, EventOpenOrCreateError as Either,
    };
    let name = service_name(topic)?;
    repairing_hung(
        iox,
        || shape(iox.service_builder(&name).event()).open_or_create(),
        |e| matches!(e, Either::EventOpenError(Open::HangsInCreation)),
    )
    .map_err(|e| Error::topic(topic, format!("cannot open its event service: {e:?}")))
}

/// Runs `open`, and once more if it failed because a killed process left the service half
/// made (see [`crate::group::remove_hung_services`]); a restarted node then starts instead of
/// failing again on what its killed predecessor left.
pub(crate) fn repairing_hung<T, E>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    open: impl Fn() -> Result<T, E>,
    hung: impl Fn(&E) -> bool,
) -> Result<T, E> {
    match open() {
        Err(e) if hung(&e) => {
            let removed = crate::group::remove_hung_services(iox.config());
            if removed == 0 {
                return Err(e);
            }
            tracing::warn!(
                "removed {removed} service(s) that a killed process left half made; opening again"
            );
            open()
        }
        result => result,
    }
}

/// The notifier that wakes a topic's event-driven subscribers.
pub(crate) fn notifier(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
) -> Result<Notifier<ipc::Service>, Error> {
    notifier_shaped(iox, topic, |b| b)
}

/// [`notifier`] on an event service that `shape` sizes (see [`open_event`]).
pub(crate) fn notifier_shaped(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    shape: impl Fn(EventBuilder) -> EventBuilder,
) -> Result<Notifier<ipc::Service>, Error> {
    open_event(iox, topic, shape)?
        .notifier_builder()
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot create notifier: {e:?}")))
}

/// A listener woken whenever a message is published on `topic`.
pub(crate) fn listener(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
) -> Result<Listener<ipc::Service>, Error> {
    listener_shaped(iox, topic, |b| b)
}

/// [`listener`] on an event service that `shape` sizes (see [`open_event`]).
pub(crate) fn listener_shaped(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    shape: impl Fn(EventBuilder) -> EventBuilder,
) -> Result<Listener<ipc::Service>, Error> {
    open_event(iox, topic, shape)?
        .listener_builder()
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot create listener: {e:?}")))
}

/// Wakes the event-driven subscribers of a topic. A failed wake-up only delays them to their
/// next event; the message itself is delivered.
pub(crate) fn wake(notifier: &Notifier<ipc::Service>) {
    let _ = notifier.notify();
}

/// Sleeps until `listener` has an event or `timeout` passed, then takes its events. The same
/// as iceoryx2's `timed_wait`, without the three system calls that set its socket's timeout and
/// blocking mode at every wait (the lockstep scheduler waits several times per tick).
pub fn wait_events(
    listener: &Listener<ipc::Service>,
    timeout: std::time::Duration,
) -> Result<(), Error> {
    use iceoryx2_bb_posix::file_descriptor::FileDescriptorBased;
    // SAFETY: the descriptor is only polled, while the listener lives.
    let fd = unsafe { listener.file_descriptor().native_handle() };
    let mut pollfd = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    // Rounded up: a timeout below a millisecond must still sleep.
    let ms = timeout.as_micros().div_ceil(1000).min(i32::MAX as u128) as i32;
    // SAFETY: one valid pollfd for the call's duration.
    if unsafe { libc::poll(&mut pollfd, 1, ms) } < 0 {
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(Error::Lockstep(format!("poll: {e}")));
        }
    }
    listener
        .try_wait(|_| {})
        .map_err(|e| Error::transport("wait", e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;
    use std::path::PathBuf;

    #[test]
    fn a_service_a_killed_process_left_half_made_is_made_again() {
        let group = format!("hung-{}", std::process::id());
        let config = crate::group::config(&group).unwrap();
        let iox = NodeBuilder::new()
            .config(&config)
            .create::<ipc::Service>()
            .unwrap();
        let prefix = crate::group::prefix(&group);
        let dir = PathBuf::from(config.global.service_dir().to_string());
        let files = || -> BTreeSet<PathBuf> {
            std::fs::read_dir(&dir)
                .into_iter()
                .flatten()
                .flatten()
                .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
                .map(|e| e.path())
                .collect()
        };
        // Made and dropped, the service leaves nothing; its description's name is kept.
        let before = files();
        let made = open_event(&iox, "t/hung", |b| b).unwrap();
        let description = files().difference(&before).next().unwrap().clone();
        drop(made);
        assert!(!description.exists());
        // What a SIGKILL during the creation leaves: the description, still writable (0600),
        // older than the creation timeout.
        {
            use std::os::unix::fs::PermissionsExt;
            let file = std::fs::File::create(&description).unwrap();
            file.set_permissions(std::fs::Permissions::from_mode(0o600))
                .unwrap();
            file.set_modified(std::time::SystemTime::now() - std::time::Duration::from_secs(60))
                .unwrap();
        }
        let plain = iox
            .service_builder(&service_name("t/hung").unwrap())
            .event()
            .open_or_create();
        assert!(
            matches!(
                plain,
                Err(
                    iceoryx2::service::builder::event::EventOpenOrCreateError::EventOpenError(
                        iceoryx2::service::builder::event::EventOpenError::HangsInCreation
                    )
                )
            ),
            "{:?}",
            plain.err()
        );
        let notifier = notifier(&iox, "t/hung");
        assert!(notifier.is_ok(), "{:?}", notifier.err());
        drop(notifier);
        drop(iox);
        crate::group::remove_resources(&group).unwrap();
    }
}
