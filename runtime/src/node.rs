//! A node: one process of a group, with its identity, params, ports and step loop.

use crate::executor::Executor;
use crate::network::NodeNet;
use crate::transport::Shared;
use crate::{ClockMode, Error, NodeIdentity, Publisher, Step, Subscriber, Topic, Trigger};
use caravan_schemas::{Message, NodeStatus};
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::{Duration, Instant};

/// One process of a group. See the crate documentation for an example.
pub struct Node {
    identity: NodeIdentity,
    shared: Rc<Shared>,
    status: Publisher<NodeStatus>,
    started: Instant,
    epoch_offset_ns: u64,
}

/// Builds a [`Node`] directly, without a launcher (tests, tools).
pub struct NodeBuilder {
    identity: NodeIdentity,
}

impl NodeBuilder {
    pub fn clock(mut self, clock: ClockMode) -> Self {
        self.identity.clock = clock;
        self
    }

    /// Spins up to `spin` for the next message or grant before sleeping (see [`crate::spin`]);
    /// more than [`crate::MAX_SPIN`] is cut to it (a launch file's or `CARAVAN_SPIN`'s is refused).
    pub fn spin(mut self, spin: Duration) -> Self {
        self.identity.spin = spin;
        self
    }

    pub fn host(mut self, host: &str) -> Self {
        self.identity.host = host.to_string();
        self
    }

    pub fn params(mut self, params: serde_json::Value) -> Self {
        self.identity.params = params;
        self
    }

    pub fn build(self) -> Result<Node, Error> {
        Node::new(self.identity)
    }
}

impl Node {
    /// The node the launcher described in the environment (see [`crate::env_vars`]).
    pub fn from_env() -> Result<Self, Error> {
        Self::new(NodeIdentity::from_env()?)
    }

    pub fn builder(group: &str, name: &str) -> NodeBuilder {
        NodeBuilder {
            identity: NodeIdentity::new(group, name),
        }
    }

    pub fn new(identity: NodeIdentity) -> Result<Self, Error> {
        crate::log::init(&identity.name);
        crate::group::validate_name(&identity.group).map_err(Error::Config)?;
        let config = match &identity.iceoryx_config {
            Some(path) => {
                crate::group::use_as_global(path)?;
                crate::group::load_config(path)?
            }
            None => crate::group::config(&identity.group)?,
        };
        let node_name = NodeName::new(&identity.name).map_err(|e| {
            Error::Config(format!(
                "node name '{}' is not usable: {e:?}",
                identity.name
            ))
        })?;
        let iox = iceoryx2::node::NodeBuilder::new()
            .name(&node_name)
            .config(&config)
            // The step loop handles SIGTERM/SIGINT through its WaitSet and exits cleanly, so
            // that iceoryx2 removes this node's shared memory.
            .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
            .create::<ipc::Service>()
            .map_err(|e| Error::transport("cannot create iceoryx2 node", e))?;
        let shared = Rc::new(Shared {
            iox,
            node_hash: identity.node_hash(),
            now_ns: Cell::new(0),
            tick_ns: Cell::new(0),
            lockstep: identity.clock == ClockMode::Lockstep,
            published: RefCell::new(Vec::with_capacity(caravan_schemas::lockstep::MAX_TOPICS)),
            step_of_grant: Cell::new(0),
            burst: Cell::new(false),
            missed: Cell::new(0),
            listeners: RefCell::new(Vec::new()),
            net: identity
                .network
                .as_ref()
                .and_then(|n| NodeNet::new(n, &identity.name, &identity.host)),
            next_arrival_ns: Cell::new(u64::MAX),
            in_step: Cell::new(false),
            step_cpu_started_ns: Cell::new(None),
            arrivals: Cell::new(0),
            ports: RefCell::new(Default::default()),
        });
        // Emulated links hold messages past the tick and a CPU slowdown stamps them late:
        // the scheduler must not overlap such a node.
        shared.ports.borrow_mut().undeclared = shared.net.is_some();
        let status = Publisher::new(shared.clone(), &caravan_schemas::topics::status())?;
        let epoch_offset_ns = identity
            .epoch_ns
            .map_or(0, |epoch| crate::wall_clock_ns().saturating_sub(epoch));
        Ok(Self {
            identity,
            shared,
            status,
            started: Instant::now(),
            epoch_offset_ns,
        })
    }

