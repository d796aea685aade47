//! `caravan bench`: latency measured side by side against baselines in one run.

mod pingpong;
mod transport;
mod wrapper;

use clap::{Args, Subcommand};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// One-way latency of Caravan topics against raw iceoryx2, both woken by events
    Wrapper(WrapperArgs),
    /// Internal: the echoing side of a ping-pong pair
    #[command(hide = true)]
    Pong(pingpong::PongArgs),
    /// One-way latency of Caravan topics against raw iceoryx2, sockets and zenoh, 16 B to 4 MiB
    Transport(transport::TransportArgs),
    /// Internal: the echoing side of `bench transport`
    #[command(hide = true)]
    TransportPong(transport::PongArgs),
    /// Internal: two hosts' relays for `bench transport --transports caravan-bridged`
    #[command(hide = true)]
    TransportRelays(transport::RelaysArgs),
}

#[derive(Args)]
pub struct WrapperArgs {
    /// Round trips measured per run (after 10 % warm-up)
    #[arg(long, default_value_t = 20_000)]
    pub rounds: u64,
    /// Runs per transport and payload; the summary gives the median
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Write the results as CSV to this file
    #[arg(long)]
    pub csv: Option<std::path::PathBuf>,
}

pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Wrapper(args) => wrapper::run(&args),
        BenchCommand::Pong(args) => pingpong::pong(&args),
        BenchCommand::Transport(args) => transport::run(&args),
        BenchCommand::TransportPong(args) => transport::pong(&args),
        BenchCommand::TransportRelays(args) => transport::relays(&args),
    }
}
