//! Checking a terrain spec before anything is generated: every key within its physical
//! range, and every primitive able to act on the field. An error names the key as a path
//! (`primitive[1].center[0]`) and its line in the spec, as `line 9: key '…': …`; the terrain
//! generator puts the file's name before it.
//!
//! Ranges, and why (launch/tracked/terrains/README.md states them):
//! - the field, approach and run-out: multiples of a block, at most 20 m each;
//! - `friction`: [0, 100], a Coulomb coefficient; contacts take the smaller of the block's
//!   and the part's, and the wheels' own is 100, so more changes nothing;
//! - `flank`, a barrier's `width` and a peak's `radius`: at most 20 m, the longest field
//!   (more is a unit mistake, cm for m); a width or radius of at least a block, else the
//!   primitive can fall between the blocks' centres and vanish;
//! - heights of barriers, peaks and hills: a step of the ladder above the ground, since they
//!   stand on it (below it they would dig a trench or a pit, which only `random` and
//!   `gaussian` may; at the ground they do nothing);
//! - a barrier's `at` and a peak's `center`: on the field, where the primitives act;
//! - `gaussian`: `mean` and `std` within the ladder's 0–0.4 m (draws are kept within it);
//! - hills: σ from a block to below a quarter of the field's shorter side, since each hill is
//!   centred at least 2 σ inside the field's edges (wider, every hill stood at its centre);
//! - at least one primitive: a spec of none is flat ground, which a world file says plainly.

use crate::params::{Range, show, show_exact};
use crate::rse::{CELL_M, GROUND_M, Primitive, STEPS_M, Spec};
use toml::de::{DeTable, DeValue};

/// The longest field side, approach or run-out, m; also the bound of a flank, a barrier's
/// width and a peak's radius.
pub const MAX_LENGTH_M: f64 = 20.0;
/// `terrain.friction`: up to the wheels' own coefficient (mu1 = 100).
pub const FRICTION: Range = Range::closed(0.0, 100.0, "");
/// `terrain.flank`.
pub const FLANK_M: Range = Range::positive(MAX_LENGTH_M, "m");
/// A barrier's `width` and a peak's `radius`: a block to the longest field.
pub const EXTENT_M: Range = Range::closed(CELL_M, MAX_LENGTH_M, "m");
/// `gaussian`'s `mean` and `std`: the ladder's span.
pub const LADDER_M: Range = Range::closed(0.0, 0.4, "m");

/// A key that is wrong: its path (for its line) and the message, which names it.
#[derive(Debug, Clone, PartialEq)]
struct Bad {
    key: String,
    text: String,
}

fn bad(key: &str, text: String) -> Bad {
    Bad {
        key: key.into(),
        text: format!("key '{key}': {text}"),
    }
}

fn range(key: &str, v: f64, r: Range) -> Result<(), Bad> {
    r.check(key, v).map(|_| ()).map_err(|text| Bad {
        key: key.into(),
        text,
    })
}

/// Parses and checks a spec file's text: `line N: key 'k': why` on error.
pub fn parse_spec(text: &str) -> Result<Spec, String> {
    let spec: Spec = toml::from_str(text).map_err(|e| toml_error(text, &e))?;
    check(&spec).map_err(|b| match line_of_key(text, &b.key) {
        Some(line) => format!("line {line}: {}", b.text),
        None => b.text,
    })?;
    Ok(spec)
}

/// Checks every key of a parsed spec; the error names the first bad key.
pub fn validate(spec: &Spec) -> Result<(), String> {
    check(spec).map_err(|b| b.text)
}

/// Blocks in `len` m, if it is a multiple of [`CELL_M`] in [`min`, `max`].
fn cells(key: &str, len: f64, min: f64, max: f64) -> Result<usize, Bad> {
    let n = (len / CELL_M).round();
    if !(len.is_finite() && (min..=max).contains(&len) && (len / CELL_M - n).abs() < 1e-6) {
        return Err(bad(
            key,
            format!(
                "{} must be a multiple of {CELL_M} m in [{min}, {max}]",
                show_exact(len)
            ),
        ));
    }
    Ok(n as usize)
}

fn ladder(key: &str, h: f64) -> Result<(), Bad> {
    if STEPS_M.iter().any(|s| (s - h).abs() < 1e-9) {
        Ok(())
    } else {
        Err(bad(
            key,
            format!(
                "{} is not a step of the ladder (0, 0.05, 0.1, 0.2, 0.3, 0.4 m)",
                show_exact(h)
            ),
        ))
    }
}

