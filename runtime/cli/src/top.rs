//! `caravan top`: a live table of a group's nodes, from the status every node publishes once
//! a second (steps, rate, deadline misses, jitter, compute time, memory) and the processes'
//! CPU time from `/proc`, as `top` shows processes.

use anyhow::Result;
use caravan_group::clean::{choose_group, live_nodes};
use caravan_group::watch::{GroupArg, follow};
use caravan_report::as_u64;
use clap::Args;
use serde_json::{Value, json};
use std::collections::{BTreeMap, HashMap};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How long `--once` listens: every node's status arrives within a second, and two of them
/// give its rate.
const ONCE_WINDOW: Duration = Duration::from_millis(2500);

#[derive(Args)]
pub struct TopArgs {
    #[command(flatten)]
    pub group: GroupArg,
    /// Print one table after 2.5 s and exit, instead of refreshing every second
    #[arg(long)]
    pub once: bool,
    /// With --once: print a JSON array instead of a table
    #[arg(long, requires = "once")]
    pub json: bool,
}

/// What is known of one node: its last status, and the rate measured between two statuses.
struct Row {
    status: Value,
    last: (u64, u64),
    steps_per_s: Option<f64>,
}

/// CPU use of processes, from the change in their `/proc/PID/stat` times between two looks.
#[derive(Default)]
struct CpuMeter {
    seen: HashMap<i32, (u64, Instant)>,
}

impl CpuMeter {
    /// Percent of one core used by `pid` since the last look (None on the first look).
    fn percent(&mut self, pid: i32) -> Option<f64> {
        let ticks = cpu_ticks(pid)?;
        let now = Instant::now();
        let before = self.seen.insert(pid, (ticks, now))?;
        // SAFETY: sysconf has no preconditions.
        let per_s = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
        let secs = now.duration_since(before.1).as_secs_f64();
        (secs > 0.0).then(|| (ticks.saturating_sub(before.0)) as f64 / per_s / secs * 100.0)
    }
}

/// User plus system time of a process, in clock ticks (fields 14 and 15 of its stat line,
/// counted after the command name, which may itself hold spaces).
fn cpu_ticks(pid: i32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let mut fields = stat.rsplit_once(')')?.1.split_whitespace().skip(11);
    Some(fields.next()?.parse::<u64>().ok()? + fields.next()?.parse::<u64>().ok()?)
}

pub fn top(args: &TopArgs) -> Result<()> {
    let group = choose_group(args.group.group.as_deref())?;
    let mut rows: BTreeMap<String, Row> = BTreeMap::new();
    let mut cpu = CpuMeter::default();
    let pids = |cpu: &mut CpuMeter| -> Result<HashMap<String, (i32, Option<f64>)>> {
        Ok(live_nodes(&group)?
            .into_iter()
            .filter(|n| !n.name.is_empty())
            .map(|n| (n.name, (n.pid, cpu.percent(n.pid))))
            .collect())
    };
    pids(&mut cpu)?;
    if args.once {
        follow(&group, "status", Some(ONCE_WINDOW), |h, s| {
            update(&mut rows, h, s);
            false
        })?;
        let table = table_json(&rows, &pids(&mut cpu)?);
        if args.json {
            println!("{}", Value::from(table));
        } else {
            print!("{}", render(&group, &table));
        }
        return Ok(());
    }
    let terminal = std::io::stdout().is_terminal();
    let mut shown = Instant::now();
    let mut failure = None;
    follow(&group, "status", None, |h, s| {
        update(&mut rows, h, s);
        if shown.elapsed() >= Duration::from_secs(1) {
            shown = Instant::now();
            match pids(&mut cpu) {
                Ok(p) => {
                    // A terminal gets the table in place; a pipe gets one table after another.
                    let clear = if terminal { "\x1b[H\x1b[2J" } else { "\n" };
                    print!("{clear}{}", render(&group, &table_json(&rows, &p)));
                }
                Err(e) => failure = Some(e),
            }
        }
        failure.is_some()
    })?;
    failure.map_or(Ok(()), Err)
}

