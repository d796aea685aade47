//! The JSON view of a message read from its bytes by its descriptor, for types a tool was not
//! compiled with. It is the view a type's `Serialize` gives (a test holds every catalog type to
//! that): fields in declaration order; a `FixedString` as a string; of an array with a count
//! only its valid items, and a count that alone counts an array (a `FixedVec`'s `_len`, a
//! scan's `beam_count`) left out; numbers as serde writes them.

use crate::describe::{Element, Kind, Scalar, TypeLayout};
use crate::descriptor::{Descriptor, is_hidden_count};
use serde_json::{Map, Value};

impl Descriptor {
    /// The JSON view of one message of this type, from its `size` bytes.
    pub fn view(&self, bytes: &[u8]) -> Result<Value, String> {
        let layout = self.layout();
        self.check_size(bytes.len())?;
        Ok(self.object(layout, bytes))
    }

    fn object(&self, layout: &TypeLayout, bytes: &[u8]) -> Value {
        let mut map = Map::new();
        for f in &layout.fields {
            if is_hidden_count(layout, &f.name) {
                continue;
            }
            let slot = &bytes[f.offset..f.offset + f.size];
            let value = match f.kind {
                Kind::Scalar(s) => scalar(s, slot),
                Kind::Struct(name) => self.nested(name, slot),
                Kind::Array(element, len) => {
                    let valid = if f.count.is_empty() {
                        len
                    } else {
                        let product = f.count.iter().fold(1u128, |n, c| {
                            n.saturating_mul(integer(layout, c, bytes) as u128)
                        });
                        product.min(len as u128) as usize
                    };
                    let stride = f.size / len.max(1);
                    if f.text {
                        let text = std::str::from_utf8(&slot[..valid]).unwrap_or("");
                        Value::String(text.to_string())
                    } else {
                        let items = (0..valid).map(|i| {
                            let item = &slot[i * stride..(i + 1) * stride];
                            match element {
                                Element::Scalar(s) => scalar(s, item),
                                Element::Struct(name) => self.nested(name, item),
                            }
                        });
                        Value::Array(items.collect())
                    }
                }
            };
            map.insert(f.name.clone(), value);
        }
        Value::Object(map)
    }

    fn nested(&self, name: &str, bytes: &[u8]) -> Value {
        match self.struct_layout(name) {
            Some(layout) => self.object(layout, bytes),
            // A checked descriptor describes every struct it holds.
            None => Value::Null,
        }
    }
}

/// The integer field `name` of `layout` in `bytes`; 0 if it is not one.
fn integer(layout: &TypeLayout, name: &str, bytes: &[u8]) -> u64 {
    match layout.fields.iter().find(|f| f.name == name) {
        Some(f) => match f.kind {
            Kind::Scalar(s) => count_value(s, &bytes[f.offset..f.offset + f.size]),
            _ => 0,
        },
        None => 0,
    }
}

/// A count read from its bytes: an integer, a negative one as 0; 0 for a float, which counts
/// nothing.
pub(crate) fn count_value(kind: Scalar, slot: &[u8]) -> u64 {
    match kind {
        Scalar::U8 => slot[0] as u64,
        Scalar::U32 => u32::from_ne_bytes(slot.try_into().unwrap_or_default()) as u64,
        Scalar::I32 => i32::from_ne_bytes(slot.try_into().unwrap_or_default()).max(0) as u64,
        Scalar::U64 => u64::from_ne_bytes(slot.try_into().unwrap_or_default()),
        Scalar::I64 => i64::from_ne_bytes(slot.try_into().unwrap_or_default()).max(0) as u64,
        _ => 0,
    }
}

/// One number, as `serde_json::to_value` gives it (a non-finite float is `null`).
fn scalar(s: Scalar, b: &[u8]) -> Value {
    fn to<const N: usize>(b: &[u8]) -> [u8; N] {
        b.try_into().unwrap_or([0; N])
    }
    let value = match s {
        Scalar::F64 => serde_json::to_value(f64::from_ne_bytes(to(b))),
        Scalar::F32 => serde_json::to_value(f32::from_ne_bytes(to(b))),
        Scalar::U64 => serde_json::to_value(u64::from_ne_bytes(to(b))),
        Scalar::I64 => serde_json::to_value(i64::from_ne_bytes(to(b))),
        Scalar::U32 => serde_json::to_value(u32::from_ne_bytes(to(b))),
        Scalar::I32 => serde_json::to_value(i32::from_ne_bytes(to(b))),
        Scalar::U8 => serde_json::to_value(b[0]),
        Scalar::I8 => serde_json::to_value(b[0] as i8),
    };
    value.unwrap_or(Value::Null)
}

#[cfg(test)]
#[path = "view_tests.rs"]
mod tests;
