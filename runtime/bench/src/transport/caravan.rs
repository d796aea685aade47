//! Caravan topics: `Publisher::loan_as_is` in place, `Subscriber::receive`, header stamping
//! and gap counting included. Woken by events through `Node::run`, or (benchmark only)
//! spinning. The same nodes measure the path between two hosts ([`super::bridged`]).

use super::payload::{Bytes, STOP, copy_mark, mark, read_mark, with_blob};
use super::{ECHO_TIMEOUT, Kind, PONG_IDLE, Pair, Recorder, ready, spin};
use anyhow::{Result, bail};
use caravan::{Delivery, Node, NodeIdentity, Publisher, Topic, Trigger};
use caravan_schemas::Message;
use std::collections::VecDeque;
use std::time::Instant;

const PING: &str = "bench/ping";
const PONG: &str = "bench/pong";

/// A node of the pair's group, with the bench's iceoryx2 config (see `iceoryx2_raw`): the
/// group's, or between hosts that of the node's host.
fn node(pair: &Pair, name: &str) -> Result<Node> {
    let mut identity = NodeIdentity::new(&pair.group, name);
    identity.iceoryx_config = Some(match pair.kind {
        Kind::CaravanBridged => super::bridged::config_path(pair, name),
        _ => pair.temp_path("toml"),
    });
    if pair.kind == Kind::CaravanSpin {
        identity.spin = pair.spin;
    }
    Ok(Node::new(identity)?)
}

/// The pair's topic `name`: as a node makes it by default with one message in flight; lossless
/// and as deep as the window with several, so none is overwritten (the window bounds every
/// queue on the way, so no publisher ever waits).
fn topic<T: Message>(pair: &Pair, name: &str) -> Topic<T> {
    match pair.in_flight {
        1 => Topic::new(name),
        n => Topic::new(name).with_delivery(Delivery::Lossless { depth: n as usize }),
    }
}

