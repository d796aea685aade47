//! The convoy and SLAM sections as Markdown for `report.md`.

use caravan_report::format::{mean_p95_max, num};
use serde_json::Value;
use std::fmt::Write;

pub fn slam(s: &Value) -> String {
    let mut md = String::new();
    let e = &s["pose_error_m"];
    let _ = writeln!(
        md,
        "## SLAM\n\nLeader pose error: mean {} m, max {} m over {} estimates.\n",
        num(&e["mean"], 3),
        num(&e["max"], 3),
        e["samples"]
    );
    if let Some(surveys) = s["surveys"].as_array() {
        md.push_str("| survey | true m | on the map m | error % |\n|---|---|---|---|\n");
        for v in surveys {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                v["name"].as_str().unwrap_or(""),
                num(&v["true_m"], 3),
                num(&v["map_m"], 3),
                num(&v["error_pct"], 2)
            );
        }
    }
    if let Some(plot) = s["plot"].as_str() {
        let _ = writeln!(md, "\n![map with the true obstacles]({plot})");
    }
    md
}

pub fn convoy(c: &Value) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Convoy\n\nGoals reached {} of {} at {} s; minimum gap {} m; collisions {}; order kept: {}.\n\n![trajectories]({})\n",
        c["goals_reached"],
        c["goals_total"],
        c["goal_times_s"]
            .as_array()
            .map(|t| t.iter().map(|x| num(x, 1)).collect::<Vec<_>>().join(", "))
            .unwrap_or_default(),
        num(&c["min_gap_m"], 3),
        c["collisions"],
        c["order_kept"],
        c["plot"].as_str().unwrap_or("")
    );
    if let Some(series) = c["series_plot"].as_str() {
        let _ = writeln!(
            md,
            "![gaps and cross-track errors against time]({series})\n"
        );
    }
    md.push_str("| follower | cross-track to predecessor mean / p95 / max m | to leader mean / p95 / max m |\n|---|---|---|\n");
    for f in c["followers"].as_array().into_iter().flatten() {
        let _ = writeln!(
            md,
            "| R{} | {} | {} |",
            f["robot"],
            mean_p95_max(&f["cross_track_to_predecessor_m"], 3),
            mean_p95_max(&f["cross_track_to_leader_m"], 3)
        );
    }
    md
}
