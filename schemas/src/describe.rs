//! Layout descriptions of the message types, for other languages.
//!
//! [`layouts`] lists every type that crosses a process boundary (the registry's message types,
//! the [`Header`] and the lockstep protocol's messages) with its size, alignment and fields.
//! Offsets come from `core::mem::offset_of!`, sizes, array lengths and field types from the
//! compiler, so a description cannot drift from the type; only the field names are listed here.
//! `caravan schemas --python` turns them into ctypes structures and `caravan schemas --layout`
//! prints them as JSON.
//!
//! [`FixedString<N>`] and [`FixedVec<T, N>`] are not types of their own in a description: a
//! field `node: FixedString<64>` becomes `node_len: u32` and `node: [u8; 64]`, a field
//! `poses: FixedVec<Pose2D, N>` becomes `poses_len: u32` and `poses: [Pose2D; N]`, each at the
//! offset the compiler gave it.

use crate::{FixedString, FixedVec};
use core::mem::size_of;
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};

/// A plain number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    F64,
    F32,
    U64,
    I64,
    U32,
    I32,
    U8,
    I8,
}

impl Scalar {
    /// Rust's name for it: `f64`, `u32`, …
    pub fn name(self) -> &'static str {
        match self {
            Scalar::F64 => "f64",
            Scalar::F32 => "f32",
            Scalar::U64 => "u64",
            Scalar::I64 => "i64",
            Scalar::U32 => "u32",
            Scalar::I32 => "i32",
            Scalar::U8 => "u8",
            Scalar::I8 => "i8",
        }
    }

    pub fn size(self) -> usize {
        match self {
            Scalar::F64 | Scalar::U64 | Scalar::I64 => 8,
            Scalar::F32 | Scalar::U32 | Scalar::I32 => 4,
            Scalar::U8 | Scalar::I8 => 1,
        }
    }
}

/// What a field or an array element is: a number or a described struct.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Element {
    Scalar(Scalar),
    /// A struct by its [`TypeLayout::name`].
    Struct(&'static str),
}

impl Element {
    /// `f64`, or the struct's name.
    pub fn name(self) -> &'static str {
        match self {
            Element::Scalar(s) => s.name(),
            Element::Struct(name) => name,
        }
    }
}

/// The type of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Scalar(Scalar),
    Struct(&'static str),
    /// A fixed-length array.
    Array(Element, usize),
}

impl Kind {
    /// The single value, or the array's element.
    pub fn element(self) -> Element {
        match self {
            Kind::Scalar(s) => Element::Scalar(s),
            Kind::Struct(name) => Element::Struct(name),
            Kind::Array(element, _) => element,
        }
    }

    /// The array's length; `None` for a single value.
    pub fn array_len(self) -> Option<usize> {
        match self {
            Kind::Array(_, len) => Some(len),
            _ => None,
        }
    }
}

/// One field of a struct.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    /// Bytes from the start of the struct.
    pub offset: usize,
    /// Bytes the field occupies.
    pub size: usize,
    pub kind: Kind,
    /// For an array of which only a front part is valid: the fields (of the same struct) whose
    /// product is the number of valid items. A `FixedVec`'s or `FixedString`'s array is counted
    /// by its own `_len`; `#[count(width, height)]` on a field of a derived type names others.
    /// Empty for a single value or an array that is valid whole.
    pub count: Vec<String>,
    /// The array holds UTF-8 text (a `FixedString`'s bytes), shown as a string.
    pub text: bool,
}

impl Field {
    /// A field valid whole (no count), not text.
    pub fn new(name: &str, offset: usize, size: usize, kind: Kind) -> Self {
        Field {
            name: name.to_string(),
            offset,
            size,
            kind,
            count: Vec::new(),
            text: false,
        }
    }
}

/// Size, alignment and fields of one type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TypeLayout {
    /// The Rust type's own name (`Pose2D`, `Hello`), also the name of its Python class.
    pub name: &'static str,
    /// The stable cross-language type name iceoryx2 matches (`caravan::Pose2D`).
    pub type_name: &'static str,
    pub size: usize,
    pub align: usize,
    /// In memory order.
    pub fields: Vec<Field>,
}

