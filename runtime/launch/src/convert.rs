//! Converters: an item of the document to a typed value, or a message saying what was expected.

use super::model::{GroupSpec, Restart};
use super::overrides::Seg;
use super::suggest;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;
use toml_edit::{Item, TableLike, Value};

pub fn found(item: &Item) -> String {
    match item {
        Item::Value(Value::String(s)) => format!("string {:?}", s.value()),
        Item::Value(Value::Integer(i)) => format!("integer {}", i.value()),
        Item::Value(Value::Float(f)) => format!("float {}", f.value()),
        Item::Value(Value::Boolean(b)) => format!("boolean {}", b.value()),
        Item::Value(Value::Datetime(d)) => format!("datetime {}", d.value()),
        Item::Value(Value::Array(_)) => "an array".into(),
        Item::ArrayOfTables(_) => "an array of tables".into(),
        _ => "a table".into(),
    }
}

pub fn expected(what: &str, item: &Item) -> String {
    format!("expected {what}, found {}", found(item))
}

pub fn string(item: &Item) -> Result<String, String> {
    item.as_str()
        .map(str::to_string)
        .ok_or_else(|| expected("a string", item))
}

pub fn probability(item: &Item) -> Result<f64, String> {
    let f = number(item)?;
    if (0.0..=1.0).contains(&f) {
        Ok(f)
    } else {
        Err(format!("must be between 0.0 and 1.0, found {f}"))
    }
}

pub fn unsigned(item: &Item) -> Result<u64, String> {
    // An integer too large for TOML reaches here from `--set` as a string of digits.
    if item
        .as_str()
        .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
    {
        return Err(format!(
            "{} is larger than {}, the largest integer TOML holds",
            item.as_str().unwrap_or_default(),
            i64::MAX
        ));
    }
    item.as_integer()
        .and_then(|i| u64::try_from(i).ok())
        .ok_or_else(|| expected("a non-negative integer", item))
}

pub fn number(item: &Item) -> Result<f64, String> {
    item.as_float()
        .or_else(|| item.as_integer().map(|i| i as f64))
        .ok_or_else(|| expected("a number", item))
}

pub fn boolean(item: &Item) -> Result<bool, String> {
    item.as_bool()
        .ok_or_else(|| expected("true or false", item))
}

pub fn strings(item: &Item) -> Result<Vec<String>, String> {
    let list = item
        .as_array()
        .ok_or_else(|| expected("an array of strings", item))?;
    list.iter()
        .map(|v| v.as_str().map(str::to_string))
        .collect::<Option<_>>()
        .ok_or_else(|| expected("an array of strings", item))
}

pub fn patterns(item: &Item) -> Result<Vec<String>, String> {
    let list = strings(item)?;
    match list
        .iter()
        .find(|p| p.trim().is_empty() || p.contains("***"))
    {
        Some(bad) => Err(format!("'{bad}' is not a topic pattern")),
        None => Ok(list),
    }
}

pub fn duration(item: &Item) -> Result<Duration, String> {
    caravan::parse_duration(&string(item)?).map_err(|e| e.to_string())
}

/// A node's spin budget (`spin = "50us"`): a duration of at most [`caravan::MAX_SPIN`].
pub fn spin(item: &Item) -> Result<Duration, String> {
    caravan::parse_spin(&string(item)?).map_err(|e| e.to_string())
}

pub fn positive_duration(item: &Item) -> Result<Duration, String> {
    let d = duration(item)?;
    if d.is_zero() {
        return Err("must be greater than zero".into());
    }
    Ok(d)
}

/// `group.host_lease`: [`GroupSpec::MIN_HOST_LEASE`] to [`GroupSpec::MAX_HOST_LEASE`].
pub fn host_lease(item: &Item) -> Result<Duration, String> {
    let d = duration(item)?;
    let (min, max) = (GroupSpec::MIN_HOST_LEASE, GroupSpec::MAX_HOST_LEASE);
    if d < min || d > max {
        return Err(format!("must be {min:?} to {max:?}, found {d:?}"));
    }
    Ok(d)
}

