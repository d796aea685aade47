//! `caravan bench transport`: one-way latency of Caravan topics side by side with raw iceoryx2,
//! Unix domain sockets, UDP, TCP and zenoh, between two processes, in one run; and of a Caravan
//! topic between two hosts, through the bridge ([`bridged`]).
//!
//! For every payload size and transport the bench starts its own executable as the echoing
//! side (`caravan bench transport-pong`), measures round trips after a warm-up and records half
//! of each in an hdrhistogram. The sizes are interleaved (every transport at 16 B, then every
//! transport at 2.7 KiB, …) so that a busier moment of the machine does not hit one transport
//! only.

mod bridged;
mod caravan;
mod cpu;
mod iceoryx2_raw;
mod payload;
mod pin;
mod plot;
mod recorder;
pub mod report;
mod stream;
mod udp;
mod watchdog;
mod zenoh_peer;

use anyhow::{Context, Result, bail};
use caravan_report::bench::{Percentiles, percentiles};
use clap::{Args, ValueEnum};
use indicatif::ProgressBar;
use recorder::{Measured, Recorder};
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use watchdog::Watchdog;

pub use bridged::{RelaysArgs, relays};
pub use payload::SIZES;

/// The transports compared, in table order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Kind {
    /// Caravan topics; the node sleeps until a message event wakes it (`Node::run` on message)
    CaravanEvent,
    /// Caravan topics; the node spins up to `--spin` for the next message, then sleeps until an
    /// event wakes it (the launch key `spin`)
    CaravanSpin,
    /// Caravan topics, polled in a spin loop without bound (benchmark only; nodes spin at most
    /// their `spin`, then sleep)
    CaravanPoll,
    /// Caravan topics between two hosts on this machine: shared memory on each, the hosts'
    /// relays joined by zenoh over TCP on loopback; woken by events
    CaravanBridged,
    /// iceoryx2 publish-subscribe woken through a WaitSet, no Caravan wrapper
    Iceoryx2Event,
    /// iceoryx2 publish-subscribe polled in a spin loop, no events
    Iceoryx2Poll,
    /// Unix domain stream socket, blocking reads
    Uds,
    /// TCP on loopback with TCP_NODELAY, blocking reads
    Tcp,
    /// UDP on loopback, fragmented into datagrams of at most 60 KiB
    Udp,
    /// zenoh peer to peer over TCP on loopback, shared memory off
    Zenoh,
    /// zenoh peer to peer, payloads allocated in zenoh's shared memory
    ZenohShm,
}

impl Kind {
    pub const ALL: [Kind; 11] = [
        Kind::CaravanEvent,
        Kind::CaravanSpin,
        Kind::CaravanPoll,
        Kind::CaravanBridged,
        Kind::Iceoryx2Event,
        Kind::Iceoryx2Poll,
        Kind::Uds,
        Kind::Tcp,
        Kind::Udp,
        Kind::Zenoh,
        Kind::ZenohShm,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::CaravanEvent => "caravan-event",
            Kind::CaravanSpin => "caravan-spin",
            Kind::CaravanPoll => "caravan-poll",
            Kind::CaravanBridged => "caravan-bridged",
            Kind::Iceoryx2Event => "iceoryx2-event",
            Kind::Iceoryx2Poll => "iceoryx2-poll",
            Kind::Uds => "uds",
            Kind::Tcp => "tcp",
            Kind::Udp => "udp",
            Kind::Zenoh => "zenoh",
            Kind::ZenohShm => "zenoh-shm",
        }
    }

    /// How the receiving side learns that a message is there.
    pub fn wake_up(self) -> &'static str {
        match self {
            Kind::CaravanPoll | Kind::Iceoryx2Poll => "busy-poll (benchmark only)",
            Kind::CaravanEvent | Kind::Iceoryx2Event => "event (iceoryx2 WaitSet)",
            Kind::CaravanSpin => "spin then event (iceoryx2 WaitSet)",
            Kind::CaravanBridged => "event (iceoryx2 WaitSet) via relays",
            Kind::Uds | Kind::Tcp | Kind::Udp => "blocking read",
            Kind::Zenoh | Kind::ZenohShm => "zenoh subscriber channel",
        }
    }

    fn uses_iceoryx2(self) -> bool {
        matches!(
            self,
            Kind::CaravanEvent
                | Kind::CaravanSpin
                | Kind::CaravanPoll
                | Kind::Iceoryx2Event
                | Kind::Iceoryx2Poll
        )
    }
}

