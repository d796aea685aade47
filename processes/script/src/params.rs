//! The script's params and their checks: everything is resolved before the node joins the
//! group (types by name, each message's bytes, each trigger's field), so a bad command exits 2
//! naming its key and nothing starts.

use crate::field::FieldPath;
use crate::message;
use crate::timeline::When;
use serde::Deserialize;
use serde_json::Value;

/// `caravan-script`'s params: `[[process.params.command]]` entries, published in this order
/// within a step.
#[derive(Debug, Deserialize, caravan::schemars::JsonSchema)]
#[schemars(crate = "caravan::schemars")]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The commands; at least one.
    #[serde(default)]
    pub command: Vec<CommandParams>,
}

/// One command: when (exactly one of `at_s`, `from_s` (with `until_s`, `every_s`), `when`),
/// where (`topic`, `type`) and what (`message`).
#[derive(Debug, Deserialize, caravan::schemars::JsonSchema)]
#[schemars(crate = "caravan::schemars")]
#[serde(deny_unknown_fields)]
pub struct CommandParams {
    /// Publish once, at the first step at or after this simulated time; s, 0 … ten years.
    pub at_s: Option<f64>,
    /// Publish on every step from this simulated time on; s, 0 … ten years.
    pub from_s: Option<f64>,
    /// With `from_s`: stop before this time; s, > `from_s`. Default: the end of the run.
    pub until_s: Option<f64>,
    /// With `from_s`: publish only at the first step at or after each `from_s + k · every_s`
    /// instead of every step; s, 1 µs … ten years.
    pub every_s: Option<f64>,
    /// Publish once, at the first step at which a field of another topic crossed a threshold.
    pub when: Option<WhenParams>,
    /// The topic to publish on: segments of letters, digits, `_`, `-`, `.` between single `/`.
    pub topic: String,
    /// The message type's stable name (`caravan::JointCommand`), as `caravan topic pub` takes
    /// it. Default: the type of a well-known topic (`robot/<i>/joint_command`, `cmd_vel`…);
    /// required for any other topic.
    #[serde(rename = "type")]
    pub type_name: Option<String>,
    /// The message's fields, in the recording's JSON shape; a field left out keeps the type's
    /// default. A float field also takes `"nan"`, `"inf"`, `"-inf"`. Default: `{}`.
    #[serde(default = "empty")]
    pub message: Value,
}

/// A trigger: a number of the newest messages of `topic` above or below a threshold.
#[derive(Debug, Deserialize, caravan::schemars::JsonSchema)]
#[schemars(crate = "caravan::schemars")]
#[serde(deny_unknown_fields)]
pub struct WhenParams {
    /// The topic to watch (same rules as a command's `topic`).
    pub topic: String,
    /// Its message type; default: the type of a well-known topic.
    #[serde(rename = "type")]
    pub type_name: Option<String>,
    /// The number to watch, as a path in the message's JSON view: `pose.position.x`,
    /// `joints[0].position`, `joints[shoulder].position` (the item of that name).
    pub field: String,
    /// Fire when the field is greater than this (finite). Exactly one of `above`, `below`.
    pub above: Option<f64>,
    /// Fire when the field is less than this (finite).
    pub below: Option<f64>,
    /// Watch only from this simulated time on; s, 0 … ten years. Default 0.
    pub after_s: Option<f64>,
}

fn empty() -> Value {
    Value::Object(Default::default())
}

/// A field compared with a threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Threshold {
    Above(f64),
    Below(f64),
}

impl Threshold {
    /// Whether `value` crossed it; never for NaN.
    pub fn holds(self, value: f64) -> bool {
        match self {
            Threshold::Above(x) => value > x,
            Threshold::Below(x) => value < x,
        }
    }
}

/// A checked trigger.
#[derive(Debug, Clone)]
pub struct Trigger {
    pub topic: String,
    pub type_name: &'static str,
    pub field: FieldPath,
    pub threshold: Threshold,
}

