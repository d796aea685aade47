//! `caravan-tracked-terrain`: a Random Step Environment terrain (see `caravan_tracked::rse`)
//! from a spec file, as a world file and a picture.
//!
//!     caravan-tracked-terrain SPEC [--seed N] --out WORLD.toml [--svg PICTURE.svg]
//!     caravan-tracked-terrain SPEC --seeds 1..=20 --out-dir DIR [--pictures]
//!
//! The second form writes `DIR/<spec stem>-<seed>.toml` (and `.svg`) per seed, for sweeps.
//! Exit 0, or 2 with a one-line message on bad input.

use caravan_tracked::{rse, rse_world};
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Generate a Random Step Environment terrain as a Caravan world file")]
struct Args {
    /// The terrain spec (TOML; see launch/tracked/terrains/README.md).
    spec: PathBuf,
    /// Seed; default the spec's `terrain.seed`.
    #[arg(long, conflicts_with = "seeds")]
    seed: Option<u64>,
    /// The world file to write.
    #[arg(long, required_unless_present = "seeds", conflicts_with = "out_dir")]
    out: Option<PathBuf>,
    /// Seeds to write one world each for: `a..=b`, `a..b` or a comma list.
    #[arg(long, requires = "out_dir", value_parser = parse_seeds)]
    seeds: Option<Seeds>,
    /// Where the `--seeds` worlds go.
    #[arg(long)]
    out_dir: Option<PathBuf>,
    /// With `--out`: also write the picture (SVG) here.
    #[arg(long, conflicts_with = "seeds")]
    svg: Option<PathBuf>,
    /// With `--seeds`: also write a picture beside each world.
    #[arg(long, requires = "seeds")]
    pictures: bool,
}

/// A list of seeds (a newtype, so clap takes it as one value).
#[derive(Clone)]
struct Seeds(Vec<u64>);

fn parse_seeds(s: &str) -> Result<Seeds, String> {
    caravan_report::seeds::parse(s).map(Seeds)
}

/// Writes the world of `seed` to `out`, and its picture to `svg`.
fn write(
    spec: &rse::Spec,
    spec_file: &str,
    seed: u64,
    out: &Path,
    svg: Option<&Path>,
) -> Result<(), String> {
    let (grid, text) = rse_world::world_file(spec, spec_file, seed);
    std::fs::write(out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    if let Some(svg) = svg {
        rse_world::draw(&grid, &[], &format!("{spec_file}, seed {seed}"), svg)
            .map_err(|e| format!("{}: {e}", svg.display()))?;
    }
    println!("{}", out.display());
    Ok(())
}

fn run(args: &Args) -> Result<(), String> {
    let file = args.spec.display().to_string();
    let text =
        std::fs::read_to_string(&args.spec).map_err(|e| format!("{file}: cannot read: {e}"))?;
    let spec = rse::parse_spec(&text).map_err(|e| format!("{file}: {e}"))?;
    let stem = args
        .spec
        .file_stem()
        .map_or("terrain".into(), |s| s.to_string_lossy().into_owned());
    let spec_name = args
        .spec
        .file_name()
        .map_or(file.clone(), |s| s.to_string_lossy().into_owned());
    match (&args.seeds, &args.out_dir, &args.out) {
        (Some(seeds), Some(dir), _) => {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            for &seed in &seeds.0 {
                let out = dir.join(format!("{stem}-{seed}.toml"));
                let svg = args
                    .pictures
                    .then(|| dir.join(format!("{stem}-{seed}.svg")));
                write(&spec, &spec_name, seed, &out, svg.as_deref())?;
            }
        }
        (None, _, Some(out)) => {
            let seed = args.seed.unwrap_or(spec.terrain.seed);
            write(&spec, &spec_name, seed, out, args.svg.as_deref())?;
        }
        _ => return Err("give --out FILE, or --seeds and --out-dir".into()),
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = match Args::try_parse() {
        Ok(a) => a,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("caravan-tracked-terrain: {e}");
            ExitCode::from(2)
        }
    }
}