/// Waits until `publisher` has a reader. On one host the other side's exists already; between
/// hosts a message sent before the bridge subscribed for the other host would be lost (as a
/// topic's messages are before its first reader, on one host too).
fn await_reader<T: Message>(publisher: &Publisher<T>) -> Result<()> {
    let start = Instant::now();
    while publisher.subscribers() == 0 {
        if start.elapsed() > ECHO_TIMEOUT {
            bail!(
                "nobody subscribed to '{}' within {ECHO_TIMEOUT:?}",
                publisher.topic()
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    Ok(())
}

/// A blob loaned as it is: only the 16 marker bytes are written, so filling a 4 MiB message
/// is not taken for moving it.
fn loan<T: Message + Bytes>(
    publisher: &Publisher<T>,
) -> Result<caravan::Loan<'_, T>, caravan::Error> {
    // SAFETY: the bench's messages are blobs, of which every bit pattern is valid.
    unsafe { publisher.loan_as_is() }
}

/// Loans a message in shared memory, writes the 16 marker bytes and publishes it.
fn send<T: Message + Bytes>(publisher: &Publisher<T>, seq: u64) -> Result<(), caravan::Error> {
    let mut loan = loan(publisher)?;
    mark(loan.bytes_mut(), seq);
    loan.send()
}

fn mismatch(expected: u64, got: Option<u64>) -> caravan::Error {
    caravan::Error::Step(format!("echo of round {expected} came back as {got:?}"))
}

pub fn ping_event(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    with_blob!(pair.bytes, ping_event_t(pair, rec))
}

/// Keeps `pair.in_flight` messages sent and not yet echoed; each echo's round trip is
/// measured from its own message's send.
fn ping_event_t<T: Message + Bytes>(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    let mut node = node(pair, "ping")?;
    let ping = node.publisher(&topic::<T>(pair, PING))?;
    let pong = node.subscriber(&topic::<T>(pair, PONG))?;
    let total = rec.total();
    // Sent and not echoed yet: when each was sent, oldest first.
    let mut sent_at = VecDeque::new();
    let (mut next, mut seq) = (0, 0);
    let mut send_next = |sent_at: &mut VecDeque<Instant>| -> Result<(), caravan::Error> {
        if next < total {
            sent_at.push_back(Instant::now());
            send(&ping, next)?;
            next += 1;
        }
        Ok(())
    };
    await_reader(&ping)?;
    for _ in 0..pair.in_flight {
        send_next(&mut sent_at)?;
    }
    node.run(Trigger::on(PONG), |step| {
        while let Some(msg) = pong.receive()? {
            let rtt = sent_at.pop_front().map(|t| t.elapsed()).unwrap_or_default();
            let got = read_mark(msg.bytes());
            if got != Some(seq) {
                return Err(mismatch(seq, got));
            }
            drop(msg);
            rec.record(rtt);
            seq += 1;
            if seq >= total {
                step.stop();
                return Ok(());
            }
            send_next(&mut sent_at)?;
        }
        Ok(())
    })?;
    send(&ping, STOP)?;
    Ok(())
}

pub fn pong_event(pair: &Pair) -> Result<()> {
    with_blob!(pair.bytes, pong_event_t(pair))
}

fn pong_event_t<T: Message + Bytes>(pair: &Pair) -> Result<()> {
    let mut node = node(pair, "pong")?;
    let ping = node.subscriber(&topic::<T>(pair, PING))?;
    let pong = node.publisher(&topic::<T>(pair, PONG))?;
    ready("");
    let mut answered = false;
    node.run(Trigger::on(PING), |step| {
        while let Some(msg) = ping.receive()? {
            if read_mark(msg.bytes()) == Some(STOP) {
                step.stop();
                return Ok(());
            }
            if !answered {
                await_reader(&pong).map_err(|e| caravan::Error::Step(format!("{e:#}")))?;
                answered = true;
            }
            let mut loan = loan(&pong)?;
            copy_mark(msg.bytes(), loan.bytes_mut());
            loan.send()?;
        }
        Ok(())
    })?;
    Ok(())
}

pub fn ping_poll(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    with_blob!(pair.bytes, ping_poll_t(pair, rec))
}

/// BENCHMARK ONLY: spins on `Subscriber::receive` instead of running the node's step loop.
/// Caravan nodes spin at most their bounded `spin`, then sleep; this shows what the transport
/// costs without the wake-up.
fn ping_poll_t<T: Message + Bytes>(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    let node = node(pair, "ping")?;
    let ping = node.publisher(&Topic::<T>::new(PING))?;
    let pong = node.subscriber(&Topic::<T>::new(PONG))?;
    for seq in 0..rec.total() {
        let sent_at = Instant::now();
        send(&ping, seq)?;
        let msg = spin(|| Ok(pong.receive()?), ECHO_TIMEOUT)?;
        let rtt = sent_at.elapsed();
        let got = read_mark(msg.bytes());
        if got != Some(seq) {
            bail!(mismatch(seq, got));
        }
        drop(msg);
        rec.record(rtt);
    }
    send(&ping, STOP)?;
    Ok(())
}

pub fn pong_poll(pair: &Pair) -> Result<()> {
    with_blob!(pair.bytes, pong_poll_t(pair))
}

/// BENCHMARK ONLY: the spinning echo side, see [`ping_poll_t`].
fn pong_poll_t<T: Message + Bytes>(pair: &Pair) -> Result<()> {
    let node = node(pair, "pong")?;
    let ping = node.subscriber(&Topic::<T>::new(PING))?;
    let pong = node.publisher(&Topic::<T>::new(PONG))?;
    ready("");
    loop {
        let msg = spin(|| Ok(ping.receive()?), PONG_IDLE)?;
        if read_mark(msg.bytes()) == Some(STOP) {
            return Ok(());
        }
        let mut loan = loan(&pong)?;
        copy_mark(msg.bytes(), loan.bytes_mut());
        loan.send()?;
    }
}
