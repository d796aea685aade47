//! `caravan bench`: latency measured side by side against baselines in one run.

mod pingpong;
mod pipeline;
mod scale;
mod stats;
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
    /// A leader and N followers in lockstep and realtime: real-time factor, CPU, latency
    Scale(scale::ScaleArgs),
    /// Realtime convoy: latency from a laser scan to the wheel set-point it caused, per hop
    Pipeline(pipeline::PipelineArgs),
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
        BenchCommand::Scale(args) => scale::run(&args),
        BenchCommand::Pipeline(args) => pipeline::run(&args),
    }
}

/// Prints a bench's table and writes `<stem>.csv` and `<stem>.md` (machine, then the table).
fn write_results(
    out: &std::path::Path,
    stem: &str,
    machine: &transport::report::Machine,
    table: &str,
    csv: &str,
) -> anyhow::Result<()> {
    println!("{table}");
    std::fs::write(out.join(format!("{stem}.csv")), csv)?;
    std::fs::write(
        out.join(format!("{stem}.md")),
        format!("{}\n\n{table}\n", machine.describe()),
    )?;
    println!("wrote {}", out.join(format!("{stem}.csv")).display());
    Ok(())
}

/// The run directory the launcher left in `runs` (a bench launches one run per directory).
fn run_dir_in(runs: &std::path::Path) -> anyhow::Result<std::path::PathBuf> {
    use anyhow::Context;
    std::fs::read_dir(runs)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.is_dir())
        .context("the launcher wrote no run directory")
}
