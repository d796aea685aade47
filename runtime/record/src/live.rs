//! The live view: a running group served to the Foxglove app over its WebSocket protocol, by
//! the `foxglove` SDK's server (`caravan launch … --foxglove [PORT]`).
//!
//! The recorder feeds it: every topic of the group (not only the recorded ones) on its raw JSON
//! channel and its Foxglove views (`tf`, `foxglove/…`), the same bytes a recording holds. The
//! server announces the `time` capability and broadcasts the group's simulated time, so the
//! app's clock follows the group in lockstep (faster or slower than the wall) as in realtime.
//! It listens on loopback only: a group's data does not leave the machine unless asked.

use anyhow::{Result, anyhow};
use foxglove::websocket::Capability;
use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer};
use std::collections::BTreeMap;
use std::sync::Arc;

/// The address the live view listens on.
pub const HOST: &str = "127.0.0.1";

/// Simulated time between two time broadcasts, ns.
const TIME_STEP_NS: u64 = 10_000_000;

pub struct LiveView {
    context: Arc<Context>,
    /// `None` once stopped.
    server: Option<foxglove::WebSocketServerHandle>,
    channels: BTreeMap<String, Arc<RawChannel>>,
    last_time_ns: u64,
}

impl LiveView {
    /// Starts listening on `port` (0: any free port). Fails, starting nothing, if the port is
    /// taken.
    pub fn start(port: u16, group: &str) -> Result<Self> {
        let context = Context::new();
        let server = WebSocketServer::new()
            .name(format!("caravan group {group}"))
            .bind(HOST, port)
            .capabilities([Capability::Time])
            .context(&context)
            .start_blocking()
            .map_err(|e| anyhow!("--foxglove {port}: cannot serve on {HOST}:{port}: {e}"))?;
        Ok(LiveView {
            context,
            server: Some(server),
            channels: BTreeMap::new(),
            last_time_ns: 0,
        })
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.server.as_ref().map_or(0, |s| s.port())
    }

    /// Advertises a raw Caravan topic: JSON with the schema generated for its type.
    pub fn advertise_raw(
        &mut self,
        topic: &str,
        descriptor: &caravan_schemas::descriptor::Descriptor,
        wall_clock: bool,
    ) -> Result<()> {
        let type_name = descriptor.type_name();
        let schema = super::schema::for_type(descriptor, wall_clock);
        let data = schema.to_string().into_bytes();
        self.advertise(topic, "json", Schema::new(type_name, "jsonschema", data))
    }

    /// Advertises a Foxglove view (`tf`, `foxglove/…`).
    pub fn advertise_view(&mut self, topic: &str, schema: super::scene::SceneSchema) -> Result<()> {
        let encoding = schema.encoding.clone();
        self.advertise(
            topic,
            &encoding,
            Schema::new(schema.name, schema.encoding, schema.data),
        )
    }

    /// Advertises `topic` (once; later calls keep the first schema).
    fn advertise(&mut self, topic: &str, encoding: &str, schema: Schema) -> Result<()> {
        if self.channels.contains_key(topic) {
            return Ok(());
        }
        let channel = ChannelBuilder::new(topic)
            .message_encoding(encoding)
            .schema(schema)
            .context(&self.context)
            .build_raw()
            .map_err(|e| anyhow!("live view: cannot advertise '{topic}': {e}"))?;
        self.channels.insert(topic.to_string(), channel);
        Ok(())
    }

    /// Sends a message of an advertised topic to every subscribed client, stamped with the
    /// group's simulated time.
    pub fn log(&mut self, topic: &str, stamp_ns: u64, bytes: &[u8]) {
        if let Some(channel) = self.channels.get(topic) {
            channel.log_with_meta(
                bytes,
                PartialMetadata {
                    log_time: Some(stamp_ns),
                },
            );
        }
        // The app's clock needs no finer steps than 10 ms of simulated time.
        if stamp_ns >= self.last_time_ns + TIME_STEP_NS {
            self.last_time_ns = stamp_ns;
            if let Some(server) = &self.server {
                server.broadcast_time(stamp_ns);
            }
        }
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        // Closes the clients' connections and waits for the server's tasks to end.
        if let Some(server) = self.server.take() {
            server.stop().wait_blocking();
        }
    }
}
