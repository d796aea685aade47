//! A number inside a message, named by a path in the message's JSON view: `pose.position.x`,
//! `joints[1].position` (an array's item by index), `joints[shoulder].position` (the item whose
//! name is `shoulder`: an array of structs with a text field, the first such field compared).
//!
//! A path is resolved once against the type's layout ([`FieldPath::resolve`]), which refuses a
//! field the type does not have, an index past an array's capacity and a path that ends at a
//! struct; it is then read straight from a message's bytes ([`FieldPath::read`]), where an
//! item past an array's valid length, or a name no item has, reads as no value.

use caravan_schemas::describe::{Element, Kind, Scalar, TypeLayout};
use caravan_schemas::descriptor::{Descriptor, is_hidden_count};

/// Reads `buf.len()` bytes of a message from byte `offset` into `buf`.
pub type Read<'a> = dyn Fn(usize, &mut [u8]) + 'a;

/// A resolved path to one number of a message type.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldPath {
    steps: Vec<Step>,
    /// The number at the end, at this offset in the struct the steps lead to.
    offset: usize,
    scalar: Scalar,
}

/// Which item of an array a path takes.
#[derive(Debug, Clone, PartialEq)]
enum Item {
    Index(usize),
    /// The item whose text field at `offset` (`len` bytes, its length in the integer at
    /// `count`) reads `name`.
    Named {
        name: String,
        offset: usize,
        len: usize,
        count: (usize, Scalar),
    },
}

/// One step down from a struct (at the running base offset) into a field.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    /// Into a struct field at this offset.
    Struct(usize),
    /// Into an item of an array at `offset` of items `stride` bytes long, of which the
    /// integer fields `counts` (same struct) give the valid number (all when empty).
    Array {
        offset: usize,
        stride: usize,
        capacity: usize,
        counts: Vec<(usize, Scalar)>,
        item: Item,
    },
}

impl FieldPath {
    /// Resolves `path` against `descriptor`'s type; the error names the part of the path.
    pub fn resolve(descriptor: &Descriptor, path: &str) -> Result<FieldPath, String> {
        let mut layout = descriptor.layout();
        let mut steps = Vec::new();
        let mut walked = String::new();
        let parts: Vec<&str> = path.split('.').collect();
        for (k, part) in parts.iter().enumerate() {
            let (key, item) = split_item(part).map_err(|e| format!("field '{path}': {e}"))?;
            let at = |walked: &str| {
                if walked.is_empty() {
                    key.to_string()
                } else {
                    format!("{walked}.{key}")
                }
            };
            let fields = || visible_fields(layout).join(", ");
            let Some(f) = layout
                .fields
                .iter()
                .find(|f| f.name == key && !is_hidden_count(layout, key))
            else {
                return Err(format!(
                    "field '{path}': {} has no field '{key}'; its fields: {}",
                    layout.name,
                    fields()
                ));
            };
            walked = at(&walked);
            let last = k + 1 == parts.len();
            let (kind, offset) = match (f.kind, item) {
                (Kind::Array(_, _), _) if f.text => {
                    return Err(format!("field '{path}': {walked} is text, not a number"));
                }
                (Kind::Array(element, capacity), Some(item)) => {
                    let stride = f.size / capacity.max(1);
                    let counts = f
                        .count
                        .iter()
                        .map(|c| integer_field(layout, c))
                        .collect::<Option<Vec<_>>>()
                        .ok_or_else(|| format!("field '{path}': {walked} has no usable count"))?;
                    let item = match item.parse::<usize>() {
                        Ok(i) if i < capacity => Item::Index(i),
                        Ok(i) => {
                            return Err(format!(
                                "field '{path}': index {i} of {walked}, which holds {capacity}"
                            ));
                        }
                        Err(_) => named_item(descriptor, element, item)
                            .map_err(|e| format!("field '{path}': {walked}: {e}"))?,
                    };
                    steps.push(Step::Array {
                        offset: f.offset,
                        stride,
                        capacity,
                        counts,
                        item,
                    });
                    walked.push_str(&format!("[{}]", part.split_once('[').map_or("", |p| p.1)));
                    let kind = match element {
                        Element::Scalar(s) => Kind::Scalar(s),
                        Element::Struct(n) => Kind::Struct(n),
                    };
                    (kind, 0)
                }
                (Kind::Array(_, _), None) => {
                    return Err(format!(
                        "field '{path}': {walked} is an array; take an item: {walked}[0], or \
                         {walked}[NAME] for the item of that name"
                    ));
                }
                (_, Some(_)) => {
                    return Err(format!(
                        "field '{path}': {walked} is not an array, so it has no items"
                    ));
                }
                (kind, None) => (kind, f.offset),
            };
            match kind {
                Kind::Scalar(scalar) if last => {
                    return Ok(FieldPath {
                        steps,
                        offset,
                        scalar,
                    });
                }
                Kind::Scalar(_) => {
                    return Err(format!(
                        "field '{path}': {walked} is a number, with no fields below it"
                    ));
                }
                Kind::Struct(name) => {
                    let inner = descriptor
                        .struct_layout(name)
                        .ok_or_else(|| format!("field '{path}': no layout for '{name}'"))?;
                    if last {
                        return Err(format!(
                            "field '{path}': {walked} is a {name}, not a number; name one of its \
                             fields: {}",
                            visible_fields(inner).join(", ")
                        ));
                    }
                    if offset != 0 {
                        steps.push(Step::Struct(offset));
                    }
                    layout = inner;
                }
                Kind::Array(..) => unreachable!("an array's items are scalars or structs"),
            }
        }
        Err(format!("field '{path}': empty"))
    }

