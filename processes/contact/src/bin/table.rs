//! Table 1 of the contact-identification reference by Monte-Carlo, with the analytical method
//! timed against the optimiser baseline in the same run.
//!
//!   caravan-contact-table                       # 10 000 trials per σ, 200 optimised
//!   caravan-contact-table --trials 500 --out docs/contact

use anyhow::{Context, Result, bail};
use caravan_contact::monte_carlo::{Config, run_level};
use caravan_contact::table::{markdown, row};
use clap::Parser;
use std::path::PathBuf;

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

fn main() -> Result<()> {
    let args = Args::parse();
    if args.trials == 0 {
        bail!("--trials must be at least 1");
    }
    if let Some(s) = args.sigmas.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
        bail!("--sigmas: a noise level must be ≥ 0 N·m, got {s}");
    }
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
