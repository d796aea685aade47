//! Single fields of a message read from its bytes by its descriptor, for a tool that needs a
//! few of them (the recorder's Foxglove views) rather than the whole JSON view. Each reads as
//! the same field of [`Descriptor::view`] would, so a tool can move from one to the other
//! without a change in what it computes: a non-finite float is "no number" (JSON's `null`),
//! an array has only its valid items.

use crate::describe::{Element, Field, Kind, Scalar, TypeLayout};
use crate::descriptor::Descriptor;
use crate::view::valid_items;

/// One struct of a message: the message itself, or a struct inside it.
#[derive(Clone, Copy)]
pub struct Fields<'a> {
    d: &'a Descriptor,
    layout: &'a TypeLayout,
    bytes: &'a [u8],
}

impl Descriptor {
    /// The fields of one message of this type, from its `size` bytes.
    pub fn fields<'a>(&'a self, bytes: &'a [u8]) -> Result<Fields<'a>, String> {
        self.check_size(bytes.len())?;
        Ok(Fields {
            d: self,
            layout: self.layout(),
            bytes,
        })
    }
}

/// A number as its JSON view holds it: `None` if not finite.
fn number(kind: Scalar, b: &[u8]) -> Option<f64> {
    fn to<const N: usize>(b: &[u8]) -> [u8; N] {
        b.try_into().unwrap_or([0; N])
    }
    let v = match kind {
        Scalar::F64 => f64::from_ne_bytes(to(b)),
        Scalar::F32 => f32::from_ne_bytes(to(b)) as f64,
        Scalar::U64 => u64::from_ne_bytes(to(b)) as f64,
        Scalar::I64 => i64::from_ne_bytes(to(b)) as f64,
        Scalar::U32 => u32::from_ne_bytes(to(b)) as f64,
        Scalar::I32 => i32::from_ne_bytes(to(b)) as f64,
        Scalar::U8 => b[0] as f64,
        Scalar::I8 => b[0] as i8 as f64,
    };
    v.is_finite().then_some(v)
}