fn update(rows: &mut BTreeMap<String, Row>, header: &caravan::Header, status: Value) {
    let Some(node) = status["node"].as_str().map(str::to_string) else {
        return;
    };
    let steps = as_u64(&status["steps"]).unwrap_or(0);
    let now = (steps, header.send_wall_ns);
    match rows.get_mut(&node) {
        Some(row) => {
            let dt = now.1.saturating_sub(row.last.1) as f64 / 1e9;
            if dt > 0.0 {
                row.steps_per_s = Some(now.0.saturating_sub(row.last.0) as f64 / dt);
            }
            row.last = now;
            row.status = status;
        }
        None => {
            rows.insert(
                node,
                Row {
                    status,
                    last: now,
                    steps_per_s: None,
                },
            );
        }
    }
}

/// One object per node: its status fields, the measured rate and its process's CPU use.
fn table_json(
    rows: &BTreeMap<String, Row>,
    pids: &HashMap<String, (i32, Option<f64>)>,
) -> Vec<Value> {
    rows.iter()
        .map(|(name, row)| {
            let mut out = row.status.clone();
            let (pid, cpu) = pids.get(name).copied().unwrap_or((0, None));
            out["pid"] = if pid > 0 { json!(pid) } else { Value::Null };
            out["steps_per_s"] = json!(row.steps_per_s);
            out["cpu_percent"] = json!(cpu);
            out
        })
        .collect()
}

fn render(group: &str, table: &[Value]) -> String {
    let ms = |v: &Value| as_u64(v).map_or("-".into(), |ns| format!("{:.2}", ns as f64 / 1e6));
    let opt = |v: &Value, digits: usize| v.as_f64().map_or("-".into(), |x| format!("{x:.digits$}"));
    let mut out = format!(
        "group {group}: {} nodes\n{:<24} {:<8} {:>7} {:>9} {:>8} {:>7} {:>8} {:>8} {:>8} {:>6} {:>8} {:>9} {:>6}\n",
        table.len(),
        "NODE",
        "HOST",
        "PID",
        "STEPS",
        "STEP/S",
        "MISSES",
        "JIT99ms",
        "COMPms",
        "COMP99ms",
        "CPU%",
        "RSS MiB",
        "SIM s",
        "LOST"
    );
    for r in table {
        let name = r["node"].as_str().unwrap_or("?");
        let ended = as_u64(&r["running"]) == Some(0);
        out += &format!(
            "{:<24} {:<8} {:>7} {:>9} {:>8} {:>7} {:>8} {:>8} {:>8} {:>6} {:>8} {:>9} {:>6}{}\n",
            name,
            r["host"].as_str().unwrap_or(""),
            r["pid"].as_i64().map_or("-".into(), |p| p.to_string()),
            as_u64(&r["steps"]).unwrap_or(0),
            opt(&r["steps_per_s"], 1),
            as_u64(&r["deadline_misses"]).unwrap_or(0),
            ms(&r["jitter_p99_ns"]),
            ms(&r["compute_mean_ns"]),
            ms(&r["compute_p99_ns"]),
            opt(&r["cpu_percent"], 1),
            as_u64(&r["rss_kib"]).map_or("-".into(), |k| format!("{:.1}", k as f64 / 1024.0)),
            as_u64(&r["sim_time_ns"]).map_or("-".into(), |ns| format!("{:.1}", ns as f64 / 1e9)),
            as_u64(&r["messages_missed"]).unwrap_or(0),
            if ended { "  ended" } else { "" },
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_ticks_are_read_for_live_processes_only() {
        let me = std::process::id() as i32;
        let before = cpu_ticks(me).expect("own stat");
        assert!(cpu_ticks(me).unwrap() >= before);
        assert_eq!(cpu_ticks(-1), None);
    }

    #[test]
    fn rate_is_measured_between_two_statuses() {
        let mut rows = BTreeMap::new();
        let header = |wall_s: u64| caravan::Header {
            send_wall_ns: wall_s * 1_000_000_000,
            ..Default::default()
        };
        update(&mut rows, &header(1), json!({"node": "a", "steps": 100}));
        assert_eq!(rows["a"].steps_per_s, None);
        update(&mut rows, &header(3), json!({"node": "a", "steps": 300}));
        assert_eq!(rows["a"].steps_per_s, Some(100.0));
        let table = table_json(&rows, &HashMap::from([("a".into(), (42, Some(12.5)))]));
        assert_eq!(table[0]["pid"], 42);
        assert_eq!(table[0]["cpu_percent"], 12.5);
        let text = render("g", &table);
        assert!(text.contains("group g: 1 nodes"), "{text}");
        assert!(text.lines().nth(2).unwrap().starts_with("a "), "{text}");
    }
}