pub fn restart(item: &Item) -> Result<Restart, String> {
    let text = string(item)?;
    text.parse::<Restart>()
        .map_err(|e| match suggest::nearest(&text, Restart::NAMES) {
            Some(near) => format!("'{text}' is not a restart policy; did you mean '{near}'?"),
            None => e,
        })
}

pub fn env(item: &Item) -> Result<BTreeMap<String, String>, String> {
    let table = item
        .as_table_like()
        .ok_or_else(|| expected("a table of strings", item))?;
    let mut env = BTreeMap::new();
    for (key, value) in table.iter() {
        if key.is_empty() || key.contains(['=', '\0']) {
            return Err(format!("'{key}' is not an environment variable name"));
        }
        let value = value
            .as_str()
            .ok_or_else(|| format!("value of '{key}': {}", expected("a string", value)))?;
        env.insert(key.to_string(), value.to_string());
    }
    Ok(env)
}

/// The most a process's params may take as JSON: they travel in one environment variable,
/// which Linux limits to 128 KiB (MAX_ARG_STRLEN).
pub const MAX_PARAMS_BYTES: usize = 120_000;

/// A params value that cannot be passed, and where it sits below `params` (so that a `--set`
/// which wrote it takes the blame, not the file's `params` line).
#[derive(Debug)]
pub struct ParamsError {
    pub below: Vec<Seg>,
    pub message: String,
}

impl From<String> for ParamsError {
    fn from(message: String) -> Self {
        ParamsError {
            below: Vec::new(),
            message,
        }
    }
}

pub fn params(item: &Item) -> Result<serde_json::Value, ParamsError> {
    if !item.is_table_like() {
        return Err(expected("a table", item).into());
    }
    let value = to_json(item, "params")?;
    let size = value.to_string().len();
    if size > MAX_PARAMS_BYTES {
        let largest = value.as_object().and_then(|o| {
            o.iter()
                .map(|(k, v)| (v.to_string().len(), k))
                .max()
                .map(|(n, k)| format!(" (key '{k}' alone takes {n})"))
        });
        return Err(format!(
            "the params take {size} bytes as JSON{}, more than the {MAX_PARAMS_BYTES} a process's environment holds; put large data in a file and name the file in params",
            largest.unwrap_or_default()
        )
        .into());
    }
    Ok(value)
}

/// A `--set` value as the file would hold it, in JSON: `3` a number, `[1, 2]` a list, `hall`
/// a string (as [`super::overrides::parse_value`] reads it). A value JSON cannot hold (`nan`)
/// stays its text.
pub fn value_json(raw: &str) -> serde_json::Value {
    to_json(&Item::Value(super::overrides::parse_value(raw)), "value")
        .unwrap_or_else(|_| serde_json::Value::String(raw.trim().to_string()))
}

/// Params are handed to nodes as JSON; TOML datetimes become strings.
pub fn to_json(item: &Item, at: &str) -> Result<serde_json::Value, ParamsError> {
    use serde_json::Value as J;
    let below = |seg: Seg| {
        move |mut e: ParamsError| {
            e.below.insert(0, seg);
            e
        }
    };
    let table = |t: &dyn TableLike| -> Result<J, ParamsError> {
        t.iter()
            .map(|(k, v)| {
                let value = to_json(v, &format!("{at}.{k}")).map_err(below(Seg::Key(k.into())))?;
                Ok((k.to_string(), value))
            })
            .collect::<Result<serde_json::Map<_, _>, _>>()
            .map(J::Object)
    };
    Ok(match item {
        Item::None => J::Null,
        Item::Table(t) => table(t)?,
        Item::ArrayOfTables(a) => J::Array(
            a.iter()
                .enumerate()
                .map(|(i, t)| table(t).map_err(below(Seg::Index(i))))
                .collect::<Result<_, _>>()?,
        ),
        Item::Value(v) => match v {
            Value::String(s) => J::String(s.value().clone()),
            Value::Integer(i) => J::from(*i.value()),
            Value::Float(f) => serde_json::Number::from_f64(*f.value())
                .map(J::Number)
                .ok_or_else(|| format!("{at}: {} cannot be passed as a parameter", f.value()))?,
            Value::Boolean(b) => J::Bool(*b.value()),
            Value::Datetime(d) => J::String(d.value().to_string()),
            Value::Array(a) => J::Array(
                a.iter()
                    .enumerate()
                    .map(|(i, v)| {
                        to_json(&Item::Value(v.clone()), at).map_err(below(Seg::Index(i)))
                    })
                    .collect::<Result<_, _>>()?,
            ),
            Value::InlineTable(t) => table(t)?,
        },
    })
}

