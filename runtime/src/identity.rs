//! Who a node is, as handed over by the launcher through the environment.

use crate::{ClockMode, Error};
use std::path::PathBuf;

/// Names of the environment variables the launcher sets for every process.
pub mod env_vars {
    pub const GROUP: &str = "CARAVAN_GROUP";
    pub const NODE: &str = "CARAVAN_NODE";
    pub const HOST: &str = "CARAVAN_HOST";
    /// The node's params table, as JSON.
    pub const PARAMS: &str = "CARAVAN_PARAMS";
    /// Path of the group's iceoryx2 config file.
    pub const ICEORYX_CONFIG: &str = "CARAVAN_ICEORYX_CONFIG";
    /// `realtime` or `lockstep`.
    pub const CLOCK: &str = "CARAVAN_CLOCK";
    /// Overrides the node's default trigger with a rate, e.g. `50Hz` or `20ms`.
    pub const RATE: &str = "CARAVAN_RATE";
    /// Overrides the node's default trigger with a topic whose messages step the node.
    pub const ON: &str = "CARAVAN_ON";
    /// How long the node looks for its next message or grant before it sleeps, e.g. `50us`
    /// (see [`crate::spin`]); unset or `0s`: it sleeps at once.
    pub const SPIN: &str = "CARAVAN_SPIN";
    /// Wall-clock ns at the group's start; realtime simulated time counts from it.
    pub const EPOCH_NS: &str = "CARAVAN_EPOCH_NS";
    /// The group's random seed; nodes derive their own streams from it.
    pub const SEED: &str = "CARAVAN_SEED";
    /// Directory of the launch file; relative paths in params are relative to it.
    pub const LAUNCH_DIR: &str = "CARAVAN_LAUNCH_DIR";
    /// The run's output directory (logs, recording, report); nodes may write artefacts there.
    pub const RUN_DIR: &str = "CARAVAN_RUN_DIR";
    /// The group's hosts, links and CPU slowdowns, as JSON (`caravan::network::Network`).
    pub const NETWORK: &str = "CARAVAN_NETWORK";
    /// Set (to `1`) when the launcher only wants the node to check its params and inputs:
    /// the node exits 0 or 2 without joining the group (see [`crate::node_main`]).
    pub const CHECK: &str = "CARAVAN_CHECK";
    /// Set for a container (launch key `container`): the process runs these nodes, a JSON
    /// list of [`crate::container::Member`]; `CARAVAN_NODE` then names the container.
    pub const CONTAINER: &str = "CARAVAN_CONTAINER";
}

/// True when the launcher started this process only to check its params and inputs
/// ([`env_vars::CHECK`]): a node that does not use [`crate::node_main`] should then validate
/// what it can and exit, 0 when its input is good and 2 when not, without joining the group.
pub fn check_only() -> bool {
    std::env::var_os(env_vars::CHECK).is_some_and(|v| !v.is_empty() && v != "0")
}

/// Identity and settings of one node.
#[derive(Debug, Clone)]
pub struct NodeIdentity {
    pub group: String,
    pub name: String,
    pub host: String,
    /// The params table as JSON (an object).
    pub params: serde_json::Value,
    /// The group's iceoryx2 config; `None` derives it from the group name.
    pub iceoryx_config: Option<PathBuf>,
    pub clock: ClockMode,
    pub rate_override: Option<String>,
    pub on_override: Option<String>,
    /// How long the node spins for its next message or grant before it sleeps (see
    /// [`crate::spin`]); zero, the default, sleeps at once. At most [`crate::MAX_SPIN`].
    pub spin: std::time::Duration,
    /// Wall-clock ns at which the group's time started (realtime).
    pub epoch_ns: Option<u64>,
    pub seed: u64,
    /// Directory relative paths in params are resolved against.
    pub launch_dir: PathBuf,
    /// Where the run's outputs go; `None` outside `caravan launch`.
    pub run_dir: Option<PathBuf>,
    /// The emulated network; `None` when the group declares no links or CPU slowdowns.
    pub network: Option<crate::network::Network>,
}

