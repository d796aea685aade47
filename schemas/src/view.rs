//! The JSON view of a message read from its bytes by its descriptor, for types a tool was not
//! compiled with. It is the view a type's `Serialize` gives (a test holds every catalog type to
//! that): fields in declaration order; a `FixedString` as a string; of an array with a count
//! only its valid items, and a count that alone counts an array (a `FixedVec`'s `_len`, a
//! scan's `beam_count`) left out; numbers as serde writes them.

use crate::describe::{Element, Field, Kind, Scalar, TypeLayout};
use crate::descriptor::{Descriptor, is_hidden_count};
use serde::ser::Serializer;
use serde_json::Value;

impl Descriptor {
    /// The JSON view of one message of this type, from its `size` bytes.
    pub fn view(&self, bytes: &[u8]) -> Result<Value, String> {
        // Read back from its text: one walk of the layout serves both (`view_text.rs`). A
        // float's text reads back as the same float (serde_json's `float_roundtrip`).
        let mut text = Vec::new();
        self.write_json(bytes, None, &mut text)?;
        serde_json::from_slice(&text).map_err(|e| e.to_string())
    }

    /// Appends the JSON text of [`Self::view`] to `out`, with `extra` as one more key (over a
    /// field of that name), straight from the bytes: the same text `serde_json::to_vec` gives
    /// of the view with `extra` inserted (keys sorted, as `serde_json::Map` keeps them), without
    /// building the `Value` tree, which was most of a recording's conversion cost.
    pub fn write_json(
        &self,
        bytes: &[u8],
        extra: Option<(&str, &Value)>,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        let text = extra
            .map(|(key, value)| serde_json::to_vec(value).map(|text| (key, text)))
            .transpose()
            .map_err(|e| e.to_string())?;
        self.write_json_text(bytes, text.as_ref().map(|(k, t)| (*k, t.as_slice())), out)
    }

    /// [`Self::write_json`] with the extra key's value given as its JSON text (`serde_json`'s,
    /// which is not checked), for a writer that renders it without a `Value`.
    pub fn write_json_text(
        &self,
        bytes: &[u8],
        extra: Option<(&str, &[u8])>,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        self.check_size(bytes.len())?;
        self.object(self.layout(), bytes, extra)
            .write_text(out)
            .map_err(|e| e.to_string())
    }

    pub(crate) fn object<'a>(
        &'a self,
        layout: &'a TypeLayout,
        bytes: &'a [u8],
        extra: Option<(&'a str, &'a [u8])>,
    ) -> Object<'a> {
        Object {
            d: self,
            layout,
            bytes,
            extra,
        }
    }
}

/// A struct's fields as a JSON object, serialised from its bytes.
pub(crate) struct Object<'a> {
    pub(crate) d: &'a Descriptor,
    pub(crate) layout: &'a TypeLayout,
    pub(crate) bytes: &'a [u8],
    /// One more key and its JSON text, written over a field of that name.
    pub(crate) extra: Option<(&'a str, &'a [u8])>,
}

