//! zenoh 1.x in peer mode, the two peers connected by TCP on loopback, multicast scouting off;
//! express publishers (no batching) with blocking congestion control; the echo re-publishes the
//! received payload. Both sides take samples from the subscriber's channel on their main thread
//! (publishing inside the callback stalls zenoh, see `pong`).
//!
//! - `zenoh`: shared memory disabled in both sessions, so every payload is serialised through
//!   the TCP link. The measuring side publishes the same `ZBytes` every round (a reference-
//!   counted clone, no copy), so only its length is checked.
//! - `zenoh-shm`: each round allocates the payload in zenoh's POSIX shared-memory provider,
//!   writes the 16 marker bytes and publishes it; only a reference crosses the link. The echo
//!   must arrive as a shared-memory buffer, or the measurement fails.

use super::payload::{mark, read_mark};
use super::{ECHO_TIMEOUT, PONG_IDLE, Pair, Recorder, ready};
use anyhow::{Result, anyhow, bail};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::bytes::ZBytes;
use zenoh::qos::CongestionControl;
use zenoh::shm::{BlockOn, GarbageCollect, ShmProviderBuilder};

const PING: &str = "caravan/bench/ping";
const PONG: &str = "caravan/bench/pong";

use caravan_bridge::z;

/// Removes zenoh shared-memory segments (`/dev/shm/*.zenoh`) whose processes are gone: the
/// segments of a finished echoing process, and of earlier runs (zenoh 1.10 leaves a
/// measuring process's segments behind when it exits).
pub fn cleanup() {
    zenoh::shm::cleanup_orphaned_shm_segments();
}

/// A TCP endpoint on loopback whose port was free a moment ago.
pub fn free_endpoint() -> Result<String> {
    let port = std::net::TcpListener::bind("127.0.0.1:0")?
        .local_addr()?
        .port();
    Ok(format!("tcp/127.0.0.1:{port}"))
}

fn config(endpoint: &str, listen: bool, shm: bool) -> Result<zenoh::Config> {
    let mut c = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, key: &str, value: &str| z(c.insert_json5(key, value));
    set(&mut c, "mode", r#""peer""#)?;
    // Only loopback: no multicast discovery, no listening on other interfaces. (Gossip stays
    // on; it only travels over the links this session has.)
    set(&mut c, "scouting/multicast/enabled", "false")?;
    if listen {
        set(&mut c, "listen/endpoints", &format!(r#"["{endpoint}"]"#))?;
    } else {
        set(&mut c, "listen/endpoints", r#"["tcp/127.0.0.1:0"]"#)?;
        set(&mut c, "connect/endpoints", &format!(r#"["{endpoint}"]"#))?;
    }
    set(
        &mut c,
        "transport/shared_memory/enabled",
        if shm { "true" } else { "false" },
    )?;
    if shm {
        // Set up shared memory when the session opens, not on the first message.
        set(&mut c, "transport/shared_memory/mode", r#""init""#)?;
    }
    Ok(c)
}

pub fn ping(pair: &Pair, rec: &mut Recorder, shm: bool) -> Result<()> {
    // zenoh logs only if RUST_LOG asks for it.
    zenoh::try_init_log_from_env();
    let session = z(zenoh::open(config(&pair.endpoint, false, shm)?).wait())?;
    let echoes = z(session.declare_subscriber(PONG).wait())?;
    let publisher = z(session
        .declare_publisher(PING)
        .congestion_control(CongestionControl::Block)
        .express(true)
        .wait())?;
    let deadline = Instant::now() + ECHO_TIMEOUT;
    while !z(publisher.matching_status().wait())?.matching() {
        if Instant::now() > deadline {
            bail!("the echoing zenoh peer did not appear within {ECHO_TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let provider = if shm {
        // Room for the payload in flight, its echo and slack for garbage collection.
        Some(z(ShmProviderBuilder::default_backend(
            4 * pair.bytes + 65_536,
        )
        .wait())?)
    } else {
        None
    };
    let fixed = ZBytes::from(vec![0u8; pair.bytes]);
    // Sent and not echoed yet: when each was sent, oldest first.
    let mut sent_at = std::collections::VecDeque::new();
    let total = rec.total();
    let mut next = 0;
    for seq in 0..total {
        // Keep `in_flight` messages on their way (one: a round trip at a time).
        while next < total && next < seq + pair.in_flight {
            sent_at.push_back(Instant::now());
            put(&publisher, provider.as_ref(), &fixed, pair.bytes, next)?;
            next += 1;
        }
        let Some(sample) = z(echoes.recv_timeout(ECHO_TIMEOUT))? else {
            bail!("no echo of round {seq} within {ECHO_TIMEOUT:?}");
        };
        let rtt = sent_at
            .pop_front()
            .map(|t: Instant| t.elapsed())
            .unwrap_or_default();
        let payload = sample.payload();
        match (shm, payload.as_shm()) {
            (true, Some(buf)) => {
                let got = read_mark(buf);
                if got != Some(seq) {
                    bail!("echo of round {seq} came back as {got:?}");
                }
            }
            (true, None) => bail!("the echo did not come through shared memory"),
            (false, Some(_)) => bail!("the echo came through shared memory though it is off"),
            (false, None) if payload.len() != pair.bytes => {
                bail!("echo of {} bytes, sent {}", payload.len(), pair.bytes)
            }
            (false, None) => {}
        }
        drop(sample);
        rec.record(rtt);
    }
    // A payload of another length stops the echo side.
    z(publisher.put(vec![0u8; 8]).wait())?;
    drop(publisher);
    drop(echoes);
    z(session.close().wait())?;
    Ok(())
}

/// Puts message `seq`: the same payload every time, or (`provider`) one allocated in zenoh's
/// shared memory and marked.
fn put(
    publisher: &zenoh::pubsub::Publisher<'_>,
    provider: Option<&zenoh::shm::ShmProvider<zenoh::shm::PosixShmProviderBackend>>,
    fixed: &ZBytes,
    bytes: usize,
    seq: u64,
) -> Result<()> {
    match provider {
        Some(provider) => {
            let mut buf = provider
                .alloc(bytes)
                .with_policy::<BlockOn<GarbageCollect>>()
                .wait()
                .map_err(|e| anyhow!("zenoh shared memory: {e:?}"))?;
            mark(&mut buf, seq);
            z(publisher.put(buf).wait())
        }
        None => z(publisher.put(fixed.clone()).wait()),
    }
}

pub fn pong(pair: &Pair, shm: bool) -> Result<()> {
    zenoh::try_init_log_from_env();
    let session = z(zenoh::open(config(&pair.endpoint, true, shm)?).wait())?;
    let publisher = z(session
        .declare_publisher(PONG)
        .congestion_control(CongestionControl::Block)
        .express(true)
        .wait())?;
    let pings = z(session.declare_subscriber(PING).wait())?;
    ready("");
    // The echo is published from this thread, not from the subscriber's callback: a put that
    // blocks (4 MiB, congestion control Block) inside the callback stalls zenoh's receiving
    // thread, and after a while zenoh closes the link ("Unable to push non droppable network
    // message").
    while let Some(sample) = z(pings.recv_timeout(PONG_IDLE))? {
        if sample.payload().len() != pair.bytes {
            break;
        }
        z(publisher.put(sample.payload().clone()).wait())?;
    }
    drop(pings);
    drop(publisher);
    z(session.close().wait())?;
    Ok(())
}
