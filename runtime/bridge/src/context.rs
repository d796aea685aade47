//! What a host's two relay threads share (the relay starts them): the relay's config,
//! its zenoh session, what is known of the other hosts, and the messages the outbound thread
//! hands the inbound one.

use super::causal::Knowledge;
use super::keys::Envelope;
use anyhow::Result;
use caravan::network::LinkStats;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How long a thread waits before it looks at the stop flag again.
pub(super) const POLL: Duration = Duration::from_millis(250);

/// Topics of the lockstep protocol: they cross hosts in a lockstep run.
pub(super) const LOCKSTEP_PREFIX: &str = "caravan/lockstep/";

pub(super) fn is_control(topic: &str) -> bool {
    topic.starts_with(LOCKSTEP_PREFIX)
}

/// What a host's relay is told when it starts.
pub struct RelayConfig {
    pub group: String,
    pub host: String,
    pub iceoryx: iceoryx2::config::Config,
    /// Node ids of the processes other hosts run.
    pub remote: BTreeSet<u64>,
    /// Lockstep: the host whose launcher owns simulated time and records.
    pub clock_host: Option<String>,
    /// Where the measured latency of the network from each host is written when the relay
    /// stops (`<this host>.json`, see [`caravan::network::NETWORK_STATS_DIR`]).
    pub stats_dir: std::path::PathBuf,
}

/// What both threads share.
pub(super) struct Ctx {
    pub session: zenoh::Session,
    pub cfg: RelayConfig,
    pub running: AtomicBool,
    /// Node ids of processes on other hosts: their messages are not sent on.
    pub remote: Mutex<BTreeSet<u64>>,
    /// The bridge's own iceoryx2 nodes: their ports read and write for other hosts.
    pub own_nodes: Mutex<Vec<UniqueNodeId>>,
    /// What this host knows was sent ([`super::causal`]): its own counts are the outbound
    /// thread's, the others' come with control messages.
    pub knowledge: Mutex<Knowledge>,
    /// host → its wishes to read that the outbound thread has acted on.
    pub wants_handled: Mutex<BTreeMap<String, u64>>,
    /// Topics read here → their message type, for naming a mismatch.
    pub reading: Mutex<BTreeMap<String, String>>,
    /// Sending host → what its messages took to be published here (header send time →
    /// publication here, wall clocks of two machines).
    pub network: Mutex<BTreeMap<String, LinkStats>>,
    pub failed: Box<dyn Fn(String) + Send + Sync>,
}

impl Ctx {
    pub fn group(&self) -> &str {
        &self.cfg.group
    }

    pub fn host(&self) -> &str {
        &self.cfg.host
    }

    pub fn is_running(&self) -> bool {
        self.running.load(Ordering::Relaxed)
    }

    /// Whether a port of node `id` belongs to this launcher's bridge.
    pub fn is_own(&self, id: &UniqueNodeId) -> bool {
        self.own_nodes.lock().unwrap().contains(id)
    }

    pub fn iox_node(&self) -> Result<iceoryx2::node::Node<ipc::Service>> {
        let node = NodeBuilder::new()
            .config(&self.cfg.iceoryx)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| anyhow::anyhow!("bridge node: {e:?}"))?;
        self.own_nodes.lock().unwrap().push(*node.id());
        Ok(node)
    }
}

/// What the outbound thread tells the inbound one.
pub(super) enum Arrival {
    /// A message from another host for this one.
    Message {
        topic: String,
        envelope: Envelope,
        wire: Vec<u8>,
    },
    /// The outbound side acted on more wishes to read: held messages may be due.
    Handled,
}
