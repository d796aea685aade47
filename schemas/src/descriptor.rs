//! A message type's descriptor: its layout and those of the structs it holds, which is all a
//! tool needs to read, show and write messages of a type it was not compiled with.
//!
//! A publisher registers its type's descriptor with its group (see `caravan::types`); the
//! recorder, `caravan topic echo` and `pub`, replay and the Python module look it up by the
//! type's stable name. As JSON a descriptor is `{"layouts": [...], "default": {...}}`: the
//! layouts as `caravan schemas --layout` prints them (`{name, type_name, size, align, fields:
//! [{name, offset, size, type, len?, count?, text?}]}`), the structs held first and the type
//! itself last, and the JSON view of the type's default value (`null`: all zeros), which
//! `topic pub` starts from.

use crate::describe::{Describe, Element, Field, Kind, Scalar, TypeLayout, check};
use serde_json::{Value, json};
use std::collections::BTreeSet;
use std::sync::Mutex;

/// The layouts a message type needs: those of the structs it holds (each after the ones it
/// holds in turn), then its own.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Descriptor {
    layouts: Vec<TypeLayout>,
    /// The JSON view of the type's default value; `null` for all zeros.
    default: Value,
}

/// Scalars by the names a description gives them.
const SCALARS: [Scalar; 8] = [
    Scalar::F64,
    Scalar::F32,
    Scalar::U64,
    Scalar::I64,
    Scalar::U32,
    Scalar::I32,
    Scalar::U8,
    Scalar::I8,
];

/// Largest message a descriptor may describe (a map is 1 MiB and a bit; the bench's largest
/// blob 4 MiB): a descriptor read from a file cannot make a tool allocate without bound.
pub const MAX_MESSAGE_BYTES: usize = 64 << 20;

impl Descriptor {
    /// From layouts in order, the type's own last: see [`crate::describe::Describe::descriptor`].
    pub fn new(layouts: Vec<TypeLayout>) -> Self {
        assert!(!layouts.is_empty(), "a descriptor describes one type");
        Descriptor {
            layouts,
            default: Value::Null,
        }
    }

    /// With the JSON view of the type's default value (see [`crate::descriptor_of`]).
    pub fn with_default(mut self, default: Value) -> Self {
        self.default = default;
        self
    }

    /// The bytes of the type's default value: zeros, with the default's view written over.
    pub fn default_bytes(&self) -> Result<Box<[u8]>, String> {
        let mut bytes = vec![0u8; self.layout().size].into_boxed_slice();
        if !self.default.is_null() {
            self.write(&self.default, &mut bytes)
                .map_err(|e| format!("{}'s default: {e}", self.type_name()))?;
        }
        Ok(bytes)
    }

    /// Everything a tool needs to read `T`: the layouts of the structs it holds, then its own.
    pub fn of<T: Describe>() -> Self {
        let mut layouts = Vec::new();
        T::dependencies(&mut layouts);
        layouts.push(T::layout());
        Descriptor::new(layouts)
    }

    /// Checks that `len` bytes are one value of the type.
    pub fn check_size(&self, len: usize) -> Result<(), String> {
        let layout = self.layout();
        if len == layout.size {
            Ok(())
        } else {
            Err(format!(
                "{} takes {} bytes, not {len}",
                layout.type_name, layout.size
            ))
        }
    }

    /// The type's own layout.
    pub fn layout(&self) -> &TypeLayout {
        self.layouts.last().expect("never empty")
    }

    /// Every layout, the structs held first.
    pub fn layouts(&self) -> &[TypeLayout] {
        &self.layouts
    }

