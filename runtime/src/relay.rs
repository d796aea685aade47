//! Relay ports: a topic's subscriber and publisher opened by type name, moving messages as
//! bytes with their original [`Header`]. A bridge between hosts uses them: the outlet reads
//! a topic on one host, the inlet publishes the same messages, header untouched, on another.
//!
//! Bytes are the message's wire form ([`caravan_schemas::wire`]): its data at the offsets of
//! the type's layout and zeros in its padding, so no uninitialised byte is ever read.

use crate::{Delivery, Error, transport};
use caravan_schemas::{Header, Message};
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

struct TypedOutlet<T: Message> {
    topic: String,
    port: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, Header>,
}

impl<T: Message> Outlet for TypedOutlet<T> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn drain(&self, each: &mut dyn FnMut(Header, Vec<u8>)) -> Result<(), Error> {
        while let Some(sample) = self
            .port
            .receive()
            .map_err(|e| Error::topic(&self.topic, format!("{e:?}")))?
        {
            let wire = caravan_schemas::wire::to_wire(sample.payload())
                .map_err(|e| Error::topic(&self.topic, e))?;
            each(*sample.user_header(), wire);
        }
        Ok(())
    }
}

struct TypedInlet<T: Message> {
    topic: String,
    port: iceoryx2::port::publisher::Publisher<ipc::Service, T, Header>,
    notifier: Notifier<ipc::Service>,
}

impl<T: Message> Inlet for TypedInlet<T> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn publish(&self, header: &Header, wire: &[u8]) -> Result<(), Error> {
        let mut sample = self
            .port
            .loan_uninit()
            .map_err(|e| Error::topic(&self.topic, format!("cannot loan a sample: {e:?}")))?;
        caravan_schemas::wire::from_wire::<T>(wire, sample.payload_mut())
            .map_err(|e| Error::topic(&self.topic, e))?;
        // SAFETY: from_wire wrote all of the payload's bytes, from a T's wire form; every bit
        // pattern is a valid Caravan message (numbers and arrays of numbers only).
        let mut sample = unsafe { sample.assume_init() };
        *sample.user_header_mut() = *header;
        sample
            .send()
            .map_err(|e| Error::topic(&self.topic, format!("cannot send: {e:?}")))?;
        transport::wake(&self.notifier);
        Ok(())
    }
}

fn unknown(topic: &str, type_name: &str) -> Error {
    Error::topic(topic, format!("unknown message type '{type_name}'"))
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
    fn open<T: Message>(
        iox: &iceoryx2::node::Node<ipc::Service>,
        topic: &str,
        delivery: Delivery,
    ) -> Result<Box<dyn Outlet>, Error> {
        let service = transport::open_pubsub::<T>(iox, topic, delivery)?;
        let port = service
            .subscriber_builder()
            .buffer_size(delivery.depth())
            .create()
            .map_err(|e| Error::topic(topic, format!("cannot subscribe: {e:?}")))?;
        Ok(Box::new(TypedOutlet::<T> {
            topic: topic.to_string(),
            port,
        }))
    }
    caravan_schemas::with_wire_type!(type_name, |T| open::<T>(iox, topic, delivery))
        .unwrap_or_else(|| Err(unknown(topic, type_name)))
}

/// Opens a publisher of `topic`, whose messages are `type_name`, with `delivery`; a topic
/// made by a local process with another type or contract is the error any publisher gets.
pub fn open_inlet(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
    delivery: Delivery,
) -> Result<Box<dyn Inlet>, Error> {
    fn open<T: Message>(
        iox: &iceoryx2::node::Node<ipc::Service>,
        topic: &str,
        delivery: Delivery,
    ) -> Result<Box<dyn Inlet>, Error> {
        let service = transport::open_pubsub::<T>(iox, topic, delivery)?;
        let port = service
            .publisher_builder()
            .backpressure_strategy(transport::backpressure(delivery.is_lossless()))
            .create()
            .map_err(|e| Error::topic(topic, format!("cannot create publisher: {e:?}")))?;
        Ok(Box::new(TypedInlet::<T> {
            topic: topic.to_string(),
            port,
            notifier: transport::notifier(iox, topic)?,
        }))
    }
    caravan_schemas::with_wire_type!(type_name, |T| open::<T>(iox, topic, delivery))
        .unwrap_or_else(|| Err(unknown(topic, type_name)))
}

/// The payload size of the message type named `type_name`, if it is one.
pub fn payload_size(type_name: &str) -> Option<usize> {
    caravan_schemas::with_message_type!(type_name, |T| size_of::<T>())
}
