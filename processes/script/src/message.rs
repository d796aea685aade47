//! A command's message: its type found by name, its bytes built once from the JSON (TOML) of
//! the launch file, written over the type's default value as `caravan topic pub` writes them
//! (`caravan_schemas::from_json`): a field left out keeps the default, an unknown field or a
//! value of the wrong type is an error naming it.
//!
//! JSON has no NaN or infinity, and the launcher refuses TOML's `nan` and `inf` in params, yet
//! some types use NaN as "unset" (a `JointCommand`'s velocity or effort: leave that target as
//! it was). A float field therefore also takes the strings `"nan"`, `"inf"` and `"-inf"` (any
//! case), written into the bytes after the JSON.

use caravan_schemas::describe::{Element, Kind, Scalar, TypeLayout};
use caravan_schemas::descriptor::Descriptor;
use serde_json::Value;

/// Where a message's JSON is wrong: the path below `message` (`joints[0].speed`, empty for the
/// message itself) and what is wrong there.
#[derive(Debug, Clone, PartialEq)]
pub struct BadMessage {
    pub path: String,
    pub message: String,
}

/// The descriptor of Caravan's message type named `type_name` (`caravan::JointCommand`).
pub fn descriptor(type_name: &str) -> Result<&'static Descriptor, String> {
    let known = caravan_schemas::message_type_names();
    if !known.contains(&type_name) {
        return Err(format!(
            "unknown message type '{type_name}'; a script publishes Caravan's message types: {}",
            known.join(", ")
        ));
    }
    caravan_schemas::catalog::descriptor(type_name)
        .ok_or_else(|| format!("message type '{type_name}' has no descriptor"))
}

/// The bytes of one message of `descriptor`'s type: its default with `json` written over.
pub fn build(descriptor: &Descriptor, json: &Value) -> Result<Box<[u8]>, BadMessage> {
    let bad = |e: String| {
        // The writer's errors read `path: what`, with `message` for the message itself.
        match e.split_once(": ") {
            Some((path, what)) if !path.contains(' ') => BadMessage {
                path: if path == "message" {
                    String::new()
                } else {
                    path.to_string()
                },
                message: what.to_string(),
            },
            _ => BadMessage {
                path: String::new(),
                message: e,
            },
        }
    };
    let mut bytes = descriptor.default_bytes().map_err(bad)?;
    let mut patches = Vec::new();
    let json = non_finite(descriptor, descriptor.layout(), json, 0, &mut patches);
    descriptor.write(&json, &mut bytes).map_err(bad)?;
    for (offset, scalar, value) in patches {
        match scalar {
            Scalar::F64 => bytes[offset..offset + 8].copy_from_slice(&value.to_ne_bytes()),
            Scalar::F32 => bytes[offset..offset + 4].copy_from_slice(&(value as f32).to_ne_bytes()),
            _ => unreachable!("only floats are patched"),
        }
    }
    Ok(bytes)
}

/// A non-finite number written as a string: `"nan"`, `"inf"`, `"-inf"`, `"+inf"`, any case.
fn non_finite_number(v: &Value) -> Option<f64> {
    match v.as_str()?.to_ascii_lowercase().as_str() {
        "nan" => Some(f64::NAN),
        "inf" | "+inf" | "infinity" => Some(f64::INFINITY),
        "-inf" | "-infinity" => Some(f64::NEG_INFINITY),
        _ => None,
    }
}

