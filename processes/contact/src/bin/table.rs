//! Table 1 of the contact-identification reference by Monte-Carlo, with the analytical method
//! timed against the optimiser baseline in the same run.
//!
//!   caravan-contact-table                       # 10 000 trials per σ, 200 optimised
//!   caravan-contact-table --trials 500 --out docs/contact

use anyhow::{Context, Result};
use caravan_contact::monte_carlo::{Config, run_level};
use caravan_contact::range::{MAX_TORQUE_NOISE_N_M, shown};
use caravan_contact::table::{markdown, row};
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

/// Trials per noise level, at most 10⁶: a hundred times the table's 10 000, minutes per level
/// in a release build; 4·10⁹ would run for weeks.
const MAX_TRIALS: usize = 1_000_000;

#[derive(Parser)]
#[command(about = "The contact-identification reference's Table 1 by Monte-Carlo")]
struct Args {
    /// Trials per noise level.
    #[arg(long, default_value_t = 10_000)]
    trials: usize,
    /// Trials per noise level also solved by the optimiser (the first ones).
    #[arg(long, default_value_t = 200)]
    optimiser_trials: usize,
    /// Torque noise levels σ, N·m.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 0.1, 0.5, 1.0, 2.0])]
    sigmas: Vec<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write table.md and table.json here.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The arguments' ranges (the noise levels as the live scenario's `estimator.torque_sigma`);
/// the error names the argument.
fn check(args: &Args) -> Result<(), String> {
    if !(1..=MAX_TRIALS).contains(&args.trials) {
        return Err(format!(
            "--trials must be between 1 and {MAX_TRIALS}, got {}",
            args.trials
        ));
    }
    let ok = |s: f64| s.is_finite() && (0.0..=MAX_TORQUE_NOISE_N_M).contains(&s);
    if let Some(s) = args.sigmas.iter().find(|s| !ok(**s)) {
        return Err(format!(
            "--sigmas: a noise level must be between 0 and {MAX_TORQUE_NOISE_N_M} N·m, got {}",
            shown(*s)
        ));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Err(e) = check(&args) {
        eprintln!("caravan-contact-table: {e}");
        return ExitCode::from(2);
    }
    match write(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caravan-contact-table: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn write(args: Args) -> Result<()> {
    let config = Config {
        trials: args.trials,
        optimiser_trials: args.optimiser_trials.min(args.trials),
        sigmas: args.sigmas,
        seed: args.seed,
        ..Config::reference()
    };
    let rows: Vec<_> = config
        .sigmas
        .iter()
        .map(|&sigma| row(sigma, &run_level(&config, sigma)))
        .collect();
    let table = markdown(&rows);
    print!("{table}");
    if let Some(out) = args.out {
        std::fs::create_dir_all(&out)
            .with_context(|| format!("cannot create {}", out.display()))?;
        std::fs::write(out.join("table.md"), &table)?;
        std::fs::write(
            out.join("table.json"),
            serde_json::to_string_pretty(&serde_json::json!({
                "seed": config.seed,
                "trials": config.trials,
                "optimiser_trials": config.optimiser_trials,
                "rows": rows,
            }))?,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trials_and_noise_levels_outside_their_ranges_are_refused_naming_the_argument() {
        let parse = |extra: &[&str]| {
            let mut all = vec!["caravan-contact-table"];
            all.extend(extra);
            check(&Args::parse_from(all))
        };
        parse(&[]).unwrap();
        let e = parse(&["--sigmas", "0.1,1e308"]).unwrap_err();
        assert!(e.starts_with("--sigmas") && e.contains("1e308"), "{e}");
        let e = parse(&["--trials", "4000000000"]).unwrap_err();
        assert!(e.starts_with("--trials"), "{e}");
        assert!(parse(&["--trials", "0"]).is_err());
    }
}