/// A checked command: its message's bytes, ready to publish.
#[derive(Debug, Clone)]
pub struct Command {
    pub topic: String,
    pub type_name: &'static str,
    pub bytes: Box<[u8]>,
    pub when: When,
}

/// Everything the node needs, checked.
#[derive(Debug, Clone)]
pub struct Plan {
    pub commands: Vec<Command>,
    /// Indexed by `When::Trigger::trigger`.
    pub triggers: Vec<Trigger>,
}

/// Seconds to simulated nanoseconds: finite, not negative, at most ten years.
fn nanos(key: &str, s: f64) -> Result<u64, String> {
    caravan::seconds(s)
        .map(|d| d.as_nanos() as u64)
        .map_err(|e| format!("key '{key}': {e}"))
}

/// Checks a topic name as the launcher checks `on`, and as iceoryx2 takes service names.
pub fn check_topic(key: &str, topic: &str) -> Result<(), String> {
    caravan::pattern::check_topic_name(topic).map_err(|e| format!("key '{key}': {e}"))?;
    if topic == "caravan" || topic.starts_with("caravan/") {
        return Err(format!(
            "key '{key}': '{topic}' is one of the group's own topics (caravan/…)"
        ));
    }
    iceoryx2::prelude::ServiceName::new(topic)
        .map(|_| ())
        .map_err(|e| format!("key '{key}': '{topic}' is not a usable topic name: {e:?}"))
}

/// The type of `topic`: `given`, which must match a well-known topic's type, or that type.
fn topic_type(
    key: &str,
    topic: &str,
    given: Option<&str>,
) -> Result<&'static caravan_schemas::descriptor::Descriptor, String> {
    let known = caravan_schemas::topics::type_of(topic);
    let name = match (given, known) {
        (Some(g), Some(k)) if g != k => {
            return Err(format!("key '{key}.type': '{topic}' carries {k}, not {g}"));
        }
        (Some(g), _) => g,
        (None, Some(k)) => k,
        (None, None) => {
            return Err(format!(
                "key '{key}.type': '{topic}' is not a well-known topic, so name its message \
                 type (e.g. type = \"caravan::Twist\")"
            ));
        }
    };
    message::descriptor(name).map_err(|e| format!("key '{key}.type': {e}"))
}

impl Params {
    /// Checks every command and builds what the node publishes and watches.
    pub fn plan(&self) -> Result<Plan, String> {
        if self.command.is_empty() {
            return Err(
                "key 'command': no commands; give at least one [[process.params.command]]".into(),
            );
        }
        let mut plan = Plan {
            commands: Vec::new(),
            triggers: Vec::new(),
        };
        for (i, c) in self.command.iter().enumerate() {
            let key = format!("command[{i}]");
            let command = c.check(&key, &mut plan.triggers)?;
            // One topic, one type: the node opens one publisher per topic.
            if let Some(other) = plan
                .commands
                .iter()
                .find(|o| o.topic == command.topic && o.type_name != command.type_name)
            {
                return Err(format!(
                    "key '{key}.type': '{}' is published as {} by an earlier command, not {}",
                    command.topic, other.type_name, command.type_name
                ));
            }
            plan.commands.push(command);
        }
        Ok(plan)
    }
}

impl CommandParams {
    fn check(&self, key: &str, triggers: &mut Vec<Trigger>) -> Result<Command, String> {
        check_topic(&format!("{key}.topic"), &self.topic)?;
        let descriptor = topic_type(key, &self.topic, self.type_name.as_deref())?;
        let bytes = message::build(descriptor, &self.message).map_err(|e| {
            let at = if e.path.is_empty() {
                format!("{key}.message")
            } else {
                format!("{key}.message.{}", e.path)
            };
            format!(
                "key '{at}': {} on '{}': {}",
                descriptor.type_name(),
                self.topic,
                e.message
            )
        })?;
        let when = self.when_to_publish(key, triggers)?;
        Ok(Command {
            topic: self.topic.clone(),
            type_name: descriptor.type_name(),
            bytes,
            when,
        })
    }

