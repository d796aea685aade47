//! Taps: subscribers opened by type name at run time, yielding JSON. The recorder and the
//! `caravan topic` commands use them to read topics whose types they learn from discovery.

use crate::Error;
use crate::transport;
use crate::untyped;
use caravan_schemas::Header;
use caravan_schemas::descriptor::Descriptor;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::sync::Arc;

/// What discovery tells about a publish-subscribe service.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicInfo {
    pub name: String,
    pub type_name: String,
    pub payload_size: usize,
    /// Nodes that have the topic open.
    pub nodes: usize,
}

/// Topics of the group of `config`, sorted by name. Internal `caravan/` services are left out
/// unless `internal`.
pub fn list_topics(
    config: &iceoryx2::config::Config,
    internal: bool,
) -> Result<Vec<TopicInfo>, Error> {
    let mut topics = Vec::new();
    ipc::Service::list(config, |details| {
        use iceoryx2::service::static_config::messaging_pattern::MessagingPattern as Pattern;
        if let Pattern::PublishSubscribe(ps) = details.static_details.messaging_pattern() {
            let name = details.static_details.name().to_string();
            let nodes = details
                .dynamic_details
                .as_ref()
                .map_or(0, |d| d.nodes.len());
            if internal || !name.starts_with("caravan/") {
                topics.push(TopicInfo {
                    name,
                    type_name: ps.message_type_details().payload.type_name().to_string(),
                    payload_size: ps.message_type_details().payload.size(),
                    nodes,
                });
            }
        }
        CallbackProgression::Continue
    })
    .map_err(|e| Error::transport("cannot list topics", e))?;
    topics.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(topics)
}

/// One message read by a tap: its header and a copy of its payload's bytes, converted to JSON
/// only when asked (the recorder converts on its writer thread, off the scheduler's path).
pub struct Tapped {
    pub header: Header,
    /// The payload's bytes, as its descriptor lays them out.
    pub bytes: Box<[u8]>,
    pub descriptor: Arc<Descriptor>,
}

impl Tapped {
    /// The payload as JSON (the `header` is not included).
    pub fn json(&self) -> Result<serde_json::Value, Error> {
        self.descriptor
            .view(&self.bytes)
            .map_err(|e| Error::Config(format!("cannot convert to JSON: {e}")))
    }
}

/// A subscriber of a topic whose type is known only by name.
pub trait DynTap {
    fn topic(&self) -> &str;
    fn type_name(&self) -> &'static str;
    /// How the topic's messages are laid out.
    fn descriptor(&self) -> &Arc<Descriptor>;
    /// Reads every waiting message, oldest first.
    fn drain(&self, out: &mut Vec<Tapped>) -> Result<(), Error> {
        self.drain_until(u64::MAX, out)
    }
    /// Reads the waiting messages stamped up to `until_ns`, oldest first, and keeps the
    /// others for a later call: in lockstep a node granted several periods at once publishes
    /// ahead of the time that ends (`caravan_lockstep`, "batches").
    fn drain_until(&self, until_ns: u64, out: &mut Vec<Tapped>) -> Result<(), Error>;
    /// Whether it keeps messages stamped later than a drain asked for.
    fn holds(&self) -> bool;
    /// Messages lost before reaching the tap (sequence gaps).
    fn missed(&self) -> u64;
}

/// A listener woken whenever a message is published on `topic`.
pub fn open_listener(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
) -> Result<Listener<ipc::Service>, Error> {
    transport::listener(iox, topic)
}

struct Tap {
    topic: String,
    descriptor: Arc<Descriptor>,
    port: untyped::Subscriber,
    last_seq: std::cell::RefCell<Vec<(u64, u64)>>,
    missed: std::cell::Cell<u64>,
    /// Read, stamped later than the last drain asked for.
    held: std::cell::RefCell<std::collections::VecDeque<Tapped>>,
}

impl DynTap for Tap {
    fn topic(&self) -> &str {
        &self.topic
    }

