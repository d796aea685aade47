use crate::describe::{Element, Kind, Scalar, TypeLayout};
use crate::descriptor::Descriptor;
use serde_json::json;

/// A small deterministic generator (xorshift64*): the test needs variety, not quality.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
}

/// Fills `bytes` (one value of `layout`) with random numbers: floats of every magnitude, now
/// and then not finite; counts within or just past their array; text as letters, now and then
/// not UTF-8.
fn fill(d: &Descriptor, layout: &TypeLayout, bytes: &mut [u8], rng: &mut Rng) {
    for f in &layout.fields {
        let slot = &mut bytes[f.offset..f.offset + f.size];
        let count = f.kind.array_len().unwrap_or(1);
        let stride = f.size / count.max(1);
        for i in 0..count {
            let item = &mut slot[i * stride..(i + 1) * stride];
            match f.kind.element() {
                Element::Scalar(s) => number(s, item, rng),
                Element::Struct(name) => fill(d, d.struct_layout(name).unwrap(), item, rng),
            }
        }
        if f.text {
            for b in slot.iter_mut() {
                *b = b'a' + rng.below(26) as u8;
            }
            if rng.below(10) == 0 {
                slot[0] = 0xff;
            }
        }
    }
    for f in &layout.fields {
        let len = f.kind.array_len().unwrap_or(0) as u64;
        let counters: Vec<_> = f
            .count
            .iter()
            .map(|c| layout.fields.iter().find(|o| o.name == *c).unwrap())
            .collect();
        for c in &counters {
            let n = if counters.len() == 1 {
                rng.below(len + 3)
            } else {
                rng.below(40)
            };
            let Kind::Scalar(s) = c.kind else { panic!() };
            let slot = &mut bytes[c.offset..c.offset + c.size];
            match s {
                Scalar::U32 | Scalar::I32 => slot.copy_from_slice(&(n as u32).to_ne_bytes()),
                Scalar::U64 | Scalar::I64 => slot.copy_from_slice(&n.to_ne_bytes()),
                Scalar::U8 => slot[0] = n as u8,
                other => panic!("{other:?} counts"),
            }
        }
    }
}

fn number(s: Scalar, slot: &mut [u8], rng: &mut Rng) {
    let r = rng.next();
    match s {
        Scalar::F64 => {
            let v = match rng.below(20) {
                0 => f64::NAN,
                1 => f64::INFINITY,
                2 => 0.0,
                _ => f64::from_bits(r) % 1e12,
            };
            let v = if v.is_nan() && rng.below(2) == 0 {
                (r as i64 as f64) * 1e-9
            } else {
                v
            };
            slot.copy_from_slice(&v.to_ne_bytes())
        }
        Scalar::F32 => {
            let v = match rng.below(20) {
                0 => f32::NAN,
                1 => f32::NEG_INFINITY,
                _ => (r as i32 as f32) * 1e-6,
            };
            slot.copy_from_slice(&v.to_ne_bytes())
        }
        _ => slot.copy_from_slice(&r.to_ne_bytes()[..slot.len()]),
    }
}

/// The descriptor's view of random values equals `Serialize`'s, for every message type and
/// the header.
#[test]
fn the_view_is_what_serialize_writes_for_every_message_type() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for name in crate::message_type_names() {
        let d = crate::catalog::descriptor(name).unwrap();
        for _ in 0..24 {
            let mut bytes = vec![0u8; d.layout().size];
            fill(d, d.layout(), &mut bytes, &mut rng);
            let serde = typed_value(name, &bytes);
            assert_eq!(d.view(&bytes).unwrap(), serde, "{name}");
        }
    }
}

#[test]
fn a_view_of_the_wrong_length_is_refused() {
    let d = crate::catalog::descriptor("caravan::Pose2D").unwrap();
    assert!(d.view(&[0; 23]).unwrap_err().contains("24 bytes"));
    assert_eq!(
        d.view(&[0; 24]).unwrap(),
        json!({"x": 0.0, "y": 0.0, "theta": 0.0})
    );
}

/// The JSON `Value` serde gives of `bytes` as the catalog type `name`.
fn typed_value(name: &str, bytes: &[u8]) -> serde_json::Value {
    crate::with_message_type!(name, |T| {
        let mut value = Box::<T>::new_uninit();
        // SAFETY: every field of a message type is a number or an array of numbers, so any
        // bytes of the right length are a valid value.
        let value = unsafe {
            std::ptr::copy_nonoverlapping(
                bytes.as_ptr(),
                value.as_mut_ptr().cast::<u8>(),
                bytes.len(),
            );
            value.assume_init()
        };
        serde_json::to_value(value.as_ref()).unwrap()
    })
    .unwrap()
}

/// `write_json` writes the very text the recorder wrote before it existed: the type's serde
/// `Value`, with the header inserted as a key, through `serde_json::to_vec` (so recordings
/// keep their bytes).
#[test]
fn write_json_is_the_text_of_the_view_with_the_header_inserted() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let header = json!({"seq": 3, "stamp_ns": 20_000_000, "source_id": "1234567890123"});
    for name in crate::message_type_names() {
        let d = crate::catalog::descriptor(name).unwrap();
        for _ in 0..24 {
            let mut bytes = vec![0u8; d.layout().size];
            fill(d, d.layout(), &mut bytes, &mut rng);
            let mut value = typed_value(name, &bytes);
            let plain_text = serde_json::to_vec(&value).unwrap();
            value["header"] = header.clone();
            let mut written = Vec::new();
            d.write_json(&bytes, Some(("header", &header)), &mut written)
                .unwrap();
            assert_eq!(
                String::from_utf8(written).unwrap(),
                String::from_utf8(serde_json::to_vec(&value).unwrap()).unwrap(),
                "{name}"
            );
            let mut plain = Vec::new();
            d.write_json(&bytes, None, &mut plain).unwrap();
            assert_eq!(plain, plain_text, "{name}");
        }
    }
}
