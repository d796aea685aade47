//! The `uav` report section: the episodes the environment summed up (`agent/episode`),
//! counted by outcome with Wilson 95 % intervals, and their measures (closest approach,
//! deviation, path length, time to pass, action smoothness, reaction latency) as means with
//! Student-t 95 % intervals.
//!
//! JSON: `{episodes, outcomes: {name: {count, rate, ci95}}, success_rate, success_ci95,
//! metrics: {name: {n, mean, ci95}}, mean_return}`.

use caravan_report::stats::describe;
use caravan_report::wilson::wilson95;
use caravan_report::{Inputs, ReportPlugin, Run, Section};
use serde::Deserialize;
use serde_json::{Value, json};
use std::collections::BTreeMap;

/// The outcomes, in the order the table shows them.
pub const OUTCOMES: [&str; 4] = ["passed", "collided", "floor", "timeout"];

#[derive(Debug, Clone, Default, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// A label for the policy in the table.
    #[serde(default)]
    pub policy: String,
    /// A label for the scenario in the table.
    #[serde(default)]
    pub scenario: String,
}

pub struct UavReport {
    p: Params,
}

impl ReportPlugin for UavReport {
    type Params = Params;

    fn new(p: Params, _: &Inputs) -> Result<Self, String> {
        Ok(Self { p })
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let episodes: Vec<&Value> = run
            .messages()?
            .iter()
            .filter(|m| m.topic == "agent/episode")
            .map(|m| &m.json)
            .collect();
        if episodes.is_empty() {
            anyhow::bail!("no finished episode on agent/episode in the recording");
        }
        let n = episodes.len();
        let mut outcomes = serde_json::Map::new();
        for name in OUTCOMES {
            let count = episodes.iter().filter(|e| e["outcome"] == name).count();
            let (lo, hi) = wilson95(count, n);
            outcomes.insert(
                name.into(),
                json!({ "count": count, "rate": count as f64 / n as f64, "ci95": [lo, hi] }),
            );
        }
        let mut samples: BTreeMap<String, Vec<f64>> = BTreeMap::new();
        for e in &episodes {
            for m in e["metrics"].as_array().into_iter().flatten() {
                if let (Some(name), Some(v)) = (m["name"].as_str(), m["value"].as_f64())
                    && v.is_finite()
                {
                    samples.entry(name.to_string()).or_default().push(v);
                }
            }
        }
        let metrics: serde_json::Map<String, Value> = samples
            .iter()
            .map(|(name, xs)| {
                let d = describe(xs);
                let ci = d.ci95.unwrap_or((d.mean, d.mean));
                (name.clone(), json!({ "n": d.n, "mean": d.mean, "ci95": [ci.0, ci.1], "min": d.min, "max": d.max }))
            })
            .collect();
        let returns: Vec<f64> = episodes
            .iter()
            .filter_map(|e| e["total_reward"].as_f64())
            .collect();
        let mean_return = returns.iter().sum::<f64>() / returns.len().max(1) as f64;
        let passed = outcomes["passed"].clone();
        let markdown = markdown(&self.p, n, &outcomes, &metrics, mean_return);
        Ok(vec![Section {
            name: "uav".into(),
            json: json!({
                "policy": self.p.policy,
                "scenario": self.p.scenario,
                "episodes": n,
                "outcomes": outcomes,
                "success_rate": passed["rate"],
                "success_ci95": passed["ci95"],
                "metrics": metrics,
                "mean_return": mean_return,
            }),
            markdown,
        }])
    }
}

fn markdown(
    p: &Params,
    n: usize,
    outcomes: &serde_json::Map<String, Value>,
    metrics: &serde_json::Map<String, Value>,
    mean_return: f64,
) -> String {
    let mut s = format!(
        "## UAV encounter\n\nPolicy `{}`, scenario `{}`, {n} episodes; mean return {mean_return:.1}.\n\n\
         | outcome | episodes | rate (Wilson 95 %) |\n|---|---:|---|\n",
        p.policy, p.scenario
    );
    for name in OUTCOMES {
        let o = &outcomes[name];
        let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN) * 100.0;
        s += &format!(
            "| {name} | {} | {:.1} % ({:.1}–{:.1} %) |\n",
            o["count"],
            f(&o["rate"]),
            f(&o["ci95"][0]),
            f(&o["ci95"][1])
        );
    }
    s += "\n| measure | episodes | mean (95 % CI) |\n|---|---:|---|\n";
    for (name, m) in metrics {
        let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
        s += &format!(
            "| {name} | {} | {:.3} ({:.3}–{:.3}) |\n",
            m["n"],
            f(&m["mean"]),
            f(&m["ci95"][0]),
            f(&m["ci95"][1])
        );
    }
    s
}