impl<'a> Fields<'a> {
    fn field(&self, name: &str) -> Option<&'a Field> {
        self.layout.fields.iter().find(|f| f.name == name)
    }

    fn slot(&self, f: &Field) -> &'a [u8] {
        &self.bytes[f.offset..f.offset + f.size]
    }

    /// Field `name` as a number (`serde_json::Value::as_f64` of the view's): `None` if it is
    /// missing, not a number, or not finite.
    pub fn number(&self, name: &str) -> Option<f64> {
        let f = self.field(name)?;
        match f.kind {
            Kind::Scalar(s) => number(s, self.slot(f)),
            _ => None,
        }
    }

    /// Field `name` as an unsigned integer (`Value::as_u64` of the view's): `None` if it is
    /// missing, a float or negative.
    pub fn unsigned(&self, name: &str) -> Option<u64> {
        let f = self.field(name)?;
        let b = self.slot(f);
        match f.kind {
            Kind::Scalar(Scalar::U64) => Some(u64::from_ne_bytes(b.try_into().ok()?)),
            Kind::Scalar(Scalar::U32) => Some(u32::from_ne_bytes(b.try_into().ok()?) as u64),
            Kind::Scalar(Scalar::U8) => Some(b[0] as u64),
            Kind::Scalar(Scalar::I64) => u64::try_from(i64::from_ne_bytes(b.try_into().ok()?)).ok(),
            Kind::Scalar(Scalar::I32) => u64::try_from(i32::from_ne_bytes(b.try_into().ok()?)).ok(),
            Kind::Scalar(Scalar::I8) => u64::try_from(b[0] as i8).ok(),
            _ => None,
        }
    }

    /// Text field `name` (a `FixedString`), `None` if missing or not UTF-8 (the view's "").
    pub fn text(&self, name: &str) -> Option<&'a str> {
        let f = self.field(name).filter(|f| f.text)?;
        let valid = valid_items(self.layout, f, self.bytes);
        std::str::from_utf8(&self.slot(f)[..valid]).ok()
    }

    /// The struct in field `name`, `None` if missing or not a struct.
    pub fn get(&self, name: &str) -> Option<Fields<'a>> {
        let f = self.field(name)?;
        match f.kind {
            Kind::Struct(s) => self.nested(s, self.slot(f)),
            _ => None,
        }
    }

    fn nested(&self, name: &str, bytes: &'a [u8]) -> Option<Fields<'a>> {
        Some(Fields {
            d: self.d,
            layout: self.d.struct_layout(name)?,
            bytes,
        })
    }

    /// The valid items of array `name`: their element, their bytes and the stride.
    fn array(&self, name: &str) -> Option<(Element, &'a [u8], usize)> {
        let f = self.field(name).filter(|f| !f.text)?;
        let Kind::Array(element, len) = f.kind else {
            return None;
        };
        let stride = (f.size / len.max(1)).max(1);
        let valid = valid_items(self.layout, f, self.bytes);
        Some((element, &self.slot(f)[..valid * stride], stride))
    }

    /// The valid numbers of array `name`, a non-finite one as NaN; empty if it is missing or
    /// holds structs.
    pub fn numbers(&self, name: &str) -> Vec<f64> {
        match self.array(name) {
            Some((Element::Scalar(s), bytes, stride)) => bytes
                .chunks_exact(stride)
                .map(|b| number(s, b).unwrap_or(f64::NAN))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The valid items of an array of bytes (`i8` or `u8`), as they lie in memory.
    pub fn bytes(&self, name: &str) -> Option<&'a [u8]> {
        match self.array(name)? {
            (Element::Scalar(Scalar::I8 | Scalar::U8), bytes, _) => Some(bytes),
            _ => None,
        }
    }

    /// The valid structs of array `name`; empty if it is missing or holds numbers.
    pub fn structs(&self, name: &str) -> Vec<Fields<'a>> {
        match self.array(name) {
            Some((Element::Struct(s), bytes, stride)) => bytes
                .chunks_exact(stride)
                .filter_map(|b| self.nested(s, b))
                .collect(),
            _ => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::catalog::descriptor;
    use serde_json::json;

    fn bytes_of(type_name: &str, value: serde_json::Value) -> Vec<u8> {
        let d = descriptor(type_name).unwrap();
        let mut bytes = d.default_bytes().unwrap().into_vec();
        d.write(&value, &mut bytes).unwrap();
        bytes
    }

    #[test]
    fn fields_read_as_the_view_shows_them() {
        let d = descriptor("caravan::LaserScan").unwrap();
        let bytes = bytes_of(
            "caravan::LaserScan",
            json!({"angle_min": -1.0, "angle_max": 1.5, "ranges": [1.0, 2.0, 3.0],
                "intensities": [0.0, 0.0, 0.0]}),
        );
        let mut bytes = bytes;
        // A range that is not finite reads as NaN, and a number that is not as none.
        let at = |name: &str| {
            d.layout()
                .fields
                .iter()
                .find(|f| f.name == name)
                .unwrap()
                .offset
        };
        let second = at("ranges") + 4;
        bytes[second..second + 4].copy_from_slice(&f32::INFINITY.to_ne_bytes());
        let min = at("angle_min");
        bytes[min..min + 4].copy_from_slice(&f32::NAN.to_ne_bytes());
        let scan = d.fields(&bytes).unwrap();
        assert_eq!(scan.number("angle_min"), None);
        let view = d.view(&bytes).unwrap();
        assert_eq!(scan.number("angle_max"), view["angle_max"].as_f64());
        let ranges = scan.numbers("ranges");
        assert_eq!(ranges.len(), 3);
        assert_eq!((ranges[0], ranges[2]), (1.0, 3.0));
        assert!(ranges[1].is_nan());
        assert_eq!(scan.number("no such field"), None);
        assert!(scan.structs("ranges").is_empty());
    }

    #[test]
    fn structs_grids_and_text_read_as_the_view_shows_them() {
        let d = descriptor("caravan::OccupancyGrid").unwrap();
        let bytes = bytes_of(
            "caravan::OccupancyGrid",
            json!({"resolution": 0.5, "width": 2, "height": 2, "origin": {"x": 1.0},
                "data": [-1, 0, 100, 7]}),
        );
        let grid = d.fields(&bytes).unwrap();
        assert_eq!(grid.unsigned("width"), Some(2));
        assert_eq!(grid.unsigned("resolution"), None);
        assert_eq!(grid.get("origin").unwrap().number("x"), Some(1.0));
        assert_eq!(grid.bytes("data").unwrap(), [255, 0, 100, 7]);
        let d = descriptor("caravan::LinkStates").unwrap();
        let bytes = bytes_of(
            "caravan::LinkStates",
            json!({"links": [{"name": "arm", "pose": {"position": {"z": 2.0}}}]}),
        );
        let links = d.fields(&bytes).unwrap().structs("links");
        assert_eq!(links.len(), 1);
        assert_eq!(links[0].text("name"), Some("arm"));
        let z = links[0].get("pose").unwrap().get("position").unwrap();
        assert_eq!(z.number("z"), Some(2.0));
    }
}