/// One value of an [`Object`].
pub(crate) enum Item<'a> {
    Field(&'a Field),
    /// JSON text, written as it is.
    Extra(&'a [u8]),
}

impl<'a> Object<'a> {
    /// The object's keys and values in the order JSON has them: `serde_json::Map` is a
    /// `BTreeMap`, so its keys come out in byte order.
    pub(crate) fn items(&self) -> Vec<(&'a str, Item<'a>)> {
        let layout = self.layout;
        let mut items: Vec<(&str, Item)> = layout
            .fields
            .iter()
            .filter(|f| !is_hidden_count(layout, &f.name))
            .filter(|f| self.extra.is_none_or(|(k, _)| k != f.name))
            .map(|f| (f.name.as_str(), Item::Field(f)))
            .collect();
        if let Some((key, value)) = self.extra {
            items.push((key, Item::Extra(value)));
        }
        items.sort_by(|a, b| a.0.cmp(b.0));
        items
    }
}

impl<'a> Object<'a> {
    pub(crate) fn field(&self, f: &'a Field) -> FieldValue<'a> {
        let slot = &self.bytes[f.offset..f.offset + f.size];
        match f.kind {
            Kind::Scalar(s) => FieldValue::Scalar(s, slot),
            Kind::Struct(name) => self.nested(name, slot),
            Kind::Array(element, len) => {
                let valid = valid_items(self.layout, f, self.bytes);
                if f.text {
                    FieldValue::Text(std::str::from_utf8(&slot[..valid]).unwrap_or(""))
                } else {
                    FieldValue::Array {
                        owner: Object {
                            extra: None,
                            ..*self
                        },
                        element,
                        items: &slot[..valid * (f.size / len.max(1))],
                        stride: f.size / len.max(1),
                    }
                }
            }
        }
    }

    pub(crate) fn nested(&self, name: &str, bytes: &'a [u8]) -> FieldValue<'a> {
        match self.d.struct_layout(name) {
            Some(layout) => FieldValue::Struct(self.d.object(layout, bytes, None)),
            // A checked descriptor describes every struct it holds.
            None => FieldValue::Null,
        }
    }
}

/// One field's value, serialised from its bytes.
pub(crate) enum FieldValue<'a> {
    Scalar(Scalar, &'a [u8]),
    Struct(Object<'a>),
    Text(&'a str),
    Array {
        /// The struct the array is a field of (for the descriptor).
        owner: Object<'a>,
        element: Element,
        /// The valid items' bytes.
        items: &'a [u8],
        stride: usize,
    },
    Null,
}

/// How many items of array field `f` of `layout` are valid in `bytes` (the struct's): all,
/// or the product of its counts, at most its length.
pub(crate) fn valid_items(layout: &TypeLayout, f: &Field, bytes: &[u8]) -> usize {
    let len = f.kind.array_len().unwrap_or(1);
    if f.count.is_empty() {
        return len;
    }
    let product = f.count.iter().fold(1u128, |n, c| {
        n.saturating_mul(integer(layout, c, bytes) as u128)
    });
    product.min(len as u128) as usize
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

/// One number, as `serde_json::to_value` of the number gives it (a non-finite float is
/// `null`). An `f32` is written as the `f64` it widens to, as a `Value` holds it: the
/// recordings have always had `0.10000000149011612` for `0.1f32`.
pub(crate) fn scalar<S: Serializer>(kind: Scalar, b: &[u8], s: S) -> Result<S::Ok, S::Error> {
    fn to<const N: usize>(b: &[u8]) -> [u8; N] {
        b.try_into().unwrap_or([0; N])
    }
    match kind {
        Scalar::F64 => s.serialize_f64(f64::from_ne_bytes(to(b))),
        Scalar::F32 => s.serialize_f64(f32::from_ne_bytes(to(b)) as f64),
        Scalar::U64 => s.serialize_u64(u64::from_ne_bytes(to(b))),
        Scalar::I64 => s.serialize_i64(i64::from_ne_bytes(to(b))),
        Scalar::U32 => s.serialize_u32(u32::from_ne_bytes(to(b))),
        Scalar::I32 => s.serialize_i32(i32::from_ne_bytes(to(b))),
        Scalar::U8 => s.serialize_u8(b[0]),
        Scalar::I8 => s.serialize_i8(b[0] as i8),
    }
}

/// A `Vec` written to a byte at a time where serde_json writes a few (a comma, a digit or
/// three), which `extend_from_slice` would copy with a call each.
pub(crate) struct Bytes<'a>(pub(crate) &'a mut Vec<u8>);

impl std::io::Write for Bytes<'_> {
    #[inline]
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.write_all(buf)?;
        Ok(buf.len())
    }

    #[inline]
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        if buf.len() <= 4 {
            for &b in buf {
                self.0.push(b);
            }
        } else {
            self.0.extend_from_slice(buf);
        }
        Ok(())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
#[path = "view_tests.rs"]
mod tests;
