//! Injectors: publishers opened by type name at run time, fed JSON. `caravan topic pub` and
//! `caravan play` use them to publish into a group from outside it, the way taps
//! ([`crate::tap`]) read from it.

use crate::Error;
use crate::transport::{self, Shared};
use crate::untyped;
use caravan_schemas::Header;
use caravan_schemas::descriptor::Descriptor;
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

struct Inject {
    topic: String,
    descriptor: Descriptor,
    port: untyped::Publisher,
    topic_hash: u64,
    notifier: Notifier<ipc::Service>,
    /// The node publishing, when the injector belongs to one ([`crate::Node::injectors`]):
    /// in lockstep its scheduler, not the notifier, wakes subscribers.
    node: Option<Rc<Shared>>,
    /// The type's default value, which the JSON's fields are written over.
    default: Box<[u8]>,
}

impl DynInject for Inject {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn publish_json(&self, header: Header, json: &serde_json::Value) -> Result<(), Error> {
        let mut bytes = self.default.clone();
        self.descriptor
            .write(json, &mut bytes)
            .map_err(|e| Error::topic(&self.topic, e))?;
        untyped::publish(&self.port, &self.topic, header, &bytes)?;
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
    let descriptor =
        crate::types::lookup(iox.config(), type_name).map_err(|e| Error::topic(topic, e))?;
    let service = match untyped::open_existing(iox, topic, &descriptor) {
        Ok(service) => service,
        Err(_) => untyped::open_or_create(iox, topic, &descriptor, delivery)?,
    };
    let lossless = !service.static_config().has_safe_overflow();
    let port = service
        .publisher_builder()
        .backpressure_strategy(transport::backpressure(lossless))
        .max_loaned_samples(2)
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot create publisher: {e:?}")))?;
    let default = descriptor
        .default_bytes()
        .map_err(|e| Error::topic(topic, e))?;
    Ok(Box::new(Inject {
        topic: topic.to_string(),
        topic_hash: caravan_schemas::lockstep::name_hash(topic),
        descriptor,
        port,
        notifier: transport::notifier(iox, topic)?,
        node,
        default,
    }))
}
