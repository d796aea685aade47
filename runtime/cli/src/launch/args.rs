//! Launch arguments, as in ROS launch files: `[args]` declares names with default values,
//! `--set args.NAME=VALUE` changes them, and `$(arg NAME)` anywhere in a string uses them.
//!
//! A string that is exactly `$(arg NAME)` becomes the argument's value with its TOML type
//! (a number stays a number, a list stays a list); inside a longer string the value is
//! spliced in as text. Substitution happens after `--set` and before validation, so a bad
//! value is reported like one written in the file.

use super::overrides::Seg;
use super::suggest;
use toml_edit::{DocumentMut, Item, Table, Value};

/// The table that declares the arguments.
pub const TABLE: &str = "args";

/// A reference to an undeclared argument, at a path into the document.
#[derive(Debug, Clone, PartialEq)]
pub struct Unknown {
    pub path: Vec<Seg>,
    pub message: String,
}

/// Replaces every `$(arg NAME)` outside `[args]`; returns the references it could not resolve.
pub fn substitute(doc: &mut DocumentMut) -> Vec<Unknown> {
    let args = match doc.get(TABLE).and_then(Item::as_table) {
        Some(t) => t.clone(),
        None => Table::new(),
    };
    let mut unknown = Vec::new();
    for (key, item) in doc.as_table_mut().iter_mut() {
        if key.get() != TABLE {
            let mut path = vec![Seg::Key(key.get().to_string())];
            walk_item(item, &args, &mut path, &mut unknown);
        }
    }
    unknown
}

fn walk_item(item: &mut Item, args: &Table, path: &mut Vec<Seg>, unknown: &mut Vec<Unknown>) {
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

fn walk_value(v: &mut Value, args: &Table, path: &mut Vec<Seg>, unknown: &mut Vec<Unknown>) {
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
                Err(message) => unknown.push(Unknown {
                    path: path.clone(),
                    message,
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
fn expand(text: &str, args: &Table) -> Result<Value, String> {
    let lookup = |name: &str| -> Result<Value, String> {
        match args.get(name).and_then(Item::as_value) {
            Some(v) => {
                let mut v = v.clone();
                v.decor_mut().clear();
                Ok(v)
            }
            None => Err(format!(
                "'$(arg {name})' names no argument in [{TABLE}]{}",
                suggest::did_you_mean(name, args.iter().map(|(k, _)| k))
            )),
        }
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
            .ok_or_else(|| format!("unclosed '$(arg' in \"{text}\""))?;
        match lookup(after[..end].trim())? {
            Value::String(s) => out.push_str(s.value()),
            other => out.push_str(&other.to_string()),
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
