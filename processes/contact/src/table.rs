//! Table 1 from the Monte-Carlo trials: per noise level, the errors' means with 95 %
//! intervals, the no-solution rate with its Wilson interval, and the time per estimate of the
//! analytical method and the optimiser, beside the reference's numbers.

use crate::identify::PointSource;
use crate::monte_carlo::Trial;
use caravan_report::stats::describe;
use caravan_report::wilson::wilson95;
use serde::Serialize;

/// The reference's Table 1: σ (N·m), force error (N), direction error (°), point error (mm),
/// no solution (%).
pub const REFERENCE: [(f64, f64, f64, f64, f64); 5] = [
    (0.0, 1e-13, 8e-14, 3e-13, 0.0),
    (0.1, 0.41, 0.33, 0.93, 0.0),
    (0.5, 2.08, 1.53, 4.63, 0.51),
    (1.0, 4.23, 2.89, 8.23, 6.86),
    (2.0, 8.31, 5.96, 12.42, 25.51),
];

/// Mean with its Student-t 95 % interval, and the spread.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Mean {
    pub n: usize,
    pub mean: f64,
    pub ci95: [f64; 2],
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// `None` for an empty sample.
pub fn mean_of(xs: &[f64]) -> Option<Mean> {
    if xs.is_empty() {
        return None;
    }
    let d = describe(xs);
    let mut sorted = xs.to_vec();
    sorted.sort_by(f64::total_cmp);
    Some(Mean {
        n: d.n,
        mean: d.mean,
        ci95: d.ci95.map_or([d.mean; 2], |(a, b)| [a, b]),
        median: quantile(&sorted, 0.5),
        p95: quantile(&sorted, 0.95),
        max: d.max,
    })
}

/// Times per estimate, µs.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Timing {
    pub n: usize,
    pub min_us: f64,
    pub median_us: f64,
    pub mean_us: f64,
    pub max_us: f64,
}

fn timing(ns: &[u64]) -> Option<Timing> {
    if ns.is_empty() {
        return None;
    }
    let mut us: Vec<f64> = ns.iter().map(|n| *n as f64 / 1e3).collect();
    us.sort_by(f64::total_cmp);
    Some(Timing {
        n: us.len(),
        min_us: us[0],
        median_us: quantile(&us, 0.5),
        mean_us: us.iter().sum::<f64>() / us.len() as f64,
        max_us: us[us.len() - 1],
    })
}

/// One noise level's row.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Row {
    pub sigma: f64,
    pub trials: usize,
    pub force_error_n: Option<Mean>,
    pub direction_error_deg: Option<Mean>,
    /// Where the line of action gave the point.
    pub point_error_mm: Option<Mean>,
    /// No point from the line of action (missed surface, outside the cone, no force): %.
    pub no_solution_pct: f64,
    pub no_solution_ci95_pct: [f64; 2],
    /// The depth fall-back's point error where it stood in, mm.
    pub fallback_point_error_mm: Option<Mean>,
    /// Estimates on the line that named another link than the pushed one, %.
    pub wrong_link_pct: f64,
    /// Trials in which the depth sensor saw the hand, %.
    pub depth_saw_pct: f64,
    pub analytic: Timing,
    pub optimiser: Option<Timing>,
    pub optimiser_point_error_mm: Option<Mean>,
    /// Largest |F_opt − F̂| (N) and |p_opt − p̂| (mm) where both found a point.
    pub max_disagreement: Option<[f64; 2]>,
}