/// A type that can appear as a field: it adds its field(s) to a description.
pub trait FieldKind {
    fn push(name: &str, offset: usize, out: &mut Vec<Field>);
    /// Adds the layouts of the structs the field holds (theirs first), unless `out` has them.
    fn dependencies(_out: &mut Vec<TypeLayout>) {}
}

/// A type that can be an array element: a number or a described struct.
pub trait ElementKind: Sized {
    const ELEMENT: Element;
    /// A described struct adds its own layout after those of the structs it holds.
    fn dependencies(_out: &mut Vec<TypeLayout>) {}
}

/// A type with a layout description: `#[derive(Describe)]` on a `#[repr(C)]` struct writes it
/// from the struct's declaration (field names from the declaration, offsets, sizes and types
/// from the compiler; `#[count(a, b)]` on an array field says that only its first `a × b`
/// items are valid).
pub trait Describe {
    fn layout() -> TypeLayout;

    /// The layouts of the structs this type holds, each after those it holds in turn (a
    /// descriptor, `caravan_schemas::descriptor::Descriptor::of`, is those and its own).
    fn dependencies(out: &mut Vec<TypeLayout>);
}

pub use caravan_schemas_derive::Describe;

fn kind_of(element: Element) -> Kind {
    match element {
        Element::Scalar(s) => Kind::Scalar(s),
        Element::Struct(name) => Kind::Struct(name),
    }
}

impl<T: ElementKind> FieldKind for T {
    fn push(name: &str, offset: usize, out: &mut Vec<Field>) {
        out.push(Field::new(
            name,
            offset,
            size_of::<T>(),
            kind_of(T::ELEMENT),
        ));
    }

    fn dependencies(out: &mut Vec<TypeLayout>) {
        <T as ElementKind>::dependencies(out)
    }
}

impl<T: ElementKind, const N: usize> FieldKind for [T; N] {
    fn push(name: &str, offset: usize, out: &mut Vec<Field>) {
        out.push(Field::new(
            name,
            offset,
            size_of::<[T; N]>(),
            Kind::Array(T::ELEMENT, N),
        ));
    }

    fn dependencies(out: &mut Vec<TypeLayout>) {
        T::dependencies(out)
    }
}

impl<const N: usize> FieldKind for FixedString<N> {
    fn push(name: &str, offset: usize, out: &mut Vec<Field>) {
        let len = format!("{name}_len");
        u32::push(&len, offset + Self::LEN_OFFSET, out);
        <[u8; N]>::push(name, offset + Self::BYTES_OFFSET, out);
        let bytes = out.last_mut().expect("just pushed");
        bytes.count = vec![len];
        bytes.text = true;
    }
}

impl<T, const N: usize> FieldKind for FixedVec<T, N>
where
    T: ElementKind + Copy + PlacementDefault + ZeroCopySend,
{
    fn push(name: &str, offset: usize, out: &mut Vec<Field>) {
        let len = format!("{name}_len");
        u32::push(&len, offset + Self::LEN_OFFSET, out);
        <[T; N]>::push(name, offset + Self::ITEMS_OFFSET, out);
        out.last_mut().expect("just pushed").count = vec![len];
    }

    fn dependencies(out: &mut Vec<TypeLayout>) {
        T::dependencies(out)
    }
}

macro_rules! scalars {
    ($($t:ty => $s:ident),* $(,)?) => {
        $(impl ElementKind for $t {
            const ELEMENT: Element = Element::Scalar(Scalar::$s);
        })*
    };
}

scalars!(f64 => F64, f32 => F32, u64 => U64, i64 => I64, u32 => U32, i32 => I32, u8 => U8, i8 => I8);

/// Alignment of a field's element: a scalar's size, or a described struct's alignment.
fn element_align(element: Element, known: &[TypeLayout]) -> Option<usize> {
    match element {
        Element::Scalar(s) => Some(s.size()),
        Element::Struct(name) => known.iter().find(|l| l.name == name).map(|l| l.align),
    }
}

