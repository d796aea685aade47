//! Typed topics: a service name bound to a message type and a delivery contract.

use crate::Message;
use std::marker::PhantomData;

/// How a topic hands messages to slow subscribers. Publisher and subscriber of one topic must
/// agree; iceoryx2 rejects a port whose contract differs from the service's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// The newest `depth` messages are kept per subscriber; older ones are overwritten and
    /// counted as missed. Publishers never wait. Right for state such as poses and scans.
    Latest { depth: usize },
    /// Nothing is lost: a publisher waits while a subscriber's queue of `depth` is full.
    Lossless { depth: usize },
}

impl Delivery {
    /// The queue depth, at least 1.
    pub fn depth(&self) -> usize {
        match *self {
            Delivery::Latest { depth } | Delivery::Lossless { depth } => depth.max(1),
        }
    }

    /// Whether publishers wait rather than overwrite (iceoryx2's safe overflow is off).
    pub fn is_lossless(&self) -> bool {
        matches!(self, Delivery::Lossless { .. })
    }
}

/// A service name bound to the message type `T`. The helpers of [`crate::topics`] return the
/// well-known ones, so that a name cannot be paired with the wrong type.
#[derive(Debug)]
pub struct Topic<T> {
    name: String,
    delivery: Delivery,
    _type: PhantomData<fn() -> T>,
}

impl<T> Clone for Topic<T> {
    fn clone(&self) -> Self {
        Self {
            name: self.name.clone(),
            delivery: self.delivery,
            _type: PhantomData,
        }
    }
}

impl<T: Message> Topic<T> {
    /// A topic with [`Delivery::Latest`] and a depth of 8.
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            delivery: Delivery::Latest { depth: 8 },
            _type: PhantomData,
        }
    }

    /// A topic on which no message is ever dropped.
    pub fn lossless(name: &str) -> Self {
        Self::new(name).with_delivery(Delivery::Lossless { depth: 256 })
    }

    /// The same topic with another delivery contract; every port of the topic must use it.
    pub fn with_delivery(mut self, delivery: Delivery) -> Self {
        self.delivery = delivery;
        self
    }

    /// The iceoryx2 service name, as recordings and `caravan topic` show it.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// How the topic hands messages to slow subscribers.
    pub fn delivery(&self) -> Delivery {
        self.delivery
    }

    /// The stable cross-language name of `T`.
    pub fn type_name(&self) -> &'static str {
        crate::type_name::<T>()
    }

    /// The lockstep protocol's hash of the name ([`crate::lockstep::name_hash`]): how a step
    /// reports which topics it published to, so the scheduler can wake their subscribers.
    pub fn name_hash(&self) -> u64 {
        crate::lockstep::name_hash(&self.name)
    }
}