    fn type_name(&self) -> &'static str {
        self.descriptor.type_name()
    }

    fn descriptor(&self) -> &Arc<Descriptor> {
        &self.descriptor
    }

    fn holds(&self) -> bool {
        !self.held.borrow().is_empty()
    }

    fn drain_until(&self, until_ns: u64, out: &mut Vec<Tapped>) -> Result<(), Error> {
        let mut held = self.held.borrow_mut();
        if !held.is_empty() {
            let (due, later): (Vec<Tapped>, _) =
                held.drain(..).partition(|m| m.header.stamp_ns <= until_ns);
            out.extend(due);
            held.extend(later);
        }
        let size = self.descriptor.layout().size;
        while let Some(sample) = self
            .port
            .receive()
            .map_err(|e| Error::topic(&self.topic, format!("{e:?}")))?
        {
            let header = untyped::header(sample.user_header());
            let mut last_seq = self.last_seq.borrow_mut();
            match last_seq.iter_mut().find(|(s, _)| *s == header.source_id) {
                Some((_, last)) => {
                    self.missed
                        .set(self.missed.get() + header.seq.saturating_sub(*last + 1));
                    *last = header.seq.max(*last);
                }
                None => last_seq.push((header.source_id, header.seq)),
            }
            let tapped = Tapped {
                header,
                bytes: untyped::payload_bytes(sample.payload(), size).into(),
                descriptor: self.descriptor.clone(),
            };
            if header.stamp_ns <= until_ns {
                out.push(tapped);
            } else {
                held.push_back(tapped);
            }
        }
        Ok(())
    }

    fn missed(&self) -> u64 {
        self.missed.get()
    }
}

/// Opens a tap on `topic`, whose payload type is named `type_name`: a type of the catalog or
/// one a process of the group registered ([`crate::types`]). The subscriber takes the
/// service's own buffer settings, so it fits whatever contract the publishers chose.
pub fn open_tap(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
) -> Result<Box<dyn DynTap>, Error> {
    let descriptor = Arc::new(
        crate::types::lookup(iox.config(), type_name).map_err(|e| Error::topic(topic, e))?,
    );
    let service = untyped::open_existing(iox, topic, &descriptor)?;
    let depth = service.static_config().subscriber_max_buffer_size();
    let port = service
        .subscriber_builder()
        .buffer_size(depth)
        .create()
        .map_err(|e| Error::topic(topic, format!("cannot subscribe: {e:?}")))?;
    Ok(Box::new(Tap {
        topic: topic.to_string(),
        descriptor,
        port,
        last_seq: Default::default(),
        missed: Default::default(),
        held: Default::default(),
    }))
}

/// Who is on a topic, as its shared-memory service records it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicPorts {
    /// Lossless (publishers wait for room) or latest (the oldest message is overwritten).
    pub lossless: bool,
    /// Messages a subscriber's buffer holds.
    pub depth: usize,
    /// The iceoryx2 node of each publisher, one entry per port.
    pub publishers: Vec<iceoryx2::identifiers::UniqueNodeId>,
    /// The iceoryx2 node of each subscriber, one entry per port.
    pub subscribers: Vec<iceoryx2::identifiers::UniqueNodeId>,
}

/// The ports of `topic`, whose payload type is named `type_name`. Only the service is opened:
/// no port is made, so looking does not change what the group's publishers wait for.
pub fn topic_ports(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
) -> Result<TopicPorts, Error> {
    Ok(watch_topic(iox, topic, type_name)?.ports())
}

/// A topic's service held open, so its ports can be read again and again: a look is a few
/// reads of shared memory, where opening the service costs system calls and maps. Holding it
/// keeps the service (not its ports) alive until the watch is dropped.
pub struct TopicWatch {
    ports: Box<dyn Fn() -> TopicPorts>,
}

impl TopicWatch {
    /// Who is on the topic now.
    pub fn ports(&self) -> TopicPorts {
        (self.ports)()
    }
}

/// Opens `topic`'s service (payload type named `type_name`) to watch its ports.
pub fn watch_topic(
    iox: &iceoryx2::node::Node<ipc::Service>,
    topic: &str,
    type_name: &str,
) -> Result<TopicWatch, Error> {
    let descriptor =
        crate::types::lookup(iox.config(), type_name).map_err(|e| Error::topic(topic, e))?;
    let service = untyped::open_existing(iox, topic, &descriptor)?;
    let ports = move || {
        let config = service.static_config();
        let mut ports = TopicPorts {
            lossless: !config.has_safe_overflow(),
            depth: config.subscriber_max_buffer_size(),
            publishers: Vec::new(),
            subscribers: Vec::new(),
        };
        let dynamic = service.dynamic_config();
        dynamic.list_publishers(|p| {
            ports.publishers.push(p.node_id);
            CallbackProgression::Continue
        });
        dynamic.list_subscribers(|s| {
            ports.subscribers.push(s.node_id);
            CallbackProgression::Continue
        });
        ports
    };
    Ok(TopicWatch {
        ports: Box::new(ports),
    })
}
