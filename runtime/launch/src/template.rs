//! Process templates: a `[[process]]` entry with `for = "i in 0..4"` stands for one entry per
//! value (Rust range syntax: `a..b` excludes `b`, `a..=b` includes it). In every string of the
//! entry `{i}` becomes the value, `{i+1}` and `{i-1}` add or subtract a literal, a string in
//! `params` that is exactly one such expression becomes an integer (the other keys take
//! strings), and `{{`/`}}` are literal braces. Only
//! entries with `for` are touched, after `$(arg …)` substitution (so an argument may hold
//! `{i}`, and the range may use arguments).

use super::overrides::Seg;
use super::source::Source;
use toml_edit::{ArrayOfTables, DocumentMut, Item, Table, Value};

/// The key that makes an entry a template.
pub const KEY: &str = "for";

/// Repetitions one template may have: enough for any group, small enough to catch a typo.
const MAX_REPETITIONS: i128 = 10_000;

/// One entry of `process` after expansion.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Its index in the file as written.
    pub from: usize,
    /// Which repetition of which template it is, for messages.
    pub note: Option<String>,
    /// A template that could not be expanded (reported); its further problems are noise.
    pub failed: bool,
}

/// Expands the templates in the `process` list of `doc`, the file `source` after argument
/// substitution, reporting problems at paths into the file as written. Returns `None` when
/// there is no template (the document is untouched), else each entry's origin.
pub fn expand(
    doc: &mut DocumentMut,
    source: &Source,
    report: &mut dyn FnMut(Vec<Seg>, String),
) -> Option<Vec<Entry>> {
    let has_template = |t: &dyn toml_edit::TableLike| t.contains_key(KEY);
    let any = match doc.get("process")? {
        Item::ArrayOfTables(a) => a.iter().any(|t| has_template(t)),
        Item::Value(Value::Array(a)) => a
            .iter()
            .any(|v| v.as_inline_table().is_some_and(|t| has_template(t))),
        _ => false,
    };
    if !any {
        return None;
    }
    let written: Vec<Option<Table>> = match doc.remove("process")? {
        Item::ArrayOfTables(a) => a.into_iter().map(Some).collect(),
        Item::Value(Value::Array(a)) => a
            .into_iter()
            .map(|v| v.as_inline_table().map(|t| t.clone().into_table()))
            .collect(),
        _ => unreachable!("checked above"),
    };
    let mut list = ArrayOfTables::new();
    let mut entries = Vec::new();
    for (j, table) in written.into_iter().enumerate() {
        let at = |key: Option<&str>| {
            let mut p = vec![Seg::Key("process".into()), Seg::Index(j)];
            p.extend(key.map(|k| Seg::Key(k.into())));
            p
        };
        let Some(table) = table else {
            report(
                at(None),
                format!("process entry {}: expected a table", j + 1),
            );
            continue;
        };
        let plain = |table| (table, None, false);
        let expanded = match table.get(KEY) {
            None => vec![plain(table)],
            Some(spec) => {
                let label = match table.get("name").and_then(Item::as_str) {
                    Some(name) => format!("process '{name}'"),
                    None => format!("process #{}", j + 1),
                };
                let line = source.line_of(&at(None));
                match repeat(&table, spec, source.at(line)) {
                    Ok(tables) => tables
                        .into_iter()
                        .map(|(t, n)| (t, Some(n), false))
                        .collect(),
                    Err(problems) => {
                        for (key, message) in problems {
                            report(at(Some(&key)), format!("{label}, key '{key}': {message}"));
                        }
                        vec![(table, None, true)]
                    }
                }
            }
        };
        for (table, note, failed) in expanded {
            list.push(table);
            entries.push(Entry {
                from: j,
                note,
                failed,
            });
        }
    }
    doc.insert("process", Item::ArrayOfTables(list));
    Some(entries)
}

/// A problem in a template, by its top-level key: (key, message).
type KeyProblem = (String, String);