    /// The number in the message `read` reads; `None` where an item is missing (past an
    /// array's valid length, or no item of the name).
    pub fn read(&self, read: &Read) -> Option<f64> {
        let mut base = 0usize;
        for step in &self.steps {
            match step {
                Step::Struct(offset) => base += offset,
                Step::Array {
                    offset,
                    stride,
                    capacity,
                    counts,
                    item,
                } => {
                    let valid = if counts.is_empty() {
                        *capacity
                    } else {
                        let product = counts.iter().fold(1u128, |n, (at, s)| {
                            n.saturating_mul(scalar(read, base + at, *s).max(0.0) as u128)
                        });
                        product.min(*capacity as u128) as usize
                    };
                    let items = base + offset;
                    let index = match item {
                        Item::Index(i) => *i,
                        Item::Named {
                            name,
                            offset: text,
                            len,
                            count,
                        } => (0..valid).find(|i| {
                            let at = items + i * stride;
                            let n =
                                (scalar(read, at + count.0, count.1).max(0.0) as usize).min(*len);
                            let mut bytes = vec![0u8; n];
                            read(at + text, &mut bytes);
                            bytes == name.as_bytes()
                        })?,
                    };
                    if index >= valid {
                        return None;
                    }
                    base = items + index * stride;
                }
            }
        }
        Some(scalar(read, base + self.offset, self.scalar))
    }
}

/// `name[item]` as (`name`, `Some(item)`), `name` as (`name`, `None`).
fn split_item(part: &str) -> Result<(&str, Option<&str>), String> {
    match part.split_once('[') {
        None if !part.is_empty() => Ok((part, None)),
        None => Err("an empty part".into()),
        Some((key, rest)) => match rest.strip_suffix(']') {
            Some(item) if !key.is_empty() && !item.is_empty() && !item.contains(['[', ']']) => {
                Ok((key, Some(item)))
            }
            _ => Err(format!("'{part}' is not `name` or `name[item]`")),
        },
    }
}

/// The fields a JSON view shows (counts of one array left out).
fn visible_fields(layout: &TypeLayout) -> Vec<&str> {
    layout
        .fields
        .iter()
        .map(|f| f.name.as_str())
        .filter(|n| !is_hidden_count(layout, n))
        .collect()
}

/// The integer field `name` of `layout`: its offset and type.
fn integer_field(layout: &TypeLayout, name: &str) -> Option<(usize, Scalar)> {
    let f = layout.fields.iter().find(|f| f.name == name)?;
    match f.kind {
        Kind::Scalar(s @ (Scalar::U8 | Scalar::U32 | Scalar::U64 | Scalar::I32 | Scalar::I64)) => {
            Some((f.offset, s))
        }
        _ => None,
    }
}

/// The item of an array of `element` named `name`: compared with the struct's first text field.
fn named_item(descriptor: &Descriptor, element: Element, name: &str) -> Result<Item, String> {
    let Element::Struct(s) = element else {
        return Err(format!(
            "'{name}' is not an index, and numbers have no names"
        ));
    };
    let layout = descriptor
        .struct_layout(s)
        .ok_or_else(|| format!("no layout for '{s}'"))?;
    let text = layout.fields.iter().find(|f| f.text).ok_or_else(|| {
        format!("'{name}' is not an index, and a {s} has no name to select it by")
    })?;
    let (Kind::Array(_, len), [count]) = (text.kind, text.count.as_slice()) else {
        return Err(format!("{s}'s text field '{}' has no length", text.name));
    };
    if name.len() > len {
        return Err(format!(
            "name '{name}' is longer than the {len} bytes a name holds"
        ));
    }
    let count = integer_field(layout, count)
        .ok_or_else(|| format!("{s}'s text field '{}' has no length", text.name))?;
    Ok(Item::Named {
        name: name.to_string(),
        offset: text.offset,
        len,
        count,
    })
}

