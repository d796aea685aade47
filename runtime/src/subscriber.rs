//! Subscriber of a typed topic: every message in order, or only the latest.

use crate::network::{LinkQueue, MessageId, NodeNet};
use crate::transport::{self, Shared};
use crate::{Error, Topic};
use caravan_schemas::{Header, Message};
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::ops::Deref;
use std::rc::Rc;

type IoxSubscriber<T> = iceoryx2::port::subscriber::Subscriber<ipc::Service, T, Header>;

/// A received message: still in shared memory, or (after crossing an emulated network link)
/// a copy. Dereferences to the payload.
pub struct Received<T: Message> {
    inner: Inner<T>,
}

enum Inner<T: Message> {
    Shared(Sample<ipc::Service, T, Header>),
    Copied(Delayed<T>),
}

/// A message that crossed a link, held until it arrives.
struct Delayed<T: Message> {
    arrival_ns: u64,
    header: Header,
    payload: Box<T>,
}

impl<T: Message> Received<T> {
    pub fn header(&self) -> &Header {
        match &self.inner {
            Inner::Shared(s) => s.user_header(),
            Inner::Copied(d) => &d.header,
        }
    }
}

impl<T: Message> Deref for Received<T> {
    type Target = T;
    fn deref(&self) -> &T {
        match &self.inner {
            Inner::Shared(s) => s.payload(),
            Inner::Copied(d) => &d.payload,
        }
    }
}

/// Receives `T` from one topic.
///
/// In lockstep, a message stamped t becomes visible at t + tick; until then it waits here, so
/// a node never sees a message from its own present or future.
pub struct Subscriber<T: Message> {
    topic: String,
    port: IoxSubscriber<T>,
    /// Received from iceoryx2 but not yet visible (lockstep only).
    pending: RefCell<VecDeque<Sample<ipc::Service, T, Header>>>,
    pending_limit: usize,
    /// The node's [`Shared::arrivals`] when a step found the port empty: until it changes,
    /// nothing the step can see comes in (lockstep only).
    empty_at: Cell<Option<u64>>,
    /// Messages that crossed a link, in arrival order.
    delayed: RefCell<VecDeque<Delayed<T>>>,
    /// Per publisher, the latest arrival so far: a link keeps each publisher's order.
    last_arrival: RefCell<Vec<(u64, u64)>>,
    /// Per link, the queue of messages being sent to this subscriber.
    queues: RefCell<Vec<LinkQueue>>,
    topic_hash: u64,
    /// Measures a message's bytes on a link (built once: it reads the type's layout).
    wire_size: caravan_schemas::wire_size::WireSize,
    /// Last sequence number seen per source, to count gaps. Groups have few publishers per
    /// topic, so a small vector beats a map and does not allocate after the first messages.
    last_seq: RefCell<Vec<(u64, u64)>>,
    missed: Cell<u64>,
    received: Cell<u64>,
    shared: Rc<Shared>,
}

impl<T: Message> Subscriber<T> {
    pub(crate) fn new(shared: Rc<Shared>, topic: &Topic<T>) -> Result<Self, Error> {
        let service =
            transport::open_pubsub::<T>(&shared.iox, topic.name(), topic.delivery(), |b| b)?;
        let port = service
            .subscriber_builder()
            .buffer_size(topic.delivery().depth())
            .create()
            .map_err(|e| Error::topic(topic.name(), format!("cannot create subscriber: {e:?}")))?;
        shared.ports.borrow_mut().input(topic.name_hash());
        if !shared.lockstep {
            // Realtime steps wake on these; in lockstep the scheduler wakes nodes instead, and
            // an unused listener would only cost every publish a system call.
            shared.listener(topic.name())?;
        }
        Ok(Self {
            topic: topic.name().to_string(),
            port,
            pending: RefCell::new(VecDeque::with_capacity(8)),
            pending_limit: topic.delivery().depth().max(8) - 1,
            empty_at: Cell::new(None),
            delayed: RefCell::new(VecDeque::new()),
            last_arrival: RefCell::new(Vec::new()),
            queues: RefCell::new(
                shared
                    .net
                    .as_ref()
                    .map_or(Vec::new(), |n| vec![LinkQueue::default(); n.links.len()]),
            ),
            topic_hash: caravan_schemas::lockstep::name_hash(topic.name()),
            wire_size: caravan_schemas::wire_size::WireSize::of::<T>(),
            last_seq: RefCell::new(Vec::with_capacity(4)),
            missed: Cell::new(0),
            received: Cell::new(0),
            shared,
        })
    }

    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// Messages lost before they reached this subscriber (gaps in sequence numbers).
    pub fn missed(&self) -> u64 {
        self.missed.get()
    }

