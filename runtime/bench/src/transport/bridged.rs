//! Caravan topics between two hosts on this machine: the measuring node on host `a`, the
//! echoing node on host `b`, each host with an iceoryx2 namespace of its own, and the two
//! hosts' relays ([`caravan_bridge::relay`], as `caravan launch --host` runs them) in a third
//! process, `caravan bench transport-relays`, their zenoh sessions joined over TCP on
//! loopback with the launcher's session settings. One way is
//!
//!   ping → shared memory a → relay a → zenoh (TCP) → relay b → shared memory b → pong
//!
//! which is what a topic read on another host takes, less the wire. The nodes are the
//! `caravan-event` ones; only their namespaces differ.
//!
//! The relays run in a process of their own because a relay never serves readers in its own
//! process (it takes them for its launcher's recorder and scheduler).
//!
//! Their sessions take the launcher's settings, with its default lease (`group.host_lease`,
//! 10 s): a relays' process held off the CPU for longer than a short lease on a loaded
//! machine (CI) closed the link and lost the message in flight.

use super::{Pair, await_ready, ready, stop_child, temp_path};
use anyhow::{Context, Result};
use caravan::schemas::lockstep::name_hash;
use caravan_bridge::relay::{Relay, RelayConfig};
use caravan_bridge::{session_config, z};
use caravan_launch::model::{GroupSpec, HostSpec};
use clap::Args;
use std::io::Read;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use zenoh::Wait;

/// The measuring node's host, and the echoing node's.
pub const HOSTS: [(&str, &str); 2] = [("a", "ping"), ("b", "pong")];

#[derive(Args)]
pub struct RelaysArgs {
    #[arg(long)]
    group: String,
    /// Where host `a` listens and host `b` connects: a zenoh endpoint such as tcp/127.0.0.1:7447
    #[arg(long)]
    endpoint: String,
}

/// The iceoryx2 namespace of `host` in bench group `group`.
fn namespace(group: &str, host: &str) -> String {
    format!("{group}-{host}")
}

/// The iceoryx2 config file of the host that runs node `name` (`ping` or `pong`).
pub fn config_path(pair: &Pair, name: &str) -> PathBuf {
    let (host, _) = HOSTS
        .iter()
        .find(|(_, n)| *n == name)
        .expect("ping or pong");
    temp_path(&namespace(&pair.group, host), "toml")
}

/// Writes both hosts' iceoryx2 configs.
pub fn write_configs(group: &str) -> Result<()> {
    for (host, _) in HOSTS {
        super::iceoryx2_raw::write_config_file(&namespace(group, host))?;
    }
    Ok(())
}

/// Removes both hosts' shared memory and config files, and the relays' statistics.
pub fn cleanup(group: &str) {
    for (host, _) in HOSTS {
        let ns = namespace(group, host);
        let _ = caravan::group::remove_resources(&ns);
        let _ = std::fs::remove_file(temp_path(&ns, "toml"));
    }
    let _ = std::fs::remove_dir_all(temp_path(group, "net"));
}

/// `caravan bench transport-relays`: both hosts' relays, until standard input closes.
pub fn relays(args: &RelaysArgs) -> Result<()> {
    let listen = HostSpec {
        listen: vec![args.endpoint.clone()],
        ..HostSpec::default()
    };
    let connect = HostSpec {
        connect: vec![args.endpoint.clone()],
        ..HostSpec::default()
    };
    let mut running = Vec::new();
    for ((host, node), spec) in HOSTS.into_iter().zip([listen, connect]) {
        let config = session_config(&spec, GroupSpec::DEFAULT_HOST_LEASE)?;
        let session = z(zenoh::open(config).wait())
            .with_context(|| format!("host '{host}': cannot open its zenoh session"))?;
        let iceoryx = super::iceoryx2_raw::config(&namespace(&args.group, host))?;
        // The node of the other host: its messages arrive through this relay and must not be
        // sent back.
        let other = HOSTS.iter().find(|(h, _)| *h != host).expect("two hosts").1;
        let cfg = RelayConfig {
            group: args.group.clone(),
            host: host.to_string(),
            iceoryx,
            remote: [name_hash(other)].into(),
            clock_host: None,
            stats_dir: temp_path(&args.group, "net"),
        };
        let relay = Relay::start(session.clone(), cfg, move |why| {
            eprintln!("caravan: relay of host '{host}' ({node}'s side): {why}");
        })?;
        running.push((relay, session));
    }
    ready("");
    // The measuring side closes our standard input when it is done (or dies).
    let _ = std::io::stdin().read_to_end(&mut Vec::new());
    for (relay, session) in running {
        relay.stop();
        let _ = session.close().wait();
    }
    Ok(())
}

/// Starts `caravan bench transport-relays` and waits until both relays run.
pub fn start_relays(group: &str, endpoint: &str) -> Result<Child> {
    let mut child = Command::new(std::env::current_exe()?)
        .args(["bench", "transport-relays", "--group", group])
        .args(["--endpoint", endpoint])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .context("cannot start the relays")?;
    match await_ready(child.stdout.take().expect("piped stdout")) {
        Ok(_) => Ok(child),
        Err(e) => {
            stop_relays(Some(child));
            Err(e.context("the relays did not start"))
        }
    }
}

/// Closes the relays' standard input, which stops them.
pub fn stop_relays(relays: Option<Child>) {
    if let Some(mut child) = relays {
        drop(child.stdin.take());
        stop_child(&mut child, "relays' process");
    }
}