/// The entries a template stands for, each with its note; or the problems, by key.
fn repeat(
    template: &Table,
    spec: &Item,
    at: String,
) -> Result<Vec<(Table, String)>, Vec<KeyProblem>> {
    let text = spec
        .as_str()
        .ok_or_else(|| vec![(KEY.to_string(), bad_range(&spec.to_string()))])?;
    let (var, values) = parse_range(text).map_err(|m| vec![(KEY.to_string(), m)])?;
    let mut body = template.clone();
    body.remove(KEY);
    // Mistakes do not depend on the value, so the first repetition finds them all.
    let mut problems = Vec::new();
    let first = *values.start();
    fill_table(
        &mut body.clone(),
        &var,
        first,
        &mut Vec::new(),
        &mut problems,
    );
    if !problems.is_empty() {
        return Err(problems);
    }
    Ok(values
        .map(|v| {
            let mut t = body.clone();
            fill_table(&mut t, &var, v, &mut Vec::new(), &mut Vec::new());
            (t, format!("from the template at {at}, {var} = {v}"))
        })
        .collect())
}

fn bad_range(text: &str) -> String {
    format!(
        "'{}' is not a template range; write for = \"i in 0..4\" (4 excluded) or \"i in 1..=4\"",
        text.trim()
    )
}

/// `"i in 1..5"` → ("i", 1..=4).
pub fn parse_range(text: &str) -> Result<(String, std::ops::RangeInclusive<i64>), String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    let (var, range) = match words.as_slice() {
        [var, "in", range @ ..] if is_ident(var) && !range.is_empty() => (*var, range.concat()),
        _ => return Err(bad_range(text)),
    };
    let (lo, hi, inclusive) = if let Some((lo, hi)) = range.split_once("..=") {
        (lo, hi, true)
    } else if let Some((lo, hi)) = range.split_once("..") {
        (lo, hi, false)
    } else {
        return Err(bad_range(text));
    };
    let (Ok(lo), Ok(hi)) = (lo.parse::<i64>(), hi.parse::<i64>()) else {
        return Err(bad_range(text));
    };
    let last = if inclusive {
        Some(hi)
    } else {
        hi.checked_sub(1)
    };
    let count = last.map_or(0, |l| i128::from(l) - i128::from(lo) + 1);
    if count <= 0 {
        return Err(format!("the range '{range}' is empty"));
    }
    if count > MAX_REPETITIONS {
        return Err(format!(
            "the range '{range}' has {count} values; a template repeats at most {MAX_REPETITIONS} times"
        ));
    }
    Ok((var.to_string(), lo..=last.expect("count > 0")))
}

