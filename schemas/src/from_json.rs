//! Messages from JSON: the inverse of the JSON views that recordings and `topic echo` print,
//! written straight into a message's bytes as its layout ([`crate::describe`]) says. It serves
//! `caravan topic pub` and `caravan play`, which learn a topic's type only at run time, and it
//! writes in place, so a 4 MiB map never passes through the stack.
//!
//! The rules mirror the JSON views: a `FixedString` is a string, a `FixedVec` an array of at
//! most its capacity (its `_len` is set from it), a fixed array takes at most its length from
//! the front, and a field left out keeps its value (the type's default in a fresh message).
//! A `header` key is ignored, so a recorded message can be given whole. Unknown keys, wrong
//! types, numbers outside their type's range and over-long arrays are errors naming the key.

use crate::describe::{Element, Kind, Scalar, TypeLayout};
use crate::descriptor::{Descriptor, is_hidden_count};
use serde_json::Value;

/// Writes `json` into `bytes`, a value of the message type named `type_name` (its stable name,
/// `caravan::Pose2D`). `bytes` must hold a valid value of that type (a default one, say): the
/// fields the JSON leaves out keep theirs.
pub fn write_message(type_name: &str, json: &Value, bytes: &mut [u8]) -> Result<(), String> {
    crate::catalog::descriptor(type_name)
        .ok_or_else(|| format!("unknown message type '{type_name}'"))?
        .write(json, bytes)
}

impl Descriptor {
    /// Writes `json` into `bytes`, a valid value of the described type (a default one, say):
    /// the fields the JSON leaves out keep theirs. See the module doc for the rules.
    pub fn write(&self, json: &Value, bytes: &mut [u8]) -> Result<(), String> {
        let layout = self.layout();
        self.check_size(bytes.len())?;
        Writer {
            known: self.layouts(),
        }
        .object(layout, json, bytes, "")
    }
}

struct Writer<'k> {
    known: &'k [TypeLayout],
}

impl Writer<'_> {
    fn layout(&self, name: &str) -> Result<&TypeLayout, String> {
        self.known
            .iter()
            .find(|l| l.name == name)
            .ok_or_else(|| format!("no layout for '{name}'"))
    }

    fn object(
        &self,
        layout: &TypeLayout,
        json: &Value,
        bytes: &mut [u8],
        at: &str,
    ) -> Result<(), String> {
        let Value::Object(map) = json else {
            return Err(format!(
                "{}: expected an object for {}, found {json}",
                name(at),
                layout.name
            ));
        };
        let field = |n: &str| layout.fields.iter().find(|f| f.name == n);
        // `x_len` of a string or vector `x` (or a scan's `beam_count`) is set from `x`, never
        // given.
        let is_count = |n: &str| is_hidden_count(layout, n);
        for (key, value) in map {
            let path = if at.is_empty() {
                key.clone()
            } else {
                format!("{at}.{key}")
            };
            if at.is_empty() && key == "header" {
                continue;
            }
            let Some(f) = field(key).filter(|_| !is_count(key)) else {
                let names: Vec<&str> = layout
                    .fields
                    .iter()
                    .map(|f| f.name.as_str())
                    .filter(|n| !is_count(n))
                    .collect();
                return Err(format!(
                    "{path}: {} has no field '{key}'; its fields: {}",
                    layout.name,
                    names.join(", ")
                ));
            };
            // A count the JSON view leaves out (one field counting the array) is set from the
            // array's length; a product of fields (a grid's width × height) is given instead.
            let counter = match f.count.as_slice() {
                [count] => field(count).map(|c| (c.offset, c.kind)),
                _ => None,
            };
            let slot = &mut bytes[f.offset..f.offset + f.size];
            let written = match f.kind {
                Kind::Scalar(s) => scalar(s, value, slot, &path).map(|_| None)?,
                Kind::Struct(n) => self
                    .object(self.layout(n)?, value, slot, &path)
                    .map(|_| None)?,
                Kind::Array(Element::Scalar(Scalar::U8), n) if f.text && value.is_string() => {
                    let text = value.as_str().unwrap_or_default().as_bytes();
                    if text.len() > n {
                        return Err(format!(
                            "{path}: {} bytes, more than the {n} it holds",
                            text.len()
                        ));
                    }
                    slot.fill(0);
                    slot[..text.len()].copy_from_slice(text);
                    Some(text.len())
                }
                Kind::Array(element, n) => Some(self.array(element, n, value, slot, &path)?),
            };
            if let (Some(count), Some((offset, Kind::Scalar(s)))) = (written, counter) {
                let slot = &mut bytes[offset..offset + s.size()];
                scalar(s, &Value::from(count), slot, &path)?;
            }
        }
        Ok(())
    }

    /// Writes the items given from the front of the array; returns how many.
    fn array(
        &self,
        element: Element,
        len: usize,
        json: &Value,
        bytes: &mut [u8],
        at: &str,
    ) -> Result<usize, String> {
        let Value::Array(items) = json else {
            return Err(format!("{at}: expected an array, found {json}"));
        };
        if items.len() > len {
            return Err(format!(
                "{at}: {} items, more than the {len} it holds",
                items.len()
            ));
        }
        let size = bytes.len() / len.max(1);
        for (i, item) in items.iter().enumerate() {
            let slot = &mut bytes[i * size..(i + 1) * size];
            let path = format!("{at}[{i}]");
            match element {
                Element::Scalar(s) => scalar(s, item, slot, &path)?,
                Element::Struct(n) => self.object(self.layout(n)?, item, slot, &path)?,
            }
        }
        Ok(items.len())
    }
}

