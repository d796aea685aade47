//! Ping-pong between two processes over Caravan topics or raw iceoryx2, woken by events.
//!
//! The pinging side measures the round trip; one-way latency is half of it. Both variants wake
//! through an iceoryx2 WaitSet on a listener, so the comparison isolates Caravan's wrapper.

use anyhow::{Context, Result, bail};
use caravan::{Node, Topic, Trigger};
use caravan_report::bench::histogram;
use caravan_schemas::{LaserScan, Message, WheelSetpoint};
use clap::{Args, ValueEnum};
use hdrhistogram::Histogram;
use iceoryx2::prelude::*;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Instant;

const PING: &str = "bench/ping";
const PONG: &str = "bench/pong";

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Variant {
    /// Caravan's Node, Publisher and Subscriber, stepping on message arrival
    Caravan,
    /// iceoryx2 publish-subscribe with a WaitSet, no wrapper
    Iceoryx2,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Payload {
    /// 16 bytes (a wheel set-point)
    Small,
    /// A laser scan (8.7 KB with its fixed capacity)
    Scan,
}

impl Payload {
    pub fn bytes(self) -> usize {
        match self {
            Payload::Small => size_of::<WheelSetpoint>(),
            Payload::Scan => size_of::<LaserScan>(),
        }
    }
}

#[derive(Args)]
pub struct PongArgs {
    #[arg(long, value_enum)]
    variant: Variant,
    #[arg(long, value_enum)]
    payload: Payload,
    #[arg(long)]
    group: String,
}

/// Measures `rounds` round trips (after a warm-up) against a freshly started pong process.
pub fn measure(
    variant: Variant,
    payload: Payload,
    rounds: u64,
    group: &str,
) -> Result<Histogram<u64>> {
    let mut child = Command::new(std::env::current_exe()?)
        .args(["bench", "pong", "--group", group])
        .args(["--variant", variant.to_possible_value().unwrap().get_name()])
        .args(["--payload", payload.to_possible_value().unwrap().get_name()])
        .stdout(Stdio::piped())
        .spawn()
        .context("cannot start the pong process")?;
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut line)?;
    if line.trim() != "ready" {
        bail!("pong process did not start");
    }
    let warmup = rounds / 10;
    let result = match (variant, payload) {
        (Variant::Caravan, Payload::Small) => ping_caravan::<WheelSetpoint>(group, rounds, warmup),
        (Variant::Caravan, Payload::Scan) => ping_caravan::<LaserScan>(group, rounds, warmup),
        (Variant::Iceoryx2, Payload::Small) => ping_raw::<WheelSetpoint>(group, rounds, warmup),
        (Variant::Iceoryx2, Payload::Scan) => ping_raw::<LaserScan>(group, rounds, warmup),
    };
    // SAFETY: signalling our own child; its WaitSet turns SIGTERM into a clean exit.
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    child.wait()?;
    let _ = caravan::group::remove_resources(group);
    result
}

pub fn pong(args: &PongArgs) -> Result<()> {
    match (args.variant, args.payload) {
        (Variant::Caravan, Payload::Small) => pong_caravan::<WheelSetpoint>(&args.group),
        (Variant::Caravan, Payload::Scan) => pong_caravan::<LaserScan>(&args.group),
        (Variant::Iceoryx2, Payload::Small) => pong_raw::<WheelSetpoint>(&args.group),
        (Variant::Iceoryx2, Payload::Scan) => pong_raw::<LaserScan>(&args.group),
    }
}

fn ready() {
    println!("ready");
}

fn ping_caravan<T: Message + Default>(
    group: &str,
    rounds: u64,
    warmup: u64,
) -> Result<Histogram<u64>> {
    let mut node = Node::builder(group, "ping").build()?;
    let ping = node.publisher(&Topic::<T>::new(PING))?;
    let pong = node.subscriber(&Topic::<T>::new(PONG))?;
    let value = T::default();
    let mut hist = histogram();
    let mut done = 0;
    let mut sent_at = Instant::now();
    ping.publish(&value)?;
    node.run(Trigger::on(PONG), |step| {
        while pong.receive()?.is_some() {
            let rtt = sent_at.elapsed().as_nanos() as u64;
            done += 1;
            if done > warmup {
                hist.saturating_record((rtt / 2).max(1));
            }
            if done >= rounds + warmup {
                step.stop();
                return Ok(());
            }
            sent_at = Instant::now();
            ping.publish(&value)?;
        }
        Ok(())
    })?;
    Ok(hist)
}

