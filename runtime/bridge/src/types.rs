//! Message types across hosts: a host's bridge may meet a type that no process of its own
//! host registered (a host that records the group, or a host whose reader started before the
//! publisher's host registered the type). Each bridge answers queries for the descriptors its
//! group registered on its host (`caravan/G/type/TYPE`), and a bridge that meets a type it
//! cannot look up asks the others once and registers the answer here, as a local process would
//! have.

use super::context::Ctx;
use super::keys;
use super::z;
use anyhow::{Result, bail};
use caravan::schemas::descriptor::Descriptor;
use std::time::Duration;
use zenoh::Wait;

/// How long a bridge waits for another host to describe a type: the hosts are connected
/// already (a message or a wish to read came from one), so an answer takes a round trip.
const ASK_TIMEOUT: Duration = Duration::from_secs(5);

/// Answers other hosts' queries for the descriptors registered on this host, until dropped.
pub(super) fn serve(ctx: &Ctx) -> Result<zenoh::query::Queryable<()>> {
    let config = ctx.cfg.iceoryx.clone();
    let prefix = keys::message_type(ctx.group(), "");
    z(ctx
        .session
        .declare_queryable(keys::message_type(ctx.group(), "**"))
        .callback(move |query| {
            let Some(type_name) = query.key_expr().as_str().strip_prefix(&prefix) else {
                return;
            };
            // A type this host does not know is not answered: another host may know it.
            if let Ok(d) = caravan::types::lookup(&config, type_name) {
                let text = serde_json::to_string(&d.to_json()).expect("JSON serialises");
                let _ = query.reply(query.key_expr().clone(), text).wait();
            }
        })
        .wait())
}

/// Makes `type_name` known on this host: already known, or described by another host's bridge.
pub(super) fn learn(ctx: &Ctx, type_name: &str) -> Result<()> {
    let config = &ctx.cfg.iceoryx;
    if caravan::types::lookup(config, type_name).is_ok() {
        return Ok(());
    }
    let replies = z(ctx
        .session
        .get(keys::message_type(ctx.group(), type_name))
        .timeout(ASK_TIMEOUT)
        .wait())?;
    while let Ok(reply) = replies.recv() {
        let Ok(sample) = reply.result() else {
            continue;
        };
        let text = sample.payload().to_bytes();
        let described = serde_json::from_slice(&text)
            .map_err(|e| e.to_string())
            .and_then(|json| Descriptor::from_json(&json));
        match described {
            Ok(d) if d.type_name() == type_name => {
                caravan::types::register(config, &d)?;
                return Ok(());
            }
            Ok(d) => bail!(
                "a host described '{}' when asked for '{type_name}'",
                d.type_name()
            ),
            Err(e) => bail!("a host sent a faulty descriptor of '{type_name}': {e}"),
        }
    }
    bail!("no host of the group knows message type '{type_name}'")
}