impl NodeIdentity {
    pub fn new(group: &str, name: &str) -> Self {
        Self {
            group: group.to_string(),
            name: name.to_string(),
            host: "localhost".to_string(),
            params: serde_json::Value::Object(Default::default()),
            iceoryx_config: None,
            clock: ClockMode::Realtime,
            rate_override: None,
            on_override: None,
            spin: std::time::Duration::ZERO,
            epoch_ns: None,
            seed: 0,
            launch_dir: PathBuf::from("."),
            run_dir: None,
            network: None,
        }
    }

    /// Reads the variables in [`env_vars`]. Group and node name are required.
    pub fn from_env() -> Result<Self, Error> {
        let required = |var: &'static str| {
            std::env::var(var).map_err(|_| Error::Env {
                var,
                message: "not set; start this process with `caravan launch`, or set it by hand"
                    .into(),
            })
        };
        let optional = |var: &'static str| std::env::var(var).ok().filter(|v| !v.is_empty());
        let mut id = Self::new(&required(env_vars::GROUP)?, &required(env_vars::NODE)?);
        if let Some(host) = optional(env_vars::HOST) {
            id.host = host;
        }
        if let Some(text) = optional(env_vars::PARAMS) {
            id.params = serde_json::from_str(&text).map_err(|e| Error::Env {
                var: env_vars::PARAMS,
                message: format!("not a JSON object: {e}"),
            })?;
        }
        id.iceoryx_config = optional(env_vars::ICEORYX_CONFIG).map(PathBuf::from);
        if let Some(clock) = optional(env_vars::CLOCK) {
            id.clock = clock.parse().map_err(|message| Error::Env {
                var: env_vars::CLOCK,
                message,
            })?;
        }
        if let Some(dir) = optional(env_vars::LAUNCH_DIR) {
            id.launch_dir = PathBuf::from(dir);
        }
        id.run_dir = optional(env_vars::RUN_DIR).map(PathBuf::from);
        if let Some(text) = optional(env_vars::NETWORK) {
            id.network = Some(
                crate::network::Network::from_json(&text).map_err(|message| Error::Env {
                    var: env_vars::NETWORK,
                    message,
                })?,
            );
        }
        id.rate_override = optional(env_vars::RATE);
        id.on_override = optional(env_vars::ON);
        if let Some(spin) = optional(env_vars::SPIN) {
            id.spin = crate::parse_spin(&spin).map_err(|e| Error::Env {
                var: env_vars::SPIN,
                message: e.to_string(),
            })?;
        }
        if let Some(seed) = optional(env_vars::SEED) {
            id.seed = seed.parse().map_err(|_| Error::Env {
                var: env_vars::SEED,
                message: format!("'{seed}' is not an unsigned integer"),
            })?;
        }
        if let Some(epoch) = optional(env_vars::EPOCH_NS) {
            id.epoch_ns = Some(epoch.parse().map_err(|_| Error::Env {
                var: env_vars::EPOCH_NS,
                message: format!("'{epoch}' is not a number of nanoseconds"),
            })?);
        }
        Ok(id)
    }

    /// `path` from a params table, resolved against the launch file's directory.
    pub fn resolve_path(&self, path: &str) -> PathBuf {
        self.launch_dir.join(path)
    }

    /// A seed for this node's random streams: the group seed mixed with the node name, so
    /// nodes draw independent but reproducible numbers.
    pub fn node_seed(&self) -> u64 {
        self.seed ^ self.node_hash().rotate_left(17)
    }

    /// Hash that identifies this node in message headers and the lockstep protocol.
    pub fn node_hash(&self) -> u64 {
        caravan_schemas::lockstep::name_hash(&self.name)
    }
}
