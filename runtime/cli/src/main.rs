//! The `caravan` command.

mod docs;
mod export;
mod info;
mod inspect;
mod params_table;
mod record;
mod schemas_py;
mod top;

use caravan_group::{clean, launch, play, report, resim};

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "caravan",
    version,
    about = "Run, inspect and measure Caravan process groups"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Launch a process group from a launch file
    Launch(launch::LaunchArgs),
    /// Run a launch file over a grid of overrides × seeds, several groups at once
    Sweep(caravan_sweep::SweepArgs),
    /// Topics of a running group
    #[command(subcommand)]
    Topic(inspect::TopicCommand),
    /// Nodes of a running group
    #[command(subcommand)]
    Node(inspect::NodeCommand),
    /// A live table of a group's nodes: rate, deadline misses, jitter, compute time, CPU, memory
    Top(top::TopArgs),
    /// Record a running group's topics to an MCAP file
    Record(record::RecordArgs),
    /// Play a recording's topics into a running group at their recorded times
    Play(play::PlayArgs),
    /// Run one node of a lockstep recording again, fed the recorded inputs, and compare its
    /// outputs with the recorded ones (deterministic re-simulation)
    Resim(resim::ResimArgs),
    /// What a recording holds: time span, channels with schema and count, metadata
    Info(info::InfoArgs),
    /// Write a recording as a rosbag2 bag that ROS 2's tools read (--ros2)
    Export(export::ExportArgs),
    /// Recompute report.json and report.md of a run directory
    Report {
        /// The run directory (runs/<group>-<time>)
        run_dir: std::path::PathBuf,
    },
    /// Remove shared memory left behind by a group whose processes are all gone: the group
    /// named, else the only such group; --all removes every such group's
    Clean(clean::CleanArgs),
    /// Latency benchmarks
    #[command(subcommand)]
    Bench(caravan_bench::BenchCommand),
    /// Message layouts for other languages: a Python module (--python) or JSON (--layout)
    Schemas(schemas_py::SchemasArgs),
    /// Documentation generated from the code: `caravan docs params` writes the params tables
    /// of docs/ from every process's `--describe-params`
    #[command(subcommand)]
    Docs(docs::DocsCommand),
    /// Print a shell completion script: `source <(caravan completions bash)`
    Completions { shell: clap_complete::Shell },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    caravan::log::init("caravan");
    if !matches!(cli.command, Command::Launch(_) | Command::Sweep(_)) {
        // A command that only prints ends quietly when its reader goes (`caravan info … |
        // head`), as Unix tools do. A launcher or a sweep keeps the default Rust handling: it
        // must stop its group in order whatever happens to its terminal.
        // SAFETY: setting a signal's disposition before any thread is started.
        unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    }
    let result = match cli.command {
        Command::Launch(args) => launch::launch(&args).map(ExitCode::from),
        Command::Sweep(args) => caravan_sweep::run(&args).map(ExitCode::from),
        Command::Topic(cmd) => inspect::topic(cmd).map(|_| ExitCode::SUCCESS),
        Command::Node(cmd) => inspect::node(cmd).map(|_| ExitCode::SUCCESS),
        Command::Record(args) => record::record(args).map(|_| ExitCode::SUCCESS),
        Command::Info(args) => info::info(&args).map(ExitCode::from),
        Command::Export(args) => export::export(&args).map(ExitCode::from),
        Command::Report { run_dir } if !run_dir.join("run.json").is_file() => {
            eprintln!(
                "caravan: {} is not a run directory (it has no run.json)",
                run_dir.display()
            );
            Ok(ExitCode::from(launch::EXIT_BAD_INPUT))
        }
        // A run directory given by hand may hold a damaged recording: read it whole first, so
        // that is said, naming the file. (The report after a run takes the counts the
        // recording's writer made and does not read the file back.)
        Command::Report { run_dir } => {
            caravan_report::read_all(&run_dir.join(caravan_report::RECORDING_FILE))
                .and_then(|_| report::write(&run_dir, false))
                .map(|w| {
                    println!("{}", report_summary(&w.report));
                    for failure in &w.failures {
                        eprintln!("caravan: {failure}");
                    }
                    if w.failures.is_empty() {
                        ExitCode::SUCCESS
                    } else {
                        ExitCode::FAILURE
                    }
                })
        }
        Command::Clean(args) => clean::clean(&args).map(|_| ExitCode::SUCCESS),
        Command::Bench(cmd) => caravan_bench::run(cmd).map(|_| ExitCode::SUCCESS),
        Command::Schemas(args) => schemas_py::run(&args).map(|_| ExitCode::SUCCESS),
        Command::Play(args) => play::play(&args).map(|_| ExitCode::SUCCESS),
        Command::Resim(args) => resim::resim(&args).map(ExitCode::from),
        Command::Top(args) => top::top(&args).map(|_| ExitCode::SUCCESS),
        Command::Docs(cmd) => docs::run(&cmd).map(ExitCode::from),
        Command::Completions { shell } => {
            use clap::CommandFactory;
            clap_complete::generate(
                shell,
                &mut Cli::command(),
                "caravan",
                &mut std::io::stdout(),
            );
            Ok(ExitCode::SUCCESS)
        }
    };
    // Bad input exits 2, a run-time failure 1 (docs/launch.md, "Exit codes").
    result.unwrap_or_else(|e| {
        eprintln!("caravan: {e:#}");
        ExitCode::from(caravan_group::bad_input::exit_code(&e))
    })
}

fn report_summary(r: &serde_json::Value) -> String {
    format!(
        "{}: {} nodes, {} topics, real-time factor {:.2}",
        r["run"]["outcome"].as_str().unwrap_or("?"),
        r["nodes"].as_array().map_or(0, Vec::len),
        r["topics"].as_array().map_or(0, Vec::len),
        r["run"]["real_time_factor"].as_f64().unwrap_or(0.0)
    )
}
