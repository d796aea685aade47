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
    /// Subscribers the last message sent reached: while some did, the next message is sent
    /// without asking how many there are (a walk of every subscriber slot of the topic).
    reached: Cell<usize>,
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
        shared
            .ports
            .borrow_mut()
            .output(topic.name_hash(), topic.delivery().depth());
        let notifier = transport::notifier(&shared.iox, topic.name())?;
        Ok(Self {
            topic: topic.name().to_string(),
            topic_hash: topic.name_hash(),
            service,
            port,
            notifier,
            seq: Cell::new(0),
            reached: Cell::new(0),
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
    ///
    /// With no subscriber on this host the message is only counted: its sequence number is
    /// taken and, in lockstep, the step reports the topic, as if it had been sent. Nobody
    /// could have read it (a subscriber that joins later never gets earlier messages), and a
    /// loan walks every subscriber slot of the topic: a physics process publishing 65
    /// robots' states spent 13–18 % of its CPU there.
    pub fn publish(&self, value: &T) -> Result<(), Error> {
        if self.unread() {
            self.count_unread();
            return Ok(());
        }
        let uninit = self
            .port
            .loan_uninit()
            .map_err(|e| Error::topic(&self.topic, format!("cannot loan a sample: {e:?}")))?;
        self.send(uninit.write_payload(*value))
    }

    /// Publishes a message written in place by `fill` (on a loan initialised to `T`'s
    /// default), or with no subscriber only counts it, as [`Self::publish`] does: `fill` then
    /// does not run. For large messages that should be neither copied nor built for nobody.
    pub fn publish_in_place(&self, fill: impl FnOnce(&mut T)) -> Result<(), Error> {
        if self.unread() {
            self.count_unread();
            return Ok(());
        }
        let mut loan = self.loan()?;
        fill(&mut loan);
        loan.send()
    }

    /// Whether nobody would read a message sent now. Asked only when the last one sent
    /// reached nobody: a subscriber that joins after a message reached others gets the next.
    fn unread(&self) -> bool {
        self.reached.get() == 0 && self.subscribers() == 0
    }

    /// A message no subscriber could read: its sequence number is used up and the step
    /// reports the topic, so what a later subscriber sees and the schedule are unchanged.
    fn count_unread(&self) {
        self.seq.set(self.seq.get() + 1);
        self.shared.sent(self.topic_hash, &self.notifier);
    }

    /// The message's simulated time: the step's, or in lockstep on a host with a CPU
    /// slowdown, later by the step's CPU time so far times the slowdown (rounded up to the
    /// tick), as if this machine's computer were that much slower. CPU time, not wall-clock
    /// time: a step that waits for one of the emulating machine's cores would not wait on
    /// its own computer.
    fn stamp_ns(&self) -> u64 {
        let now = self.shared.now_ns.get();
        match (
            self.shared.stamping_slowdown(),
            self.shared.step_cpu_started_ns.get(),
        ) {
            (Some(factor), Some(started)) => {
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
        let reached = sample
            .send()
            .map_err(|e| Error::topic(&self.topic, format!("cannot send: {e:?}")))?;
        self.reached.set(reached);
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

#[cfg(test)]
mod tests {
    use crate::{Node, Topic};
    use caravan_schemas::Pose2D;
    use std::cell::Cell;

    #[test]
    fn a_message_nobody_reads_is_counted_not_sent() {
        let group = format!("unread-{}", std::process::id());
        let node = Node::builder(&group, "writer").build().unwrap();
        let topic = Topic::<Pose2D>::new("t/pose");
        let out = node.publisher(&topic).unwrap();
        let filled = Cell::new(0);
        out.publish(&Pose2D::default()).unwrap();
        out.publish_in_place(|_| filled.set(filled.get() + 1))
            .unwrap();
        assert_eq!((out.sequence(), filled.get()), (2, 0));

        // A subscriber that joins later gets the next message, numbered after the unread
        // ones, and counts none of them as missed.
        let reader = node.subscriber(&topic).unwrap();
        out.publish_in_place(|m| {
            filled.set(filled.get() + 1);
            m.x = 3.0;
        })
        .unwrap();
        out.publish(&Pose2D {
            x: 4.0,
            ..Pose2D::default()
        })
        .unwrap();
        let first = reader.receive().unwrap().unwrap();
        assert_eq!((first.header().seq, first.x, filled.get()), (3, 3.0, 1));
        let second = reader.receive().unwrap().unwrap();
        assert_eq!((second.header().seq, second.x), (4, 4.0));
        assert_eq!(reader.missed(), 0);

        // Once the reader is gone the next message reaches nobody, and the ones after it
        // are only counted; a new reader gets the next one sent.
        drop(reader);
        out.publish(&Pose2D::default()).unwrap();
        out.publish_in_place(|_| filled.set(filled.get() + 1))
            .unwrap();
        assert_eq!((out.sequence(), filled.get()), (6, 1));
        let reader = node.subscriber(&topic).unwrap();
        out.publish(&Pose2D {
            x: 7.0,
            ..Pose2D::default()
        })
        .unwrap();
        let next = reader.receive().unwrap().unwrap();
        assert_eq!((next.header().seq, next.x), (7, 7.0));
        drop((reader, out, node));
        let _ = crate::group::remove_resources(&group);
    }
}