/// Parses a bandwidth like `"54Mbit"`, `"500kbit"` or `"1Gbit"` into bits per second.
pub fn parse_bandwidth(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "bit" => 1.0,
        "kbit" => 1e3,
        "mbit" => 1e6,
        "gbit" => 1e9,
        _ => f64::NAN,
    };
    let bps = number
        .parse::<f64>()
        .map(|n| (n * scale).round())
        .unwrap_or(f64::NAN);
    if bps.is_finite() && bps >= 1.0 && bps < u64::MAX as f64 {
        Ok(bps as u64)
    } else {
        Err(format!(
            "'{text}' is not a bandwidth; write a number and a unit: bit, kbit, Mbit or Gbit (\"54Mbit\")"
        ))
    }
}

/// The longest process name: it names the node, its status and its lockstep services, which
/// iceoryx2 bounds.
pub const MAX_PROCESS_NAME: usize = 64;

pub fn is_process_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= MAX_PROCESS_NAME
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

pub fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    path.metadata()
        .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// The transports this build of Caravan can reach other hosts over: plain TCP, or QUIC (TLS
/// 1.3 inside, both sides' certificates checked) for hosts with a `tls` table.
pub const ENDPOINT_PROTOCOLS: &[&str] = &["tcp", "quic"];

/// Why zenoh's `tls/` links are not offered (the encrypted transport is `quic/`).
pub const TLS_LINK_REFUSED: &str = "zenoh's tls/ link reads and writes one TLS stream from two threads at once (zenoh issue #2557), which drops connections at random and is unsound; use quic/ with the same tls table: QUIC is TLS 1.3 and checks both sides' certificates";

/// A list of zenoh endpoints, each `PROTOCOL/HOST:PORT` (e.g. `tcp/192.168.1.10:7447`).
pub fn endpoints(item: &Item) -> Result<Vec<String>, String> {
    let list = strings(item)
        .map_err(|_| expected("an array of endpoints like \"tcp/192.168.1.10:7447\"", item))?;
    for e in &list {
        endpoint(e)?;
    }
    Ok(list)
}

fn endpoint(text: &str) -> Result<(), String> {
    let parsed: zenoh::config::EndPoint = text
        .parse()
        .map_err(|e| format!("'{text}' is not an endpoint ({e}); write it as \"tcp/HOST:PORT\""))?;
    let protocol = parsed.protocol();
    let protocol = protocol.as_str();
    if protocol == "tls" {
        return Err(format!("'{text}': {TLS_LINK_REFUSED}"));
    }
    if !ENDPOINT_PROTOCOLS.contains(&protocol) {
        return Err(format!(
            "'{text}': protocol '{protocol}' is not available; use {}",
            ENDPOINT_PROTOCOLS.join(", ")
        ));
    }
    let address = parsed.address();
    let port = address.as_str().rsplit_once(':').map(|(_, p)| p);
    match port.map(str::parse::<u16>) {
        Some(Ok(_)) => Ok(()),
        _ => Err(format!(
            "'{text}' has no port; write it as \"{protocol}/HOST:PORT\""
        )),
    }
}
