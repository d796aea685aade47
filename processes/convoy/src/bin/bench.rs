//! `caravan-convoy-bench`: the convoy's benchmarks (see `caravan_convoy::bench`).

use caravan_convoy::bench::{pipeline, scale};
use clap::Parser;

#[derive(Parser)]
#[command(
    name = "caravan-convoy-bench",
    about = "Benchmarks of the convoy scenario"
)]
enum Command {
    /// A leader and N followers in lockstep and realtime: real-time factor, CPU, latency
    Scale(scale::ScaleArgs),
    /// Realtime convoy: latency from a laser scan to the wheel set-point it caused, per hop
    Pipeline(pipeline::PipelineArgs),
}

fn main() -> std::process::ExitCode {
    let result = match Command::parse() {
        Command::Scale(args) => scale::run(&args),
        Command::Pipeline(args) => pipeline::run(&args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caravan-convoy-bench: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
