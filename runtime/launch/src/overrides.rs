//! `--set KEY=VALUE` overrides, applied to the document text before validation so that an
//! overridden value is checked exactly like one written in the file.

use super::suggest;
use toml_edit::{DocumentMut, InlineTable, Item, Key, TableLike, Value};

/// The table that declares a launch file's arguments.
pub const ARGS_TABLE: &str = "args";

/// One step of a path into the document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Seg {
    Key(String),
    Index(usize),
}

impl Seg {
    pub fn is_key(&self, key: &str) -> bool {
        matches!(self, Seg::Key(k) if k == key)
    }
}

/// An override that was applied, with the document path it set (a process chosen by name is
/// replaced by its index), so errors in the value can be blamed on the override.
#[derive(Debug, Clone)]
pub struct Applied {
    pub text: String,
    pub path: Vec<Seg>,
}

/// An override that could not be applied.
#[derive(Debug, Clone)]
pub struct Rejected {
    pub text: String,
    pub message: String,
}

/// Applies each override in order (a later one wins); returns those applied and those not.
pub fn apply(doc: &mut DocumentMut, sets: &[String]) -> (Vec<Applied>, Vec<Rejected>) {
    apply_with(doc, sets, &|v| Ok(v))
}

/// [`apply`], passing each value through `map` first (to substitute arguments in it).
pub fn apply_with(
    doc: &mut DocumentMut,
    sets: &[String],
    map: &dyn Fn(Value) -> Result<Value, String>,
) -> (Vec<Applied>, Vec<Rejected>) {
    let mut applied = Vec::new();
    let mut rejected = Vec::new();
    for text in sets {
        match apply_one(doc, text, map) {
            Ok(path) => applied.push(Applied {
                text: text.clone(),
                path,
            }),
            Err(message) => rejected.push(Rejected {
                text: text.clone(),
                message,
            }),
        }
    }
    (applied, rejected)
}

/// A value as TOML when it parses (`3`, `true`, `["a"]`), else as a plain string (`250Hz`).
pub fn parse_value(raw: &str) -> Value {
    raw.trim()
        .parse::<Value>()
        .unwrap_or_else(|_| Value::from(raw.trim()))
}

/// Whether an override sets an argument (`args.NAME=…`): those apply before substitution.
pub fn targets_args(text: &str) -> bool {
    let key = text.split_once('=').map_or(text, |(k, _)| k);
    Key::parse(key.trim()).is_ok_and(|keys| keys.first().is_some_and(|k| k.get() == ARGS_TABLE))
}

fn apply_one(
    doc: &mut DocumentMut,
    text: &str,
    map: &dyn Fn(Value) -> Result<Value, String>,
) -> Result<Vec<Seg>, String> {
    let (key, raw) = text
        .split_once('=')
        .ok_or("expected KEY=VALUE, e.g. --set group.seed=3")?;
    let keys: Vec<String> = Key::parse(key.trim())
        .map_err(|_| format!("'{key}' is not a key path like group.seed"))?
        .iter()
        .map(|k| k.get().to_string())
        .collect();
    let Some((last, parents)) = keys.split_last() else {
        return Err("empty key".into());
    };
    let mut value = map(parse_value(raw))?;
    let mut path = Vec::new();
    let mut table: &mut dyn TableLike = doc.as_table_mut();
    let mut i = 0;
    while i < parents.len() {
        let seg = &parents[i];
        if !table.contains_key(seg) {
            if !may_create(&path, seg) {
                return Err(missing(&keys[..i], seg, table));
            }
            // Inline, so the new table stays inside its [[process]] when written back.
            table.insert(seg, Item::Value(Value::InlineTable(InlineTable::new())));
        }
        path.push(Seg::Key(seg.clone()));
        let item = table.get_mut(seg).expect("present or just inserted");
        if is_array(item) {
            // The next key picks an element: a process by name, anything else by index.
            let Some(pick) = parents.get(i + 1) else {
                return Err(list_needs_entry(&keys[..=i], last));
            };
            let index = pick_index(item, &path, pick)?;
            path.push(Seg::Index(index));
            table = element_mut(item, index).ok_or_else(|| {
                format!("entry {pick} of '{}' is not a table", keys[..=i].join("."))
            })?;
            i += 2;
        } else {
            let kind = item.type_name();
            table = item
                .as_table_like_mut()
                .ok_or_else(|| format!("'{}' is a {kind}, not a table", keys[..=i].join(".")))?;
            i += 1;
        }
    }
    // An argument must be declared in the file, so a misspelt one is not silently ignored.
    if path.len() == 1 && path[0].is_key(ARGS_TABLE) && !table.contains_key(last) {
        return Err(missing(parents, last, table));
    }
    match table.get_mut(last) {
        // Keep the old value's spacing and trailing comment.
        Some(Item::Value(old)) => {
            *value.decor_mut() = old.decor().clone();
            *old = value;
        }
        _ => {
            table.insert(last, Item::Value(value));
        }
    }
    path.push(Seg::Key(last.clone()));
    Ok(path)
}

/// Params are free-form, so an override may add keys and tables anywhere inside them; other
/// tables must already exist, which catches misspelt paths.
fn may_create(path: &[Seg], seg: &str) -> bool {
    path.len() >= 2
        && (path[0].is_key("process") || path[0].is_key("report"))
        && ((path.len() == 2 && seg == "params") || path[2].is_key("params"))
}

fn missing(parents: &[String], seg: &str, table: &dyn TableLike) -> String {
    let keys: Vec<&str> = table.iter().map(|(k, _)| k).collect();
    let near = suggest::did_you_mean(seg, keys.iter().copied());
    if parents.is_empty() {
        format!("the file has no table '{seg}'{near}")
    } else {
        format!("'{}' has no key '{seg}'{near}", parents.join("."))
    }
}

