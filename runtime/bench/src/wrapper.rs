//! Caravan's wrapper against raw iceoryx2: the runtime issue's latency target.

use super::WrapperArgs;
use super::pingpong::{Payload, Variant, measure};
use anyhow::Result;
use caravan_report::bench::{median, percentiles};
use std::fmt::Write;

pub fn run(args: &WrapperArgs) -> Result<()> {
    let mut csv = String::from("payload,bytes,variant,run,p50_ns,p90_ns,p99_ns,p999_ns,max_ns\n");
    println!(
        "one-way latency (round trip / 2), {} round trips per run, {} runs",
        args.rounds, args.runs
    );
    println!(
        "{:<7} {:>7} {:<9} {:>9} {:>9}   (medians over runs)",
        "payload", "bytes", "variant", "p50 µs", "p99 µs"
    );
    for payload in [Payload::Small, Payload::Scan] {
        let mut p50 = [Vec::new(), Vec::new()];
        let mut p99 = [Vec::new(), Vec::new()];
        for run in 0..args.runs {
            // Alternate the order so that neither variant always runs on a warmer machine.
            let order = if run % 2 == 0 {
                [Variant::Iceoryx2, Variant::Caravan]
            } else {
                [Variant::Caravan, Variant::Iceoryx2]
            };
            for variant in order {
                let group = format!("bench-{}-{run}-{}", std::process::id(), variant as u8);
                let p = percentiles(&measure(variant, payload, args.rounds, &group)?);
                let i = variant as usize;
                p50[i].push(p.p50_ns);
                p99[i].push(p.p99_ns);
                writeln!(
                    csv,
                    "{payload:?},{},{variant:?},{run},{},{},{},{},{}",
                    payload.bytes(),
                    p.p50_ns,
                    p.p90_ns,
                    p.p99_ns,
                    p.p999_ns,
                    p.max_ns
                )?;
            }
        }
        let mut med = [(0, 0); 2];
        for variant in [Variant::Iceoryx2, Variant::Caravan] {
            let i = variant as usize;
            med[i] = (median(p50[i].clone()), median(p99[i].clone()));
            println!(
                "{:<7} {:>7} {:<9} {:>9.2} {:>9.2}",
                format!("{payload:?}"),
                payload.bytes(),
                format!("{variant:?}"),
                med[i].0 as f64 / 1e3,
                med[i].1 as f64 / 1e3
            );
        }
        let (c, r) = (
            med[Variant::Caravan as usize],
            med[Variant::Iceoryx2 as usize],
        );
        println!(
            "{:<7} ratio Caravan / iceoryx2: p50 {:.2}, p99 {:.2}",
            format!("{payload:?}"),
            c.0 as f64 / r.0 as f64,
            c.1 as f64 / r.1 as f64
        );
    }
    if let Some(path) = &args.csv {
        std::fs::write(path, csv)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
