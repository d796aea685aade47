//! The control services' ports (hellos, grants, reports), made alike by the node's client and
//! the launcher's scheduler (`caravan-lockstep`).

use crate::Error;
use crate::transport;
pub use crate::transport::wait_events;
use caravan_schemas::Header;
use iceoryx2::prelude::*;

pub type Pub<T> = iceoryx2::port::publisher::Publisher<ipc::Service, T, Header>;
pub type Sub<T> = iceoryx2::port::subscriber::Subscriber<ipc::Service, T, Header>;

/// Room in a control service for its readers (subscribers and listeners): the scheduler (of
/// hellos and reports) or the node (of its grants), the bridge relaying them to another host,
/// a restarted node's while iceoryx2 cleans up the dead one's, a tool looking on. iceoryx2
/// walks every reader's slot at each loan, send and notify: sized as a topic's (80), those
/// walks were a seventh of the scheduler's time, and every node's report walked 80 slots too
/// (docs/benchmarks.md, "Fourth round").
const CONTROL_READERS: usize = 4;

fn control_topic<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, Header>,
    Error,
> {
    // Control messages must never be lost; queues are deep enough that nobody waits in practice.
    let delivery = crate::Delivery::Lossless { depth: 256 };
    transport::open_pubsub::<T>(iox, name, delivery, |b| b.max_subscribers(CONTROL_READERS))
}

/// How a control topic's event service is made: its readers as [`control_topic`]'s, and one
/// event id (notifications carry the default, 0; a listener clears a counter for every
/// possible id at each wait, 256 by default).
fn control_event(b: transport::EventBuilder) -> transport::EventBuilder {
    b.event_id_max_value(1).max_listeners(CONTROL_READERS)
}

pub fn listener(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<iceoryx2::port::listener::Listener<ipc::Service>, Error> {
    transport::listener_shaped(iox, name, control_event)
}

pub fn notifier(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<iceoryx2::port::notifier::Notifier<ipc::Service>, Error> {
    transport::notifier_shaped(iox, name, control_event)
}

pub fn publisher<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<Pub<T>, Error> {
    control_topic::<T>(iox, name)?
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
        .create()
        .map_err(|e| Error::transport(name, e))
}

pub fn subscriber<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<Sub<T>, Error> {
    control_topic::<T>(iox, name)?
        .subscriber_builder()
        .buffer_size(256)
        .create()
        .map_err(|e| Error::transport(name, e))
}

/// Spin, then park: looks up to `spin` for `has` to say something came; true if it did, so
/// the caller need not sleep on `listener` (whose notifications are then taken, so the next
/// wait does not return at once for a message already read).
pub fn spin_on(
    mut has: impl FnMut() -> Result<bool, Error>,
    listener: &iceoryx2::port::listener::Listener<ipc::Service>,
    spin: std::time::Duration,
    name: &str,
) -> Result<bool, Error> {
    if spin.is_zero() {
        return Ok(false);
    }
    if crate::spin::spin_for(spin, || Ok(has()?.then_some(())))?.is_none() {
        return Ok(false);
    }
    listener
        .try_wait(|_| {})
        .map_err(|e| Error::transport(name, e))?;
    Ok(true)
}

/// Whether `sub` holds a sample.
pub fn has_samples<T: caravan_schemas::Message>(sub: &Sub<T>, name: &str) -> Result<bool, Error> {
    sub.has_samples().map_err(|e| Error::transport(name, e))
}

pub fn send<T: caravan_schemas::Message>(port: &Pub<T>, value: T, name: &str) -> Result<(), Error> {
    let sample = port.loan_uninit().map_err(|e| Error::transport(name, e))?;
    sample
        .write_payload(value)
        .send()
        .map_err(|e| Error::transport(name, e))?;
    Ok(())
}