fn list_needs_entry(list: &[String], last: &str) -> String {
    if list == ["process"] {
        format!("name a key of process '{last}', e.g. process.{last}.rate=100Hz")
    } else {
        let list = list.join(".");
        format!("'{list}' is a list; name an entry and a key, e.g. {list}.0.{last}")
    }
}

fn is_array(item: &Item) -> bool {
    item.is_array_of_tables() || item.is_array()
}

fn entries(item: &Item) -> Vec<Option<&dyn TableLike>> {
    match item {
        Item::ArrayOfTables(a) => a.iter().map(|t| Some(t as &dyn TableLike)).collect(),
        Item::Value(Value::Array(a)) => a
            .iter()
            .map(|v| v.as_inline_table().map(|t| t as &dyn TableLike))
            .collect(),
        _ => Vec::new(),
    }
}

fn pick_index(item: &Item, path: &[Seg], pick: &str) -> Result<usize, String> {
    let entries = entries(item);
    if path.len() == 1 && path[0].is_key("process") {
        let names: Vec<&str> = entries
            .iter()
            .filter_map(|t| t.and_then(|t| t.get("name")).and_then(|n| n.as_str()))
            .collect();
        let found = entries
            .iter()
            .position(|t| t.and_then(|t| t.get("name")).and_then(|n| n.as_str()) == Some(pick));
        return found.ok_or_else(|| {
            format!(
                "no process '{pick}'{}",
                suggest::did_you_mean(pick, names.iter().copied())
            )
        });
    }
    let index: usize = pick
        .parse()
        .map_err(|_| format!("'{pick}' is not an entry number (0, 1, …)"))?;
    if index >= entries.len() {
        return Err(format!(
            "there are only {} entries, numbered from 0",
            entries.len()
        ));
    }
    Ok(index)
}

fn element_mut(item: &mut Item, index: usize) -> Option<&mut dyn TableLike> {
    match item {
        Item::ArrayOfTables(a) => a.get_mut(index).map(|t| t as &mut dyn TableLike),
        Item::Value(Value::Array(a)) => a
            .get_mut(index)?
            .as_inline_table_mut()
            .map(|t| t as &mut dyn TableLike),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = r#"[group]
name = "convoy"
seed = 7 # the seed

[hosts.rpi-0]

[[links]]
between = ["rpi-*", "rpi-*"]

[[process]]
name = "physics"
exec = "caravan-physics"
params = { count = 5 }

[[process]]
name = "planner"
exec = "planner"
"#;

    fn run(sets: &[&str]) -> (String, Vec<Applied>, Vec<Rejected>) {
        let mut doc: DocumentMut = DOC.parse().unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let (applied, rejected) = apply(&mut doc, &sets);
        (doc.to_string(), applied, rejected)
    }

    #[test]
    fn launch_overrides_replace_and_add() {
        let (text, applied, rejected) = run(&[
            "group.seed=3",
            "group.duration=10s",
            "hosts.rpi-0.cpu_slowdown=4.5",
            "links.0.latency=2ms",
            "process.planner.rate=250Hz",
            "process.physics.params.count=9",
            "process.physics.params.world.size=[1, 2]",
            "process.planner.args=[\"-v\"]",
        ]);
        assert!(rejected.is_empty(), "{rejected:?}");
        assert!(text.contains("seed = 3 # the seed"), "{text}");
        assert!(text.contains("duration = \"10s\""), "{text}");
        assert!(text.contains("cpu_slowdown = 4.5"), "{text}");
        assert!(text.contains("latency = \"2ms\""), "{text}");
        assert!(text.contains("rate = \"250Hz\""), "{text}");
        assert!(text.contains("count = 9"), "{text}");
        let doc: DocumentMut = text.parse().unwrap();
        assert_eq!(doc["process"][1]["args"][0].as_str(), Some("-v"));
        assert_eq!(
            doc["process"][0]["params"]["world"]["size"][1].as_integer(),
            Some(2)
        );
        assert_eq!(
            applied[4].path,
            vec![
                Seg::Key("process".into()),
                Seg::Index(1),
                Seg::Key("rate".into())
            ]
        );
    }

    #[test]
    fn launch_overrides_reject_bad_paths() {
        let (_, applied, rejected) = run(&[
            "process.phyiscs.rate=1Hz",
            "grup.seed=1",
            "group.sed.x=1",
            "group.seed",
            "links.4.latency=1ms",
            "process.physics=1",
        ]);
        assert!(applied.is_empty(), "{applied:?}");
        let messages: Vec<&str> = rejected.iter().map(|r| r.message.as_str()).collect();
        assert_eq!(messages[0], "no process 'phyiscs'; did you mean 'physics'?");
        assert_eq!(
            messages[1],
            "the file has no table 'grup'; did you mean 'group'?"
        );
        assert_eq!(
            messages[2],
            "'group' has no key 'sed'; did you mean 'seed'?"
        );
        assert!(messages[3].contains("KEY=VALUE"));
        assert!(messages[4].contains("only 1 entries"));
        assert!(messages[5].contains("name a key of process"));
    }

    #[test]
    fn launch_overrides_parse_values() {
        assert_eq!(parse_value("3").as_integer(), Some(3));
        assert_eq!(parse_value("true").as_bool(), Some(true));
        assert_eq!(parse_value("1.5").as_float(), Some(1.5));
        assert_eq!(parse_value("250Hz").as_str(), Some("250Hz"));
        assert_eq!(parse_value("abc").as_str(), Some("abc"));
        assert_eq!(
            parse_value("[\"a\",\"b\"]").as_array().map(|a| a.len()),
            Some(2)
        );
    }
}