#[derive(Args)]
pub struct TransportArgs {
    /// A short run (fewer round trips) that finishes in well under a minute
    #[arg(long)]
    pub quick: bool,
    /// Directory for transport.csv and transport.svg
    #[arg(long, default_value = "bench-results")]
    pub out: PathBuf,
    /// Round trips measured per transport and payload, after 10 % warm-up
    /// [default: 10000, or 200 with --quick]
    #[arg(long)]
    pub rounds: Option<u64>,
    /// Only these transports, comma-separated [default: all]
    #[arg(long, value_enum, value_delimiter = ',')]
    pub transports: Vec<Kind>,
    /// Only these payload sizes in bytes, comma-separated [default: 16,2728,65536,1048576,4194304]
    #[arg(long, value_delimiter = ',')]
    pub sizes: Vec<usize>,
    /// Messages in flight: the measuring side keeps this many sent and not yet echoed, so the
    /// topics stream (latency is then under load). Above 1 only for caravan-event,
    /// caravan-spin, caravan-bridged and zenoh, whose topics become lossless with this depth
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=256))]
    pub in_flight: u64,
    /// How long caravan-spin's nodes spin for the next message before they sleep (at most 1ms)
    #[arg(long, default_value = "50us", value_parser = spin_arg)]
    pub spin: Duration,
    /// Let the scheduler place both sides (default: the measuring side on the first CPU this
    /// process may use, the echoing side on the second)
    #[arg(long)]
    pub no_pin: bool,
}

#[derive(Args)]
pub struct PongArgs {
    #[arg(long, value_enum)]
    transport: Kind,
    #[arg(long)]
    bytes: usize,
    #[arg(long, default_value_t = 1)]
    in_flight: u64,
    #[arg(long, default_value = "0s", value_parser = spin_arg)]
    spin: Duration,
    #[arg(long)]
    group: String,
    /// Where to listen (zenoh): a zenoh endpoint such as tcp/127.0.0.1:7447
    #[arg(long)]
    endpoint: Option<String>,
    /// Pin the echoing process to this CPU
    #[arg(long)]
    cpu: Option<usize>,
}

/// What both sides of one measurement agree on.
pub struct Pair {
    pub kind: Kind,
    pub bytes: usize,
    /// Messages in flight (1: one round trip at a time).
    pub in_flight: u64,
    /// How long a Caravan node spins for the next message before it sleeps.
    pub spin: Duration,
    /// Unique per measurement: iceoryx2 group, socket file name.
    pub group: String,
    /// What the pong side reported when ready (a port), or what it was told (zenoh endpoint).
    pub endpoint: String,
}

impl Pair {
    /// Path of the Unix domain socket (and of the Caravan iceoryx2 config) of this pair.
    fn temp_path(&self, ext: &str) -> PathBuf {
        temp_path(&self.group, ext)
    }
}

fn spin_arg(text: &str) -> std::result::Result<Duration, String> {
    ::caravan::parse_spin(text).map_err(|e| e.to_string())
}

fn temp_path(group: &str, ext: &str) -> PathBuf {
    std::env::temp_dir().join(format!("caravan-bench-{group}.{ext}"))
}

/// Spins on `poll` until it yields a value. BENCHMARK ONLY: burns a core while waiting.
///
/// After [`SPIN_BEFORE_YIELD`] empty polls it calls `sched_yield` between polls: that returns at
/// once when nothing else wants the core, but keeps the two spinning processes (and anything
/// else running) from starving each other on a machine with few cores.
pub fn spin<R>(mut poll: impl FnMut() -> Result<Option<R>>, timeout: Duration) -> Result<R> {
    let start = Instant::now();
    let mut n: u32 = 0;
    loop {
        if let Some(r) = poll()? {
            return Ok(r);
        }
        n = n.wrapping_add(1);
        if n < SPIN_BEFORE_YIELD {
            std::hint::spin_loop();
            continue;
        }
        std::thread::yield_now();
        if n.is_multiple_of(1024) && start.elapsed() > timeout {
            bail!("nothing received for {timeout:?}");
        }
    }
}

/// Empty polls before a spinning side starts yielding the core between polls.
pub const SPIN_BEFORE_YIELD: u32 = 1_000;

/// How long the echoing side waits for a message before it gives up.
pub const PONG_IDLE: Duration = Duration::from_secs(60);
/// How long the measuring side waits for an echo before it gives up.
pub const ECHO_TIMEOUT: Duration = Duration::from_secs(10);

