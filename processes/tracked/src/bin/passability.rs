//! `caravan-tracked-passability SWEEP_DIR`: the passability table of a finished sweep over
//! `args.variant` × `args.terrain` × `args.terrain_seed` (see `caravan_tracked::passability`),
//! as Markdown on stdout and `passability.md` in the sweep directory.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir] = args.as_slice() else {
        eprintln!("usage: caravan-tracked-passability SWEEP_DIR");
        return ExitCode::from(2);
    };
    match run(&PathBuf::from(dir)) {
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