/// A step of the ladder above the ground: what barriers, peaks and hills stand on.
fn above_ground(key: &str, what: &str, h: f64) -> Result<(), Bad> {
    ladder(key, h)?;
    if h > GROUND_M + 1e-9 {
        return Ok(());
    }
    Err(bad(
        key,
        format!(
            "{} m must be above the ground, {GROUND_M} m: {what} stands on the ground (a \
             lower one would dig into it, which only `random` and `gaussian` may; one at the \
             ground does nothing)",
            show_exact(h)
        ),
    ))
}

/// `v` within [0, `len`]: on the field along an axis.
fn on_field(key: &str, what: &str, v: f64, axis: char, len: f64) -> Result<(), Bad> {
    if v.is_finite() && (0.0..=len).contains(&v) {
        return Ok(());
    }
    Err(bad(
        key,
        format!(
            "{} m is outside the field, whose {axis} runs from 0 to {} m (positions are from \
             its first corner); {what} must be on it",
            show_exact(v),
            show(len)
        ),
    ))
}

/// A barrier's keys: where (`at`, on the field), how thick, how high, how soft.
fn wall_keys(
    key: &dyn Fn(&str) -> String,
    field: [f64; 2],
    [at, width, height, softness]: [f64; 4],
) -> Result<(), Bad> {
    on_field(&key("at"), "a barrier's middle", at, 'x', field[0])?;
    range(&key("width"), width, EXTENT_M)?;
    above_ground(&key("height"), "a barrier", height)?;
    if !(0.0..=100.0).contains(&softness) {
        return Err(bad(
            &key("softness"),
            format!("softness {} is outside [0, 100]", show_exact(softness)),
        ));
    }
    Ok(())
}

/// Hills' σ: a block at least, and below a quarter of the field's shorter side.
fn hill_sigma(key: &str, sigma: f64, field: [f64; 2]) -> Result<(), Bad> {
    if !(sigma.is_finite() && sigma >= CELL_M) {
        return Err(bad(
            key,
            format!(
                "must be at least {CELL_M} m (a block), got {}: a narrower hill can fall \
                 between the blocks' centres and vanish",
                show_exact(sigma)
            ),
        ));
    }
    let shorter = field[0].min(field[1]);
    if 4.0 * sigma < shorter {
        return Ok(());
    }
    Err(bad(
        key,
        format!(
            "{} m is too wide for the {} × {} m field: each hill is centred at least 2 σ \
             inside its edges, so σ must be below a quarter of its shorter side ({} m); \
             wider, every hill would stand at the field's centre",
            show_exact(sigma),
            show(field[0]),
            show(field[1]),
            show(shorter / 4.0)
        ),
    ))
}

fn check(spec: &Spec) -> Result<(), Bad> {
    let t = &spec.terrain;
    cells("terrain.field[0]", t.field[0], CELL_M, MAX_LENGTH_M)?;
    cells("terrain.field[1]", t.field[1], CELL_M, MAX_LENGTH_M)?;
    cells("terrain.approach", t.approach, 0.0, MAX_LENGTH_M)?;
    cells("terrain.run_out", t.run_out, 0.0, MAX_LENGTH_M)?;
    range("terrain.friction", t.friction, FRICTION)?;
    range("terrain.flank", t.flank, FLANK_M)?;
    if spec.primitives.is_empty() {
        return Err(bad(
            "primitive",
            "none given; a terrain needs at least one [[primitive]] (flat ground is a world \
             file of one box, as launch/tracked/worlds/flat.toml)"
                .into(),
        ));
    }
    let field = t.field;
    for (i, p) in spec.primitives.iter().enumerate() {
        let key = |k: &str| format!("primitive[{i}].{k}");
        match *p {
            Primitive::Random { min, max } => {
                ladder(&key("min"), min)?;
                ladder(&key("max"), max)?;
                if min > max {
                    return Err(bad(&key("min"), format!("{min} is above max {max}")));
                }
            }
            Primitive::Gaussian { mean, std } => {
                range(&key("mean"), mean, LADDER_M)?;
                range(&key("std"), std, LADDER_M)?;
            }
            Primitive::HorizontalBarrier {
                at,
                width,
                height,
                softness,
            } => wall_keys(&key, field, [at, width, height, softness])?,
            Primitive::DiagonalBarrier {
                at,
                width,
                height,
                angle_deg,
                softness,
            } => {
                wall_keys(&key, field, [at, width, height, softness])?;
                if !(angle_deg.is_finite() && angle_deg.abs() < 90.0) {
                    return Err(bad(
                        &key("angle_deg"),
                        format!("{} must be within (−90, 90) degrees", show_exact(angle_deg)),
                    ));
                }
            }
            Primitive::Peak {
                center,
                height,
                radius,
            } => {
                on_field(
                    &key("center[0]"),
                    "a peak's centre",
                    center[0],
                    'x',
                    field[0],
                )?;
                on_field(
                    &key("center[1]"),
                    "a peak's centre",
                    center[1],
                    'y',
                    field[1],
                )?;
                above_ground(&key("height"), "a peak", height)?;
                range(&key("radius"), radius, EXTENT_M)?;
            }
            Primitive::Hills {
                count,
                height,
                sigma,
            } => {
                if !(1..=100).contains(&count) {
                    return Err(bad(&key("count"), format!("{count} must be 1 to 100")));
                }
                above_ground(&key("height"), "a hill", height)?;
                hill_sigma(&key("sigma"), sigma, field)?;
            }
        }
    }
    Ok(())
}

