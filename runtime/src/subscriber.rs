//! Subscriber of a typed topic: every message in order, or only the latest.

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

/// A received message, still in shared memory. Dereferences to the payload.
pub struct Received<T: Message> {
    sample: Sample<ipc::Service, T, Header>,
}

impl<T: Message> Received<T> {
    pub fn header(&self) -> &Header {
        self.sample.user_header()
    }
}

impl<T: Message> Deref for Received<T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.sample.payload()
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
    /// Last sequence number seen per source, to count gaps. Groups have few publishers per
    /// topic, so a small vector beats a map and does not allocate after the first messages.
    last_seq: RefCell<Vec<(u64, u64)>>,
    missed: Cell<u64>,
    received: Cell<u64>,
    shared: Rc<Shared>,
}

impl<T: Message> Subscriber<T> {
    pub(crate) fn new(shared: Rc<Shared>, topic: &Topic<T>) -> Result<Self, Error> {
        let service = transport::open_pubsub::<T>(&shared.iox, topic.name(), topic.delivery())?;
        let port = service
            .subscriber_builder()
            .buffer_size(topic.delivery().depth())
            .create()
            .map_err(|e| Error::topic(topic.name(), format!("cannot create subscriber: {e:?}")))?;
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
        let sample = if self.shared.lockstep {
            self.next_visible()?
        } else {
            self.pull()?
        };
        Ok(sample.map(|sample| {
            self.account(sample.user_header());
            Received { sample }
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
        while pending.len() < self.pending_limit {
            match self.pull()? {
                Some(sample) => pending.push_back(sample),
                None => break,
            }
        }
        // Stamps of one publisher only grow, so taking the first visible one keeps each
        // publisher's order.
        let index = pending
            .iter()
            .position(|s| self.shared.is_visible(s.user_header()));
        Ok(index.and_then(|i| pending.remove(i)))
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
