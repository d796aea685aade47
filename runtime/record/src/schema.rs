//! JSON schemas for recorded channels, generated from the message types themselves: a default
//! value of the type gives the fields the recorder writes, and the type's layout
//! ([`caravan_schemas::describe`]) gives every field's type, so an array is described with its
//! `items` even when the default value's array is empty (Foxglove's JSON-schema reader needs
//! them).
//!
//! Integers that can pass 2⁵³, which JavaScript readers would round, are written as decimal
//! strings: the header's `source_id` (a hash) and `send_wall_ns` (Unix time in ns). Counts and
//! stamps (simulated or since the group's start) stay integers; they are exact up to 2⁵³
//! (104 days in ns).

use caravan_schemas::describe::{Element, Kind, Scalar, TypeLayout};
use caravan_schemas::descriptor::Descriptor;
use serde_json::{Value, json};

/// The key under which a recorded channel's schema carries its type's descriptor (layouts and
/// default), so that a recording replays into a group where no process knows the type. JSON
/// Schema readers (Foxglove's among them) ignore keys they do not know.
pub const DESCRIPTOR_KEY: &str = "x-caravan-descriptor";

fn scalar(s: Scalar) -> Value {
    match s {
        Scalar::F64 | Scalar::F32 => json!({"type": "number"}),
        _ => json!({"type": "integer"}),
    }
}

fn element(e: Element, known: &[TypeLayout]) -> Value {
    match e {
        Element::Scalar(s) => scalar(s),
        Element::Struct(name) => match known.iter().find(|l| l.name == name) {
            Some(layout) => from_layout(layout, known),
            None => json!({}),
        },
    }
}

/// A struct described from its layout alone (array items have no sample value): a
/// `FixedString` (`x_len` + `x: [u8; N]`) is a string, a `FixedVec` (`x_len` + `x: [T; N]`)
/// an array, reserved padding is left out.
fn from_layout(layout: &TypeLayout, known: &[TypeLayout]) -> Value {
    let names: Vec<&str> = layout.fields.iter().map(|f| f.name.as_str()).collect();
    let mut props = serde_json::Map::new();
    for f in &layout.fields {
        let counted = |base: &str| names.contains(&base);
        if f.name.starts_with('_') || f.name.strip_suffix("_len").is_some_and(counted) {
            continue;
        }
        let has_len = names.contains(&format!("{}_len", f.name).as_str());
        let schema = match f.kind {
            Kind::Array(Element::Scalar(Scalar::U8), _) if has_len => json!({"type": "string"}),
            Kind::Array(e, _) => json!({"type": "array", "items": element(e, known)}),
            Kind::Scalar(s) => scalar(s),
            Kind::Struct(_) => element(f.kind.element(), known),
        };
        props.insert(f.name.clone(), schema);
    }
    json!({"type": "object", "properties": props})
}

/// The schema of values shaped like `sample`, typed by `layout` where it names the field.
fn describe(sample: &Value, layout: Option<&TypeLayout>, known: &[TypeLayout]) -> Value {
    let field = |name: &str| layout.and_then(|l| l.fields.iter().find(|f| f.name == name));
    match sample {
        Value::Null => json!({}),
        Value::Bool(_) => json!({"type": "boolean"}),
        Value::Number(n) if n.is_f64() => json!({"type": "number"}),
        Value::Number(_) => json!({"type": "integer"}),
        Value::String(_) => json!({"type": "string"}),
        Value::Array(items) => match items.first() {
            Some(first) => json!({"type": "array", "items": describe(first, None, known)}),
            None => json!({"type": "array", "items": {}}),
        },
        Value::Object(fields) => {
            let mut props = serde_json::Map::new();
            for (k, v) in fields {
                let schema = match (field(k).map(|f| f.kind), v) {
                    (Some(Kind::Array(e, _)), Value::Array(_)) => {
                        json!({"type": "array", "items": element(e, known)})
                    }
                    (Some(Kind::Struct(name)), _) => {
                        describe(v, known.iter().find(|l| l.name == name), known)
                    }
                    (Some(Kind::Scalar(s)), Value::Number(_)) => scalar(s),
                    _ => describe(v, None, known),
                };
                props.insert(k.clone(), schema);
            }
            json!({"type": "object", "properties": props})
        }
    }
}

/// The schema of a recorded message of the type `descriptor` describes: the payload's fields
/// plus `header`.
pub fn for_type(descriptor: &Descriptor, with_wall_clock: bool) -> Value {
    let payload = descriptor
        .default_bytes()
        .and_then(|bytes| descriptor.view(&bytes))
        .unwrap_or(Value::Null);
    let known = descriptor.layouts();
    let mut schema = describe(&payload, Some(descriptor.layout()), known);
    schema["title"] = json!(descriptor.type_name());
    schema["properties"]["header"] = header_schema(with_wall_clock);
    schema[DESCRIPTOR_KEY] = descriptor.to_json();
    schema
}

/// The descriptor a recorded schema (its data) carries: `None` in a recording made before
/// recordings carried descriptors, an error when it does not describe a type.
pub fn recorded_descriptor(schema: &[u8]) -> Option<Result<Descriptor, String>> {
    let json: Value = serde_json::from_slice(schema).ok()?;
    let d = json.get(DESCRIPTOR_KEY)?;
    Some(Descriptor::from_json(d))
}