fn name(at: &str) -> &str {
    if at.is_empty() { "message" } else { at }
}

/// Writes one number in native byte order, refusing what its type cannot hold.
fn scalar(s: Scalar, json: &Value, slot: &mut [u8], at: &str) -> Result<(), String> {
    let bad = || format!("{at}: expected {}, found {json}", s.name());
    let int = || {
        json.as_i64()
            .map(i128::from)
            .or_else(|| json.as_u64().map(i128::from))
            .ok_or_else(bad)
    };
    let ranged = |min: i128, max: i128| -> Result<i128, String> {
        let v = int()?;
        if v < min || v > max {
            return Err(format!(
                "{at}: {v} does not fit in {} ({min}…{max})",
                s.name()
            ));
        }
        Ok(v)
    };
    match s {
        Scalar::F64 => slot.copy_from_slice(&json.as_f64().ok_or_else(bad)?.to_ne_bytes()),
        Scalar::F32 => {
            let v = json.as_f64().ok_or_else(bad)?;
            if v.abs() > f32::MAX as f64 {
                return Err(format!("{at}: {v} does not fit in f32"));
            }
            slot.copy_from_slice(&(v as f32).to_ne_bytes())
        }
        // u64 values may come as decimal strings, as the recordings write large ones.
        Scalar::U64 => {
            let v = match json.as_str() {
                Some(text) => text.parse::<u64>().map_err(|_| bad())?,
                None => ranged(0, u64::MAX as i128)? as u64,
            };
            slot.copy_from_slice(&v.to_ne_bytes())
        }
        Scalar::I64 => slot
            .copy_from_slice(&(ranged(i64::MIN as i128, i64::MAX as i128)? as i64).to_ne_bytes()),
        Scalar::U32 => slot.copy_from_slice(&(ranged(0, u32::MAX as i128)? as u32).to_ne_bytes()),
        Scalar::I32 => slot
            .copy_from_slice(&(ranged(i32::MIN as i128, i32::MAX as i128)? as i32).to_ne_bytes()),
        Scalar::U8 => slot.copy_from_slice(&(ranged(0, u8::MAX as i128)? as u8).to_ne_bytes()),
        Scalar::I8 => {
            slot.copy_from_slice(&(ranged(i8::MIN as i128, i8::MAX as i128)? as i8).to_ne_bytes())
        }
    }
    Ok(())
}

/// Writes `json` into `msg`, a valid message (a default one, say): see [`write_message`].
pub fn write_into<T: crate::Message>(msg: &mut T, json: &Value) -> Result<(), String> {
    // SAFETY: `T` is plain data (ZeroCopySend, repr(C)) whose fields are all numbers or arrays
    // of numbers; the slice covers exactly `msg`, and `write_message` writes valid numbers only.
    let bytes = unsafe {
        core::slice::from_raw_parts_mut((msg as *mut T).cast::<u8>(), core::mem::size_of::<T>())
    };
    write_message(crate::type_name::<T>(), json, bytes)
}