/// `json` with each non-finite string at a float field replaced by 0, and the number noted in
/// `patches` as (offset in the message, float type, value). Where `json` does not fit the
/// layout, it is left as it is, for the writer to name the error.
fn non_finite(
    d: &Descriptor,
    layout: &TypeLayout,
    json: &Value,
    base: usize,
    patches: &mut Vec<(usize, Scalar, f64)>,
) -> Value {
    let Value::Object(map) = json else {
        return json.clone();
    };
    let mut out = map.clone();
    for (key, value) in map {
        let Some(f) = layout.fields.iter().find(|f| f.name == *key) else {
            continue;
        };
        let at = base + f.offset;
        let replaced = match (f.kind, value) {
            (Kind::Scalar(s @ (Scalar::F64 | Scalar::F32)), v) => non_finite_number(v).map(|x| {
                patches.push((at, s, x));
                Value::from(0.0)
            }),
            (Kind::Struct(n), v) => d
                .struct_layout(n)
                .map(|inner| non_finite(d, inner, v, at, patches)),
            (Kind::Array(element, len), Value::Array(items)) if !f.text => {
                let stride = f.size / len.max(1);
                let items = items.iter().take(len).enumerate().map(|(i, item)| {
                    let at = at + i * stride;
                    match element {
                        Element::Scalar(s @ (Scalar::F64 | Scalar::F32)) => {
                            match non_finite_number(item) {
                                Some(x) => {
                                    patches.push((at, s, x));
                                    Value::from(0.0)
                                }
                                None => item.clone(),
                            }
                        }
                        Element::Struct(n) => match d.struct_layout(n) {
                            Some(inner) => non_finite(d, inner, item, at, patches),
                            None => item.clone(),
                        },
                        Element::Scalar(_) => item.clone(),
                    }
                });
                let mut items: Vec<Value> = items.collect();
                // Past the capacity: left for the writer to refuse.
                if let Value::Array(all) = value {
                    items.extend(all.iter().skip(len).cloned());
                }
                Some(Value::Array(items))
            }
            _ => None,
        };
        if let Some(v) = replaced {
            out.insert(key.clone(), v);
        }
    }
    Value::Object(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{JointCommand, Twist};
    use serde_json::json;

    /// `bytes` as a `T` (a catalog type: plain numbers).
    fn as_msg<T: caravan_schemas::Message>(bytes: &[u8]) -> Box<T> {
        assert_eq!(bytes.len(), size_of::<T>());
        let mut msg = caravan_schemas::boxed_placement_new::<T>();
        // SAFETY: `bytes` are a whole value of `T`, which is plain numbers.
        unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                (msg.as_mut() as *mut T).cast::<u8>(),
                bytes.len(),
            )
        };
        msg
    }

    #[test]
    fn fields_left_out_keep_the_default_and_non_finite_strings_become_numbers() {
        let d = descriptor("caravan::JointCommand").unwrap();
        let json = json!({"joints": [
            {"name": "shoulder", "position": 0.5},
            {"name": "elbow", "position": "NaN", "velocity": 1.0, "effort": "-inf"},
        ]});
        let cmd = as_msg::<JointCommand>(&build(d, &json).unwrap());
        let j = cmd.joints.as_slice();
        assert_eq!(j.len(), 2);
        assert_eq!(
            (j[0].name.as_str(), j[0].position, j[0].velocity),
            ("shoulder", 0.5, 0.0)
        );
        assert!(j[1].position.is_nan());
        assert_eq!((j[1].velocity, j[1].effort), (1.0, f64::NEG_INFINITY));

        let d = descriptor("caravan::Twist").unwrap();
        let twist = as_msg::<Twist>(&build(d, &json!({"linear": {"x": 0.3}})).unwrap());
        assert_eq!(
            (twist.linear.x, twist.linear.y, twist.angular.z),
            (0.3, 0.0, 0.0)
        );
        let twist = as_msg::<Twist>(&build(d, &json!({})).unwrap());
        assert_eq!(twist.linear.x, 0.0);
    }

    #[test]
    fn bad_messages_name_the_path_below_the_message() {
        let d = descriptor("caravan::JointCommand").unwrap();
        let e = build(d, &json!({"joints": [{"name": "a", "speed": 1.0}]})).unwrap_err();
        assert_eq!(e.path, "joints[0].speed", "{e:?}");
        assert!(e.message.contains("has no field 'speed'"), "{e:?}");
        let e = build(d, &json!({"joints": [{"position": "fast"}]})).unwrap_err();
        assert_eq!(e.path, "joints[0].position", "{e:?}");
        assert!(e.message.contains("expected f64"), "{e:?}");
        let e = build(d, &json!({"joints": 3})).unwrap_err();
        assert_eq!(e.path, "joints", "{e:?}");
        let e = build(d, &json!([1])).unwrap_err();
        assert_eq!(e.path, "", "{e:?}");
        // A string that is not a number, even at a float field.
        let e = build(d, &json!({"joints": [{"effort": "none"}]})).unwrap_err();
        assert_eq!(e.path, "joints[0].effort", "{e:?}");
        assert!(
            descriptor("caravan::Nope")
                .unwrap_err()
                .contains("caravan::JointCommand")
        );
    }
}
