//! `caravan-tracked-urdf`: writes the tracked robot's description for each running-gear
//! variant (see `caravan_tracked::urdf`), `v1.urdf` … `v4.urdf` in `--out`.

use caravan_tracked::running_gear::Variant;
use caravan_tracked::urdf::Flippers;
use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Generate the tracked robot's URDF for each running-gear variant")]
struct Args {
    /// Output directory.
    #[arg(long, default_value = "launch/tracked/robots")]
    out: PathBuf,
    /// Only this variant (v1, v2, v3 or v4); default all four.
    #[arg(long, value_parser = Variant::parse)]
    variant: Option<Variant>,
    /// Fix the flippers at this angle above the track's line, degrees in [0, 90], instead of
    /// on revolute joints (the default, for trying poses).
    #[arg(long)]
    flipper_angle: Option<f64>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Some(a) = args.flipper_angle.filter(|a| !(0.0..=90.0).contains(a)) {
        eprintln!("caravan-tracked-urdf: --flipper-angle: {a} is outside [0, 90] degrees");
        return ExitCode::from(2);
    }
    let flippers = args
        .flipper_angle
        .map_or(Flippers::Movable, Flippers::Fixed);
    let variants = args.variant.map_or(Variant::ALL.to_vec(), |v| vec![v]);
    for v in variants {
        let path = args.out.join(format!("{}.urdf", v.name()));
        let written = std::fs::create_dir_all(&args.out).and_then(|()| {
            std::fs::write(
                &path,
                caravan_tracked::urdf::urdf_with_flippers(v, flippers),
            )
        });
        if let Err(e) = written {
            eprintln!("caravan-tracked-urdf: {}: {e}", path.display());
            return ExitCode::FAILURE;
        }
        println!("{}", path.display());
    }
    ExitCode::SUCCESS
}