    /// Messages handed to the caller so far.
    pub fn received(&self) -> u64 {
        self.received.get()
    }

    /// The next visible message, oldest first.
    pub fn receive(&self) -> Result<Option<Received<T>>, Error> {
        let inner = match &self.shared.net {
            Some(net) if !net.links.is_empty() => self.next_over_links(net)?,
            _ if self.shared.lockstep => self.next_visible()?.map(Inner::Shared),
            _ => self.pull()?.map(Inner::Shared),
        };
        Ok(inner.map(|inner| {
            let received = Received { inner };
            self.account(received.header());
            received
        }))
    }

    /// The newest visible message, discarding (but counting) older ones.
    pub fn latest(&self) -> Result<Option<Received<T>>, Error> {
        let mut newest = None;
        while let Some(msg) = self.receive()? {
            newest = Some(msg);
        }
        Ok(newest)
    }

    fn pull(&self) -> Result<Option<Sample<ipc::Service, T, Header>>, Error> {
        self.port
            .receive()
            .map_err(|e| Error::topic(&self.topic, format!("cannot receive: {e:?}")))
    }

    fn next_visible(&self) -> Result<Option<Sample<ipc::Service, T, Header>>, Error> {
        let mut pending = self.pending.borrow_mut();
        self.fill(&mut pending)?;
        Ok(self.take_visible(&mut pending))
    }

    /// Pulls from iceoryx2 until the queue is empty or `pending` holds its limit; within a
    /// step, not again once the port was empty (see [`Shared::arrivals`]): `latest` and a
    /// loop of `receive` would otherwise look once more per message.
    fn fill(&self, pending: &mut VecDeque<Sample<ipc::Service, T, Header>>) -> Result<(), Error> {
        // Realtime messages come in while a step runs, and a step sees what came.
        let in_step = self.shared.lockstep && self.shared.in_step.get();
        let arrivals = self.shared.arrivals.get();
        if in_step && self.empty_at.get() == Some(arrivals) {
            return Ok(());
        }
        while pending.len() < self.pending_limit {
            match self.pull()? {
                Some(sample) => pending.push_back(sample),
                None => {
                    self.empty_at.set(in_step.then_some(arrivals));
                    break;
                }
            }
        }
        Ok(())
    }

    /// The first visible message of `pending`; notes when the first invisible one shows.
    fn take_visible(
        &self,
        pending: &mut VecDeque<Sample<ipc::Service, T, Header>>,
    ) -> Option<Sample<ipc::Service, T, Header>> {
        // Stamps of one publisher only grow, so taking the first visible one keeps each
        // publisher's order.
        let index = pending
            .iter()
            .position(|s| self.shared.is_visible(s.user_header()));
        let next = index.and_then(|i| pending.remove(i));
        // A message stamped later (a compute budget) asks its node to step when it shows.
        let tick = self.shared.tick_ns.get();
        if let Some(at) = pending
            .iter()
            .filter(|s| !self.shared.is_visible(s.user_header()))
            .map(|s| s.user_header().stamp_ns + tick)
            .min()
        {
            self.note_arrival(at);
        }
        next
    }

    fn note_arrival(&self, at_ns: u64) {
        let next = &self.shared.next_arrival_ns;
        next.set(next.get().min(at_ns));
    }

