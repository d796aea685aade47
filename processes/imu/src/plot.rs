//! Plots of the readings against time, as the reference's figures: specific force (x, y, z)
//! above, angular rate below, one SVG per run (`imu.svg` in the run directory).

use crate::phase_errors::Reading;
use plotters::prelude::*;
use std::path::Path;

/// Most points drawn per series; longer runs are thinned evenly.
const MAX_POINTS: usize = 2000;

const AXES: [(&str, RGBColor); 3] = [
    ("x", RGBColor(214, 39, 40)),
    ("y", RGBColor(44, 160, 44)),
    ("z", RGBColor(31, 119, 180)),
];

/// Picks the plotted vector out of a reading.
type Field = fn(&Reading) -> [f64; 3];

/// Writes the readings' plot to `path`, titled `title`.
pub fn readings_svg(path: &Path, title: &str, readings: &[Reading]) -> anyhow::Result<()> {
    let every = readings.len().div_ceil(MAX_POINTS).max(1);
    let shown: Vec<&Reading> = readings.iter().step_by(every).collect();
    let t_end = readings.last().map_or(1.0, |r| r.t_s);
    let root = SVGBackend::new(path, (900, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(320);
    let panels: [(_, &str, Field); 2] = [
        (top, "specific force (m/s²)", |r| r.accel),
        (bottom, "angular rate (rad/s)", |r| r.gyro),
    ];
    for (k, (area, label, value)) in panels.into_iter().enumerate() {
        let (lo, hi) = shown
            .iter()
            .flat_map(|r| value(r))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let pad = ((hi - lo) * 0.08).max(0.05);
        let caption = if k == 0 { title } else { "" };
        let mut chart = ChartBuilder::on(&area)
            .caption(caption, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(55)
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(label)
            .draw()?;
        for (axis, (name, colour)) in AXES.iter().enumerate() {
            chart
                .draw_series(LineSeries::new(
                    shown.iter().map(|r| (r.t_s, value(r)[axis])),
                    colour,
                ))?
                .label(*name)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], *colour));
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
