//! Relay ports: a topic's subscriber and publisher opened by type name (a catalog type or one
//! registered with the group, [`crate::types`]), moving messages as bytes with their original
//! [`Header`]. A bridge between hosts uses them: the outlet reads
//! a topic on one host, the inlet publishes the same messages, header untouched, on another.
//!
//! Bytes are the message's wire form ([`caravan_schemas::wire`]): its data at the offsets of
//! the type's layout and zeros in its padding, so no uninitialised byte is ever read.

use crate::{Delivery, Error, transport, untyped};
use caravan_schemas::Header;
use caravan_schemas::descriptor::Descriptor;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;

/// Reads a topic's messages as bytes.
pub trait Outlet {
    fn topic(&self) -> &str;
    /// Hands every waiting message, oldest first, to `each` as its header and wire bytes.
    fn drain(&self, each: &mut dyn FnMut(Header, Vec<u8>)) -> Result<(), Error>;
}

/// Publishes messages given as bytes, with the header they came with.
pub trait Inlet {
    fn topic(&self) -> &str;
    /// Publishes one message and wakes the topic's event-driven subscribers. On a lossless
    /// topic it waits while a subscriber's queue is full, as any publisher does.
    fn publish(&self, header: &Header, wire: &[u8]) -> Result<(), Error>;
}

struct DescribedOutlet {
    topic: String,
    size: usize,
    /// Where the type's data lies; the rest is padding, sent as zeros.
    ranges: Vec<(usize, usize)>,
    port: untyped::Subscriber,
}

impl Outlet for DescribedOutlet {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn drain(&self, each: &mut dyn FnMut(Header, Vec<u8>)) -> Result<(), Error> {
        while let Some(sample) = self
            .port
            .receive()
            .map_err(|e| Error::topic(&self.topic, format!("{e:?}")))?
        {
            let payload = untyped::payload_bytes(sample.payload(), self.size);
            let wire = caravan_schemas::wire::wire_bytes(payload, &self.ranges);
            each(untyped::header(sample.user_header()), wire);
        }
        Ok(())
    }
}

struct DescribedInlet {
    topic: String,
    descriptor: Descriptor,
    port: untyped::Publisher,
    notifier: Notifier<ipc::Service>,
}

impl Inlet for DescribedInlet {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn publish(&self, header: &Header, wire: &[u8]) -> Result<(), Error> {
        self.descriptor
            .check_size(wire.len())
            .map_err(|e| Error::topic(&self.topic, e))?;
        untyped::publish(&self.port, &self.topic, *header, wire)?;
        transport::wake(&self.notifier);
        Ok(())
    }
}

/// The descriptor of `type_name` in `iox`'s group (see [`crate::types`]).
fn descriptor(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
) -> Result<Descriptor, Error> {
    crate::types::lookup(iox.config(), type_name).map_err(|e| Error::topic(topic, e))
}

/// Opens a subscriber of `topic`, whose messages are `type_name`, creating the topic with
/// `delivery` if no process has made it yet: messages published from then on are kept for
/// the outlet, as for any subscriber.
pub fn open_outlet(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
    delivery: Delivery,
) -> Result<Box<dyn Outlet>, Error> {
    let descriptor = descriptor(iox, topic, type_name)?;
    let ranges = descriptor
        .data_ranges()
        .ok_or_else(|| Error::topic(topic, format!("{type_name}: a faulty layout")))?;
    let service = untyped::open_or_create(iox, topic, &descriptor, delivery)?;
    let port = service
        .subscriber_builder()
        .buffer_size(delivery.depth())
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot subscribe: {e:?}")))?;
    Ok(Box::new(DescribedOutlet {
        topic: topic.to_string(),
        size: descriptor.layout().size,
        ranges,
        port,
    }))
}

/// Opens a publisher of `topic`, whose messages are `type_name`, with `delivery`; a topic
/// made by a local process with another type or contract is the error any publisher gets.
pub fn open_inlet(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
    delivery: Delivery,
) -> Result<Box<dyn Inlet>, Error> {
    let descriptor = descriptor(iox, topic, type_name)?;
    let service = untyped::open_or_create(iox, topic, &descriptor, delivery)?;
    let port = service
        .publisher_builder()
        .backpressure_strategy(transport::backpressure(delivery.is_lossless()))
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot create publisher: {e:?}")))?;
    Ok(Box::new(DescribedInlet {
        topic: topic.to_string(),
        descriptor,
        port,
        notifier: transport::notifier(iox, topic)?,
    }))
}
