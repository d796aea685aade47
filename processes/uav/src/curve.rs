//! Learning curves: the training log's episodes (`train.py`'s CSV) as return against training
//! steps, with a running mean, one line per run.

use plotters::prelude::*;
use std::path::Path;

/// One training episode: total steps when it ended, its return, whether it passed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub total_steps: f64,
    pub ret: f64,
    pub passed: bool,
}

/// Reads `episode,total_steps,steps,return,outcome,wall_s` rows.
pub fn parse(text: &str) -> Result<Vec<Point>, String> {
    let mut lines = text.lines();
    let header = lines.next().ok_or("an empty file")?;
    if !header.starts_with("episode,total_steps,steps,return,outcome") {
        return Err(format!("not a training log: header '{header}'"));
    }
    lines
        .enumerate()
        .map(|(i, line)| {
            let f: Vec<&str> = line.split(',').collect();
            let num = |k: usize| -> Result<f64, String> {
                f.get(k)
                    .and_then(|s| s.parse().ok())
                    .ok_or_else(|| format!("line {}: column {} is not a number", i + 2, k + 1))
            };
            Ok(Point {
                total_steps: num(1)?,
                ret: num(3)?,
                passed: f.get(4) == Some(&"passed"),
            })
        })
        .collect()
}

/// The mean of each point and the `window − 1` before it.
pub fn running_mean(points: &[Point], window: usize) -> Vec<(f64, f64)> {
    (0..points.len())
        .map(|i| {
            let from = (i + 1).saturating_sub(window);
            let slice = &points[from..=i];
            (
                points[i].total_steps,
                slice.iter().map(|p| p.ret).sum::<f64>() / slice.len() as f64,
            )
        })
        .collect()
}

const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Draws every run's episodes (dots) and running mean of 10 (line) into `path`.
pub fn svg(path: &Path, runs: &[(String, Vec<Point>)]) -> anyhow::Result<()> {
    let all = || runs.iter().flat_map(|r| r.1.iter());
    let x_max = all().map(|p| p.total_steps).fold(1.0, f64::max);
    let (lo, hi) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        (a.min(p.ret), b.max(p.ret))
    });
    let root = SVGBackend::new(path, (900, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "learning curve: episode return (dots) and running mean of 10",
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_max * 1.02, (lo - 50.0)..(hi + 50.0))?;
    chart
        .configure_mesh()
        .x_desc("training steps")
        .y_desc("return")
        .draw()?;
    for (k, (name, points)) in runs.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        chart.draw_series(
            points
                .iter()
                .map(|p| Circle::new((p.total_steps, p.ret), 2, colour.mix(0.3).filled())),
        )?;
        chart
            .draw_series(LineSeries::new(
                running_mean(points, 10),
                colour.stroke_width(2),
            ))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logs_parse_and_average() {
        let text = "episode,total_steps,steps,return,outcome,wall_s\n1,100,100,-1000,collided,1.0\n2,340,240,900,passed,2.0\n";
        let p = parse(text).unwrap();
        assert_eq!(p.len(), 2);
        assert!(p[1].passed && !p[0].passed);
        assert_eq!(running_mean(&p, 10), vec![(100.0, -1000.0), (340.0, -50.0)]);
        assert!(parse("a,b\n").is_err());
        assert!(
            parse("episode,total_steps,steps,return,outcome,wall_s\n1,x,1,1,passed,0\n").is_err()
        );
    }
}
