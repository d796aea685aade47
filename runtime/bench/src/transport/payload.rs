//! Benchmark payloads: fixed-size byte blobs, and the 16 marker bytes every transport writes.
//!
//! Every round trip writes the same thing whatever the transport and size: the round's sequence
//! number into the first and the last 8 bytes of the payload. The rest of a blob is never
//! touched by the benchmark, so the cost of filling a 4 MiB message is not mistaken for the cost
//! of moving it. Sockets still send (and the kernel copies) every byte: that is their nature.

use caravan_schemas::bench::Blob;

/// The sizes measured, in bytes (see [`caravan_schemas::bench::BLOB_SIZES`]).
pub const SIZES: [usize; 5] = caravan_schemas::bench::BLOB_SIZES;

/// Sent instead of a sequence number to end the echoing side.
pub const STOP: u64 = u64::MAX;

/// Writes `seq` into the first and the last 8 bytes of `bytes` (at least 16 long).
pub fn mark(bytes: &mut [u8], seq: u64) {
    let n = bytes.len();
    bytes[..8].copy_from_slice(&seq.to_le_bytes());
    bytes[n - 8..].copy_from_slice(&seq.to_le_bytes());
}

/// The sequence number in the first 8 bytes, if the last 8 bytes agree.
pub fn read_mark(bytes: &[u8]) -> Option<u64> {
    let n = bytes.len();
    let first = u64::from_le_bytes(bytes[..8].try_into().ok()?);
    let last = u64::from_le_bytes(bytes[n - 8..].try_into().ok()?);
    (first == last).then_some(first)
}

/// Copies the 16 marker bytes of `from` into `to` (the echoing side's write).
pub fn copy_mark(from: &[u8], to: &mut [u8]) {
    let n = from.len();
    to[..8].copy_from_slice(&from[..8]);
    to[n - 8..].copy_from_slice(&from[n - 8..]);
}

/// Human-readable size: `16 B`, `2.7 KiB`, `64 KiB`, `4 MiB`.
pub fn label(bytes: usize) -> String {
    if bytes >= 1024 * 1024 && bytes.is_multiple_of(1024 * 1024) {
        format!("{} MiB", bytes / (1024 * 1024))
    } else if bytes >= 1024 && bytes.is_multiple_of(1024) {
        format!("{} KiB", bytes / 1024)
    } else if bytes >= 1024 {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    } else {
        format!("{bytes} B")
    }
}

/// Calls `$f::<Blob<N>>($args)` for the blob of `$bytes` bytes, one of [`SIZES`].
macro_rules! with_blob {
    ($bytes:expr, $f:ident ( $($arg:expr),* $(,)? )) => {
        match $bytes {
            16 => $f::<caravan_schemas::bench::Blob<16>>($($arg),*),
            2_728 => $f::<caravan_schemas::bench::Blob<2_728>>($($arg),*),
            65_536 => $f::<caravan_schemas::bench::Blob<65_536>>($($arg),*),
            1_048_576 => $f::<caravan_schemas::bench::Blob<1_048_576>>($($arg),*),
            4_194_304 => $f::<caravan_schemas::bench::Blob<4_194_304>>($($arg),*),
            other => Err(anyhow::anyhow!(
                "no blob type for {other} bytes; sizes are {:?}",
                $crate::transport::payload::SIZES
            )),
        }
    };
}
pub(crate) use with_blob;

/// Access to a blob's bytes for code generic over the blob size.
pub trait Bytes {
    fn bytes(&self) -> &[u8];
    fn bytes_mut(&mut self) -> &mut [u8];
}

impl<const N: usize> Bytes for Blob<N> {
    fn bytes(&self) -> &[u8] {
        &self.bytes
    }
    fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marks_round_trip() {
        let mut b = vec![0u8; 16];
        mark(&mut b, 42);
        assert_eq!(read_mark(&b), Some(42));
        let mut c = vec![0u8; 16];
        copy_mark(&b, &mut c);
        assert_eq!(read_mark(&c), Some(42));
        assert_eq!(label(2_728), "2.7 KiB");
        assert_eq!(label(4 << 20), "4 MiB");
        assert_eq!(label(64 << 10), "64 KiB");
    }
}
