//! Launch arguments, as in ROS launch files: `[args]` declares names with default values,
//! `--set args.NAME=VALUE` changes them, and `$(arg NAME)` anywhere in a string uses them.
//!
//! A string that is exactly `$(arg NAME)` becomes the argument's value with its TOML type
//! (a number stays a number, a list stays a list); inside a longer string the value is
//! spliced in as text. Substitution happens after `--set` and before validation, so a bad
//! value is reported like one written in the file. An argument's default may itself use
//! other arguments (`world_file = "worlds/$(arg world).toml"`); a cycle is an error.

use super::overrides::Seg;
use super::suggest;
use std::collections::HashMap;
use toml_edit::{DocumentMut, Item, Table, Value};

pub use super::overrides::ARGS_TABLE as TABLE;

/// A reference that could not be resolved, at a path into the document.
#[derive(Debug, Clone, PartialEq)]
pub struct Unknown {
    pub path: Vec<Seg>,
    pub message: String,
    /// The reference is to an argument that is broken itself and reported there: the value
    /// is silenced, nothing more is said.
    pub quiet: bool,
}

/// Why a reference could not be resolved.
enum Miss {
    Message(String),
    /// The argument exists but could not be resolved itself.
    Broken,
}

/// Resolves the arguments that use other arguments, then replaces every `$(arg NAME)` outside
/// `[args]`; returns the references it could not resolve.
pub fn substitute(doc: &mut DocumentMut) -> Vec<Unknown> {
    let (resolved, mut unknown) = resolve_args(doc);
    let names: Vec<String> = resolved.keys().cloned().collect();
    let mut lookup = |name: &str| match resolved.get(name) {
        Some(Some(v)) => Ok(v.clone()),
        Some(None) => Err(Miss::Broken),
        None => Err(unknown_name(name, &names)),
    };
    for (key, item) in doc.as_table_mut().iter_mut() {
        if key.get() != TABLE {
            let mut path = vec![Seg::Key(key.get().to_string())];
            walk_item(item, &mut lookup, &mut path, &mut unknown);
        }
    }
    unknown
}

/// A value given on the command line with its references replaced by `args`, the resolved
/// arguments.
pub fn expand_value(value: Value, args: &Table) -> Result<Value, String> {
    let names: Vec<String> = args.iter().map(|(k, _)| k.to_string()).collect();
    let mut lookup = |name: &str| match args.get(name).and_then(Item::as_value) {
        Some(v) => Ok(v.clone()),
        None => Err(unknown_name(name, &names)),
    };
    let mut value = value;
    let mut unknown = Vec::new();
    walk_value(&mut value, &mut lookup, &mut Vec::new(), &mut unknown);
    match unknown.into_iter().next() {
        Some(u) => Err(u.message),
        None => Ok(value),
    }
}

fn unknown_name(name: &str, names: &[String]) -> Miss {
    Miss::Message(format!(
        "'$(arg {name})' names no argument in [{TABLE}]{}",
        suggest::did_you_mean(name, names.iter().map(String::as_str))
    ))
}

/// Resolves references between arguments (after `--set args.*`), writing the results back;
/// returns each argument's value (`None` when it could not be resolved) and the problems.
fn resolve_args(doc: &mut DocumentMut) -> (HashMap<String, Option<Value>>, Vec<Unknown>) {
    let Some(table) = doc.get_mut(TABLE).and_then(Item::as_table_like_mut) else {
        return (HashMap::new(), Vec::new());
    };
    let mut r = Resolver {
        raw: table
            .iter()
            .filter_map(|(k, i)| Some((k.to_string(), i.as_value()?.clone())))
            .collect(),
        done: HashMap::new(),
        stack: Vec::new(),
        unknown: Vec::new(),
    };
    let names: Vec<String> = r.raw.iter().map(|(k, _)| k.clone()).collect();
    for name in &names {
        let _ = r.value(name);
    }
    for (name, item) in table.iter_mut() {
        if let (Some(Some(new)), Item::Value(old)) = (r.done.get(name.get()), item)
            && old.to_string().contains("$(arg ")
        {
            let decor = old.decor().clone();
            *old = new.clone();
            *old.decor_mut() = decor;
        }
    }
    (r.done, r.unknown)
}

