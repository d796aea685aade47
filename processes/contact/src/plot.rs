//! The live run's plot (`contact.svg`): the true and estimated force components against time
//! above, the point error below.

use crate::live::ScoredEstimate;
use plotters::prelude::*;
use std::path::Path;

/// Picks one component of a force.
type Component = fn(&nalgebra::Vector2<f64>) -> f64;

/// Most estimates drawn; longer runs are thinned evenly.
const MAX_POINTS: usize = 3000;

pub fn contact_svg(path: &Path, sigma: f64, scored: &[ScoredEstimate]) -> anyhow::Result<()> {
    let every = scored.len().div_ceil(MAX_POINTS).max(1);
    let shown: Vec<&ScoredEstimate> = scored.iter().step_by(every).collect();
    let (t0, t1) = (
        shown.first().map_or(0.0, |s| s.t_s),
        shown
            .last()
            .map_or(1.0, |s| s.t_s)
            .max(shown.first().map_or(0.0, |s| s.t_s) + 1e-3),
    );
    let root = SVGBackend::new(path, (900, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(360);
    let f_max = shown
        .iter()
        .flat_map(|s| [s.true_force.x.abs(), s.true_force.y.abs()])
        .fold(1.0, f64::max)
        * 1.15;
    let mut chart = ChartBuilder::on(&top)
        .caption(
            format!("contact force, true (lines) and estimated (dots), σ = {sigma} N·m"),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(55)
        .build_cartesian_2d(t0..t1, -f_max..f_max)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("force (N)")
        .draw()?;
    let components: [(&str, RGBColor, Component); 2] = [
        ("F_x", RGBColor(214, 39, 40), |v| v.x),
        ("F_y", RGBColor(31, 119, 180), |v| v.y),
    ];
    for (name, colour, pick) in components {
        chart
            .draw_series(
                shown
                    .iter()
                    .map(|s| Circle::new((s.t_s, pick(&s.true_force)), 1, colour.filled())),
            )?
            .label(format!("{name} true"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour));
        chart.draw_series(shown.iter().filter_map(|s| {
            s.force
                .map(|f| Circle::new((s.t_s, pick(&f)), 2, colour.mix(0.35).filled()))
        }))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    let e_max = shown
        .iter()
        .filter_map(|s| s.point_error_mm)
        .fold(1.0, f64::max)
        * 1.1;
    let mut chart = ChartBuilder::on(&bottom)
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(55)
        .build_cartesian_2d(t0..t1, 0.0..e_max)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("point error (mm)")
        .draw()?;
    chart.draw_series(shown.iter().filter_map(|s| {
        s.point_error_mm
            .map(|e| Circle::new((s.t_s, e), 1, RGBColor(44, 160, 44).filled()))
    }))?;
    root.present()?;
    Ok(())
}