/// Tells the measuring side that the echoing side is listening, with what it should know.
pub fn ready(info: &str) {
    println!("ready {info}");
}

/// One result row: percentiles, or why the transport cannot carry this payload.
pub struct Row {
    pub kind: Kind,
    pub bytes: usize,
    pub rounds: u64,
    pub result: std::result::Result<Percentiles, String>,
    pub mean_ns: f64,
    /// Payload bytes moved per second, both ways ([`recorder::Measured::bytes_per_s`]).
    pub bytes_per_s: f64,
    /// CPU time of both sides per message, ns ([`recorder::Measured::cpu_ns_per_message`]).
    pub cpu_ns_per_message: Option<f64>,
    /// Why the first attempt failed, when this row is a second attempt.
    pub retried: Option<String>,
}

pub fn run(args: &TransportArgs) -> Result<()> {
    let kinds: Vec<Kind> = if args.transports.is_empty() {
        Kind::ALL.to_vec()
    } else {
        args.transports.clone()
    };
    let sizes: Vec<usize> = if args.sizes.is_empty() {
        SIZES.to_vec()
    } else {
        args.sizes.clone()
    };
    if let Some(bad) = sizes.iter().find(|s| !SIZES.contains(s)) {
        bail!("payload size {bad} is not one of {SIZES:?}");
    }
    let streams = [
        Kind::CaravanEvent,
        Kind::CaravanSpin,
        Kind::CaravanBridged,
        Kind::Zenoh,
    ];
    if let Some(k) = kinds.iter().find(|k| !streams.contains(k))
        && args.in_flight > 1
    {
        bail!(
            "--in-flight {} is offered for caravan-event, caravan-spin, caravan-bridged and zenoh only, not {}; choose them with --transports",
            args.in_flight,
            k.name()
        );
    }
    let rounds = args.rounds.unwrap_or(if args.quick { 200 } else { 10_000 });
    let warmup = (rounds / 10).max(10);
    let mut machine = caravan_report::bench::Machine::detect();
    // Both sides on fixed, different CPUs: otherwise the scheduler puts them sometimes on one
    // core (a wake-up is a context switch) and sometimes on two (a wake-up is an inter-processor
    // interrupt, slower in a VM), and each measurement lands in one of the two modes by chance.
    let cpus = if args.no_pin { None } else { pin::two_cpus() };
    if let Some((ping_cpu, pong_cpu)) = cpus {
        pin::to(ping_cpu)?;
        machine.placement =
            format!("measuring side on CPU {ping_cpu}, echoing side on CPU {pong_cpu}");
    }
    // zenoh's shared-memory segments can outlive their processes; remove those of earlier runs.
    zenoh_peer::cleanup();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;

    println!("{}", machine.describe());
    println!(
        "one-way latency = round trip / 2; {rounds} round trips per transport and payload after \
         {warmup} warm-up, {} in flight{}",
        args.in_flight,
        if args.quick { " (--quick)" } else { "" }
    );
    let progress = recorder::progress_bar(kinds.len() * sizes.len(), rounds + warmup);
    let setup = Setup {
        rounds,
        warmup,
        in_flight: args.in_flight,
        spin: args.spin,
        pong_cpu: cpus.map(|(_, c)| c),
    };
    let mut rows = Vec::new();
    for &bytes in &sizes {
        for &kind in &kinds {
            progress.set_message(format!("{} {}", kind.name(), payload::label(bytes)));
            let mut result = measure(kind, bytes, &setup, &progress);
            // One lost echo on a loaded machine (a peer held off the CPU past a timeout) says
            // nothing about the transport's latency: measure once more, and say so.
            let mut retried = None;
            if let Err(e) = &result {
                let why = format!("failed: {e:#}");
                progress.suspend(|| eprintln!("{} {bytes}: {why}; measuring again", kind.name()));
                progress.inc_length(setup.rounds + setup.warmup);
                retried = Some(why);
                result = measure(kind, bytes, &setup, &progress);
            }
            let (result, mean_ns, bytes_per_s, cpu) = match result {
                Ok(Some(m)) => (
                    Ok(percentiles(&m.hist)),
                    m.hist.mean(),
                    m.bytes_per_s,
                    m.cpu_ns_per_message,
                ),
                Ok(None) => (Err(unsupported(kind, bytes)), 0.0, 0.0, None),
                Err(e) => (Err(format!("failed: {e:#}")), 0.0, 0.0, None),
            };
            if let Err(why) = &result {
                progress.suspend(|| eprintln!("{} {}: {why}", kind.name(), bytes));
            }
            rows.push(Row {
                kind,
                bytes,
                rounds,
                result,
                mean_ns,
                bytes_per_s,
                cpu_ns_per_message: cpu,
                retried,
            });
        }
    }
    progress.finish_and_clear();
    zenoh_peer::cleanup();
    print!("{}", report::table(&rows));
    print!("{}", report::ratios(&rows));
    let csv_path = args.out.join("transport.csv");
    let csv = report::csv(&machine, &rows, &setup);
    std::fs::write(&csv_path, csv)
        .with_context(|| format!("cannot write {}", csv_path.display()))?;
    let svg_path = args.out.join("transport.svg");
    std::fs::write(&svg_path, plot::svg(&machine, &rows, rounds))
        .with_context(|| format!("cannot write {}", svg_path.display()))?;
    println!("wrote {} and {}", csv_path.display(), svg_path.display());
    let failed = rows
        .iter()
        .filter(|r| matches!(&r.result, Err(e) if e.starts_with("failed")))
        .count();
    if failed > 0 {
        bail!("{failed} measurements failed (see the table)");
    }
    Ok(())
}