pub fn row(sigma: f64, trials: &[Trial]) -> Row {
    let n = trials.len();
    let collect =
        |f: &dyn Fn(&Trial) -> Option<f64>| trials.iter().filter_map(f).collect::<Vec<_>>();
    let on_line = |t: &Trial| {
        t.point_error
            .filter(|p| p.1 == PointSource::Line)
            .map(|p| p.0)
    };
    let line = collect(&on_line);
    let no_solution = n - line.len();
    let (lo, hi) = wilson95(no_solution, n.max(1));
    let wrong = trials
        .iter()
        .filter(|t| on_line(t).is_some() && !t.right_link)
        .count();
    let optimised: Vec<_> = trials.iter().filter_map(|t| t.optimiser).collect();
    let disagreements: Vec<(f64, f64)> = optimised.iter().filter_map(|o| o.disagreement).collect();
    let pct = |k: usize| 100.0 * k as f64 / n.max(1) as f64;
    Row {
        sigma,
        trials: n,
        force_error_n: mean_of(&collect(&|t| t.force_error)),
        direction_error_deg: mean_of(&collect(&|t| t.direction_error)),
        point_error_mm: mean_of(&line),
        no_solution_pct: pct(no_solution),
        // Round-off below 1e-12 % is 0.
        no_solution_ci95_pct: [100.0 * lo, 100.0 * hi].map(|x| if x < 1e-12 { 0.0 } else { x }),
        fallback_point_error_mm: mean_of(&collect(&|t| {
            t.point_error
                .filter(|p| p.1 == PointSource::Depth)
                .map(|p| p.0)
        })),
        wrong_link_pct: 100.0 * wrong as f64 / line.len().max(1) as f64,
        depth_saw_pct: pct(trials.iter().filter(|t| t.depth_saw).count()),
        analytic: timing(&trials.iter().map(|t| t.analytic_ns).collect::<Vec<_>>())
            .expect("at least one trial"),
        optimiser: timing(&optimised.iter().map(|o| o.ns).collect::<Vec<_>>()),
        optimiser_point_error_mm: mean_of(
            &optimised
                .iter()
                .filter_map(|o| o.point_error_mm)
                .collect::<Vec<_>>(),
        ),
        max_disagreement: (!disagreements.is_empty()).then(|| {
            [
                disagreements.iter().map(|d| d.0).fold(0.0, f64::max),
                disagreements.iter().map(|d| d.1).fold(0.0, f64::max),
            ]
        }),
    }
}

fn num(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) {
        format!("{x:.1e}")
    } else {
        format!("{x:.3}")
    }
}

fn cell(m: &Option<Mean>) -> String {
    m.as_ref().map_or("–".into(), |m| {
        format!(
            "{} [{}, {}] ({})",
            num(m.mean),
            num(m.ci95[0]),
            num(m.ci95[1]),
            num(m.median)
        )
    })
}

/// The table as Markdown: ours (means with 95 % intervals, medians in brackets) beside the
/// reference's, then the timing.
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| σ (N·m) | force error (N) | ref. | direction error (°) | ref. | point error (mm) | ref. | no solution (%) | ref. | wrong link (%) | depth fall-back point error (mm) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let reference = REFERENCE.iter().find(|x| x.0 == r.sigma);
        let refcol = |f: fn(&(f64, f64, f64, f64, f64)) -> f64| {
            reference.map_or("–".into(), |x| num(f(x)))
        };
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} [{}, {}] | {} | {} | {} |\n",
            r.sigma,
            cell(&r.force_error_n),
            refcol(|x| x.1),
            cell(&r.direction_error_deg),
            refcol(|x| x.2),
            cell(&r.point_error_mm),
            refcol(|x| x.3),
            num(r.no_solution_pct),
            num(r.no_solution_ci95_pct[0]),
            num(r.no_solution_ci95_pct[1]),
            refcol(|x| x.4),
            num(r.wrong_link_pct),
            cell(&r.fallback_point_error_mm),
        );
    }
    s += "\n| σ (N·m) | analytical µs min / median / max (n) | optimiser µs min / median / max (n) | median ratio | optimiser − analytical, max (N, mm) |\n|---|---|---|---|---|\n";
    for r in rows {
        let t = |t: &Timing| {
            format!(
                "{:.3} / {:.3} / {:.1} ({})",
                t.min_us, t.median_us, t.max_us, t.n
            )
        };
        s += &format!(
            "| {} | {} | {} | {} | {} |\n",
            r.sigma,
            t(&r.analytic),
            r.optimiser.as_ref().map_or("–".into(), t),
            r.optimiser.as_ref().map_or("–".into(), |o| format!(
                "{:.0}×",
                o.median_us / r.analytic.median_us
            )),
            r.max_disagreement
                .map_or("–".into(), |d| format!("{}, {}", num(d[0]), num(d[1]))),
        );
    }
    s
}
