//! A params table from a process's JSON Schema (`PROGRAM --describe-params`): one row per
//! key, nested tables flattened, tagged variants spelled out, and the rows compared with a
//! page's (`caravan docs params`).

use serde_json::{Map, Value};
use std::collections::BTreeMap;

/// One row of a params table.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub key: String,
    pub kind: String,
    pub default: String,
    pub meaning: String,
}

impl Row {
    fn line(&self) -> String {
        format!(
            "| `{}` | {} | {} | {} |",
            self.key, self.kind, self.default, self.meaning
        )
    }
}

/// The table's Markdown, a header and a row per key.
pub fn render(rows: &[Row]) -> String {
    if rows.is_empty() {
        return "It takes no params: any key is refused (exit 2).\n".into();
    }
    let mut s = String::from("| key | type | default | meaning |\n|---|---|---|---|\n");
    for row in rows {
        s.push_str(&row.line());
        s.push('\n');
    }
    s
}

/// What differs between the rows the code gives and the table `body` on the page, by key.
pub fn differences(rows: &[Row], body: &str) -> Vec<String> {
    let on_page: BTreeMap<String, &str> = body
        .lines()
        .filter_map(|l| {
            let key = l.strip_prefix("| `")?.split_once("` |")?.0;
            Some((key.to_string(), l))
        })
        .collect();
    let mut out = Vec::new();
    for row in rows {
        match on_page.get(&row.key) {
            None => out.push(format!("the page lacks param '{}'", row.key)),
            Some(line) if *line != row.line() => out.push(format!(
                "the row of param '{}' differs from the code:\n  page: {line}\n  code: {}",
                row.key,
                row.line()
            )),
            Some(_) => {}
        }
    }
    for key in on_page.keys() {
        if !rows.iter().any(|r| &r.key == key) {
            out.push(format!(
                "the page documents param '{key}', which the process does not take"
            ));
        }
    }
    if out.is_empty() {
        out.push("the table's layout differs from the generated one".into());
    }
    out
}

/// The rows of a process's params schema (`--describe-params`).
pub fn rows_of(schema: &Value) -> Vec<Row> {
    let mut rows = Vec::new();
    let empty = Map::new();
    let root = schema.as_object().unwrap_or(&empty);
    match variants(root) {
        Some((tag, variants)) => {
            for (value, variant) in variants {
                let note = format!("`{tag} = {value}`: ");
                rows.push(variant_row(&tag, &value, variant, &note));
                flatten(variant, "", &note, &[tag.as_str()], &mut rows);
            }
        }
        None => flatten(root, "", "", &[], &mut rows),
    }
    // A key given in two variants (`kp` of `position` and of `velocity`) gets one row each;
    // tell them apart by the variant.
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for row in rows.iter() {
        *seen.entry(row.key.clone()).or_default() += 1;
    }
    for row in rows.iter_mut() {
        if seen[&row.key] > 1
            && let Some(tagged) = row.meaning.strip_prefix('`')
            && let Some((variant, _)) = tagged.split_once('`')
        {
            row.key = format!("{} ({variant})", row.key);
        }
    }
    rows
}