    /// The stable name of the type (`caravan::Pose2D`).
    pub fn type_name(&self) -> &'static str {
        self.layout().type_name
    }

    /// The layout of the struct named `name` (its Rust name, as fields give it).
    pub fn struct_layout(&self, name: &str) -> Option<&TypeLayout> {
        self.layouts.iter().find(|l| l.name == name)
    }

    /// As JSON (see the module doc).
    pub fn to_json(&self) -> Value {
        json!({
            "layouts": self.layouts.iter().map(layout_json).collect::<Vec<_>>(),
            "default": self.default,
        })
    }

    /// Reads a descriptor written by [`Descriptor::to_json`], checking that it makes sense: each
    /// layout's fields lie in order within its size, each struct a field holds is described
    /// before it, counts name integer fields of their struct, text is bytes.
    pub fn from_json(json: &Value) -> Result<Self, String> {
        let items = json["layouts"]
            .as_array()
            .filter(|a| !a.is_empty())
            .ok_or("a descriptor's 'layouts' is a non-empty list")?;
        let mut layouts: Vec<TypeLayout> = Vec::new();
        for (i, item) in items.iter().enumerate() {
            let layout = parse_layout(item, &layouts).map_err(|e| format!("layout {i}: {e}"))?;
            check(&layout, &layouts)?;
            check_counts(&layout)?;
            if layout.size > MAX_MESSAGE_BYTES {
                return Err(format!(
                    "{}: {} bytes, more than the {MAX_MESSAGE_BYTES} a message may take",
                    layout.name, layout.size
                ));
            }
            layouts.push(layout);
        }
        let d = Descriptor::new(layouts).with_default(json["default"].clone());
        d.default_bytes()?;
        Ok(d)
    }
}

/// One layout as JSON (see the module doc).
pub fn layout_json(l: &TypeLayout) -> Value {
    let fields: Vec<Value> = l
        .fields
        .iter()
        .map(|f| {
            let mut v = json!({
                "name": f.name,
                "offset": f.offset,
                "size": f.size,
                "type": f.kind.element().name(),
            });
            if let Some(len) = f.kind.array_len() {
                v["len"] = len.into();
            }
            if !f.count.is_empty() {
                v["count"] = json!(f.count);
            }
            if f.text {
                v["text"] = true.into();
            }
            v
        })
        .collect();
    json!({
        "name": l.name,
        "type_name": l.type_name,
        "size": l.size,
        "align": l.align,
        "fields": fields,
    })
}

/// A name kept for the life of the process: layouts name types with `&'static str`, and a
/// process meets only so many types.
fn intern(name: &str) -> &'static str {
    static NAMES: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());
    let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(known) = names.get(name) {
        return known;
    }
    let leaked: &'static str = Box::leak(name.to_string().into_boxed_str());
    names.insert(leaked);
    leaked
}