    /// The next message when links lead into this node's host: same-host messages as
    /// usual, linked ones once they arrive.
    fn next_over_links(&self, net: &NodeNet) -> Result<Option<Inner<T>>, Error> {
        let lockstep = self.shared.lockstep;
        let now = if lockstep {
            self.shared.now_ns.get()
        } else {
            crate::wall_clock_ns()
        };
        let tick = self.shared.tick_ns.get();
        let mut pending = self.pending.borrow_mut();
        // Linked messages are copied out as soon as they may go on their link, which frees
        // their shared-memory samples; the rest wait in `pending` as usual. In lockstep a
        // message may go once every message of its time has been published, and all go in a
        // fixed order, so that queueing on the link is reproducible.
        let mut crossing: Vec<(usize, Header, Box<T>)> = Vec::new();
        loop {
            self.fill(&mut pending)?;
            let before = crossing.len();
            pending.retain(|sample| {
                let h = *sample.user_header();
                match net.link_of(h.source_id) {
                    Some(link) if !lockstep || h.stamp_ns + tick <= now => {
                        let mut payload = caravan_schemas::boxed_placement_new::<T>();
                        *payload = *sample.payload();
                        crossing.push((link, h, payload));
                        false
                    }
                    _ => true,
                }
            });
            if crossing.len() == before {
                break;
            }
        }
        crossing.sort_by_key(|(_, h, _)| (h.stamp_ns, h.source_id, h.seq));
        for (link, header, payload) in crossing {
            self.cross(net, link, header, payload, lockstep);
        }
        if let Some(sample) = self.take_visible(&mut pending) {
            return Ok(Some(Inner::Shared(sample)));
        }
        let mut delayed = self.delayed.borrow_mut();
        let arrived = |d: &Delayed<T>| d.arrival_ns + if lockstep { tick } else { 0 } <= now;
        let next = match delayed.front() {
            Some(d) if arrived(d) => delayed.pop_front().map(Inner::Copied),
            _ => None,
        };
        if let Some(d) = delayed.front() {
            self.note_arrival(d.arrival_ns + if lockstep { tick } else { 0 });
        }
        Ok(next)
    }

    /// Sends one message over its link: drops it, or keeps it until its arrival.
    fn cross(&self, net: &NodeNet, link: usize, header: Header, payload: Box<T>, lockstep: bool) {
        let sent = if lockstep {
            header.stamp_ns
        } else {
            header.send_wall_ns
        };
        let id = MessageId {
            seed: net.seed,
            source: header.source_id,
            topic: self.topic_hash,
            seq: header.seq,
            subscriber: net.node_hash,
        };
        let bytes = size_of::<Header>() + self.wire_size.measure(&*payload);
        let mut queues = self.queues.borrow_mut();
        let arrival = net.links[link].arrival(&id, bytes, sent, &mut queues[link]);
        let arrival = arrival.map(|t| {
            // A link delivers each publisher's messages in order.
            let mut last = self.last_arrival.borrow_mut();
            match last.iter_mut().find(|(s, _)| *s == header.source_id) {
                Some((_, a)) => {
                    *a = (*a).max(t);
                    *a
                }
                None => {
                    last.push((header.source_id, t));
                    t
                }
            }
        });
        net.stats.borrow_mut()[link].record(arrival.map(|t| t - sent));
        if let Some(arrival_ns) = arrival {
            let mut delayed = self.delayed.borrow_mut();
            let at = delayed.partition_point(|d| d.arrival_ns <= arrival_ns);
            delayed.insert(
                at,
                Delayed {
                    arrival_ns,
                    header,
                    payload,
                },
            );
        }
    }

    fn account(&self, header: &Header) {
        self.received.set(self.received.get() + 1);
        let mut last = self.last_seq.borrow_mut();
        match last
            .iter_mut()
            .find(|(source, _)| *source == header.source_id)
        {
            Some((_, seq)) => {
                if header.seq > *seq + 1 {
                    let gap = header.seq - *seq - 1;
                    self.missed.set(self.missed.get() + gap);
                    self.shared.missed.set(self.shared.missed.get() + gap);
                }
                *seq = header.seq.max(*seq);
            }
            None => last.push((header.source_id, header.seq)),
        }
    }
}