fn unsupported(kind: Kind, bytes: usize) -> String {
    match kind {
        Kind::Udp => format!(
            "unsupported: the UDP receive buffer cannot hold {} (raise net.core.rmem_max)",
            payload::label(bytes)
        ),
        _ => "unsupported".into(),
    }
}

/// How every measurement of a run is made (and the CSV says so).
struct Setup {
    rounds: u64,
    warmup: u64,
    in_flight: u64,
    spin: Duration,
    pong_cpu: Option<usize>,
}

/// Starts the echoing side, measures, stops it. `Ok(None)`: the transport cannot carry `bytes`.
fn measure(
    kind: Kind,
    bytes: usize,
    setup: &Setup,
    progress: &ProgressBar,
) -> Result<Option<Measured>> {
    let (rounds, warmup) = (setup.rounds, setup.warmup);
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    // Group names are at most 40 of [A-Za-z0-9-].
    let group = format!(
        "bt-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    if kind == Kind::Udp && !udp::supports(bytes) {
        progress.inc(rounds + warmup);
        return Ok(None);
    }
    // Removes whatever this measurement made, on every way out of it.
    let mut made = Made {
        kind,
        group: group.clone(),
        pong: None,
        relays: None,
    };
    if kind.uses_iceoryx2() {
        iceoryx2_raw::write_config_file(&group)?;
    }
    if kind == Kind::CaravanBridged {
        bridged::write_configs(&group)?;
    }
    let endpoint = match kind {
        Kind::Zenoh | Kind::ZenohShm | Kind::CaravanBridged => Some(zenoh_peer::free_endpoint()?),
        _ => None,
    };
    // Between hosts: both hosts' relays, in a process of their own, before either side.
    if let (Kind::CaravanBridged, Some(e)) = (kind, &endpoint) {
        made.relays = Some(bridged::start_relays(&group, e)?);
    }
    let mut cmd = Command::new(std::env::current_exe()?);
    cmd.args(["bench", "transport-pong", "--group", &group])
        .args(["--transport", kind.name()])
        .args(["--bytes", &bytes.to_string()])
        .args(["--in-flight", &setup.in_flight.to_string()])
        .args(["--spin", &::caravan::spin::spin_text(setup.spin)]);
    if let Some(e) = endpoint.as_ref().filter(|_| kind != Kind::CaravanBridged) {
        cmd.args(["--endpoint", e]);
    }
    if let Some(cpu) = setup.pong_cpu {
        cmd.args(["--cpu", &cpu.to_string()]);
    }
    let child = made.pong.insert(
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .spawn()
            .context("cannot start the echoing process")?,
    );
    let info = await_ready(child.stdout.take().expect("piped stdout"))?;
    let pair = Pair {
        kind,
        bytes,
        in_flight: setup.in_flight,
        spin: setup.spin,
        group: group.clone(),
        endpoint: endpoint.clone().unwrap_or(info),
    };
    let alive = Arc::new(AtomicU64::new(0));
    // Both sides' CPU: this process, the echoing one and (between hosts) the relays.
    let others = [Some(child.id()), made.relays.as_ref().map(Child::id)]
        .into_iter()
        .flatten()
        .collect();
    let mut recorder = Recorder::new(
        bytes,
        rounds + warmup,
        warmup,
        progress.clone(),
        alive.clone(),
        cpu::CpuMeter::new(others),
    );
    let watchdog = Watchdog::start(alive, child.id(), kind, bytes);
    let outcome = ping(&pair, &mut recorder);
    watchdog.stop();
    outcome?;
    recorder.finish().map(Some)
}