fn parse_layout(v: &Value, before: &[TypeLayout]) -> Result<TypeLayout, String> {
    let text = |key: &str| {
        v[key]
            .as_str()
            .filter(|s| !s.is_empty() && s.len() <= 256)
            .ok_or_else(|| format!("'{key}' must be a name of 1 to 256 bytes"))
    };
    let number = |v: &Value, key: &str| {
        v[key]
            .as_u64()
            .map(|n| n as usize)
            .ok_or_else(|| format!("'{key}' must be a whole number"))
    };
    let name = text("name")?;
    let align = number(v, "align")?;
    if !align.is_power_of_two() || align > 4096 {
        return Err(format!(
            "{name}: alignment {align} is not a power of two up to 4096"
        ));
    }
    let mut fields = Vec::new();
    for f in v["fields"].as_array().ok_or("'fields' must be a list")? {
        let field_name = f["name"]
            .as_str()
            .filter(|s| !s.is_empty() && s.len() <= 256)
            .ok_or_else(|| format!("{name}: a field's 'name' must be 1 to 256 bytes"))?;
        let type_name = f["type"]
            .as_str()
            .ok_or_else(|| format!("{name}.{field_name}: 'type' must be a name"))?;
        let element = match SCALARS.iter().find(|s| s.name() == type_name) {
            Some(s) => Element::Scalar(*s),
            None => Element::Struct(
                before
                    .iter()
                    .find(|l| l.name == type_name)
                    .map(|l| l.name)
                    .ok_or_else(|| {
                        format!("{name}.{field_name}: '{type_name}' is not described before it")
                    })?,
            ),
        };
        let kind = match f.get("len") {
            None => match element {
                Element::Scalar(s) => Kind::Scalar(s),
                Element::Struct(n) => Kind::Struct(n),
            },
            Some(_) => Kind::Array(element, number(f, "len")?),
        };
        let mut field = Field::new(field_name, number(f, "offset")?, number(f, "size")?, kind);
        field.text = f["text"].as_bool().unwrap_or(false);
        if let Some(count) = f.get("count") {
            field.count = count
                .as_array()
                .ok_or_else(|| format!("{name}.{field_name}: 'count' must be a list of fields"))?
                .iter()
                .map(|c| c.as_str().map(str::to_string))
                .collect::<Option<_>>()
                .ok_or_else(|| format!("{name}.{field_name}: 'count' must name fields"))?;
        }
        fields.push(field);
    }
    // Sizes come from the file: an element's size times the length must be the field's.
    for f in &fields {
        let element_size = match f.kind.element() {
            Element::Scalar(s) => s.size(),
            Element::Struct(n) => before.iter().find(|l| l.name == n).map_or(0, |l| l.size),
        };
        let expected = element_size.checked_mul(f.kind.array_len().unwrap_or(1));
        if expected != Some(f.size) {
            return Err(format!(
                "{name}.{}: {} bytes, but its type takes {expected:?}",
                f.name, f.size
            ));
        }
    }
    Ok(TypeLayout {
        name: intern(name),
        type_name: intern(text("type_name")?),
        size: number(v, "size")?,
        align,
        fields,
    })
}

/// Counts name integer fields of the same struct and count arrays; text is an array of bytes.
fn check_counts(layout: &TypeLayout) -> Result<(), String> {
    for f in &layout.fields {
        if f.text
            && f.kind != Kind::Array(Element::Scalar(Scalar::U8), f.kind.array_len().unwrap_or(0))
        {
            return Err(format!(
                "{}.{}: text must be an array of u8",
                layout.name, f.name
            ));
        }
        if !f.count.is_empty() && f.kind.array_len().is_none() {
            return Err(format!(
                "{}.{}: only an array is counted",
                layout.name, f.name
            ));
        }
        for c in &f.count {
            let counter = layout.fields.iter().find(|o| o.name == *c);
            let integer = counter.is_some_and(|o| {
                matches!(
                    o.kind,
                    Kind::Scalar(
                        Scalar::U8 | Scalar::U32 | Scalar::U64 | Scalar::I32 | Scalar::I64
                    )
                )
            });
            if !integer {
                return Err(format!(
                    "{}.{}: counted by '{c}', which is not an integer field of {}",
                    layout.name, f.name, layout.name
                ));
            }
        }
    }
    Ok(())
}

