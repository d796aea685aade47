//! The payloads of `caravan bench transport`: fixed-size byte blobs.
//!
//! They live here, beside the schema types, so that the bridge between hosts can carry them
//! (`with_wire_type!` knows them, and the wire encoding has their layout) and the bench can
//! measure the path a topic takes between two hosts. They are not message types of the
//! registry: recordings, `caravan topic echo` and the Python generator never meet them.

use crate::describe::{Describe, Element, Field, Kind, Scalar, TypeLayout};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};

/// The sizes of blob the bench measures, in bytes: a wheel set-point, a 682-beam laser scan's
/// ranges (682 × f32), a small image, a point cloud and a large map or image.
pub const BLOB_SIZES: [usize; 5] = [16, 2_728, 64 * 1024, 1024 * 1024, 4 * 1024 * 1024];

/// A message of `N` opaque bytes. Its stable name is `caravan::bench::Blob<N>`.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Blob<const N: usize> {
    pub bytes: [u8; N],
}

// SAFETY: plain bytes in a `repr(C)` struct, the same layout in every process; the name below
// is unique per `N`.
unsafe impl<const N: usize> ZeroCopySend for Blob<N> {
    unsafe fn type_name() -> &'static str {
        match N {
            16 => "caravan::bench::Blob<16>",
            2_728 => "caravan::bench::Blob<2728>",
            65_536 => "caravan::bench::Blob<65536>",
            1_048_576 => "caravan::bench::Blob<1048576>",
            4_194_304 => "caravan::bench::Blob<4194304>",
            _ => core::any::type_name::<Self>(),
        }
    }
}

/// All zeros. The bench loans blobs with `Publisher::loan_as_is`, which skips this memset
/// (every bit pattern is a valid blob), so the cost of filling a 4 MiB message is not taken
/// for the cost of moving it.
impl<const N: usize> PlacementDefault for Blob<N> {
    unsafe fn placement_default(ptr: *mut Self) {
        // SAFETY: the caller gives a pointer valid for writes of one `Self`.
        unsafe { ptr.write_bytes(0, 1) };
    }
}

impl<const N: usize> std::fmt::Debug for Blob<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Blob<{N}>")
    }
}

/// Blobs are never recorded; serialising one gives only its length.
impl<const N: usize> serde::Serialize for Blob<N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(N as u64)
    }
}

/// One array of bytes, no padding.
impl<const N: usize> Describe for Blob<N> {
    fn layout() -> TypeLayout {
        TypeLayout {
            name: "Blob",
            type_name: crate::type_name::<Blob<N>>(),
            size: N,
            align: 1,
            fields: vec![Field::new(
                "bytes",
                0,
                N,
                Kind::Array(Element::Scalar(Scalar::U8), N),
            )],
        }
    }

    fn dependencies(_out: &mut Vec<TypeLayout>) {}
}

/// The layouts of the blobs of [`BLOB_SIZES`].
pub(crate) fn layouts() -> Vec<TypeLayout> {
    vec![
        Blob::<16>::layout(),
        Blob::<2_728>::layout(),
        Blob::<65_536>::layout(),
        Blob::<1_048_576>::layout(),
        Blob::<4_194_304>::layout(),
    ]
}

/// Runs `$body` with `$T` bound to the blob type named `$name`; `None` for another name.
#[doc(hidden)]
#[macro_export]
macro_rules! with_blob_type {
    ($name:expr, |$T:ident| $body:expr) => {{
        let name: &str = $name;
        $crate::with_blob_type!(@arms name, $T, $body; 16 2_728 65_536 1_048_576 4_194_304)
    }};
    (@arms $name:ident, $T:ident, $body:expr; $($n:literal)*) => {
        $(
            if $name == $crate::type_name::<$crate::bench::Blob<$n>>() {
                #[allow(dead_code)]
                type $T = $crate::bench::Blob<$n>;
                Some($body)
            } else
        )* { None }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_size_has_a_layout_and_a_wire_type() {
        let all = layouts();
        assert_eq!(all.len(), BLOB_SIZES.len());
        for (layout, size) in all.iter().zip(BLOB_SIZES) {
            assert_eq!(layout.size, size);
            let known = crate::with_wire_type!(layout.type_name, |T| size_of::<T>());
            assert_eq!(known, Some(size), "{}", layout.type_name);
            assert_eq!(
                crate::wire::data_ranges(layout.type_name),
                Some(&[(0, size)][..])
            );
        }
        // Not message types: nothing records or generates code for them.
        assert!(crate::with_message_type!(all[0].type_name, |T| ()).is_none());
    }

    #[test]
    fn a_blob_crosses_the_wire_whole() {
        let mut blob = Box::new(Blob::<2_728> { bytes: [0; 2_728] });
        blob.bytes[0] = 7;
        blob.bytes[2_727] = 9;
        let wire = crate::wire::to_wire(blob.as_ref()).unwrap();
        let mut back = Box::<Blob<2_728>>::new_uninit();
        crate::wire::from_wire(&wire, &mut back).unwrap();
        // SAFETY: `from_wire` returned Ok.
        let back = unsafe { back.assume_init() };
        assert_eq!(back.bytes[..], blob.bytes[..]);
    }
}