fn header_schema(with_wall_clock: bool) -> Value {
    let mut props = json!({
        "seq": {"type": "integer"},
        "stamp_ns": {"type": "integer"},
        "source_id": {"type": "string", "description": "u64 in decimal"},
    });
    if with_wall_clock {
        props["send_wall_ns"] = json!({"type": "string", "description": "u64 in decimal"});
    }
    json!({"type": "object", "properties": props})
}

/// The header as the recorder writes it (see the module doc for the strings), as a value: the
/// text of [`write_header_json`] read back.
pub fn header_json(h: &caravan_schemas::Header, with_wall_clock: bool) -> Value {
    let mut text = Vec::new();
    write_header_json(h, with_wall_clock, &mut text);
    serde_json::from_slice(&text).expect("the header's text is JSON")
}

/// Appends the header's JSON text as the recorder writes it, without building a value: the
/// writer's per-message path. Keys come in byte order, as `serde_json::Map` keeps them, so the
/// text is what `serde_json::to_vec` gives of [`header_json`].
pub fn write_header_json(h: &caravan_schemas::Header, with_wall_clock: bool, out: &mut Vec<u8>) {
    use std::io::Write;
    out.push(b'{');
    if with_wall_clock {
        // Writing to a Vec cannot fail.
        let _ = write!(out, "\"send_wall_ns\":\"{}\",", h.send_wall_ns);
    }
    let _ = write!(
        out,
        "\"seq\":{},\"source_id\":\"{}\",\"stamp_ns\":{}}}",
        h.seq, h.source_id, h.stamp_ns
    );
}

#[cfg(test)]
mod tests {
    use serde_json::Value;

    #[test]
    fn the_header_text_is_serde_jsons() {
        let h = caravan_schemas::Header {
            seq: 7,
            stamp_ns: 1_500_000_000,
            source_id: u64::MAX,
            send_wall_ns: 1_700_000_000_123_456_789,
        };
        for wall in [false, true] {
            let mut text = Vec::new();
            super::write_header_json(&h, wall, &mut text);
            let expected = serde_json::to_vec(&super::header_json(&h, wall)).unwrap();
            assert_eq!(
                String::from_utf8(text).unwrap(),
                String::from_utf8(expected).unwrap()
            );
            // The numbers a reader can take as JSON numbers are numbers; the u64s beyond
            // JSON's exact integers are decimal strings.
            let mut want = serde_json::json!({
                "seq": 7,
                "stamp_ns": 1_500_000_000u64,
                "source_id": u64::MAX.to_string(),
            });
            if wall {
                want["send_wall_ns"] = "1700000000123456789".into();
            }
            assert_eq!(super::header_json(&h, wall), want);
        }
    }

    /// Every array in `schema` has `items`; returns the paths of those that do not.
    fn arrays_without_items(schema: &Value, path: &str, out: &mut Vec<String>) {
        if schema["type"] == "array" && schema.get("items").is_none() {
            out.push(path.to_string());
        }
        if let Some(props) = schema["properties"].as_object() {
            for (k, v) in props {
                arrays_without_items(v, &format!("{path}.{k}"), out);
            }
        }
        if let Some(items) = schema.get("items") {
            arrays_without_items(items, &format!("{path}[]"), out);
        }
    }

    /// The schema of the catalog's type `name`.
    fn for_name(name: &str, with_wall_clock: bool) -> Value {
        super::for_type(
            caravan_schemas::catalog::descriptor(name).unwrap(),
            with_wall_clock,
        )
    }

    #[test]
    fn pose_schema_lists_fields_and_header() {
        let s = for_name("caravan::Pose2D", false);
        assert_eq!(s["properties"]["theta"]["type"], "number");
        let header = &s["properties"]["header"]["properties"];
        assert_eq!(header["seq"]["type"], "integer");
        assert_eq!(header["source_id"]["type"], "string");
        assert!(header.get("send_wall_ns").is_none());
    }

    #[test]
    fn every_array_of_every_message_type_has_items() {
        for name in caravan_schemas::message_type_names() {
            let s = for_name(name, true);
            let layout = caravan_schemas::catalog::descriptor(name).unwrap().layout();
            let mut missing = Vec::new();
            arrays_without_items(&s, layout.type_name, &mut missing);
            assert!(missing.is_empty(), "arrays without items: {missing:?}");
        }
    }

    #[test]
    fn arrays_are_typed_by_their_elements() {
        let scan = for_name("caravan::LaserScan", false);
        assert_eq!(scan["properties"]["ranges"]["items"]["type"], "number");
        let path = for_name("caravan::Path2D", false);
        let pose = &path["properties"]["poses"]["items"]["properties"];
        assert_eq!(pose["theta"]["type"], "number");
        let map = for_name("caravan::OccupancyGrid", false);
        assert_eq!(map["properties"]["data"]["items"]["type"], "integer");
        let joints = for_name("caravan::JointState", false);
        let joint = &joints["properties"]["joints"]["items"]["properties"];
        assert_eq!(joint["name"]["type"], "string");
        assert_eq!(joint["effort"]["type"], "number");
        assert!(joint.get("name_len").is_none());
    }
}