fn pong_caravan<T: Message + Default>(group: &str) -> Result<()> {
    let mut node = Node::builder(group, "pong").build()?;
    let ping = node.subscriber(&Topic::<T>::new(PING))?;
    let pong = node.publisher(&Topic::<T>::new(PONG))?;
    ready();
    node.run(Trigger::on(PING), |_| {
        while let Some(msg) = ping.receive()? {
            pong.publish(&msg)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Raw iceoryx2 ports of one side: publisher + notifier out, subscriber + listener in.
pub(super) struct RawSide<T: Message> {
    pub(super) publisher: iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
    pub(super) notifier: iceoryx2::port::notifier::Notifier<ipc::Service>,
    pub(super) subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>,
    pub(super) listener: iceoryx2::port::listener::Listener<ipc::Service>,
    _node: iceoryx2::node::Node<ipc::Service>,
}

impl<T: Message> RawSide<T> {
    fn open(group: &str, out: &str, input: &str) -> Result<Self> {
        Self::open_with(&caravan::group::config(group)?, out, input)
    }

    /// Opens the ports with an explicit iceoryx2 config (`bench transport` shrinks the
    /// per-service subscriber count so that 4 MiB samples fit in memory).
    pub(super) fn open_with(
        config: &iceoryx2::config::Config,
        out: &str,
        input: &str,
    ) -> Result<Self> {
        let node = NodeBuilder::new()
            .config(config)
            .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
            .create::<ipc::Service>()?;
        let pubsub = |name: &str| -> Result<_> {
            Ok(node
                .service_builder(&name.try_into()?)
                .publish_subscribe::<T>()
                .enable_safe_overflow(true)
                .subscriber_max_buffer_size(8)
                .subscriber_max_borrowed_samples(8)
                .open_or_create()?)
        };
        let event = |name: &str| -> Result<_> {
            Ok(node
                .service_builder(&name.try_into()?)
                .event()
                .open_or_create()?)
        };
        Ok(Self {
            publisher: pubsub(out)?.publisher_builder().create()?,
            notifier: event(out)?.notifier_builder().create()?,
            subscriber: pubsub(input)?
                .subscriber_builder()
                .buffer_size(8)
                .create()?,
            listener: event(input)?.listener_builder().create()?,
            _node: node,
        })
    }

    fn send(&self, value: &T) -> Result<()> {
        self.publisher.loan_uninit()?.write_payload(*value).send()?;
        self.notifier.notify()?;
        Ok(())
    }

    /// Loans a sample as it is (as Caravan's `Publisher::loan_as_is` does), lets `fill`
    /// write to it and sends it; wakes the other side if `notify`.
    ///
    /// # Safety
    /// Every bit pattern must be a valid `T` (see `Publisher::loan_as_is`).
    pub(super) unsafe fn send_in_place(
        &self,
        notify: bool,
        fill: impl FnOnce(&mut T),
    ) -> Result<()> {
        let uninit = self.publisher.loan_uninit()?;
        // SAFETY: a slot holds zeros from the OS or an earlier whole `T`, and every bit
        // pattern is a valid `T` (the caller's promise).
        let mut sample = unsafe { uninit.assume_init() };
        fill(sample.payload_mut());
        sample.send()?;
        if notify {
            self.notifier.notify()?;
        }
        Ok(())
    }
}

fn ping_raw<T: Message + Default>(group: &str, rounds: u64, warmup: u64) -> Result<Histogram<u64>> {
    let side = RawSide::<T>::open(group, PING, PONG)?;
    let waitset = WaitSetBuilder::new().create::<ipc::Service>()?;
    let _guard = waitset.attach_notification(&side.listener)?;
    let value = T::default();
    let mut hist = histogram();
    for i in 0..rounds + warmup {
        let sent_at = Instant::now();
        side.send(&value)?;
        loop {
            waitset.wait_and_process_once(|_| CallbackProgression::Continue)?;
            side.listener.try_wait(|_| {})?;
            if side.subscriber.receive()?.is_some() {
                break;
            }
        }
        if i >= warmup {
            hist.saturating_record((sent_at.elapsed().as_nanos() as u64 / 2).max(1));
        }
    }
    Ok(hist)
}

fn pong_raw<T: Message>(group: &str) -> Result<()> {
    let side = RawSide::<T>::open(group, PONG, PING)?;
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()?;
    let _guard = waitset.attach_notification(&side.listener)?;
    ready();
    loop {
        let result = waitset.wait_and_process_once(|_| CallbackProgression::Continue)?;
        if !matches!(
            result,
            iceoryx2::waitset::WaitSetRunResult::AllEventsHandled
        ) {
            return Ok(());
        }
        side.listener.try_wait(|_| {})?;
        while let Some(sample) = side.subscriber.receive()? {
            side.send(sample.payload())?;
        }
    }
}
