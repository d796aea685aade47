//! `caravan-tracked-passability SWEEP_DIR`: the passability table of a finished sweep over
//! `args.variant` × `args.terrain` × `args.terrain_seed` (see `caravan_tracked::passability`),
//! as Markdown on stdout and `passability.md` in the sweep directory.

use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    about = "The passability table of a finished sweep over args.variant × args.terrain × args.terrain_seed"
)]
struct Args {
    /// The sweep's output directory (with its summary.json).
    sweep_dir: PathBuf,
}

fn run(dir: &Path) -> Result<String, String> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let summary = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let tallies = caravan_tracked::passability::pool(&summary)?;
    let table = caravan_tracked::passability::table(&tallies);
    let out = dir.join("passability.md");
    std::fs::write(&out, &table).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(table)
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args.sweep_dir) {
        Ok(table) => {
            print!("{table}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("caravan-tracked-passability: {e}");
            ExitCode::from(2)
        }
    }
}