struct Resolver {
    raw: Vec<(String, Value)>,
    done: HashMap<String, Option<Value>>,
    /// The arguments being resolved, outermost first, to catch cycles.
    stack: Vec<String>,
    unknown: Vec<Unknown>,
}

impl Resolver {
    fn value(&mut self, name: &str) -> Result<Value, Miss> {
        if let Some(done) = self.done.get(name) {
            return done.clone().ok_or(Miss::Broken);
        }
        let Some(raw) = self
            .raw
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.clone())
        else {
            let names: Vec<String> = self.raw.iter().map(|(k, _)| k.clone()).collect();
            return Err(unknown_name(name, &names));
        };
        if let Some(start) = self.stack.iter().position(|n| n == name) {
            let mut chain = self.stack[start..].to_vec();
            chain.push(name.to_string());
            return Err(Miss::Message(format!(
                "arguments refer to each other in a cycle: {}",
                chain.join(" → ")
            )));
        }
        self.stack.push(name.to_string());
        let mut value = raw;
        value.decor_mut().clear();
        let mut path = vec![Seg::Key(TABLE.into()), Seg::Key(name.into())];
        let mut misses = Vec::new();
        walk_value(&mut value, &mut |n| self.value(n), &mut path, &mut misses);
        self.stack.pop();
        let ok = misses.is_empty();
        self.unknown.extend(misses);
        let value = ok.then_some(value);
        self.done.insert(name.to_string(), value.clone());
        value.ok_or(Miss::Broken)
    }
}

type Lookup<'l> = dyn FnMut(&str) -> Result<Value, Miss> + 'l;

fn walk_item(item: &mut Item, args: &mut Lookup, path: &mut Vec<Seg>, unknown: &mut Vec<Unknown>) {
    match item {
        Item::Value(v) => walk_value(v, args, path, unknown),
        Item::Table(t) => {
            for (k, i) in t.iter_mut() {
                path.push(Seg::Key(k.get().to_string()));
                walk_item(i, args, path, unknown);
                path.pop();
            }
        }
        Item::ArrayOfTables(a) => {
            for (n, t) in a.iter_mut().enumerate() {
                path.push(Seg::Index(n));
                for (k, i) in t.iter_mut() {
                    path.push(Seg::Key(k.get().to_string()));
                    walk_item(i, args, path, unknown);
                    path.pop();
                }
                path.pop();
            }
        }
        Item::None => {}
    }
}

fn walk_value(v: &mut Value, args: &mut Lookup, path: &mut Vec<Seg>, unknown: &mut Vec<Unknown>) {
    match v {
        Value::String(s) => {
            let text = s.value().clone();
            if !text.contains("$(arg ") {
                return;
            }
            match expand(&text, args) {
                Ok(new) => {
                    let decor = v.decor().clone();
                    *v = new;
                    *v.decor_mut() = decor;
                }
                Err(miss) => unknown.push(Unknown {
                    path: path.clone(),
                    quiet: matches!(miss, Miss::Broken),
                    message: match miss {
                        Miss::Message(m) => m,
                        Miss::Broken => String::new(),
                    },
                }),
            }
        }
        Value::Array(a) => {
            for (n, e) in a.iter_mut().enumerate() {
                path.push(Seg::Index(n));
                walk_value(e, args, path, unknown);
                path.pop();
            }
        }
        Value::InlineTable(t) => {
            for (k, e) in t.iter_mut() {
                path.push(Seg::Key(k.get().to_string()));
                walk_value(e, args, path, unknown);
                path.pop();
            }
        }
        _ => {}
    }
}

