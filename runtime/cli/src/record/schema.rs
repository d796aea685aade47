//! JSON schemas for recorded channels, generated from the message types themselves: a default
//! value of the type is serialised and its structure described, so the schema always matches
//! what the recorder writes.

use serde_json::{Value, json};

/// The JSON schema of values shaped like `sample`.
pub fn describe(sample: &Value) -> Value {
    match sample {
        Value::Null => json!({}),
        Value::Bool(_) => json!({"type": "boolean"}),
        Value::Number(n) if n.is_f64() => json!({"type": "number"}),
        Value::Number(_) => json!({"type": "integer"}),
        Value::String(_) => json!({"type": "string"}),
        // Fixed-capacity containers serialise only their valid part, so a default value's
        // arrays are empty; numbers are the common case and Foxglove accepts any item type.
        Value::Array(items) => match items.first() {
            Some(first) => json!({"type": "array", "items": describe(first)}),
            None => json!({"type": "array"}),
        },
        Value::Object(fields) => {
            let properties: serde_json::Map<String, Value> = fields
                .iter()
                .map(|(k, v)| (k.clone(), describe(v)))
                .collect();
            json!({"type": "object", "properties": properties})
        }
    }
}

/// The schema of a recorded message of type `type_name`: the payload's fields plus `header`.
pub fn for_type(type_name: &str, with_wall_clock: bool) -> Option<Value> {
    let payload = caravan_schemas::with_message_type!(type_name, |T| {
        serde_json::to_value(caravan_schemas::boxed_placement_new::<T>().as_ref())
            .unwrap_or(Value::Null)
    })?;
    let mut schema = describe(&payload);
    schema["title"] = json!(type_name);
    schema["properties"]["header"] = header_schema(with_wall_clock);
    Some(schema)
}

fn header_schema(with_wall_clock: bool) -> Value {
    let mut props = json!({
        "seq": {"type": "integer"},
        "stamp_ns": {"type": "integer"},
        "source_id": {"type": "integer"},
    });
    if with_wall_clock {
        props["send_wall_ns"] = json!({"type": "integer"});
    }
    json!({"type": "object", "properties": props})
}

#[cfg(test)]
mod tests {
    #[test]
    fn pose_schema_lists_fields_and_header() {
        let s = super::for_type("caravan::Pose2D", false).unwrap();
        assert_eq!(s["properties"]["theta"]["type"], "number");
        assert_eq!(
            s["properties"]["header"]["properties"]["seq"]["type"],
            "integer"
        );
        assert!(
            s["properties"]["header"]["properties"]
                .get("send_wall_ns")
                .is_none()
        );
    }
}