/// The number of type `s` at `offset`, as f64.
fn scalar(read: &Read, offset: usize, s: Scalar) -> f64 {
    let mut b = [0u8; 8];
    let b = &mut b[..s.size()];
    read(offset, b);
    let to = |b: &[u8]| -> [u8; 8] {
        let mut full = [0u8; 8];
        full[..b.len()].copy_from_slice(b);
        full
    };
    match s {
        Scalar::F64 => f64::from_ne_bytes(to(b)),
        Scalar::F32 => f32::from_ne_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        Scalar::U64 => u64::from_ne_bytes(to(b)) as f64,
        Scalar::I64 => i64::from_ne_bytes(to(b)) as f64,
        Scalar::U32 => u32::from_ne_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        Scalar::I32 => i32::from_ne_bytes(b.try_into().unwrap_or([0; 4])) as f64,
        Scalar::U8 => b[0] as f64,
        Scalar::I8 => b[0] as i8 as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{JointState, JointValue, Name, Odometry};

    fn descriptor(name: &str) -> &'static Descriptor {
        caravan_schemas::catalog::descriptor(name).unwrap()
    }

    /// Reads `path` from `msg` through its bytes.
    fn read<T: caravan_schemas::Message>(msg: &T, path: &str) -> Option<f64> {
        let d = descriptor(caravan_schemas::type_name::<T>());
        let p = FieldPath::resolve(d, path).unwrap();
        let base = (msg as *const T).cast::<u8>();
        p.read(&|offset, buf: &mut [u8]| {
            assert!(offset + buf.len() <= size_of::<T>());
            // SAFETY: within `msg`, at a field's bytes.
            unsafe { std::ptr::copy_nonoverlapping(base.add(offset), buf.as_mut_ptr(), buf.len()) }
        })
    }

    #[test]
    fn reads_nested_fields_items_by_index_and_by_name() {
        let mut odom = caravan_schemas::placement_new::<Odometry>();
        odom.pose.position.x = 3.5;
        odom.twist.angular.z = -1.0;
        odom.pose_covariance[7] = 2.0;
        odom.pose.orientation.w = 1.0;
        assert_eq!(read(&odom, "pose.position.x"), Some(3.5));
        assert_eq!(read(&odom, "twist.angular.z"), Some(-1.0));
        assert_eq!(read(&odom, "pose.orientation.w"), Some(1.0));
        assert_eq!(read(&odom, "pose_covariance[7]"), Some(2.0));

        let mut js = caravan_schemas::placement_new::<JointState>();
        for (name, position) in [("shoulder", 0.25), ("elbow", -0.5)] {
            let _ = js.joints.push(JointValue {
                name: Name::new(name),
                position,
                ..JointValue::default()
            });
        }
        assert_eq!(read(&js, "joints[1].position"), Some(-0.5));
        assert_eq!(read(&js, "joints[shoulder].position"), Some(0.25));
        assert_eq!(read(&js, "joints[elbow].position"), Some(-0.5));
        // Past the valid items, or a name no joint has: no value.
        assert_eq!(read(&js, "joints[2].position"), None);
        assert_eq!(read(&js, "joints[wrist].position"), None);
        assert_eq!(read(&js, "joints[shoulde].position"), None);
    }

    #[test]
    fn refuses_paths_the_type_does_not_have() {
        let odom = descriptor("caravan::Odometry");
        let js = descriptor("caravan::JointState");
        let err = |d, path| FieldPath::resolve(d, path).unwrap_err();
        let e = err(odom, "pose.position.q");
        assert!(
            e.contains("Vector3 has no field 'q'") || e.contains("has no field 'q'"),
            "{e}"
        );
        assert!(e.contains("x, y, z"), "{e}");
        assert!(err(odom, "pose.position").contains("not a number"));
        assert!(err(odom, "pose.position.x.y").contains("is a number"));
        assert!(err(odom, "pose_covariance").contains("is an array"));
        assert!(err(odom, "pose_covariance[36]").contains("which holds 36"));
        assert!(err(odom, "pose[0].x").contains("not an array"));
        assert!(err(js, "joints[0].name").contains("is text"));
        assert!(err(js, "joints_len").contains("has no field 'joints_len'"));
        assert!(err(js, "joints[].position").contains("not `name` or `name[item]`"));
        assert!(err(odom, "pose..x").contains("empty part"));
        let long = format!("joints[{}].position", "j".repeat(61));
        assert!(err(js, &long).contains("longer than the 60 bytes"));
    }
}