    pub fn identity(&self) -> &NodeIdentity {
        &self.identity
    }

    pub fn name(&self) -> &str {
        &self.identity.name
    }

    pub fn group(&self) -> &str {
        &self.identity.group
    }

    pub fn clock(&self) -> ClockMode {
        self.identity.clock
    }

    /// The node's params, deserialised from the launch file's table. Unknown or mistyped keys
    /// are errors naming the key.
    pub fn params<P: DeserializeOwned>(&self) -> Result<P, Error> {
        crate::parse_params(&self.identity.name, &self.identity.params)
    }

    pub fn publisher<T: Message>(&self, topic: &Topic<T>) -> Result<Publisher<T>, Error> {
        Publisher::new(self.shared.clone(), topic)
    }

    pub fn subscriber<T: Message>(&self, topic: &Topic<T>) -> Result<Subscriber<T>, Error> {
        Subscriber::new(self.shared.clone(), topic)
    }

    /// Opens publishers of topics whose type is known only by name, fed JSON: what a player
    /// of recordings publishes with. The opener can be moved into the step function.
    ///
    /// A node with injectors may publish to any topic at any time, so the lockstep scheduler
    /// never steps it beside another node.
    pub fn injectors(&self) -> crate::inject::Injectors {
        self.shared.ports.borrow_mut().undeclared = true;
        crate::inject::Injectors {
            shared: self.shared.clone(),
        }
    }

    /// Simulated time of the current (or last) step.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.shared.now_ns.get())
    }

    /// The trigger this node runs with: the launch file's `rate` or `on` if given, else
    /// `default`.
    pub fn trigger(&self, default: Trigger) -> Result<Trigger, Error> {
        if let Some(rate) = &self.identity.rate_override {
            return Ok(Trigger::Every(crate::parse_rate(rate)?));
        }
        if let Some(topic) = &self.identity.on_override {
            return Ok(Trigger::OnMessage(topic.clone()));
        }
        Ok(default)
    }

    /// Runs `step` on `default_trigger` (or the launch file's) until the run ends: SIGTERM or
    /// SIGINT, the lockstep scheduler's stop, or [`Step::stop`]. A final status is published
    /// on exit. Returns the node's statistics.
    pub fn run<F>(
        &mut self,
        default_trigger: Trigger,
        step: F,
    ) -> Result<caravan_schemas::NodeStatus, Error>
    where
        F: FnMut(&mut Step) -> Result<(), Error>,
    {
        let trigger = self.trigger(default_trigger)?;
        let executor = Executor {
            shared: self.shared.clone(),
            name: &self.identity.name,
            host: &self.identity.host,
            status: &self.status,
            epoch: self.started,
            epoch_offset_ns: self.epoch_offset_ns,
            spin: self.identity.spin.min(crate::MAX_SPIN),
        };
        let result = match self.identity.clock {
            ClockMode::Realtime => executor.run_realtime(&trigger, step),
            ClockMode::Lockstep => executor.run_lockstep(&trigger, step),
        };
        self.write_link_stats();
        result
    }

    /// What this node received over emulated links, as `links/<node>.json` in the run
    /// directory, for the run report.
    fn write_link_stats(&self) {
        let (Some(net), Some(dir)) = (&self.shared.net, &self.identity.run_dir) else {
            return;
        };
        let stats = net.stats.borrow();
        if stats.iter().all(|s| s.delivered + s.dropped == 0) {
            return;
        }
        let dir = dir.join(crate::network::LINK_STATS_DIR);
        let written = std::fs::create_dir_all(&dir).and_then(|_| {
            let text = serde_json::to_string(&*stats).map_err(std::io::Error::other)?;
            std::fs::write(dir.join(format!("{}.json", self.identity.name)), text)
        });
        if let Err(e) = written {
            eprintln!("{}: cannot write link statistics: {e}", self.identity.name);
        }
    }
}
