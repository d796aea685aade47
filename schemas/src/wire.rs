//! Messages as bytes and back, for a bridge that copies them between hosts.
//!
//! Viewing a whole `&T` as `&[u8]` is unsound when `T` has padding (a `FixedVec`'s `_len: u32`
//! before an 8-aligned array, say): padding bytes are uninitialised, and reading them is
//! undefined behaviour. [`to_wire`] therefore reads only the bytes that hold data, as the
//! layout descriptions ([`crate::describe`]) locate them, and sends zeros for the padding.
//! [`from_wire`] writes all the bytes back; see there why the result is a valid message.
//!
//! Numbers travel in native byte order: the bridge's hosts must agree on it.

use crate::Message;
use crate::catalog::layouts;
use crate::describe::{Element, TypeLayout};
use core::mem::{MaybeUninit, size_of};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// Byte ranges `(offset, len)`, sorted and merged.
type Ranges = Vec<(usize, usize)>;

/// The byte ranges of the type named `type_name` (its stable name, `caravan::Pose2D`) that
/// hold data: every number of every field, through nested structs and arrays, sorted, with
/// adjacent ranges merged. Everything outside them is padding. `None` for an undescribed type.
pub fn data_ranges(type_name: &str) -> Option<&'static [(usize, usize)]> {
    table().get(type_name).map(|(_, ranges)| ranges.as_slice())
}

/// Every described type's size and data ranges by its stable name, built once: the bridge
/// sends every message through here, and a map's ranges span a megabyte.
fn table() -> &'static BTreeMap<&'static str, (usize, Ranges)> {
    static TABLE: OnceLock<BTreeMap<&'static str, (usize, Ranges)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        // Each layout comes after the types it contains, so their ranges are ready.
        let mut by_name = BTreeMap::new();
        let mut table = BTreeMap::new();
        // The bench's blobs cross hosts too, though they are not message types.
        for layout in layouts().into_iter().chain(crate::bench::layouts()) {
            if let Some(ranges) = ranges_of(&layout, &by_name) {
                by_name.insert(layout.name, ranges.clone());
                table.insert(layout.type_name, (layout.size, ranges));
            }
        }
        table
    })
}

/// The data ranges of `layout`, from those of the structs it contains (`known`, by name).
/// `None` if a nested struct is unknown or the fields are out of order or outside the size, so
/// that a faulty description can never make [`to_wire`] read outside the data.
fn ranges_of(layout: &TypeLayout, known: &BTreeMap<&str, Ranges>) -> Option<Ranges> {
    let mut out = Ranges::new();
    for f in &layout.fields {
        let count = f.kind.array_len().unwrap_or(1);
        if count == 0 {
            continue;
        }
        let stride = f.size / count;
        let scalar;
        let element: &[(usize, usize)] = match f.kind.element() {
            Element::Scalar(s) => {
                scalar = [(0, s.size())];
                &scalar
            }
            Element::Struct(name) => known.get(name)?,
        };
        if element == [(0, stride)] {
            // Elements without padding: the array is one range (a map's cells, a path's poses).
            push(&mut out, f.offset, f.size)?;
        } else {
            // Padded elements: the element's ranges repeated at the stride.
            for i in 0..count {
                for &(offset, len) in element {
                    push(&mut out, f.offset + i * stride + offset, len)?;
                }
            }
        }
    }
    let end = out.last().map_or(0, |&(offset, len)| offset + len);
    (end <= layout.size).then_some(out)
}

impl crate::descriptor::Descriptor {
    /// The byte ranges of the described type that hold data (see [`data_ranges`]); `None` if
    /// the layouts are out of order.
    pub fn data_ranges(&self) -> Option<Vec<(usize, usize)>> {
        let mut known = BTreeMap::new();
        for layout in self.layouts() {
            known.insert(layout.name, ranges_of(layout, &known)?);
        }
        known.remove(self.layout().name)
    }
}

