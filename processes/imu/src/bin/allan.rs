//! `caravan-imu-allan`: the Allan-deviation check of the IMU's error model (see
//! `caravan_imu::allan_run`). Writes `allan.json` and `allan.svg` into `--out`.

use caravan_imu::allan_run::{example_errors, run};
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Allan deviation of a static IMU with the example error model")]
struct Args {
    /// Simulated length of the static run, s.
    #[arg(long, default_value_t = 100_000.0)]
    seconds: f64,
    /// IMU rate, Hz.
    #[arg(long, default_value_t = 100.0)]
    rate_hz: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory.
    #[arg(long, default_value = "allan")]
    out: PathBuf,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if !(args.seconds > 0.0 && args.rate_hz > 0.0 && args.seconds * args.rate_hz >= 1000.0) {
        eprintln!("caravan-imu-allan: give --seconds and --rate-hz for at least 1000 readings");
        return ExitCode::from(2);
    }
    let errors = example_errors();
    let triads = run(&errors, args.rate_hz, args.seconds, args.seed);
    let write = || -> anyhow::Result<()> {
        std::fs::create_dir_all(&args.out)?;
        let json = serde_json::json!({
            "seconds": args.seconds, "rate_hz": args.rate_hz, "seed": args.seed,
            "bias_correlation_s": errors.bias_correlation_s, "triads": triads,
        });
        std::fs::write(
            args.out.join("allan.json"),
            serde_json::to_string_pretty(&json)?,
        )?;
        caravan_imu::plot::allan_svg(&args.out.join("allan.svg"), &triads)?;
        Ok(())
    };
    if let Err(e) = write() {
        eprintln!("caravan-imu-allan: {e}");
        return ExitCode::FAILURE;
    }
    println!("triad  N configured / read off, error   B configured / read off, error");
    for t in &triads {
        println!("{}", t.cells().join("  "));
    }
    ExitCode::SUCCESS
}
