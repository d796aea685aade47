//! The table on stdout, the Caravan ratios and the CSV.

use super::payload::label;
use super::{Kind, Row, Setup};
use caravan_report::bench::Machine;
use std::fmt::Write;

fn us(ns: u64) -> String {
    let us = ns as f64 / 1e3;
    if us >= 1000.0 {
        format!("{us:.0}")
    } else if us >= 10.0 {
        format!("{us:.1}")
    } else {
        format!("{us:.2}")
    }
}

pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "\n{:<15} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}   wake-up",
        "transport",
        "payload",
        "p50 µs",
        "p90 µs",
        "p99 µs",
        "p99.9 µs",
        "max µs",
        "MB/s",
        "CPU µs/msg"
    );
    let mut last = None;
    for r in rows {
        if last.is_some_and(|b| b != r.bytes) {
            out.push('\n');
        }
        last = Some(r.bytes);
        let _ = match &r.result {
            Ok(p) => writeln!(
                out,
                "{:<15} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9.1} {:>9}   {}",
                r.kind.name(),
                label(r.bytes),
                us(p.p50_ns),
                us(p.p90_ns),
                us(p.p99_ns),
                us(p.p999_ns),
                us(p.max_ns),
                r.bytes_per_s / 1e6,
                r.cpu_ns_per_message
                    .map_or_else(|| "-".into(), |ns| us(ns as u64)),
                r.kind.wake_up()
            ),
            Err(why) => writeln!(out, "{:<15} {:>9}   {why}", r.kind.name(), label(r.bytes)),
        };
    }
    out
}

fn p50(rows: &[Row], kind: Kind, bytes: usize) -> Option<u64> {
    rows.iter()
        .find(|r| r.kind == kind && r.bytes == bytes)
        .and_then(|r| r.result.as_ref().ok())
        .map(|p| p.p50_ns)
}

/// Caravan's p50 divided by each baseline's, per payload size.
pub fn ratios(rows: &[Row]) -> String {
    let pairs = [
        (Kind::CaravanEvent, Kind::Iceoryx2Event),
        (Kind::CaravanPoll, Kind::Iceoryx2Poll),
        (Kind::CaravanEvent, Kind::Uds),
        (Kind::CaravanSpin, Kind::Uds),
        (Kind::CaravanSpin, Kind::CaravanEvent),
        (Kind::CaravanEvent, Kind::Zenoh),
        (Kind::CaravanEvent, Kind::ZenohShm),
        // Between hosts: what the bridge adds to one host's path, and to zenoh's own.
        (Kind::CaravanBridged, Kind::CaravanEvent),
        (Kind::CaravanBridged, Kind::Zenoh),
    ];
    let mut sizes: Vec<usize> = rows.iter().map(|r| r.bytes).collect();
    sizes.dedup();
    let mut out = String::new();
    let mut header = format!("\np50 ratios (< 1: the first is faster)\n{:<32}", "");
    for &b in &sizes {
        let _ = write!(header, " {:>9}", label(b));
    }
    header.push('\n');
    for (caravan, base) in pairs {
        let mut line = format!("{:<32}", format!("{} / {}", caravan.name(), base.name()));
        let mut any = false;
        for &b in &sizes {
            let cell = match (p50(rows, caravan, b), p50(rows, base, b)) {
                (Some(c), Some(r)) if r > 0 => {
                    any = true;
                    let ratio = c as f64 / r as f64;
                    if ratio < 0.1 {
                        format!("{ratio:.3}")
                    } else {
                        format!("{ratio:.2}")
                    }
                }
                _ => "-".into(),
            };
            let _ = write!(line, " {cell:>9}");
        }
        if any {
            out.push_str(&line);
            out.push('\n');
        }
    }
    if out.is_empty() {
        return out;
    }
    header + &out
}

pub(super) fn csv(machine: &Machine, rows: &[Row], setup: &Setup) -> String {
    let (rounds, warmup, in_flight, spin) =
        (setup.rounds, setup.warmup, setup.in_flight, setup.spin);
    let mut out = String::new();
    let _ = writeln!(out, "# caravan bench transport");
    let _ = writeln!(out, "# cpu: {}", machine.cpu);
    let _ = writeln!(out, "# cores: {}", machine.cores);
    let _ = writeln!(out, "# kernel: {}", machine.kernel);
    let _ = writeln!(out, "# placement: {}", machine.placement);
    let _ = writeln!(
        out,
        "# one-way latency = round trip / 2 in ns; {rounds} round trips after {warmup} warm-up; {in_flight} in flight"
    );
    let _ = writeln!(
        out,
        "# caravan-spin: nodes spin up to {spin:?} before they sleep"
    );
    let _ = writeln!(
        out,
        "# throughput = payload bytes moved per second, both ways (each echo is a message too)"
    );
    let _ = writeln!(
        out,
        "# cpu per message = CPU time of both sides' processes over the measured round trips / messages (two per round trip)"
    );
    for r in rows {
        if let Some(why) = &r.retried {
            let _ = writeln!(
                out,
                "# {} {} B was measured twice; the first attempt {why}",
                r.kind.name(),
                r.bytes
            );
        }
    }
    let _ = writeln!(
        out,
        "transport,wake_up,payload_bytes,in_flight,rounds,p50_ns,p90_ns,p99_ns,p999_ns,max_ns,mean_ns,throughput_bytes_per_s,cpu_ns_per_message,status"
    );
    for r in rows {
        let _ = match &r.result {
            Ok(p) => writeln!(
                out,
                "{},{},{},{in_flight},{},{},{},{},{},{},{:.0},{:.0},{},ok",
                r.kind.name(),
                r.kind.wake_up(),
                r.bytes,
                r.rounds,
                p.p50_ns,
                p.p90_ns,
                p.p99_ns,
                p.p999_ns,
                p.max_ns,
                r.mean_ns,
                r.bytes_per_s,
                r.cpu_ns_per_message
                    .map_or_else(String::new, |ns| format!("{ns:.0}"))
            ),
            Err(why) => writeln!(
                out,
                "{},{},{},{in_flight},{},,,,,,,,,{}",
                r.kind.name(),
                r.kind.wake_up(),
                r.bytes,
                r.rounds,
                why.replace(',', ";")
            ),
        };
    }
    out
}
