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

/// Draws the series' labels in a box.
fn legend<'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, CT>,
) -> anyhow::Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

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
        legend(&mut chart)?;
    }
    root.present()?;
    Ok(())
}

/// Writes the Allan deviation of each triad (log–log) with its configured model
/// √(N²/τ + (0.664·B)²) to `path`.
pub fn allan_svg(path: &Path, triads: &[crate::allan_run::TriadResult]) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (900, 380 * triads.len() as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((triads.len(), 1));
    for (area, t) in areas.iter().zip(triads) {
        let (tau_lo, tau_hi) = (t.adev[0].0, t.adev[t.adev.len() - 1].0);
        let model = |tau: f64| {
            (t.noise_density.powi(2) / tau
                + (caravan_sensor::imu_errors::FLICKER_FLOOR * t.bias_instability).powi(2))
            .sqrt()
        };
        let (lo, hi) = t
            .adev
            .iter()
            .map(|(tau, s)| (s.min(model(*tau)), s.max(model(*tau))))
            .fold((f64::INFINITY, 0.0f64), |(a, b), (l, h)| {
                (a.min(l), b.max(h))
            });
        let unit = if t.triad == "gyro" { "rad/s" } else { "m/s²" };
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "{}: N = {:.3e} (fit {:.3e}), B = {:.3e} (fit {:.3e}) {unit}",
                    t.triad,
                    t.noise_density,
                    t.noise_density_estimated,
                    t.bias_instability,
                    t.bias_instability_estimated
                ),
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (tau_lo..tau_hi).log_scale(),
                (lo * 0.8..hi * 1.25).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("τ (s)")
            .y_desc(format!("Allan deviation ({unit})"))
            .draw()?;
        chart
            .draw_series(LineSeries::new(t.adev.iter().copied(), &AXES[2].1))?
            .label("measured")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], AXES[2].1));
        chart
            .draw_series(LineSeries::new(
                t.adev.iter().map(|(tau, _)| (*tau, model(*tau))),
                &AXES[0].1,
            ))?
            .label("configured N, B")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], AXES[0].1));
        legend(&mut chart)?;
    }
    root.present()?;
    Ok(())
}