fn is_ident(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Fills every string below `table`; problems are recorded with the top-level key.
fn fill_table(
    table: &mut Table,
    var: &str,
    v: i64,
    path: &mut Vec<String>,
    problems: &mut Vec<(String, String)>,
) {
    for (k, item) in table.iter_mut() {
        path.push(k.get().to_string());
        match item {
            Item::Value(value) => fill_value(value, var, v, path, problems),
            Item::Table(t) => fill_table(t, var, v, path, problems),
            Item::ArrayOfTables(a) => {
                for t in a.iter_mut() {
                    fill_table(t, var, v, path, problems);
                }
            }
            Item::None => {}
        }
        path.pop();
    }
}

fn fill_value(
    value: &mut Value,
    var: &str,
    v: i64,
    path: &mut Vec<String>,
    problems: &mut Vec<(String, String)>,
) {
    match value {
        // Only params take typed values; the other keys take strings.
        Value::String(s) => match fill(s.value(), var, v, path[0] == "params") {
            Ok(Some(new)) => {
                let decor = value.decor().clone();
                *value = new;
                *value.decor_mut() = decor;
            }
            Ok(None) => {}
            Err(message) => problems.push((path[0].clone(), message)),
        },
        Value::Array(a) => {
            for e in a.iter_mut() {
                fill_value(e, var, v, path, problems);
            }
        }
        Value::InlineTable(t) => {
            for (_, e) in t.iter_mut() {
                fill_value(e, var, v, path, problems);
            }
        }
        _ => {}
    }
}

/// `text` with its expressions replaced (`None`: it has no braces); when `typed`, an integer
/// if it is exactly one expression.
pub fn fill(text: &str, var: &str, v: i64, typed: bool) -> Result<Option<Value>, String> {
    if !text.contains(['{', '}']) {
        return Ok(None);
    }
    let trimmed = text.trim();
    if typed
        && let Some(inner) = trimmed.strip_prefix('{').and_then(|r| r.strip_suffix('}'))
        && !inner.contains(['{', '}'])
    {
        return eval(inner, var, v).map(|n| Some(Value::from(n)));
    }
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find(['{', '}']) {
        out.push_str(&rest[..at]);
        let brace = rest.as_bytes()[at];
        let after = &rest[at + 1..];
        if after.as_bytes().first() == Some(&brace) {
            out.push(brace as char);
            rest = &after[1..];
        } else if brace == b'}' {
            return Err(format!(
                "a lone '}}' in \"{text}\"; write '}}}}' for a literal brace"
            ));
        } else {
            let end = after
                .find('}')
                .filter(|&e| !after[..e].contains('{'))
                .ok_or_else(|| {
                    format!("an unclosed '{{' in \"{text}\"; write '{{{{' for a literal brace")
                })?;
            out.push_str(&eval(&after[..end], var, v)?.to_string());
            rest = &after[end + 1..];
        }
    }
    out.push_str(rest);
    Ok(Some(Value::from(out)))
}

/// `i`, `i+2` or `i-1` for variable `var` at value `v`.
fn eval(expr: &str, var: &str, v: i64) -> Result<i64, String> {
    let e = expr.trim();
    let not_expr = || {
        format!(
            "'{{{expr}}}' is not a template expression; write {{{var}}}, {{{var}+1}} or {{{var}-1}}, and '{{{{' for a literal brace"
        )
    };
    let (name, offset) = match e.find(['+', '-']) {
        Some(k) => {
            let digits = e[k + 1..].trim();
            if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(not_expr());
            }
            let n: i64 = digits.parse().map_err(|_| not_expr())?;
            (e[..k].trim(), if &e[k..=k] == "-" { -n } else { n })
        }
        None => (e, 0),
    };
    if !is_ident(name) {
        return Err(not_expr());
    }
    if name != var {
        return Err(format!(
            "unknown variable '{name}' in '{{{expr}}}'; the template's variable is '{var}'"
        ));
    }
    v.checked_add(offset)
        .ok_or_else(|| format!("'{{{expr}}}' overflows at {var} = {v}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn launch_template_ranges() {
        assert_eq!(parse_range("i in 1..5"), Ok(("i".into(), 1..=4)));
        assert_eq!(parse_range(" k in 0 ..= 2 "), Ok(("k".into(), 0..=2)));
        assert_eq!(parse_range("robot in -1..1"), Ok(("robot".into(), -1..=0)));
        for bad in [
            "i in 1...5",
            "i 1..5",
            "1 in 1..5",
            "i in a..b",
            "i in 5",
            "in 1..2",
        ] {
            let e = parse_range(bad).unwrap_err();
            assert!(e.contains("is not a template range"), "{bad}: {e}");
        }
        assert_eq!(
            parse_range("i in 3..3").unwrap_err(),
            "the range '3..3' is empty"
        );
        assert!(
            parse_range("i in 0..=100000")
                .unwrap_err()
                .contains("at most")
        );
    }

    #[test]
    fn launch_template_fill() {
        let s = |t: &str| fill(t, "i", 3, true).map(|v| v.map(|v| v.to_string()));
        assert_eq!(s("sensor-{i}"), Ok(Some("\"sensor-3\"".into())));
        assert_eq!(s("{i-1}/{ i+1 }"), Ok(Some("\"2/4\"".into())));
        assert_eq!(s("{i}"), Ok(Some("3".into())));
        assert_eq!(s(" {i-1} "), Ok(Some("2".into())));
        assert_eq!(s("{{i}} {{"), Ok(Some("\"{i} {\"".into())));
        assert_eq!(s("plain"), Ok(None));
        let untyped = fill("{i}", "i", 3, false).unwrap().unwrap();
        assert_eq!(untyped.as_str(), Some("3"));
        assert!(s("{j}").unwrap_err().contains("unknown variable 'j'"));
        assert!(
            s("{i*2}")
                .unwrap_err()
                .contains("not a template expression")
        );
        assert!(s("a{i").unwrap_err().contains("unclosed '{'"));
        assert!(s("a}b").unwrap_err().contains("lone '}'"));
    }
}
