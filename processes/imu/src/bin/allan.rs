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

/// IMU output rates, Hz: MEMS parts read from 1 Hz to a few kHz (the MPU-6050's gyro up to
/// 8 kHz); 10 kHz is past all of them.
const RATE_HZ: [f64; 2] = [1.0, 10_000.0];

/// The longest run, s: 10⁶ s (11.6 days), the longest flicker correlation time the sensor's
/// error model takes (`bias_correlation_s`); the long check of docs/imu.md is 10⁵ s.
const MAX_SECONDS: f64 = 1e6;

/// Readings: at least 1000 for an Allan deviation of a few clusters; at most 10⁸, two f64
/// each (1.6 GB) held for the analysis.
const READINGS: [f64; 2] = [1000.0, 1e8];

/// The arguments' ranges; the error names the argument.
fn check(args: &Args) -> Result<(), String> {
    let [lo, hi] = RATE_HZ;
    if !(args.rate_hz.is_finite() && (lo..=hi).contains(&args.rate_hz)) {
        return Err(format!(
            "--rate-hz must be between {lo} and {hi} Hz, got {:?}",
            args.rate_hz
        ));
    }
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= MAX_SECONDS) {
        return Err(format!(
            "--seconds must be above 0 and at most {MAX_SECONDS:e} s, got {:?}",
            args.seconds
        ));
    }
    let [lo, hi] = READINGS;
    let readings = args.seconds * args.rate_hz;
    if !(lo..=hi).contains(&readings) {
        return Err(format!(
            "--seconds × --rate-hz must give between {lo} and {hi:e} readings, got {readings:?}"
        ));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Err(e) = check(&args) {
        eprintln!("caravan-imu-allan: {e}");
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

#[cfg(test)]
mod tests {
    use super::*;

    fn args(seconds: f64, rate_hz: f64) -> Args {
        Args {
            seconds,
            rate_hz,
            seed: 1,
            out: PathBuf::from("allan"),
        }
    }

    #[test]
    fn runs_outside_the_ranges_are_refused_naming_the_argument() {
        check(&args(100_000.0, 100.0)).unwrap();
        for (a, says) in [
            (args(1e308, 100.0), "--seconds"),
            (args(100.0, 1e-300), "--rate-hz"),
            (args(1.0, 100.0), "readings"),
            (args(1e6, 1000.0), "readings"),
        ] {
            let e = check(&a).unwrap_err();
            assert!(e.contains(says), "{e}");
        }
    }
}
