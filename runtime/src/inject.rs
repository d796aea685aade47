//! Injectors: publishers opened by type name at run time, fed JSON. `caravan topic pub` and
//! `caravan play` use them to publish into a group from outside it, the way taps
//! ([`crate::tap`]) read from it.

use crate::Error;
use crate::transport::{self, Shared};
use caravan_schemas::{Header, Message};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use std::rc::Rc;

/// A publisher of a topic whose type is known only by name.
pub trait DynInject {
    fn topic(&self) -> &str;
    /// Publishes `json` (a message in the recording's shape) with `header` as given, and
    /// wakes the topic's event-driven subscribers.
    fn publish_json(&self, header: Header, json: &serde_json::Value) -> Result<(), Error>;
}

struct Inject<T: Message> {
    topic: String,
    port: iceoryx2::port::publisher::Publisher<ipc::Service, T, Header>,
    topic_hash: u64,
    notifier: Notifier<ipc::Service>,
    /// The node publishing, when the injector belongs to one ([`crate::Node::injectors`]):
    /// in lockstep its scheduler, not the notifier, wakes subscribers.
    node: Option<Rc<Shared>>,
}

impl<T: Message> DynInject for Inject<T> {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn publish_json(&self, header: Header, json: &serde_json::Value) -> Result<(), Error> {
        let mut sample = crate::publisher::loan_default(&self.port, &self.topic)?;
        caravan_schemas::from_json::write_into(sample.payload_mut(), json)
            .map_err(|e| Error::topic(&self.topic, e))?;
        *sample.user_header_mut() = header;
        sample
            .send()
            .map_err(|e| Error::topic(&self.topic, format!("cannot send: {e:?}")))?;
        match &self.node {
            Some(shared) => shared.sent(self.topic_hash, &self.notifier),
            None => transport::wake(&self.notifier),
        }
        Ok(())
    }
}

/// Opens a publisher on `topic` of the type named `type_name`. An existing topic keeps its
/// delivery contract; a new one is made with `delivery`. The publisher waits for room on a
/// lossless topic, as the group's own publishers do.
pub fn open_injector(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
    delivery: crate::Delivery,
) -> Result<Box<dyn DynInject>, Error> {
    open_for(iox, None, topic, type_name, delivery)
}

/// Opens injectors for a node of the group ([`crate::Node::injectors`]); its lockstep
/// scheduler learns of what they publish.
pub struct Injectors {
    pub(crate) shared: Rc<Shared>,
}

impl Injectors {
    /// A publisher of `topic`, whose type is named `type_name` (e.g. `caravan::Twist`). An
    /// existing topic keeps its contract; a new one gets `delivery`.
    pub fn open(
        &self,
        topic: &str,
        type_name: &str,
        delivery: crate::Delivery,
    ) -> Result<Box<dyn DynInject>, Error> {
        open_for(
            &self.shared.iox,
            Some(self.shared.clone()),
            topic,
            type_name,
            delivery,
        )
    }
}

/// [`open_injector`] for a node of the group (`node`), whose publications its lockstep
/// scheduler learns of.
fn open_for(
    iox: &iceoryx2::node::Node<ipc::Service>,
    node: Option<Rc<Shared>>,
    topic: &str,
    type_name: &str,
    delivery: crate::Delivery,
) -> Result<Box<dyn DynInject>, Error> {
    fn open<T: Message>(
        iox: &iceoryx2::node::Node<ipc::Service>,
        node: Option<Rc<Shared>>,
        topic: &str,
        delivery: crate::Delivery,
    ) -> Result<Box<dyn DynInject>, Error> {
        let service = match transport::open_existing::<T>(iox, topic) {
            Ok(service) => service,
            Err(_) => transport::open_pubsub::<T>(iox, topic, delivery)?,
        };
        let lossless = !service.static_config().has_safe_overflow();
        let port = service
            .publisher_builder()
            .backpressure_strategy(transport::backpressure(lossless))
            .max_loaned_samples(2)
            .create()
            .map_err(|e| Error::topic(topic, format!("cannot create publisher: {e:?}")))?;
        Ok(Box::new(Inject::<T> {
            topic: topic.to_string(),
            topic_hash: caravan_schemas::lockstep::name_hash(topic),
            port,
            notifier: transport::notifier(iox, topic)?,
            node,
        }))
    }
    caravan_schemas::with_message_type!(type_name, |T| open::<T>(
        iox,
        node.clone(),
        topic,
        delivery
    ))
    .unwrap_or_else(|| {
        Err(Error::topic(
            topic,
            format!("unknown message type '{type_name}'"),
        ))
    })
}
