//! A tiny scenario's report plugin, for the report-plugin tests: counts the recorded messages
//! of one topic and the sum of a numeric field. `fail = true` makes it fail after reading
//! the run (exit 1), to test how the launcher reports a failing plugin.

use caravan_report::{Inputs, ReportPlugin, Run, Section};
use serde::Deserialize;

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    /// The topic whose messages are counted.
    topic: String,
    /// A numeric field of its messages to add up.
    #[serde(default)]
    field: Option<String>,
    #[serde(default)]
    fail: bool,
}

struct Count(Params);

impl ReportPlugin for Count {
    type Params = Params;

    fn new(p: Params, _: &Inputs) -> Result<Self, String> {
        if p.topic.is_empty() {
            return Err("key 'topic': name the topic to count".into());
        }
        Ok(Count(p))
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let messages: Vec<_> = run
            .messages()?
            .iter()
            .filter(|m| m.topic == self.0.topic)
            .collect();
        if self.0.fail {
            anyhow::bail!("asked to fail after reading {} messages", messages.len());
        }
        let sum: f64 = match &self.0.field {
            Some(f) => messages.iter().map(|m| m.f64(f)).sum(),
            None => 0.0,
        };
        let n = messages.len();
        Ok(vec![Section {
            name: "count".into(),
            json: serde_json::json!({"topic": self.0.topic, "messages": n, "sum": sum}),
            markdown: format!("## Count\n\n{n} messages on `{}`.\n", self.0.topic),
        }])
    }
}

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<Count>("caravan-count-report")
}
