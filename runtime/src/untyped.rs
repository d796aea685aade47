//! Ports of a topic whose type a process knows only by its [`Descriptor`]: the recorder's and
//! `topic echo`'s taps, `topic pub`'s and the player's injectors, the bridge's inlets and
//! outlets. They read and write a message's bytes; the descriptor says what the bytes mean.
//!
//! iceoryx2 matches a topic's payload by type name, size and alignment; an untyped port
//! states those of the descriptor, so it meets the typed ports of the same topic (iceoryx2's
//! own gateways do the same).

use crate::Error;
use crate::transport::{repairing_hung, service_name};
use caravan_schemas::Header;
use caravan_schemas::descriptor::Descriptor;
use iceoryx2::prelude::*;
use iceoryx2::service::marker::{CustomHeaderMarker, CustomPayloadMarker};
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use iceoryx2::service::static_config::message_type_details::{TypeDetail, TypeVariant};

/// The payload of an untyped port: bytes, as many as the descriptor's type takes.
pub type Bytes = [CustomPayloadMarker];

/// The user header of an untyped port: Caravan's [`Header`], which iceoryx2 is told of by its
/// type detail (its API loans untyped payloads only with an untyped header).
pub type HeaderBytes = CustomHeaderMarker;

/// A topic's service seen through a descriptor.
pub type Service = PortFactory<ipc::Service, Bytes, HeaderBytes>;

/// A publisher of described messages.
pub type Publisher = iceoryx2::port::publisher::Publisher<ipc::Service, Bytes, HeaderBytes>;

/// A subscriber of described messages.
pub type Subscriber = iceoryx2::port::subscriber::Subscriber<ipc::Service, Bytes, HeaderBytes>;

type Builder =
    iceoryx2::service::builder::publish_subscribe::Builder<Bytes, HeaderBytes, ipc::Service>;

/// The service name of `topic` and the payload type detail of `descriptor`.
fn names(topic: &str, descriptor: &Descriptor) -> Result<(ServiceName, TypeDetail), Error> {
    let layout = descriptor.layout();
    let detail = TypeDetail::__internal_new_from_parts(
        TypeVariant::FixedSize,
        layout.type_name,
        layout.size,
        layout.align,
    )
    .map_err(|e| Error::topic(topic, format!("type name '{}': {e:?}", layout.type_name)))?;
    Ok((service_name(topic)?, detail))
}

/// The builder of a service with the payload `detail` states.
fn builder(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &ServiceName,
    detail: &TypeDetail,
) -> Builder {
    let builder = iox
        .service_builder(name)
        .publish_subscribe::<Bytes>()
        .user_header::<HeaderBytes>();
    let header = TypeDetail::new::<Header>(TypeVariant::FixedSize);
    // SAFETY: the details are the described type's and the header's, whose ports (typed or
    // not) read and write exactly their sizes; `publish` and `header` below keep to them.
    unsafe {
        builder
            .__internal_set_payload_type_details(detail)
            .__internal_set_user_header_type_details(&header)
    }
}

/// Opens `topic`'s existing service, whatever its contract.
pub fn open_existing(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    descriptor: &Descriptor,
) -> Result<Service, Error> {
    use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError as Open;
    let (name, detail) = names(topic, descriptor)?;
    repairing_hung(
        iox,
        || builder(iox, &name, &detail).open(),
        |e| matches!(e, Open::HangsInCreation),
    )
    .map_err(|e| Error::topic(topic, format!("cannot open: {e:?}")))
}

/// Opens `topic`'s service, or makes it with `delivery`'s contract, as a typed publisher would.
pub fn open_or_create(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    descriptor: &Descriptor,
    delivery: crate::Delivery,
) -> Result<Service, Error> {
    use iceoryx2::service::builder::publish_subscribe::{
        PublishSubscribeOpenError as Open, PublishSubscribeOpenOrCreateError as Either,
    };
    let (name, detail) = names(topic, descriptor)?;
    repairing_hung(
        iox,
        || crate::transport::with_contract(builder(iox, &name, &detail), delivery).open_or_create(),
        |e| matches!(e, Either::PublishSubscribeOpenError(Open::HangsInCreation)),
    )
    .map_err(|e| {
        Error::topic(
            topic,
            format!(
                "cannot open as {} ({e:?}); another process uses this topic with a different \
                 message type or delivery contract",
                descriptor.type_name()
            ),
        )
    })
}

/// Publishes one message: `bytes`, a whole value of the publisher's described type, with
/// `header`.
pub fn publish(port: &Publisher, topic: &str, header: Header, bytes: &[u8]) -> Result<(), Error> {
    // SAFETY: one element, as the payload is of fixed size; the chunk holds the described
    // type's `size` bytes, which `bytes` is (the caller sized it by the same descriptor).
    let mut sample = unsafe { port.loan_custom_payload(1) }
        .map_err(|e| Error::topic(topic, format!("cannot loan: {e:?}")))?;
    let payload = sample.payload_mut().as_mut_ptr().cast::<u8>();
    let user_header = (sample.user_header_mut() as *mut HeaderBytes).cast::<Header>();
    // SAFETY: the chunk has room for `bytes` after the payload pointer and for a `Header` at
    // the user header's (its type detail is `Header`'s, so iceoryx2 placed and aligned it).
    let sample = unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), payload, bytes.len());
        user_header.write(header);
        sample.assume_init()
    };
    sample
        .send()
        .map_err(|e| Error::topic(topic, format!("cannot send: {e:?}")))?;
    Ok(())
}

/// The header of a received untyped message.
pub fn header(user_header: &HeaderBytes) -> Header {
    // SAFETY: the port's user header type detail is `Header`'s: a `Header` lies there.
    unsafe { (user_header as *const HeaderBytes).cast::<Header>().read() }
}

/// The `size` payload bytes of a received untyped message.
pub fn payload_bytes(payload: &Bytes, size: usize) -> &[u8] {
    // SAFETY: an untyped port's sample holds one message of the described type, `size` bytes
    // from the payload's start (iceoryx2 sizes the chunk by the payload type detail), in
    // shared memory that another process wrote and this one only maps: its bytes, a value's
    // padding included, are whatever the mapping holds, never uninitialised to this process.
    unsafe { std::slice::from_raw_parts(payload.as_ptr().cast::<u8>(), size) }
}