/// What one measurement made. Dropped, it stops the echoing process (after its stop message,
/// or killing it) and the relays, and removes the shared memory, configs and sockets.
struct Made {
    kind: Kind,
    group: String,
    pong: Option<Child>,
    relays: Option<Child>,
}

impl Drop for Made {
    fn drop(&mut self) {
        if let Some(mut child) = self.pong.take() {
            stop_child(&mut child, "echoing process");
        }
        bridged::stop_relays(self.relays.take());
        let group = self.group.as_str();
        if self.kind.uses_iceoryx2() {
            let _ = ::caravan::group::remove_resources(group);
            let _ = std::fs::remove_file(temp_path(group, "toml"));
        }
        if self.kind == Kind::Uds {
            let _ = std::fs::remove_file(temp_path(group, "sock"));
        }
        if self.kind == Kind::CaravanBridged {
            bridged::cleanup(group);
        }
    }
}

/// Reads the echoing process's stdout up to its `ready` line and returns what follows `ready`.
/// Anything else it prints (zenoh logs there when RUST_LOG is set) goes on to our stderr, by a
/// thread that keeps draining the pipe so the echoing process never blocks on it.
pub(super) fn await_ready(stdout: std::process::ChildStdout) -> Result<String> {
    let mut lines = BufReader::new(stdout).lines();
    loop {
        let Some(line) = lines.next().transpose()? else {
            bail!("the echoing process did not start");
        };
        if let Some(info) = line.strip_prefix("ready") {
            std::thread::spawn(move || {
                for line in lines.map_while(std::result::Result::ok) {
                    eprintln!("{line}");
                }
            });
            return Ok(info.trim().to_string());
        }
        eprintln!("{line}");
    }
}

fn ping(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    match pair.kind {
        Kind::CaravanEvent | Kind::CaravanSpin | Kind::CaravanBridged => {
            caravan::ping_event(pair, rec)
        }
        Kind::CaravanPoll => caravan::ping_poll(pair, rec),
        Kind::Iceoryx2Event => iceoryx2_raw::ping(pair, rec, false),
        Kind::Iceoryx2Poll => iceoryx2_raw::ping(pair, rec, true),
        Kind::Uds => stream::ping_uds(pair, rec),
        Kind::Tcp => stream::ping_tcp(pair, rec),
        Kind::Udp => udp::ping(pair, rec),
        Kind::Zenoh => zenoh_peer::ping(pair, rec, false),
        Kind::ZenohShm => zenoh_peer::ping(pair, rec, true),
    }
}

/// The echoing side (`caravan bench transport-pong`).
pub fn pong(args: &PongArgs) -> Result<()> {
    if let Some(cpu) = args.cpu {
        pin::to(cpu)?;
    }
    let pair = Pair {
        kind: args.transport,
        bytes: args.bytes,
        in_flight: args.in_flight,
        spin: args.spin,
        group: args.group.clone(),
        endpoint: args.endpoint.clone().unwrap_or_default(),
    };
    match pair.kind {
        Kind::CaravanEvent | Kind::CaravanSpin | Kind::CaravanBridged => caravan::pong_event(&pair),
        Kind::CaravanPoll => caravan::pong_poll(&pair),
        Kind::Iceoryx2Event => iceoryx2_raw::pong(&pair, false),
        Kind::Iceoryx2Poll => iceoryx2_raw::pong(&pair, true),
        Kind::Uds => stream::pong_uds(&pair),
        Kind::Tcp => stream::pong_tcp(&pair),
        Kind::Udp => udp::pong(&pair),
        Kind::Zenoh => zenoh_peer::pong(&pair, false),
        Kind::ZenohShm => zenoh_peer::pong(&pair, true),
    }
}

/// Waits for the echoing side to exit after the stop message; kills it if it does not.
pub(super) fn stop_child(child: &mut Child, what: &str) {
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        if let Ok(Some(_)) = child.try_wait() {
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    eprintln!("caravan: the {what} did not stop; killing it");
    let _ = child.kill();
    let _ = child.wait();
}