    fn when_to_publish(&self, key: &str, triggers: &mut Vec<Trigger>) -> Result<When, String> {
        let k = |name: &str| format!("{key}.{name}");
        let given = [
            self.at_s.is_some(),
            self.from_s.is_some(),
            self.when.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(format!(
                "key '{key}': say when to publish with exactly one of at_s (once), from_s (held, \
                 with until_s and every_s) or when (a trigger)"
            ));
        }
        let held_only = [("until_s", self.until_s), ("every_s", self.every_s)];
        if self.from_s.is_none()
            && let Some((name, _)) = held_only.iter().find(|(_, v)| v.is_some())
        {
            return Err(format!(
                "key '{}': only a held command (from_s) takes {name}",
                k(name)
            ));
        }
        if let Some(at) = self.at_s {
            return Ok(When::At(nanos(&k("at_s"), at)?));
        }
        if let Some(from_s) = self.from_s {
            let from = nanos(&k("from_s"), from_s)?;
            let until = match self.until_s {
                Some(until_s) => {
                    let until = nanos(&k("until_s"), until_s)?;
                    if until <= from {
                        return Err(format!(
                            "key '{}': must be after from_s ({from_s} s), got {until_s} s",
                            k("until_s")
                        ));
                    }
                    until
                }
                None => u64::MAX,
            };
            let every = match self.every_s {
                Some(every_s) => {
                    let every = nanos(&k("every_s"), every_s)?;
                    if every < caravan::MIN_PERIOD.as_nanos() as u64 {
                        return Err(format!(
                            "key '{}': must be at least 1 µs, got {every_s} s",
                            k("every_s")
                        ));
                    }
                    Some(every)
                }
                None => None,
            };
            return Ok(When::Held { from, until, every });
        }
        let w = self.when.as_ref().expect("one of the three is given");
        let wk = k("when");
        check_topic(&format!("{wk}.topic"), &w.topic)?;
        let descriptor = topic_type(&wk, &w.topic, w.type_name.as_deref())?;
        let field = FieldPath::resolve(descriptor, &w.field).map_err(|e| {
            format!(
                "key '{wk}.field': {} on '{}': {e}",
                descriptor.type_name(),
                w.topic
            )
        })?;
        let threshold = match (w.above, w.below) {
            (Some(x), None) => Threshold::Above(x),
            (None, Some(x)) => Threshold::Below(x),
            _ => {
                return Err(format!("key '{wk}': give exactly one of above and below"));
            }
        };
        if let Threshold::Above(x) | Threshold::Below(x) = threshold
            && !x.is_finite()
        {
            return Err(format!("key '{wk}': the threshold must be finite, got {x}"));
        }
        let after = nanos(&format!("{wk}.after_s"), w.after_s.unwrap_or(0.0))?;
        triggers.push(Trigger {
            topic: w.topic.clone(),
            type_name: descriptor.type_name(),
            field,
            threshold,
        });
        Ok(When::Trigger {
            trigger: triggers.len() - 1,
            after,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn plan(commands: Value) -> Result<Plan, String> {
        let p: Params = serde_json::from_value(json!({ "command": commands })).unwrap();
        p.plan()
    }

    #[test]
    fn good_commands_are_planned() {
        let p = plan(json!([
            {"at_s": 2.0, "topic": "robot/0/joint_command",
             "message": {"joints": [{"name": "shoulder", "position": 0.5}]}},
            {"from_s": 3.0, "until_s": 4.0, "every_s": 0.5, "topic": "robot/0/wrench",
             "type": "caravan::Wrench", "message": {"link": "cube", "force": {"x": 1.0}}},
            {"when": {"topic": "robot/0/ground_truth", "field": "pose.position.x",
                      "above": 3.0, "after_s": 1.0},
             "topic": "my/twist", "type": "caravan::Twist"},
        ]))
        .unwrap();
        assert_eq!(
            plan_whens(&p),
            [
                When::At(2_000_000_000),
                When::Held {
                    from: 3_000_000_000,
                    until: 4_000_000_000,
                    every: Some(500_000_000)
                },
                When::Trigger {
                    trigger: 0,
                    after: 1_000_000_000
                },
            ]
        );
        assert_eq!(p.commands[0].type_name, "caravan::JointCommand");
        assert_eq!(p.triggers[0].type_name, "caravan::Odometry");
        assert_eq!(p.triggers[0].threshold, Threshold::Above(3.0));
    }

    fn plan_whens(p: &Plan) -> Vec<When> {
        p.commands.iter().map(|c| c.when).collect()
    }

    #[test]
    fn bad_commands_name_their_key() {
        let bad = |c: Value| plan(json!([c])).unwrap_err();
        let twist = |extra: Value| {
            let mut c = json!({"topic": "robot/0/cmd_vel"});
            c.as_object_mut()
                .unwrap()
                .extend(extra.as_object().unwrap().clone());
            c
        };
        let cases = [
            (twist(json!({})), "key 'command[0]': say when"),
            (twist(json!({"at_s": 1.0, "from_s": 1.0})), "exactly one of"),
            (twist(json!({"at_s": -1.0})), "key 'command[0].at_s'"),
            (
                twist(json!({"from_s": 2.0, "until_s": 2.0})),
                "key 'command[0].until_s': must be after",
            ),
            (
                twist(json!({"at_s": 1.0, "until_s": 2.0})),
                "key 'command[0].until_s': only a held",
            ),
            (
                twist(json!({"from_s": 0.0, "every_s": 0.0})),
                "key 'command[0].every_s'",
            ),
            (
                twist(json!({"at_s": 1.0, "type": "caravan::Pose2D"})),
                "carries caravan::Twist",
            ),
            (
                twist(json!({"at_s": 1.0, "message": {"linear": {"w": 1}}})),
                "key 'command[0].message.linear.w'",
            ),
            (
                json!({"at_s": 1.0, "topic": "my/topic"}),
                "name its message type",
            ),
            (
                json!({"at_s": 1.0, "topic": "my/topic", "type": "caravan::Nope"}),
                "unknown message type 'caravan::Nope'",
            ),
            (
                json!({"at_s": 1.0, "topic": "robot//cmd_vel"}),
                "is not a topic name",
            ),
            (
                json!({"at_s": 1.0, "topic": "caravan/lockstep"}),
                "the group's own topics",
            ),
            (
                twist(
                    json!({"when": {"topic": "robot/0/ground_truth", "field": "pose.x",
                                   "above": 1.0}}),
                ),
                "key 'command[0].when.field'",
            ),
            (
                twist(
                    json!({"when": {"topic": "robot/0/ground_truth", "field": "pose.position.x"}}),
                ),
                "exactly one of above and below",
            ),
        ];
        for (c, expected) in cases {
            let e = bad(c.clone());
            assert!(e.contains(expected), "{c}: {e}");
        }
        let e = plan(json!([
            {"at_s": 1.0, "topic": "a", "type": "caravan::Twist"},
            {"at_s": 1.0, "topic": "a", "type": "caravan::Pose2D"},
        ]))
        .unwrap_err();
        assert!(e.contains("key 'command[1].type'"), "{e}");
        assert!(plan(json!([])).unwrap_err().contains("no commands"));
    }

    #[test]
    fn thresholds_never_hold_for_nan() {
        assert!(Threshold::Above(1.0).holds(1.5) && !Threshold::Above(1.0).holds(1.0));
        assert!(Threshold::Below(1.0).holds(0.5) && !Threshold::Below(1.0).holds(f64::NAN));
        assert!(!Threshold::Above(1.0).holds(f64::NAN));
    }
}