/// Rows of the properties of object schema `s`, their keys after `prefix`, their meanings
/// after `note`; `skip` names tag properties already given by the note.
fn flatten(s: &Map<String, Value>, prefix: &str, note: &str, skip: &[&str], rows: &mut Vec<Row>) {
    let required: Vec<&str> = s
        .get("required")
        .and_then(Value::as_array)
        .map(|r| r.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    let Some(props) = s.get("properties").and_then(Value::as_object) else {
        return;
    };
    for (name, prop) in props {
        if skip.contains(&name.as_str()) {
            continue;
        }
        let Some(prop) = prop.as_object() else {
            continue;
        };
        let key = format!("{prefix}{name}");
        let inner = non_null(prop);
        let default = match prop.get("default") {
            _ if required.contains(&name.as_str()) => "required".to_string(),
            Some(Value::Null) => "none".to_string(),
            Some(v) => format!("`{}`", compact(v)),
            None if inner.is_some_and(|i| !std::ptr::eq(i, prop)) || nullable(prop) => {
                "none".to_string()
            }
            None => String::new(),
        };
        let inner = inner.unwrap_or(prop);
        let description = prop
            .get("description")
            .or_else(|| inner.get("description"))
            .and_then(Value::as_str)
            .unwrap_or("");
        let values = value_docs(inner);
        let sep = if description.is_empty() || values.is_empty() {
            ""
        } else {
            " "
        };
        rows.push(Row {
            key: key.clone(),
            kind: type_of(inner),
            default,
            meaning: cell(&format!("{note}{description}{sep}{values}")),
        });
        // Nested tables: their keys follow, dotted.
        if has_properties(inner) {
            flatten(inner, &format!("{key}."), note, &[], rows);
        } else if let Some(items) = list_items(inner) {
            if has_properties(items) {
                flatten(items, &format!("{key}[]."), note, &[], rows);
            } else if let Some((tag, variants)) = variants(items) {
                for (value, variant) in variants {
                    let note = format!("{note}`{tag} = {value}`: ");
                    rows.push(variant_row(
                        &format!("{key}[].{tag}"),
                        &value,
                        variant,
                        &note,
                    ));
                    flatten(variant, &format!("{key}[]."), &note, &[tag.as_str()], rows);
                }
            }
        } else if let Some((tag, variants)) = variants(inner) {
            for (value, variant) in variants {
                let note = format!("{note}`{tag} = {value}`: ");
                rows.push(variant_row(&format!("{key}.{tag}"), &value, variant, &note));
                flatten(variant, &format!("{key}."), &note, &[tag.as_str()], rows);
            }
        }
    }
}

/// The row of a tagged variant: its tag's key, its value and its doc comment.
fn variant_row(key: &str, value: &str, variant: &Map<String, Value>, note: &str) -> Row {
    let description = variant
        .get("description")
        .and_then(Value::as_str)
        .unwrap_or("");
    Row {
        key: key.to_string(),
        kind: format!("`{value}`"),
        default: String::new(),
        meaning: cell(&format!("{note}{description}")),
    }
}

/// The doc comments of a unit enum's values, as `` `a`: its doc; `b`: its doc ``.
fn value_docs(s: &Map<String, Value>) -> String {
    let Some(branches) = s.get("oneOf").and_then(Value::as_array) else {
        return String::new();
    };
    let docs: Vec<String> = branches
        .iter()
        .filter_map(|b| {
            let value = b.get("const")?;
            let doc = b.get("description")?.as_str()?;
            Some(format!("`{}`: {}", compact(value), doc))
        })
        .collect();
    docs.join("; ")
}

/// The schema inside `Option`: the one non-null branch of an `anyOf`/`oneOf`, or `s` itself.
fn non_null(s: &Map<String, Value>) -> Option<&Map<String, Value>> {
    for key in ["anyOf", "oneOf"] {
        if let Some(branches) = s.get(key).and_then(Value::as_array) {
            let other: Vec<_> = branches
                .iter()
                .filter_map(Value::as_object)
                .filter(|b| b.get("type").and_then(Value::as_str) != Some("null"))
                .collect();
            if other.len() == 1 && other.len() < branches.len() {
                return other.first().copied();
            }
        }
    }
    Some(s)
}

fn nullable(s: &Map<String, Value>) -> bool {
    match s.get("type") {
        Some(Value::Array(types)) => types.iter().any(|t| t == "null"),
        _ => false,
    }
}

fn has_properties(s: &Map<String, Value>) -> bool {
    s.get("properties")
        .and_then(Value::as_object)
        .is_some_and(|p| !p.is_empty())
}

/// The item schema of a list (not of a fixed-length tuple).
fn list_items(s: &Map<String, Value>) -> Option<&Map<String, Value>> {
    if s.contains_key("prefixItems") {
        return None;
    }
    s.get("items").and_then(Value::as_object)
}

/// A tagged enum's variants: each tag value with its object schema.
type Variants<'a> = Vec<(String, &'a Map<String, Value>)>;

/// A tagged enum's tag and its variants (each an object whose tag property is a constant).
fn variants(s: &Map<String, Value>) -> Option<(String, Variants<'_>)> {
    let branches = s.get("oneOf").or_else(|| s.get("anyOf"))?.as_array()?;
    let mut tag = None;
    let mut out = Vec::new();
    for b in branches {
        let b = b.as_object()?;
        let props = b.get("properties")?.as_object()?;
        let (name, value) = props.iter().find_map(|(k, v)| {
            let c = v.get("const").or_else(|| {
                v.get("enum")
                    .and_then(Value::as_array)
                    .filter(|e| e.len() == 1)
                    .and_then(|e| e.first())
            })?;
            Some((k.clone(), compact(c)))
        })?;
        if tag.get_or_insert_with(|| name.clone()) != &name {
            return None;
        }
        out.push((value, b));
    }
    Some((tag?, out))
}

