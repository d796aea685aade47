//! The plot: p50 (solid) and p99 (dashed) one-way latency against payload size per transport,
//! both axes logarithmic. Written as plain SVG; no font or drawing library needed.

use super::payload::label;
use super::{Kind, Row};
use caravan_report::bench::{Machine, Percentiles};
use std::fmt::Write;

const WIDTH: f64 = 980.0;
const HEIGHT: f64 = 620.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 230.0;
const TOP: f64 = 76.0;
const BOTTOM: f64 = 60.0;

const COLORS: [&str; 11] = [
    "#d62728", "#393b79", "#ff7f0e", "#bcbd22", "#1f77b4", "#17becf", "#2ca02c", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f",
];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

pub fn svg(machine: &Machine, rows: &[Row], rounds: u64) -> String {
    let ok: Vec<(&Row, &Percentiles)> = rows
        .iter()
        .filter_map(|r| r.result.as_ref().ok().map(|p| (r, p)))
        .collect();
    let mut sizes: Vec<usize> = rows.iter().map(|r| r.bytes).collect();
    sizes.sort_unstable();
    sizes.dedup();
    let (x_min, x_max) = match (sizes.first(), sizes.last()) {
        (Some(&a), Some(&b)) => ((a as f64).log2() - 0.5, (b as f64).log2() + 0.5),
        _ => (0.0, 1.0),
    };
    let lo = ok
        .iter()
        .map(|(_, p)| p.p50_ns)
        .min()
        .unwrap_or(1_000)
        .max(1);
    let hi = ok
        .iter()
        .map(|(_, p)| p.p99_ns)
        .max()
        .unwrap_or(1_000)
        .max(lo);
    let y_min = (lo as f64 / 1e3).log10().floor();
    let y_max = ((hi as f64 / 1e3).log10().ceil()).max(y_min + 1.0);
    let plot_w = WIDTH - LEFT - RIGHT;
    let plot_h = HEIGHT - TOP - BOTTOM;
    let x = |bytes: usize| LEFT + ((bytes as f64).log2() - x_min) / (x_max - x_min) * plot_w;
    let y = |ns: u64| {
        let v = (ns.max(1) as f64 / 1e3).log10();
        TOP + plot_h - (v - y_min) / (y_max - y_min) * plot_h
    };

    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"##
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="white"/>"##);
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="24" font-size="16" font-weight="bold">One-way latency between two processes (round trip / 2)</text>"##
    );
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="42" fill="#444">{}</text><text x="{LEFT}" y="58" fill="#444">{rounds} round trips per point · solid p50, dashed p99</text>"##,
        escape(&machine.describe())
    );

    // Horizontal grid: decades labelled, 2× and 5× faint.
    let mut decade = y_min as i32;
    while decade as f64 <= y_max {
        for (m, major) in [(1.0, true), (2.0, false), (5.0, false)] {
            let v = 10f64.powi(decade) * m;
            if v.log10() > y_max + 1e-9 {
                continue;
            }
            let ns = (v * 1e3).round() as u64;
            let py = y(ns);
            let (stroke, width) = if major {
                ("#bbb", 1.0)
            } else {
                ("#e6e6e6", 0.8)
            };
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="{stroke}" stroke-width="{width}"/>"##,
                LEFT + plot_w
            );
            if major {
                let text = if v >= 1e6 {
                    format!("{:.0} s", v / 1e6)
                } else if v >= 1e3 {
                    format!("{:.0} ms", v / 1e3)
                } else {
                    format!("{v} µs")
                };
                let _ = writeln!(
                    s,
                    r##"<text x="{:.1}" y="{:.1}" text-anchor="end">{text}</text>"##,
                    LEFT - 8.0,
                    py + 4.0
                );
            }
        }
        decade += 1;
    }
    // Vertical grid at the measured sizes.
    for &b in &sizes {
        let px = x(b);
        let _ = writeln!(
            s,
            r##"<line x1="{px:.1}" y1="{TOP}" x2="{px:.1}" y2="{:.1}" stroke="#e6e6e6"/>"##,
            TOP + plot_h
        );
        let _ = writeln!(
            s,
            r##"<text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            TOP + plot_h + 18.0,
            label(b)
        );
    }
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="none" stroke="#333"/>"##
    );
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="middle">payload size (log scale)</text>"##,
        LEFT + plot_w / 2.0,
        HEIGHT - 14.0
    );
    let _ = writeln!(
        s,
        r##"<text transform="translate(22 {:.1}) rotate(-90)" text-anchor="middle">one-way latency (log scale)</text>"##,
        TOP + plot_h / 2.0
    );

    // One solid p50 and one dashed p99 line per transport, and the legend.
    for (i, kind) in Kind::ALL.iter().enumerate() {
        let points: Vec<_> = ok.iter().filter(|(r, _)| r.kind == *kind).collect();
        if points.is_empty() {
            continue;
        }
        let color = COLORS[i % COLORS.len()];
        for (dash, pick) in [
            ("", (|p| p.p50_ns) as fn(&Percentiles) -> u64),
            (r##" stroke-dasharray="6 4""##, |p| p.p99_ns),
        ] {
            let path: Vec<String> = points
                .iter()
                .map(|(r, p)| format!("{:.1},{:.1}", x(r.bytes), y(pick(p))))
                .collect();
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="{color}" stroke-width="1.8"{dash}/>"##,
                path.join(" ")
            );
            for (r, p) in &points {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="{color}"/>"##,
                    x(r.bytes),
                    y(pick(p)),
                    if dash.is_empty() { 3.0 } else { 2.0 }
                );
            }
        }
        let ly = TOP + 10.0 + i as f64 * 22.0;
        let lx = LEFT + plot_w + 18.0;
        let _ = writeln!(
            s,
            r##"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{color}" stroke-width="2.5"/>"##,
            lx + 24.0
        );
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}">{}</text>"##,
            lx + 30.0,
            ly + 4.0,
            kind.name()
        );
    }
    let ly = TOP + 10.0 + Kind::ALL.len() as f64 * 22.0 + 10.0;
    let lx = LEFT + plot_w + 18.0;
    let _ = writeln!(
        s,
        r##"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="#333" stroke-width="1.8"/><text x="{:.1}" y="{:.1}">p50</text>"##,
        lx + 24.0,
        lx + 30.0,
        ly + 4.0
    );
    let _ = writeln!(
        s,
        r##"<line x1="{lx:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#333" stroke-width="1.8" stroke-dasharray="6 4"/><text x="{:.1}" y="{:.1}">p99</text>"##,
        ly + 20.0,
        lx + 24.0,
        ly + 20.0,
        lx + 30.0,
        ly + 24.0
    );
    s.push_str("</svg>\n");
    s
}
