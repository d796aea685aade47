//! Raw iceoryx2 publish-subscribe, no Caravan wrapper: the ports of `bench wrapper`
//! (`pingpong::RawSide`), with samples written in place. Woken through a WaitSet on an event
//! listener, or (benchmark only) polled in a spin loop without events.
//!
//! Both this and the Caravan variant use [`config`]: the group's iceoryx2 config with at most 4
//! subscribers per service. With the group default (80 subscribers × (8 queued + 8 borrowed)
//! samples) every publisher of a 4 MiB topic would have a 5 GiB data segment, which iceoryx2
//! zero-fills when it creates it.

use super::payload::{Bytes, STOP, copy_mark, mark, read_mark, with_blob};
use super::{ECHO_TIMEOUT, PONG_IDLE, Pair, Recorder, ready, spin};
use crate::pingpong::RawSide;
use anyhow::{Result, bail};
use caravan_schemas::Message;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use std::time::Instant;

const PING: &str = "bench/ping";
const PONG: &str = "bench/pong";

/// Subscribers (and publishers) per service in the bench groups.
const PORTS_PER_SERVICE: usize = 4;

/// The iceoryx2 config of a bench group.
pub fn config(group: &str) -> Result<iceoryx2::config::Config> {
    let mut config = caravan::group::config(group)?;
    let ps = &mut config.defaults.publish_subscribe;
    ps.max_subscribers = PORTS_PER_SERVICE;
    ps.max_publishers = PORTS_PER_SERVICE;
    Ok(config)
}

/// Writes [`config`] where the Caravan nodes of the group read it (`Pair::temp_path("toml")`).
pub fn write_config_file(group: &str) -> Result<()> {
    let path = super::temp_path(group, "toml");
    std::fs::write(&path, toml::to_string(&config(group)?)?)?;
    Ok(())
}

pub fn ping(pair: &Pair, rec: &mut Recorder, poll: bool) -> Result<()> {
    with_blob!(pair.bytes, ping_t(pair, rec, poll))
}

fn ping_t<T: Message + Bytes>(pair: &Pair, rec: &mut Recorder, poll: bool) -> Result<()> {
    let side = RawSide::<T>::open_with(&config(&pair.group)?, PING, PONG)?;
    let waitset = WaitSetBuilder::new().create::<ipc::Service>()?;
    let _guard = waitset.attach_notification(&side.listener)?;
    for seq in 0..rec.total() {
        let sent_at = Instant::now();
        // SAFETY: every bit pattern is a valid blob.
        unsafe { side.send_in_place(!poll, |blob| mark(blob.bytes_mut(), seq)) }?;
        let sample = if poll {
            // BENCHMARK ONLY: spin instead of sleeping until the event.
            spin(|| Ok(side.subscriber.receive()?), ECHO_TIMEOUT)?
        } else {
            loop {
                let result = waitset.wait_and_process_once_with_timeout(
                    |_| CallbackProgression::Continue,
                    ECHO_TIMEOUT,
                )?;
                if !matches!(result, WaitSetRunResult::AllEventsHandled) {
                    bail!("interrupted ({result:?})");
                }
                side.listener.try_wait(|_| {})?;
                if let Some(sample) = side.subscriber.receive()? {
                    break sample;
                }
                if sent_at.elapsed() > ECHO_TIMEOUT {
                    bail!("no echo of round {seq} within {ECHO_TIMEOUT:?}");
                }
            }
        };
        let rtt = sent_at.elapsed();
        let got = read_mark(sample.payload().bytes());
        if got != Some(seq) {
            bail!("echo of round {seq} came back as {got:?}");
        }
        drop(sample);
        rec.record(rtt);
    }
    // SAFETY: every bit pattern is a valid blob.
    unsafe { side.send_in_place(!poll, |blob| mark(blob.bytes_mut(), STOP)) }?;
    Ok(())
}

pub fn pong(pair: &Pair, poll: bool) -> Result<()> {
    with_blob!(pair.bytes, pong_t(pair, poll))
}

fn pong_t<T: Message + Bytes>(pair: &Pair, poll: bool) -> Result<()> {
    let side = RawSide::<T>::open_with(&config(&pair.group)?, PONG, PING)?;
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()?;
    let _guard = waitset.attach_notification(&side.listener)?;
    ready("");
    loop {
        let sample = if poll {
            // BENCHMARK ONLY: spin instead of sleeping until the event.
            spin(|| Ok(side.subscriber.receive()?), PONG_IDLE)?
        } else {
            let result = waitset
                .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, PONG_IDLE)?;
            if !matches!(result, WaitSetRunResult::AllEventsHandled) {
                return Ok(());
            }
            side.listener.try_wait(|_| {})?;
            match side.subscriber.receive()? {
                Some(sample) => sample,
                None => continue,
            }
        };
        let bytes = sample.payload().bytes();
        if read_mark(bytes) == Some(STOP) {
            return Ok(());
        }
        // SAFETY: every bit pattern is a valid blob.
        unsafe { side.send_in_place(!poll, |blob| copy_mark(bytes, blob.bytes_mut())) }?;
    }
}