/// The type column: float, integer, bool, string, `"a"` or `"b"`, `[float, float]`, list of …,
/// table.
fn type_of(s: &Map<String, Value>) -> String {
    if let Some(c) = s.get("const") {
        return format!("`{}`", compact(c));
    }
    if let Some(values) = s.get("enum").and_then(Value::as_array) {
        let values = values.iter().filter(|v| !v.is_null());
        return one_of(values.map(|v| format!("`{}`", compact(v))).collect());
    }
    if let Some((tag, variants)) = variants(s) {
        let names = variants.iter().map(|(v, _)| format!("`{v}`")).collect();
        return format!("table by `{tag}`: {}", one_of(names));
    }
    for key in ["oneOf", "anyOf"] {
        if let Some(branches) = s.get(key).and_then(Value::as_array) {
            let kinds: Vec<String> = branches
                .iter()
                .filter_map(Value::as_object)
                .filter(|b| b.get("type").and_then(Value::as_str) != Some("null"))
                .map(type_of)
                .collect();
            return one_of(kinds);
        }
    }
    let ty = match s.get("type") {
        Some(Value::String(t)) => t.as_str(),
        Some(Value::Array(types)) => types
            .iter()
            .filter_map(Value::as_str)
            .find(|t| *t != "null")
            .unwrap_or("null"),
        _ => "",
    };
    match ty {
        "number" => "float".into(),
        "integer" => "integer".into(),
        "boolean" => "bool".into(),
        "string" => "string".into(),
        "array" => {
            if let Some(items) = s.get("prefixItems").and_then(Value::as_array) {
                let kinds: Vec<String> = items
                    .iter()
                    .filter_map(Value::as_object)
                    .map(type_of)
                    .collect();
                format!("[{}]", kinds.join(", "))
            } else if let Some(items) = list_items(s) {
                let len = |k: &str| s.get(k).and_then(Value::as_u64);
                match (len("minItems"), len("maxItems")) {
                    (Some(n), Some(m)) if n == m && n <= 8 => {
                        format!("[{}]", vec![type_of(items); n as usize].join(", "))
                    }
                    _ => format!("list of {}", type_of(items)),
                }
            } else {
                "list".into()
            }
        }
        "object" => match s.get("additionalProperties").and_then(Value::as_object) {
            Some(values) if !has_properties(s) => format!("table of {}", type_of(values)),
            _ => "table".into(),
        },
        _ => String::new(),
    }
}

fn one_of(mut names: Vec<String>) -> String {
    match names.len() {
        0 => String::new(),
        1 => names.remove(0),
        n => format!("{} or {}", names[..n - 1].join(", "), names[n - 1]),
    }
}

/// A value as compact JSON (floats keep their decimal point).
fn compact(v: &Value) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

/// A doc comment as one table cell: lines joined, `|` escaped, rustdoc's intra-doc links
/// (`` [`Params::validate`] ``) reduced to their code.
fn cell(doc: &str) -> String {
    let joined = doc
        .split('\n')
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    let mut out = String::with_capacity(joined.len());
    let mut rest = joined.as_str();
    while let Some(i) = rest.find("[`") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        match after.find("`]") {
            Some(j) if !after[j + 2..].starts_with(['(', '[']) => {
                out.push_str(&after[..=j]);
                rest = &after[j + 2..];
            }
            _ => {
                out.push('[');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out.replace('|', "\\|")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn nested_tables_lists_and_options_flatten_to_dotted_keys() {
        let schema = json!({
            "type": "object",
            "properties": {
                "count": { "type": "integer", "description": "Robots, 1 … 16." },
                "gain": { "type": "number", "default": 2.0, "description": "Gain, 1/s, > 0." },
                "world": { "type": ["string", "null"], "default": null },
                "pose": { "type": "array", "prefixItems": [{ "type": "number" }, { "type": "number" }],
                          "default": [0.0, 1.5] },
                "mode": { "type": "string", "enum": ["slam", "odometry"] },
                "slam": { "type": "object", "properties": {
                    "levels": { "type": "integer", "default": 3, "description": "Map levels.\nEach | twice." }
                } },
                "robots": { "type": "array", "items": { "type": "object", "properties": {
                    "urdf": { "type": "string" } }, "required": ["urdf"] } }
            },
            "required": ["count"]
        });
        let rows = rows_of(&schema);
        let keys: Vec<_> = rows.iter().map(|r| r.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "count",
                "gain",
                "mode",
                "pose",
                "robots",
                "robots[].urdf",
                "slam",
                "slam.levels",
                "world"
            ]
        );
        let row = |k: &str| rows.iter().find(|r| r.key == k).unwrap().clone();
        assert_eq!(row("count").default, "required");
        assert_eq!(row("gain").default, "`2.0`");
        assert_eq!(row("gain").kind, "float");
        assert_eq!(row("world").default, "none");
        assert_eq!(row("pose").kind, "[float, float]");
        assert_eq!(row("mode").kind, "`\"slam\"` or `\"odometry\"`");
        assert_eq!(row("slam.levels").meaning, "Map levels. Each \\| twice.");
        assert_eq!(row("robots[].urdf").default, "required");
    }

    #[test]
    fn the_check_names_the_key_the_page_lacks() {
        let rows = vec![Row {
            key: "gain".into(),
            kind: "float".into(),
            default: "`2.0`".into(),
            meaning: "Gain.".into(),
        }];
        let d = differences(
            &rows,
            "\n| key | type | default | meaning |\n|---|---|---|---|\n",
        );
        assert_eq!(d, ["the page lacks param 'gain'"]);
    }
}