/// Whether the JSON view leaves field `name` of `layout` out: the count of exactly one array
/// (a `FixedVec`'s `_len`, a scan's `beam_count`), which the array's length says.
pub fn is_hidden_count(layout: &TypeLayout, name: &str) -> bool {
    layout
        .fields
        .iter()
        .any(|f| matches!(f.count.as_slice(), [only] if only == name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalog::layouts;
    use crate::{LaserScan, OccupancyGrid, Path2D};

    #[test]
    fn every_catalog_type_round_trips_through_json() {
        for name in crate::message_type_names() {
            assert!(crate::catalog::descriptor(name).is_some(), "{name}");
        }
        let all = layouts();
        // The structs that messages only hold (a scene's shapes) are described inside them.
        for layout in all
            .iter()
            .filter(|l| crate::catalog::descriptor(l.type_name).is_some())
        {
            let d = crate::catalog::descriptor(layout.type_name).unwrap();
            assert_eq!(d.layout(), layout);
            assert_eq!(&Descriptor::from_json(&d.to_json()).unwrap(), d);
            // Each struct held is described before it, once.
            for (i, l) in d.layouts().iter().enumerate() {
                check(l, &d.layouts()[..i]).unwrap();
                assert!(all.contains(l));
            }
        }
    }

    /// A catalog type's default bytes are its `PlacementDefault` (identity quaternions…), on
    /// every byte that holds data.
    #[test]
    fn default_bytes_are_the_placement_default() {
        for name in crate::message_type_names() {
            let d = crate::catalog::descriptor(name).unwrap();
            let bytes = d.default_bytes().unwrap();
            let typed = crate::with_message_type!(name, |T| {
                let value = crate::boxed_placement_new::<T>();
                crate::wire::to_wire(value.as_ref()).unwrap()
            })
            .unwrap();
            for &(offset, len) in crate::wire::data_ranges(name).unwrap() {
                assert_eq!(
                    bytes[offset..offset + len],
                    typed[offset..offset + len],
                    "{name} at {offset}"
                );
            }
        }
    }

    /// A `FixedVec` of 8-byte items after a `u32`: its length sits 8 bytes on, not 4.
    #[test]
    fn a_container_aligned_past_its_predecessor_is_described() {
        use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
        #[repr(C)]
        #[derive(Clone, Copy, ZeroCopySend, PlacementDefault, Describe)]
        #[type_name("test::Gap")]
        struct Gap {
            a: u32,
            v: crate::FixedVec<f64, 2>,
        }
        let layout = Gap::layout();
        assert_eq!(layout.fields[1].offset, 8);
        check(&layout, &[]).unwrap();
        let d = Descriptor::of::<Gap>();
        assert_eq!(Descriptor::from_json(&d.to_json()).unwrap(), d);
    }

    #[test]
    fn counts_come_from_the_declaration() {
        let scan = LaserScan::layout();
        let ranges = scan.fields.iter().find(|f| f.name == "ranges").unwrap();
        assert_eq!(ranges.count, ["beam_count"]);
        assert!(is_hidden_count(&scan, "beam_count"));
        let grid = OccupancyGrid::layout();
        let data = grid.fields.iter().find(|f| f.name == "data").unwrap();
        assert_eq!(data.count, ["width", "height"]);
        assert!(!is_hidden_count(&grid, "width"));
        let path = Descriptor::of::<Path2D>();
        assert_eq!(path.layouts()[0].name, "Pose2D");
        assert_eq!(path.layout().fields[1].count, ["poses_len"]);
    }

    #[test]
    fn a_descriptor_that_makes_no_sense_is_refused() {
        let good = Descriptor::of::<Path2D>().to_json()["layouts"].clone();
        let refused = |edit: &dyn Fn(&mut Value)| {
            let mut v = good.clone();
            edit(&mut v);
            Descriptor::from_json(&json!({"layouts": v})).unwrap_err()
        };
        assert!(
            refused(&|v| v[1]["fields"][1]["type"] = "Pose9D".into()).contains("not described")
        );
        assert!(refused(&|v| v[1]["fields"][1]["offset"] = 2.into()).contains("offset"));
        assert!(refused(&|v| v[1]["fields"][1]["size"] = 7.into()).contains("bytes"));
        assert!(refused(&|v| v[1]["fields"][1]["count"] = json!(["nothing"])).contains("counted"));
        assert!(refused(&|v| v[1]["align"] = 3.into()).contains("power of two"));
        assert!(refused(&|v| v[1]["fields"][1]["text"] = true.into()).contains("u8"));
        assert!(Descriptor::from_json(&json!({"layouts": []})).is_err());
        assert!(Descriptor::from_json(&json!([{"name": "x"}])).is_err());
        let bad_default = json!({"layouts": good, "default": {"poses": 3}});
        assert!(
            Descriptor::from_json(&bad_default)
                .unwrap_err()
                .contains("default")
        );
    }
}
