//! Line plots against time for report plugins (SVG, plotters): one or more panels stacked, each
//! with labelled series drawn as segments (a series may have gaps), axes and a legend.

use plotters::prelude::*;
use std::path::Path;

/// Most points drawn per segment; longer ones are thinned evenly.
const MAX_POINTS: usize = 2000;

/// Colours of the series, in order.
pub const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(0, 0, 0),
];

/// One labelled line, drawn as separate segments (gaps between them).
pub struct Series {
    pub label: String,
    pub segments: Vec<Vec<(f64, f64)>>,
}

/// One panel: its y-axis label and its series.
pub struct Panel {
    pub y_label: String,
    pub series: Vec<Series>,
}

/// Writes `panels` stacked, against time in seconds, to `path`, titled `title`.
pub fn lines_svg(path: &Path, title: &str, panels: &[Panel]) -> anyhow::Result<()> {
    let height = 80 + 320 * panels.len().max(1) as u32;
    let root = SVGBackend::new(path, (900, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 18))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    let t_end = panels
        .iter()
        .flat_map(|p| p.series.iter().flat_map(|s| s.segments.iter().flatten()))
        .fold(0.0f64, |a, p| a.max(p.0))
        .max(1e-3);
    for (area, panel) in areas.iter().zip(panels) {
        let points = || {
            panel
                .series
                .iter()
                .flat_map(|s| s.segments.iter().flatten())
        };
        let (lo, hi) = points().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.1), a.1.max(p.1))
        });
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
        let pad = ((hi - lo) * 0.08).max(0.05);
        let mut chart = ChartBuilder::on(area)
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(panel.y_label.as_str())
            .draw()?;
        for (s, colour) in panel.series.iter().zip(COLOURS.iter().cycle()) {
            for (k, segment) in s.segments.iter().enumerate() {
                let every = segment.len().div_ceil(MAX_POINTS).max(1);
                let drawn = chart.draw_series(LineSeries::new(
                    segment.iter().step_by(every).copied(),
                    colour,
                ))?;
                if k == 0 {
                    drawn
                        .label(s.label.as_str())
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], *colour));
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// One row of a bar chart: its label and its values, one bar per value name.
pub struct BarRow {
    pub label: String,
    pub values: Vec<f64>,
}

/// Writes horizontal grouped bars to `path`: per row one bar per entry of `names` (missing or
/// non-finite values are left out), on a shared linear axis from 0 labelled `x_label`.
pub fn bars_svg(
    path: &Path,
    title: &str,
    x_label: &str,
    names: &[&str],
    rows: &[BarRow],
) -> anyhow::Result<()> {
    use std::fmt::Write;
    const LABEL_PX: f64 = 220.0;
    const PLOT_PX: f64 = 620.0;
    let bar = 10.0;
    let row_px = bar * names.len().max(1) as f64 + 10.0;
    let top = 50.0;
    let height = top + row_px * rows.len() as f64 + 70.0;
    let max = rows
        .iter()
        .flat_map(|r| r.values.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-9);
    let x = |v: f64| LABEL_PX + v / max * PLOT_PX;
    let hex = |c: &RGBColor| format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2);
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{height:.0}\" viewBox=\"0 0 {w} {height:.0}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"22\" font-size=\"16\" font-family=\"sans-serif\">{}</text>\n",
        escape(title),
        w = LABEL_PX + PLOT_PX + 60.0,
    );
    for (i, row) in rows.iter().enumerate() {
        let y0 = top + i as f64 * row_px;
        let _ = writeln!(
            svg,
            r#"<text x="{:.0}" y="{:.1}" font-size="11" font-family="sans-serif" text-anchor="end">{}</text>"#,
            LABEL_PX - 6.0,
            y0 + row_px / 2.0,
            escape(&row.label)
        );
        for (k, v) in row.values.iter().enumerate().filter(|(_, v)| v.is_finite()) {
            let _ = writeln!(
                svg,
                r#"<rect x="{LABEL_PX}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{}"/>"#,
                y0 + k as f64 * bar,
                x(*v) - LABEL_PX,
                bar - 1.0,
                hex(&COLOURS[k % COLOURS.len()])
            );
        }
    }
    let axis_y = top + row_px * rows.len() as f64 + 5.0;
    for k in 0..=4 {
        let v = max * k as f64 / 4.0;
        let _ = writeln!(
            svg,
            r##"<line x1="{0:.1}" y1="{top}" x2="{0:.1}" y2="{axis_y:.1}" stroke="#ddd"/><text x="{0:.1}" y="{1:.1}" font-size="10" font-family="sans-serif" text-anchor="middle">{2}</text>"##,
            x(v),
            axis_y + 14.0,
            tick(v)
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{:.0}" y="{:.1}" font-size="11" font-family="sans-serif" text-anchor="middle">{}</text>"#,
        LABEL_PX + PLOT_PX / 2.0,
        axis_y + 32.0,
        escape(x_label)
    );
    for (k, name) in names.iter().enumerate() {
        let lx = LABEL_PX + k as f64 * 90.0;
        let _ = writeln!(
            svg,
            r#"<rect x="{lx}" y="{:.1}" width="12" height="8" fill="{}"/><text x="{:.0}" y="{:.1}" font-size="11" font-family="sans-serif">{}</text>"#,
            axis_y + 42.0,
            hex(&COLOURS[k % COLOURS.len()]),
            lx + 16.0,
            axis_y + 50.0,
            escape(name)
        );
    }
    svg.push_str("</svg>\n");
    std::fs::write(path, svg)?;
    Ok(())
}

/// An axis label: three decimals at most, without trailing zeros.
fn tick(v: f64) -> String {
    let text = format!("{v:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_are_drawn_with_their_labels_and_series() {
        let path = std::env::temp_dir().join(format!("caravan-plot-{}.svg", std::process::id()));
        let line = |label: &str, k: f64| Series {
            label: label.into(),
            segments: vec![(0..50).map(|i| (i as f64 * 0.1, k * i as f64)).collect()],
        };
        lines_svg(
            &path,
            "Title",
            &[
                Panel {
                    y_label: "gap (m)".into(),
                    series: vec![line("robot 1", 1.0), line("robot 2", 2.0)],
                },
                Panel {
                    y_label: "error (m)".into(),
                    series: vec![Series {
                        label: "empty".into(),
                        segments: vec![],
                    }],
                },
            ],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for text in ["Title", "gap (m)", "error (m)", "robot 2", "time (s)"] {
            assert!(svg.contains(text), "{text}");
        }
        assert!(svg.matches("<polyline").count() >= 2);
        let _ = std::fs::remove_file(path);
    }

    #[test]
    fn bars_are_scaled_to_the_largest_value_and_skip_missing_ones() {
        let path = std::env::temp_dir().join(format!("caravan-bars-{}.svg", std::process::id()));
        let rows = [
            BarRow {
                label: "robot/0/scan <raw>".into(),
                values: vec![1.0, 4.0],
            },
            BarRow {
                label: "map".into(),
                values: vec![2.0, f64::NAN],
            },
        ];
        bars_svg(&path, "Latency", "µs", &["p50", "p99"], &rows).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("robot/0/scan &lt;raw&gt;"));
        assert_eq!(svg.matches(r#"height="9.0""#).count(), 3, "NaN is left out");
        // The largest value spans the whole plot width.
        assert!(svg.contains(r#"width="620.0""#), "{svg}");
        assert!(svg.contains(">p99</text>") && svg.contains(">µs</text>"));
        let _ = std::fs::remove_file(path);
    }
}