/// Builds a message of type `T` from JSON (on the heap: some messages are megabytes).
pub fn message_from_json<T: crate::Message>(json: &Value) -> Result<Box<T>, String> {
    let mut value = crate::boxed_placement_new::<T>();
    write_into(value.as_mut(), json)?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{JointState, LaserScan, NodeStatus, OccupancyGrid, Path2D, Pose2D};
    use serde_json::json;

    /// A message's JSON view read back gives the same JSON view.
    fn round_trip<T: crate::Message>(json: Value) {
        let msg = message_from_json::<T>(&json).unwrap();
        assert_eq!(serde_json::to_value(msg.as_ref()).unwrap(), json);
    }

    #[test]
    fn json_views_round_trip() {
        round_trip::<Pose2D>(json!({"x": 1.5, "y": -2.0, "theta": 0.25}));
        let mut status = serde_json::to_value(crate::placement_new::<NodeStatus>()).unwrap();
        status["node"] = json!("ping");
        status["steps"] = json!(12);
        round_trip::<NodeStatus>(status);
        let mut path =
            serde_json::to_value(crate::boxed_placement_new::<Path2D>().as_ref()).unwrap();
        path["poses"] =
            json!([{"x": 1.0, "y": 2.0, "theta": 0.0}, {"x": 3.0, "y": 4.0, "theta": 1.0}]);
        round_trip::<Path2D>(path);
        let mut scan =
            serde_json::to_value(crate::boxed_placement_new::<LaserScan>().as_ref()).unwrap();
        scan["ranges"] = json!([1.0, 2.0, 3.0]);
        scan["intensities"] = json!([0.0, 0.5, 1.0]);
        round_trip::<LaserScan>(scan);
        let mut grid =
            serde_json::to_value(crate::boxed_placement_new::<OccupancyGrid>().as_ref()).unwrap();
        grid["width"] = json!(2);
        grid["height"] = json!(2);
        grid["data"] = json!([0, 100, -1, 50]);
        round_trip::<OccupancyGrid>(grid);
        let mut joints =
            serde_json::to_value(crate::boxed_placement_new::<JointState>().as_ref()).unwrap();
        joints["joints"] =
            json!([{"name": "elbow", "position": 0.5, "velocity": 0.0, "effort": 1.0}]);
        round_trip::<JointState>(joints);
    }

    #[test]
    fn left_out_fields_keep_their_defaults_and_the_header_is_ignored() {
        let pose = message_from_json::<Pose2D>(&json!({"x": 2.0, "header": {"seq": 1}})).unwrap();
        assert_eq!((pose.x, pose.y, pose.theta), (2.0, 0.0, 0.0));
        let big = json!({"sim_time_ns": "18446744073709551615"});
        let status = message_from_json::<NodeStatus>(&big).unwrap();
        assert_eq!(status.sim_time_ns, u64::MAX);
    }

    #[test]
    fn bad_values_are_named_with_their_path() {
        let err = |json: Value| message_from_json::<Path2D>(&json).unwrap_err();
        assert_eq!(
            message_from_json::<Pose2D>(&json!({"z": 1.0})).unwrap_err(),
            "z: Pose2D has no field 'z'; its fields: x, y, theta"
        );
        assert_eq!(
            message_from_json::<Pose2D>(&json!({"x": "far"})).unwrap_err(),
            "x: expected f64, found \"far\""
        );
        assert_eq!(
            err(json!({"poses": [{"x": 1.0}, {"x": true}]})),
            "poses[1].x: expected f64, found true"
        );
        let too_many: Vec<Value> = (0..=crate::PATH_MAX_POSES).map(|_| json!({})).collect();
        assert!(err(json!({"poses": too_many})).contains("more than the"));
        assert_eq!(
            message_from_json::<NodeStatus>(&json!({"running": -1})).unwrap_err(),
            "running: -1 does not fit in u32 (0…4294967295)"
        );
        assert!(
            message_from_json::<NodeStatus>(&json!({"node": "x".repeat(65)}))
                .unwrap_err()
                .contains("65 bytes")
        );
        assert_eq!(
            message_from_json::<Pose2D>(&json!([1, 2])).unwrap_err(),
            "message: expected an object for Pose2D, found [1,2]"
        );
    }
}
