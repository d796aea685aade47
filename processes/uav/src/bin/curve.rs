//! `caravan-uav-curve`: the learning curves of training logs (`train.py`'s CSVs) as one SVG.
//!
//!   caravan-uav-curve launch/uav/policies/td3-seed*-curve.csv --out docs/uav/learning-curve.svg

use anyhow::{Context, Result, bail};
use clap::Parser;
use std::path::PathBuf;

#[derive(Parser)]
#[command(about = "Learning curves of the UAV agent's training logs")]
struct Args {
    /// Training logs (CSV), one curve each.
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    #[arg(long)]
    out: PathBuf,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let mut runs = Vec::new();
    for log in &args.logs {
        let text = std::fs::read_to_string(log)
            .with_context(|| format!("cannot read {}", log.display()))?;
        let points = caravan_uav::curve::parse(&text)
            .map_err(|e| anyhow::anyhow!("{}: {e}", log.display()))?;
        if points.is_empty() {
            bail!("{}: no episodes", log.display());
        }
        let name = log
            .file_stem()
            .map_or("run".into(), |s| s.to_string_lossy().replace("-curve", ""));
        runs.push((name, points));
    }
    caravan_uav::curve::svg(&args.out, &runs)
}