/// Checks that `layout` reads like its C declaration: fields in increasing order, each at the
/// next offset its alignment allows (so no field is missing between two listed ones), all
/// within the size; nested structs are described earlier in `known`.
pub fn check(layout: &TypeLayout, known: &[TypeLayout]) -> Result<(), String> {
    let mut end: usize = 0;
    let align_of = |f: &Field| {
        element_align(f.kind.element(), known).ok_or_else(|| {
            format!(
                "{}.{}: {} is not described before it",
                layout.name,
                f.name,
                f.kind.element().name()
            )
        })
    };
    for (i, f) in layout.fields.iter().enumerate() {
        let mut align = align_of(f)?;
        // A `FixedVec`'s or `FixedString`'s length opens the container, which is aligned as
        // its items are: after a `u32`, a `FixedVec<f64, N>` starts 8 bytes on.
        if let Some(next) = layout.fields.get(i + 1)
            && next.count == [f.name.as_str()]
            && next.name.len() + 4 == f.name.len()
        {
            align = align.max(align_of(next)?);
        }
        let expected = end.next_multiple_of(align);
        if f.offset != expected {
            return Err(format!(
                "{}.{}: at offset {}, but the field before it ends at {end} (expected {expected}); \
                 a field is missing from the description or out of order",
                layout.name, f.name, f.offset
            ));
        }
        end = f.offset + f.size;
    }
    if end > layout.size || layout.size != end.next_multiple_of(layout.align) {
        return Err(format!(
            "{}: fields end at {end}, size is {} with alignment {}",
            layout.name, layout.size, layout.align
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalog::{layouts, layouts_json};
    use crate::lockstep::Hello;
    use crate::{NodeStatus, Path2D};

    #[test]
    fn offsets_increase_and_end_within_the_size() {
        let all = layouts();
        for (i, layout) in all.iter().enumerate() {
            check(layout, &all[..i]).unwrap();
            for pair in layout.fields.windows(2) {
                assert!(
                    pair[0].offset + pair[0].size <= pair[1].offset,
                    "{layout:?}"
                );
            }
            let last = layout.fields.last().unwrap();
            assert!(last.offset + last.size <= layout.size, "{layout:?}");
        }
    }

    #[test]
    fn every_registry_type_is_described() {
        let all = layouts();
        for name in crate::message_type_names() {
            assert!(all.iter().any(|l| l.type_name == name), "{name}");
        }
        for name in [
            "caravan::Header",
            "caravan::lockstep::Hello",
            "caravan::lockstep::Grant",
            "caravan::lockstep::Done",
        ] {
            assert!(all.iter().any(|l| l.type_name == name), "{name}");
        }
        let mut names: Vec<_> = all.iter().map(|l| l.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), all.len(), "type names must be unique");
    }

    #[test]
    fn fixed_containers_expand_to_length_and_array() {
        let status = NodeStatus::layout();
        let f = |name: &str| status.fields.iter().find(|f| f.name == name).unwrap();
        assert_eq!(
            (f("node_len").offset, f("node_len").kind),
            (0, Kind::Scalar(Scalar::U32))
        );
        assert_eq!(
            (f("node").offset, f("node").kind),
            (4, Kind::Array(Element::Scalar(Scalar::U8), 64))
        );
        assert_eq!(f("host_len").offset, 68);
        assert_eq!(f("period_ns").offset, 104);
        let hello = Hello::layout();
        let triggers = hello.fields.iter().find(|f| f.name == "triggers").unwrap();
        assert_eq!(
            triggers.kind,
            Kind::Array(Element::Scalar(Scalar::U64), crate::lockstep::MAX_TOPICS)
        );
        let path = Path2D::layout();
        assert_eq!(path.fields[1].offset, 8);
        assert_eq!(
            path.fields[1].kind,
            Kind::Array(Element::Struct("Pose2D"), crate::PATH_MAX_POSES)
        );
    }

    #[test]
    fn json_names_types_and_lengths() {
        let json = layouts_json();
        let scan = json
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["name"] == "LaserScan")
            .unwrap();
        assert_eq!(scan["type_name"], "caravan::LaserScan");
        let ranges = &scan["fields"][8];
        assert_eq!(ranges["name"], "ranges");
        assert_eq!(ranges["type"], "f32");
        assert_eq!(ranges["len"], crate::SCAN_MAX_BEAMS);
        assert_eq!(ranges["offset"], 32);
    }
}
