//! The JSON text of a view written straight into a buffer: the recording writer's path.
//!
//! The text is exactly what `serde_json::to_vec` gives of the type's serde value (the tests
//! hold it to that for every catalog type), and the view is read back from it. Objects and
//! arrays are written here rather than through serde's per-element calls, and a byte array
//! (a map's quarter of a million cells) from a table of the 256 numbers' texts. Numbers and
//! strings still go through serde_json, one at a time, so their text cannot drift from it.

use crate::describe::{Element, Scalar};
use crate::view::{Bytes, FieldValue, Item, Object, scalar};
use serde::Serialize;

type Json<'a> = serde_json::Serializer<Bytes<'a>>;

impl Object<'_> {
    /// Appends the object's JSON text to `out`.
    pub(crate) fn write_text(&self, out: &mut Vec<u8>) -> Result<(), serde_json::Error> {
        out.push(b'{');
        for (n, (name, item)) in self.items().into_iter().enumerate() {
            if n > 0 {
                out.push(b',');
            }
            name.serialize(&mut Json::new(Bytes(out)))?;
            out.push(b':');
            match item {
                Item::Extra(text) => out.extend_from_slice(text),
                Item::Field(f) => self.field(f).write_text(out)?,
            }
        }
        out.push(b'}');
        Ok(())
    }
}

impl FieldValue<'_> {
    fn write_text(&self, out: &mut Vec<u8>) -> Result<(), serde_json::Error> {
        match self {
            FieldValue::Scalar(kind, bytes) => scalar(*kind, bytes, &mut Json::new(Bytes(out))),
            FieldValue::Struct(object) => object.write_text(out),
            FieldValue::Text(text) => text.serialize(&mut Json::new(Bytes(out))),
            FieldValue::Null => {
                out.extend_from_slice(b"null");
                Ok(())
            }
            FieldValue::Array {
                owner,
                element,
                items,
                stride,
            } => {
                let stride = (*stride).max(1);
                out.push(b'[');
                match element {
                    Element::Scalar(Scalar::U8) => bytes_text(items, false, out),
                    Element::Scalar(Scalar::I8) => bytes_text(items, true, out),
                    Element::Scalar(kind) => each(items, stride, out, |item, out| {
                        scalar(*kind, item, &mut Json::new(Bytes(out)))
                    })?,
                    Element::Struct(name) => each(items, stride, out, |item, out| {
                        owner.nested(name, item).write_text(out)
                    })?,
                }
                out.push(b']');
                Ok(())
            }
        }
    }
}

/// Appends `write` of each item of `stride` bytes, separated by commas.
fn each(
    items: &[u8],
    stride: usize,
    out: &mut Vec<u8>,
    write: impl Fn(&[u8], &mut Vec<u8>) -> Result<(), serde_json::Error>,
) -> Result<(), serde_json::Error> {
    for (n, item) in items.chunks_exact(stride).enumerate() {
        if n > 0 {
            out.push(b',');
        }
        write(item, out)?;
    }
    Ok(())
}

/// The texts of −128 … 255 (`TEXTS[v + 128]`), each followed by a comma, with its length:
/// one copy per byte of an array instead of a formatter's call.
static TEXTS: std::sync::LazyLock<Vec<([u8; 5], u8)>> = std::sync::LazyLock::new(|| {
    (-128i16..=255)
        .map(|v| {
            let text = format!("{v},");
            let mut slot = [0; 5];
            slot[..text.len()].copy_from_slice(text.as_bytes());
            (slot, text.len() as u8)
        })
        .collect()
});

/// Appends `items`, one number each (an `i8` if `signed`, else a `u8`), separated by commas.
fn bytes_text(items: &[u8], signed: bool, out: &mut Vec<u8>) {
    let texts: &[([u8; 5], u8)] = if signed { &TEXTS[..256] } else { &TEXTS[128..] };
    out.reserve(items.len() * 5);
    for &b in items {
        // A signed byte's place is its value + 128, which flipping the top bit gives.
        let (text, len) = &texts[usize::from(if signed { b ^ 0x80 } else { b })];
        // All five bytes, then back to the text's end: a copy of a constant length, which
        // compiles to a move, rather than a call to copy a varying one.
        out.extend_from_slice(text);
        out.truncate(out.len() - 5 + usize::from(*len));
    }
    if !items.is_empty() {
        out.pop(); // the last comma
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_is_written_as_serde_json_writes_it() {
        let all: Vec<u8> = (0..=255).collect();
        let signed: Vec<i8> = all.iter().map(|&b| b as i8).collect();
        for (is_signed, expected) in [
            (false, serde_json::to_vec(&all).unwrap()),
            (true, serde_json::to_vec(&signed).unwrap()),
        ] {
            let mut out = Vec::new();
            bytes_text(&all, is_signed, &mut out);
            assert_eq!(out, &expected[1..expected.len() - 1]);
            let mut out = Vec::new();
            bytes_text(&[], is_signed, &mut out);
            assert!(out.is_empty());
        }
    }
}
