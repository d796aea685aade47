//! Stamping, zero-copy publisher of a typed topic.

use crate::transport::{self, Shared};
use crate::{Error, Topic};
use caravan_schemas::{Header, Message};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use iceoryx2::sample_mut::SampleMut;
use std::cell::Cell;
use std::ops::{Deref, DerefMut};
use std::rc::Rc;

type IoxPublisher<T> = iceoryx2::port::publisher::Publisher<ipc::Service, T, Header>;

/// Publishes `T` on one topic. Each message gets a [`Header`] with the next sequence number,
/// the node's simulated time, the wall-clock send time and the node's id, and wakes
/// event-driven subscribers.
pub struct Publisher<T: Message> {
    topic: String,
    topic_hash: u64,
    service:
        iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, Header>,
    port: IoxPublisher<T>,
    notifier: Notifier<ipc::Service>,
    seq: Cell<u64>,
    shared: Rc<Shared>,
}

/// A message being written in place in shared memory; [`Loan::send`] publishes it.
pub struct Loan<'p, T: Message> {
    sample: SampleMut<ipc::Service, T, Header>,
    publisher: &'p Publisher<T>,
}

impl<T: Message> Publisher<T> {
    pub(crate) fn new(shared: Rc<Shared>, topic: &Topic<T>) -> Result<Self, Error> {
        let service =
            transport::open_pubsub::<T>(&shared.iox, topic.name(), topic.delivery(), |b| b)?;
        let port = service
            .publisher_builder()
            .backpressure_strategy(transport::backpressure(topic.delivery().is_lossless()))
            .max_loaned_samples(2)
            .create()
            .map_err(|e| Error::topic(topic.name(), format!("cannot create publisher: {e:?}")))?;
        shared.ports.borrow_mut().output(topic.name_hash());
        let notifier = transport::notifier(&shared.iox, topic.name())?;
        Ok(Self {
            topic: topic.name().to_string(),
            topic_hash: topic.name_hash(),
            service,
            port,
            notifier,
            seq: Cell::new(0),
            shared,
        })
    }

    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// How many subscribers the topic has on this host now (on a group across hosts, the
    /// bridge counts as one for each host that reads the topic). A lossless stream that must
    /// not start before its reader can wait for one, as with ROS 2's subscription count.
    pub fn subscribers(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    /// Messages published so far.
    pub fn sequence(&self) -> u64 {
        self.seq.get()
    }

    /// Loans a message in shared memory, initialised to its default, to be filled in place.
    /// Use it for large messages (scans, maps) to avoid copies.
    pub fn loan(&self) -> Result<Loan<'_, T>, Error> {
        Ok(Loan {
            sample: loan_default(&self.port, &self.topic)?,
            publisher: self,
        })
    }

    /// Loans a message in shared memory as it is: the bytes the sample's slot holds (zeros,
    /// or an earlier message of this topic), without writing `T`'s default first. For
    /// benchmarks and very large messages that are overwritten in part, where the default's
    /// memset would cost more than the transport.
    ///
    /// # Safety
    /// Every bit pattern must be a valid `T` (plain numbers and arrays of them, no `bool`,
    /// enum or reference): a slot holds zeros when the OS made the segment and afterwards
    /// only whole messages of this topic, but not necessarily `T`'s default.
    pub unsafe fn loan_as_is(&self) -> Result<Loan<'_, T>, Error> {
        let uninit = self
            .port
            .loan_uninit()
            .map_err(|e| Error::topic(&self.topic, format!("cannot loan a sample: {e:?}")))?;
        Ok(Loan {
            // SAFETY: the slot's bytes are initialised (see above) and, by the caller's
            // promise, a valid `T`.
            sample: unsafe { uninit.assume_init() },
            publisher: self,
        })
    }

    /// Publishes a copy of `value`.
    pub fn publish(&self, value: &T) -> Result<(), Error> {
        let uninit = self
            .port
            .loan_uninit()
            .map_err(|e| Error::topic(&self.topic, format!("cannot loan a sample: {e:?}")))?;
        self.send(uninit.write_payload(*value))
    }

    /// The message's simulated time: the step's, or in lockstep on a host with a CPU
    /// slowdown, later by the step's CPU time so far times the slowdown (rounded up to the
    /// tick), as if this machine's computer were that much slower. CPU time, not wall-clock
    /// time: a step that waits for one of the emulating machine's cores would not wait on
    /// its own computer.
    fn stamp_ns(&self) -> u64 {
        let now = self.shared.now_ns.get();
        let slowdown = self.shared.net.as_ref().and_then(|n| n.slowdown);
        match (slowdown, self.shared.step_cpu_started_ns.get()) {
            (Some(factor), Some(started)) if self.shared.lockstep => {
                let cpu = crate::stats::thread_cpu_ns().saturating_sub(started);
                let compute = (cpu as f64 * factor) as u64;
                let tick = self.shared.tick_ns.get().max(1);
                now.saturating_add(compute.div_ceil(tick).saturating_mul(tick))
            }
            _ => now,
        }
    }

    fn send(&self, mut sample: SampleMut<ipc::Service, T, Header>) -> Result<(), Error> {
        let seq = self.seq.get() + 1;
        self.seq.set(seq);
        *sample.user_header_mut() = Header {
            seq,
            stamp_ns: self.stamp_ns(),
            send_wall_ns: crate::wall_clock_ns(),
            source_id: self.shared.node_hash,
        };
        sample
            .send()
            .map_err(|e| Error::topic(&self.topic, format!("cannot send: {e:?}")))?;
        self.shared.sent(self.topic_hash, &self.notifier);
        Ok(())
    }
}

/// A sample of `port` loaned in shared memory and initialised in place to `T`'s default.
pub(crate) fn loan_default<T: Message>(
    port: &IoxPublisher<T>,
    topic: &str,
) -> Result<SampleMut<ipc::Service, T, Header>, Error> {
    let mut uninit = port
        .loan_uninit()
        .map_err(|e| Error::topic(topic, format!("cannot loan a sample: {e:?}")))?;
    // SAFETY: placement_default initialises every field of the payload in place.
    Ok(unsafe {
        T::placement_default(uninit.payload_mut().as_mut_ptr());
        uninit.assume_init()
    })
}

impl<T: Message> Loan<'_, T> {
    pub fn send(self) -> Result<(), Error> {
        self.publisher.send(self.sample)
    }
}

impl<T: Message> Deref for Loan<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.sample.payload()
    }
}

impl<T: Message> DerefMut for Loan<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        self.sample.payload_mut()
    }
}
