//! Fixed-capacity containers that are plain data (no pointers), for shared-memory messages.

use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};

/// A UTF-8 string of at most `N` bytes, zero-padded.
#[repr(C)]
#[derive(Clone, Copy, PartialEq, Eq, ZeroCopySend, PlacementDefault)]
pub struct FixedString<const N: usize> {
    len: u32,
    bytes: [u8; N],
}

impl<const N: usize> Default for FixedString<N> {
    fn default() -> Self {
        Self {
            len: 0,
            bytes: [0; N],
        }
    }
}

impl<const N: usize> FixedString<N> {
    /// Offsets of the length and the bytes inside the string, for layout descriptions.
    pub(crate) const LEN_OFFSET: usize = core::mem::offset_of!(Self, len);
    pub(crate) const BYTES_OFFSET: usize = core::mem::offset_of!(Self, bytes);

    /// Copies `s`, truncated to `N` bytes at a character boundary.
    pub fn new(s: &str) -> Self {
        let mut end = s.len().min(N);
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        let mut out = Self::default();
        out.bytes[..end].copy_from_slice(&s.as_bytes()[..end]);
        out.len = end as u32;
        out
    }

    pub fn as_str(&self) -> &str {
        let len = (self.len as usize).min(N);
        core::str::from_utf8(&self.bytes[..len]).unwrap_or("")
    }
}

impl<const N: usize> core::fmt::Debug for FixedString<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

/// A vector of at most `N` elements stored inline.
#[repr(C)]
#[derive(Clone, Copy, ZeroCopySend, PlacementDefault)]
pub struct FixedVec<T: Copy + PlacementDefault + ZeroCopySend, const N: usize> {
    len: u32,
    items: [T; N],
}

impl<T: Copy + PlacementDefault + ZeroCopySend, const N: usize> FixedVec<T, N> {
    pub const CAPACITY: usize = N;
    /// Offsets of the length and the items inside the vector, for layout descriptions.
    pub(crate) const LEN_OFFSET: usize = core::mem::offset_of!(Self, len);
    pub(crate) const ITEMS_OFFSET: usize = core::mem::offset_of!(Self, items);

    /// An empty vector.
    pub fn new() -> Self {
        crate::placement_new()
    }

    pub fn as_slice(&self) -> &[T] {
        &self.items[..(self.len as usize).min(N)]
    }

    pub fn len(&self) -> usize {
        self.as_slice().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends `item`; returns it back when the vector is full.
    pub fn push(&mut self, item: T) -> Result<(), T> {
        let len = self.len as usize;
        if len >= N {
            return Err(item);
        }
        self.items[len] = item;
        self.len += 1;
        Ok(())
    }

    /// Replaces the contents with `items`, truncated to the capacity; returns how many were kept.
    pub fn set_from_slice(&mut self, items: &[T]) -> usize {
        let n = items.len().min(N);
        self.items[..n].copy_from_slice(&items[..n]);
        self.len = n as u32;
        n
    }
}

impl<T: Copy + PlacementDefault + ZeroCopySend, const N: usize> Default for FixedVec<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy + PlacementDefault + ZeroCopySend + core::fmt::Debug, const N: usize> core::fmt::Debug
    for FixedVec<T, N>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let s = self.as_slice();
        if s.len() > 8 {
            write!(f, "[{:?}, … {} items]", &s[..8], s.len())
        } else {
            write!(f, "{s:?}")
        }
    }
}
