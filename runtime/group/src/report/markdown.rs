//! `report.md`: the generic report as tables for people (plugins append their sections).

use caravan_report::format::{num, quantiles};
use serde_json::Value;
use std::fmt::Write;

pub fn render(r: &Value) -> String {
    let mut md = String::new();
    let run = &r["run"];
    let _ = writeln!(
        md,
        "# Run report: {}\n",
        r["group"]["name"].as_str().unwrap_or("?")
    );
    let _ = writeln!(
        md,
        "Clock {}, seed {}, outcome **{}**{}.\n",
        r["group"]["clock"].as_str().unwrap_or("?"),
        r["group"]["seed"],
        run["outcome"].as_str().unwrap_or("?"),
        run["failure"]
            .as_str()
            .map(|f| format!(" ({f})"))
            .unwrap_or_default()
    );
    for w in run["warnings"].as_array().into_iter().flatten() {
        let _ = writeln!(md, "**Warning:** {}\n", w.as_str().unwrap_or(""));
    }
    if let Some(clock) = run["clock_host"].as_str() {
        let _ = writeln!(
            md,
            "Host '{clock}' kept simulated time and recorded the group (see its report); this host's processes ran for {} s of wall time.\n",
            num(&run["wall_time_s"], 2),
        );
    } else {
        let _ = writeln!(
            md,
            "Simulated {} s in {} s of wall time: real-time factor {}.\n",
            num(&run["sim_time_s"], 2),
            num(&run["wall_time_s"], 2),
            num(&run["real_time_factor"], 2)
        );
    }
    let schedule = &run["schedule"];
    if let (Some(advances), Some(steps), Some(overlapped)) = (
        schedule["advances"].as_u64(),
        schedule["steps"].as_u64(),
        schedule["overlapped_steps"].as_u64(),
    ) {
        let count = |key: &str| schedule[key].as_u64().unwrap_or(0);
        let (wake_ups, reports, grants, batched) = (
            count("wake_ups"),
            count("slot_reports"),
            count("slot_grants"),
            count("batched_steps"),
        );
        let _ = writeln!(
            md,
            "Lockstep: {advances} advances of simulated time, {steps} node steps, {overlapped} of \
             them started while the tick before was still running, {batched} taken within a \
             grant of several periods; {wake_ups} wake-ups sent with the grants; {reports} \
             reports and {grants} grants through the shared page.\n"
        );
    }
    md.push_str("## Nodes\n\n| node | host | steps | rate Hz | deadline misses | jitter p50/p99/max ms | compute mean/p99/max ms | missed msgs | CPU s | peak MiB | restarts | exit |\n|---|---|---:|---:|---:|---|---|---:|---:|---:|---:|---|\n");
    for n in r["nodes"].as_array().into_iter().flatten() {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} / {} / {} | {} / {} / {} | {} | {} | {} | {} | {} |",
            n["name"].as_str().unwrap_or(""),
            n["host"].as_str().unwrap_or(""),
            n["steps"],
            num(&n["rate_hz"], 1),
            n["deadline_misses"],
            num(&n["jitter_p50_ms"], 3),
            num(&n["jitter_p99_ms"], 3),
            num(&n["jitter_max_ms"], 3),
            num(&n["compute_mean_ms"], 3),
            num(&n["compute_p99_ms"], 3),
            num(&n["compute_max_ms"], 3),
            n["messages_missed"],
            num(&n["cpu_s"], 2),
            num(&n["max_rss_mib"], 1),
            n["restarts"],
            match n["container"].as_str() {
                // CPU and memory too are the container's.
                Some(c) => format!(
                    "{} (container {c})",
                    n["exit_status"].as_str().unwrap_or("")
                ),
                None => n["exit_status"].as_str().unwrap_or("").to_string(),
            }
        );
    }
    md.push_str("\n## Topics\n\n| topic | type | messages | gaps | latency p50/p90/p99/max µs |\n|---|---|---:|---:|---|\n");
    for t in r["topics"].as_array().into_iter().flatten() {
        let l = &t["latency_us"];
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            t["name"].as_str().unwrap_or(""),
            t["type"].as_str().unwrap_or(""),
            t["messages"],
            t["gaps"],
            quantiles(l, 1)
        );
    }
    if let Some(links) = r["links"].as_array() {
        md.push_str("\n## Links\n\nEmulated: the `[[links]]` a message crossed (drawn delays and losses). Network: the real network between two machines, as the receiving host's launcher measured it (publisher's send → published there; two machines' wall clocks).\n\n| link | from | to | delivered | dropped | loss % | latency p50 / p90 / p99 / max ms |\n|---|---|---|---|---|---|---|\n");
        for l in links {
            let q = &l["latency_ms"];
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                l["kind"].as_str().unwrap_or(""),
                l["from"].as_str().unwrap_or(""),
                l["to"].as_str().unwrap_or(""),
                l["delivered"],
                l["dropped"],
                num(&l["loss_pct"], 2),
                quantiles(q, 2)
            );
        }
    }
    md
}