/// The 1-based line of byte `offset` in `text`.
fn line_at(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// A toml error as `line N: key 'k': message` (the key whose value or name holds the error's
/// place, when the text parses as TOML), or toml's own message when it has no place.
fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim_end().replace('\n', " ");
    let Some(span) = e.span() else {
        return message;
    };
    let line = line_at(text, span.start);
    match key_at(text, span.start) {
        Some(key) => format!("line {line}: key '{key}': {message}"),
        None => format!("line {line}: {message}"),
    }
}

/// One step of a key path: a table's key or an array's index.
enum Seg<'a> {
    Key(&'a str),
    Index(usize),
}

/// `primitive[1].center[0]` as its steps.
fn segments(path: &str) -> Vec<Seg<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_once('[').map_or((part, ""), |(n, r)| (n, r));
        out.push(Seg::Key(name));
        while let Some((index, after)) = rest.split_once(']') {
            if let Ok(i) = index.parse() {
                out.push(Seg::Index(i));
            }
            rest = after.strip_prefix('[').unwrap_or("");
        }
    }
    out
}

/// The line of `path` in the spec: of its value, or of the deepest part of it the file
/// writes (a primitive's table for a key left to its default); the last line for a key the
/// file does not write at all (where it would go).
fn line_of_key(text: &str, path: &str) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let mut span = None;
    let mut table = Some(doc.get_ref());
    let mut value: Option<&DeValue> = None;
    for seg in segments(path) {
        let found = match (seg, table, value) {
            (Seg::Key(k), Some(t), _) => {
                t.iter().find(|(key, _)| key.get_ref() == k).map(|(_, v)| v)
            }
            (Seg::Index(i), _, Some(DeValue::Array(a))) => a.get(i),
            _ => None,
        };
        let Some(v) = found else { break };
        span = Some(v.span());
        value = Some(v.get_ref());
        table = match v.get_ref() {
            DeValue::Table(t) => Some(t),
            _ => None,
        };
    }
    match span {
        Some(s) => Some(line_at(text, s.start)),
        None => Some(text.lines().count().max(1)),
    }
}

/// Every key and array element of a TOML value with its path and the spans of its name and
/// value (a table's value span is its header).
fn flatten(value: &DeValue, path: &str, out: &mut Vec<(String, std::ops::Range<usize>)>) {
    let mut add = |path: String, spans: &[std::ops::Range<usize>], v: &DeValue| {
        for s in spans {
            out.push((path.clone(), s.clone()));
        }
        flatten(v, &path, out);
    };
    match value {
        DeValue::Table(t) => {
            for (k, v) in t.iter() {
                let path = if path.is_empty() {
                    k.get_ref().to_string()
                } else {
                    format!("{path}.{}", k.get_ref())
                };
                add(path, &[k.span(), v.span()], v.get_ref());
            }
        }
        DeValue::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                add(format!("{path}[{i}]"), &[v.span()], v.get_ref());
            }
        }
        _ => {}
    }
}

/// The path of the innermost key or element whose name or value holds byte `offset`.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    let mut all = Vec::new();
    flatten(&DeValue::Table(doc.into_inner()), "", &mut all);
    // The narrowest wins; of equal ones (an array of tables and its element share the
    // header), the deeper, which comes later.
    all.into_iter()
        .rev()
        .filter(|(_, s)| s.start <= offset && offset < s.end.max(s.start + 1))
        .min_by_key(|(_, s)| s.end - s.start)
        .map(|(path, _)| path)
}

#[cfg(test)]
#[path = "rse_check_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "rse_fuzz_tests.rs"]
mod fuzz_tests;