/// A message's bytes as they go on the wire: `payload`'s bytes in `ranges` (from
/// [`crate::descriptor::Descriptor::data_ranges`]), zeros in its padding.
pub fn wire_bytes(payload: &[u8], ranges: &[(usize, usize)]) -> Vec<u8> {
    let mut out = vec![0u8; payload.len()];
    for &(offset, len) in ranges {
        out[offset..offset + len].copy_from_slice(&payload[offset..offset + len]);
    }
    out
}

/// Appends a range after the last one, merging them when adjacent; `None` if it goes back.
fn push(ranges: &mut Ranges, offset: usize, len: usize) -> Option<()> {
    match ranges.last_mut() {
        Some((o, l)) if *o + *l == offset => *l += len,
        Some((o, l)) if *o + *l > offset => return None,
        _ => ranges.push((offset, len)),
    }
    Some(())
}

/// The data ranges of `T`, checked to describe a type of `T`'s size.
fn ranges_for<T: Message>() -> Result<&'static [(usize, usize)], String> {
    let name = crate::type_name::<T>();
    match table().get(name) {
        Some((size, ranges)) if *size == size_of::<T>() => Ok(ranges),
        Some((size, _)) => Err(format!(
            "{name} is described with {size} bytes, but has {}",
            size_of::<T>()
        )),
        None => Err(format!("{name} has no layout description")),
    }
}

/// `msg` as `size_of::<T>()` bytes: its data as in memory, zeros for its padding. Errors for a
/// type without a layout description, whose padding is unknown.
pub fn to_wire<T: Message>(msg: &T) -> Result<Vec<u8>, String> {
    let ranges = ranges_for::<T>()?;
    let mut out = vec![0u8; size_of::<T>()];
    let base = (msg as *const T).cast::<u8>();
    for &(offset, len) in ranges {
        // SAFETY: the range lies within `*msg` (checked against `T`'s size when the table was
        // built), and it covers fields only, whose bytes are initialised; `u8` needs no
        // alignment.
        let data = unsafe { core::slice::from_raw_parts(base.add(offset), len) };
        out[offset..offset + len].copy_from_slice(data);
    }
    Ok(out)
}