/// The string with its references replaced: typed when it is one whole reference.
/// The longest string an expansion may make: arguments that double each other would
/// otherwise fill the memory from a few lines.
const MAX_EXPANDED: usize = 1 << 20;

fn expand(text: &str, args: &mut Lookup) -> Result<Value, Miss> {
    let mut lookup = |name: &str| -> Result<Value, Miss> {
        let mut v = args(name)?;
        v.decor_mut().clear();
        Ok(v)
    };
    let trimmed = text.trim();
    if let Some(name) = whole_reference(trimmed) {
        return lookup(name);
    }
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("$(arg ") {
        out.push_str(&rest[..start]);
        let after = &rest[start + "$(arg ".len()..];
        let end = after
            .find(')')
            .ok_or_else(|| Miss::Message(format!("unclosed '$(arg' in \"{text}\"")))?;
        match lookup(after[..end].trim())? {
            Value::String(s) => out.push_str(s.value()),
            other => out.push_str(&other.to_string()),
        }
        if out.len() > MAX_EXPANDED {
            return Err(Miss::Message(format!(
                "expanding \"{text}\" makes more than {MAX_EXPANDED} bytes"
            )));
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(Value::from(out))
}

fn whole_reference(text: &str) -> Option<&str> {
    let name = text.strip_prefix("$(arg ")?.strip_suffix(')')?;
    (!name.contains(')')).then(|| name.trim())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(text: &str) -> (String, Vec<Unknown>) {
        let mut doc: DocumentMut = text.parse().unwrap();
        let unknown = substitute(&mut doc);
        (doc.to_string(), unknown)
    }

    #[test]
    fn arguments_that_double_each_other_are_an_error_not_an_exhausted_memory() {
        let mut text = String::from("[args]\na0 = \"xxxxxxxxxxxxxxxx\"\n");
        for i in 1..64 {
            text.push_str(&format!("a{i} = \"$(arg a{})$(arg a{})\"\n", i - 1, i - 1));
        }
        text.push_str("[group]\nname = \"$(arg a63)\"\n");
        let (_, unknown) = run(&text);
        let messages: Vec<&str> = unknown.iter().map(|u| u.message.as_str()).collect();
        assert!(
            messages
                .iter()
                .any(|m| m.contains("more than 1048576 bytes")),
            "{messages:?}"
        );
    }

    #[test]
    fn whole_references_keep_their_type() {
        let (out, unknown) = run(
            "[args]\nn = 3\nxs = [1, 2]\non = true\n[group]\na = \"$(arg n)\"\nb = \"$(arg xs)\"\nc = { d = \"$(arg on)\" }\n",
        );
        assert!(unknown.is_empty());
        let doc: toml::Table = toml::from_str(&out).unwrap();
        assert_eq!(doc["group"]["a"].as_integer(), Some(3));
        assert_eq!(doc["group"]["b"].as_array().unwrap().len(), 2);
        assert_eq!(doc["group"]["c"]["d"].as_bool(), Some(true));
    }

    #[test]
    fn references_inside_strings_are_spliced() {
        let (out, unknown) = run(
            "[args]\nworld = \"hall\"\nn = 2\n[[process]]\nparams = { w = \"worlds/$(arg world).toml\", k = \"x$(arg n)y\" }\n",
        );
        assert!(unknown.is_empty());
        assert!(out.contains("\"worlds/hall.toml\""), "{out}");
        assert!(out.contains("\"x2y\""), "{out}");
    }

    #[test]
    fn unknown_names_are_reported_with_their_path_and_a_suggestion() {
        let (_, unknown) = run("[args]\nworld = \"hall\"\n[[process]]\nx = \"$(arg wrld)\"\n");
        assert_eq!(unknown.len(), 1);
        assert_eq!(
            unknown[0].path,
            vec![
                Seg::Key("process".into()),
                Seg::Index(0),
                Seg::Key("x".into())
            ]
        );
        assert!(
            unknown[0].message.contains("did you mean 'world'"),
            "{unknown:?}"
        );
    }
}