/// Writes `bytes`, from [`to_wire`], into `out`. After `Ok`, `out` holds a valid `T` and the
/// caller may `assume_init` it.
///
/// Why that is sound: a described type's fields are numbers, arrays of numbers and structs of
/// them, with no `bool`, `char`, enum, reference or pointer (a description can express nothing
/// else, and `describe::check` finds any field left out between two others), so every bit
/// pattern of its data bytes is a valid `T`; padding may hold anything. Types without a
/// description are refused, as nothing then vouches for them.
///
/// Contract for a meaningful (not merely valid) message: `bytes` come from `to_wire::<T>` of
/// the same type and layout on a host of the same byte order; the bridge checks the type
/// name and size before. Errors if `bytes` is not `size_of::<T>()` long.
pub fn from_wire<T: Message>(bytes: &[u8], out: &mut MaybeUninit<T>) -> Result<(), String> {
    ranges_for::<T>()?;
    let size = size_of::<T>();
    if bytes.len() != size {
        return Err(format!(
            "{} takes {size} bytes, not {}",
            crate::type_name::<T>(),
            bytes.len()
        ));
    }
    // SAFETY: `out` is valid for `size` bytes of writes, `bytes` for `size` bytes of reads,
    // they cannot overlap (one is borrowed mutably) and `u8` needs no alignment.
    unsafe { core::ptr::copy_nonoverlapping(bytes.as_ptr(), out.as_mut_ptr().cast(), size) };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{JointState, JointValue, LaserScan, Name, NodeStatus, Path2D, Pose2D, Scene};

    /// Bytes of the numbers in the type named `name`, counted field by field.
    fn scalar_bytes(name: &str, all: &[TypeLayout]) -> usize {
        let layout = all.iter().find(|l| l.name == name).unwrap();
        let element = |e: Element| match e {
            Element::Scalar(s) => s.size(),
            Element::Struct(n) => scalar_bytes(n, all),
        };
        let fields = layout.fields.iter();
        fields
            .map(|f| f.kind.array_len().unwrap_or(1) * element(f.kind.element()))
            .sum()
    }

    #[test]
    fn ranges_are_merged_and_cover_every_number() {
        let all = layouts();
        for layout in &all {
            let ranges = data_ranges(layout.type_name).expect(layout.type_name);
            for pair in ranges.windows(2) {
                assert!(pair[0].0 + pair[0].1 < pair[1].0, "{}", layout.name);
            }
            assert!(ranges.iter().all(|&(_, len)| len > 0), "{}", layout.name);
            let end = ranges.last().map_or(0, |&(o, l)| o + l);
            assert!(end <= layout.size, "{}", layout.name);
            let total: usize = ranges.iter().map(|&(_, len)| len).sum();
            assert_eq!(total, scalar_bytes(layout.name, &all), "{}", layout.name);
        }
        assert_eq!(data_ranges("caravan::Header"), Some(&[(0, 32)][..]));
        let grid = data_ranges("caravan::OccupancyGrid").unwrap();
        assert_eq!(grid, [(0, size_of::<crate::OccupancyGrid>())]);
        assert_eq!(data_ranges("caravan::Nothing"), None);
    }

    #[test]
    fn padding_is_left_out() {
        // `_len: u32`, 4 bytes of padding, then the 8-aligned items.
        let path = data_ranges("caravan::Path2D").unwrap();
        assert_eq!(path, [(0, 4), (8, size_of::<Path2D>() - 8)]);
        let joints = data_ranges("caravan::JointState").unwrap();
        assert_eq!(joints, [(0, 4), (8, size_of::<JointState>() - 8)]);
    }

    #[test]
    fn padded_elements_repeat_at_their_stride() {
        use crate::describe::{Field, Kind, Scalar};
        let field = |offset, size, kind| Field::new("", offset, size, kind);
        // `[E; 3]` where `E` is `{ u64, u32 }` and 4 bytes of padding.
        let known = BTreeMap::from([("E", vec![(0, 12)])]);
        let mut outer = TypeLayout {
            name: "Outer",
            type_name: "Outer",
            size: 52,
            align: 8,
            fields: vec![
                field(0, 4, Kind::Scalar(Scalar::U32)),
                field(4, 48, Kind::Array(Element::Struct("E"), 3)),
            ],
        };
        let expected = [(0, 16), (20, 12), (36, 12)];
        assert_eq!(ranges_of(&outer, &known).unwrap(), expected);
        outer.size = 47;
        assert_eq!(ranges_of(&outer, &known), None, "beyond the size");
        outer.size = 52;
        outer.fields.swap(0, 1);
        assert_eq!(ranges_of(&outer, &known), None, "out of order");
    }

    /// `msg` to bytes and back, checked to give the same bytes.
    fn round_trip<T: Message>(msg: &T) -> Box<T> {
        let bytes = to_wire(msg).unwrap();
        assert_eq!(bytes.len(), size_of::<T>());
        let mut out = Box::<T>::new_uninit();
        from_wire(&bytes, &mut *out).unwrap();
        // SAFETY: `from_wire` wrote all of it.
        let back = unsafe { out.assume_init() };
        assert_eq!(to_wire(back.as_ref()).unwrap(), bytes);
        back
    }

    #[test]
    fn messages_round_trip() {
        let pose = Pose2D {
            x: 1.5,
            y: -2.0,
            theta: 0.25,
        };
        assert_eq!(*round_trip(&pose), pose);
        let mut path = crate::boxed_placement_new::<Path2D>();
        path.poses
            .set_from_slice(&[pose, Pose2D { x: 3.0, ..pose }]);
        assert_eq!(
            round_trip(path.as_ref()).poses.as_slice(),
            path.poses.as_slice()
        );
        let mut scan = crate::boxed_placement_new::<LaserScan>();
        scan.beam_count = 3;
        scan.ranges[..3].copy_from_slice(&[1.0, 2.0, 3.0]);
        scan.range_max = 10.0;
        assert_eq!(round_trip(scan.as_ref()), scan);
        let mut joints = crate::boxed_placement_new::<JointState>();
        let elbow = JointValue {
            name: Name::new("elbow"),
            position: 0.5,
            velocity: -1.0,
            effort: 2.0,
        };
        joints.joints.push(elbow).unwrap();
        assert_eq!(round_trip(joints.as_ref()).joints.as_slice(), [elbow]);
        let mut scene = crate::boxed_placement_new::<Scene>();
        let mut shape = crate::Shape {
            kind: crate::Shape::SPHERE,
            ..Default::default()
        };
        shape.size.x = 0.5;
        scene.shapes.push(shape).unwrap();
        assert_eq!(round_trip(scene.as_ref()).shapes.as_slice(), [shape]);
        let status = NodeStatus {
            node: crate::FixedString::new("ping"),
            steps: 12,
            ..Default::default()
        };
        assert_eq!(*round_trip(&status), status);
        // The lockstep protocol's messages cross hosts too.
        let mut done = crate::boxed_placement_new::<crate::lockstep::Done>();
        done.now_ns = 7;
        done.published.push(42).unwrap();
        let back = round_trip(done.as_ref());
        assert_eq!((back.now_ns, back.published.as_slice()), (7, &[42][..]));
        let grant = crate::lockstep::Grant::step(10, 1);
        assert_eq!(round_trip(&grant).now_ns, 10);
    }

    #[test]
    fn every_wire_type_is_known_by_name() {
        for name in [
            "caravan::Pose2D",
            "caravan::lockstep::Hello",
            "caravan::lockstep::Done",
        ] {
            let size = crate::with_wire_type!(name, |T| size_of::<T>());
            assert_eq!(size, data_ranges(name).map(|_| size.unwrap()), "{name}");
        }
        assert_eq!(
            crate::with_wire_type!("caravan::Nothing", |T| size_of::<T>()),
            None
        );
    }

    /// Fills every byte of a `T`, padding too, with 0xA5; checks that the wire holds the data
    /// bytes and zeros for the padding, and that nothing the JSON view shows is lost.
    fn padding_is_zero<T: Message>() {
        let mut filled = Box::<T>::new_uninit();
        // SAFETY: the bytes are written, and any bit pattern is a valid `T` (see `from_wire`).
        let filled = unsafe {
            filled
                .as_mut_ptr()
                .cast::<u8>()
                .write_bytes(0xA5, size_of::<T>());
            filled.assume_init()
        };
        let bytes = to_wire(filled.as_ref()).unwrap();
        let mut data = vec![false; bytes.len()];
        for &(offset, len) in data_ranges(crate::type_name::<T>()).unwrap() {
            data[offset..offset + len].fill(true);
        }
        for (i, (&byte, &is_data)) in bytes.iter().zip(&data).enumerate() {
            assert_eq!(byte, if is_data { 0xA5 } else { 0 }, "byte {i}");
        }
        let back = round_trip(filled.as_ref());
        let json = |m: &T| serde_json::to_value(m).unwrap();
        assert!(json(&back) == json(&filled), "{}", crate::type_name::<T>());
    }

    #[test]
    fn padding_travels_as_zeros() {
        for name in crate::message_type_names() {
            crate::with_message_type!(name, |T| padding_is_zero::<T>()).unwrap();
        }
        padding_is_zero::<crate::Header>();
    }

    #[test]
    fn wrong_length_is_an_error_naming_the_type() {
        let mut out = MaybeUninit::<Pose2D>::uninit();
        assert_eq!(
            from_wire(&[0; 23], &mut out).unwrap_err(),
            "caravan::Pose2D takes 24 bytes, not 23"
        );
        let mut path = Box::<Path2D>::new_uninit();
        let err = from_wire(&[0; 8], &mut *path).unwrap_err();
        assert!(err.starts_with("caravan::Path2D takes"), "{err}");
    }
}
