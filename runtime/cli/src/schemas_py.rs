//! `caravan schemas`: the message layouts for other languages.
//!
//! `--python` writes a module of `ctypes.Structure` classes generated from
//! `caravan_schemas::describe` (checked in as `python/caravan/schemas.py`); `--layout` prints
//! the descriptions as JSON, which the layout test compares with what ctypes makes of the module.

use anyhow::{Context, Result, bail};
use caravan_schemas::catalog::{self, ROBOT_TOPICS, TOPIC_CONSTANTS};
use caravan_schemas::describe::{Element, Field, Kind, Scalar, TypeLayout};
use caravan_schemas::lockstep;
use std::fmt::Write;
use std::path::PathBuf;

/// Where the generated module is checked in, relative to the workspace root.
#[cfg(test)]
const CHECKED_IN: &str = "python/caravan/schemas.py";

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["python", "layout"])))]
pub struct SchemasArgs {
    /// Generate the Python module of ctypes structures
    #[arg(long)]
    python: bool,
    /// Print every type's size, alignment and field offsets as JSON
    #[arg(long)]
    layout: bool,
    /// Write to this file instead of standard output
    #[arg(short, long)]
    output: Option<PathBuf>,
}

pub fn run(args: &SchemasArgs) -> Result<()> {
    if let Some(path) = &args.output {
        output_place(path)?;
    }
    let text = if args.python {
        python_module()?
    } else {
        serde_json::to_string_pretty(&catalog::layouts_json())? + "\n"
    };
    match &args.output {
        Some(path) => {
            std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
        }
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

/// Whether `-o PATH` names a place a file can be written: a folder that exists, and not a
/// folder itself. Either is bad input (exit 2), found before anything is generated.
fn output_place(path: &std::path::Path) -> Result<()> {
    use caravan_group::bad_input::bad;
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if !folder.is_dir() {
        return Err(bad(format!(
            "-o {}: the folder {} does not exist",
            path.display(),
            folder.display()
        )));
    }
    if path.is_dir() {
        return Err(bad(format!(
            "-o {}: is a folder; name the file to write",
            path.display()
        )));
    }
    Ok(())
}

fn ctype(scalar: Scalar) -> &'static str {
    match scalar {
        Scalar::F64 => "ctypes.c_double",
        Scalar::F32 => "ctypes.c_float",
        Scalar::U64 => "ctypes.c_uint64",
        Scalar::I64 => "ctypes.c_int64",
        Scalar::U32 => "ctypes.c_uint32",
        Scalar::I32 => "ctypes.c_int32",
        Scalar::U8 => "ctypes.c_uint8",
        Scalar::I8 => "ctypes.c_int8",
    }
}

fn element_ctype(element: Element) -> String {
    match element {
        Element::Scalar(s) => ctype(s).to_string(),
        Element::Struct(name) => name.to_string(),
    }
}

fn field_ctype(kind: Kind) -> String {
    match kind {
        Kind::Array(element, len) => format!("{} * {len}", element_ctype(element)),
        other => element_ctype(other.element()),
    }
}

/// Alignment ctypes gives a field: that of its element, as in C.
fn ctypes_align(element: Element, done: &[TypeLayout]) -> Result<usize> {
    Ok(match element {
        Element::Scalar(s) => s.size(),
        Element::Struct(name) => {
            done.iter()
                .find(|l| l.name == name)
                .with_context(|| format!("{name} is used before it is described"))?
                .align
        }
    })
}

/// `_fields_` entries for `layout`, with explicit padding wherever ctypes' natural placement
/// would differ from the offsets the Rust compiler chose.
fn ctypes_fields(layout: &TypeLayout, done: &[TypeLayout]) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    let mut end = 0usize;
    let mut pads = 0;
    let mut pad = |out: &mut Vec<(String, String)>, bytes: usize| {
        out.push((format!("_pad{pads}"), format!("ctypes.c_uint8 * {bytes}")));
        pads += 1;
    };
    let mut max_align = 1;
    for Field {
        name,
        offset,
        size,
        kind,
        ..
    } in &layout.fields
    {
        let align = ctypes_align(kind.element(), done)?;
        max_align = max_align.max(align);
        if *offset < end || offset % align != 0 {
            bail!(
                "{}.{name}: offset {offset} cannot be expressed with ctypes",
                layout.name
            );
        }
        if end.next_multiple_of(align) != *offset {
            pad(&mut out, offset - end);
        }
        out.push((name.clone(), field_ctype(*kind)));
        end = offset + size;
    }
    if max_align != layout.align {
        bail!(
            "{}: ctypes would align it to {max_align}, Rust aligns it to {}",
            layout.name,
            layout.align
        );
    }
    if end.next_multiple_of(max_align) != layout.size {
        pad(&mut out, layout.size - end);
    }
    Ok(out)
}

const HEADER: &str = r#"# Generated by `caravan schemas --python` from the Rust message types (crate caravan-schemas).
# Do not edit: run `cargo run -p caravan-cli -- schemas --python -o python/caravan/schemas.py`.
"""Caravan's message types as ctypes structures, with the Rust layouts and type names.

Every class has the Rust type's name and its fields in memory order (with explicit ``_pad``
fields where C pads differently from ctypes), plus ``SIZE``, ``ALIGN``, ``OFFSETS`` (field name
to byte offset) and ``type_name()``: the name iceoryx2 compares across languages, so a Python
port and a Rust port of one topic only connect when they agree on the type.

A Rust ``FixedString<N>`` field ``node`` appears as ``node_len`` and ``node`` (N bytes), a
``FixedVec<T, N>`` field ``poses`` as ``poses_len`` and ``poses`` (N items); read and write
them with ``fixed_str``, ``set_fixed_str``, ``fixed_vec`` and ``set_fixed_vec``. Every class
derives from ``Message``: ``msg.to_dict()`` is the message as recordings and ``caravan topic
echo`` show it, and ``print(msg)`` prints it readably.
"""
"#;

const HELPERS: &str = r#"

def fixed_str(msg: ctypes.Structure, field: str) -> str:
    """The text of the fixed-capacity string ``field`` of ``msg``."""
    data = getattr(msg, field)
    n = min(getattr(msg, field + "_len"), len(data))
    return bytes(data[:n]).decode("utf-8", errors="replace")


def set_fixed_str(msg: ctypes.Structure, field: str, text: str) -> None:
    """Stores ``text`` in the string ``field``, cut at a character boundary to its capacity."""
    data = getattr(msg, field)
    raw = text.encode("utf-8")
    if len(raw) > len(data):
        raw = raw[: len(data)].decode("utf-8", errors="ignore").encode("utf-8")
    data[: len(raw)] = raw
    setattr(msg, field + "_len", len(raw))


def fixed_vec(msg: ctypes.Structure, field: str) -> list:
    """The valid items of the fixed-capacity vector ``field`` of ``msg``."""
    items = getattr(msg, field)
    return items[: min(getattr(msg, field + "_len"), len(items))]


def set_fixed_vec(msg: ctypes.Structure, field: str, values) -> int:
    """Stores ``values`` in the vector ``field``, up to its capacity; returns how many fit."""
    items = getattr(msg, field)
    n = 0
    for value in values:
        if n == len(items):
            break
        items[n] = value
        n += 1
    setattr(msg, field + "_len", n)
    return n


class Message(ctypes.Structure):
    """Base of every generated structure. ``to_dict()`` gives the JSON view that recordings
    and ``caravan topic echo`` print (strings as text, vectors and counted arrays cut to their
    valid part, explicit padding left out); ``repr()`` prints it readably."""

    # Array field -> the fields whose product counts its valid part (LaserScan's beam_count).
    _counts_ = {}

    def to_dict(self) -> dict:
        names = {name for name, _ in self._fields_}
        # A count that alone counts an array is implied by the array's length.
        implied = {by[0] for by in self._counts_.values() if len(by) == 1}
        out = {}
        for name, ctype in self._fields_:
            if name.startswith("_pad") or (name.endswith("_len") and name[:-4] in names):
                continue
            if name in implied:
                continue
            value = getattr(self, name)
            if name + "_len" in names and getattr(ctype, "_type_", None) is ctypes.c_uint8:
                out[name] = fixed_str(self, name)
                continue
            if name + "_len" in names:
                value = fixed_vec(self, name)
            elif name in self._counts_:
                n = 1
                for count in self._counts_[name]:
                    n *= getattr(self, count)
                value = value[: min(n, len(value))]
            out[name] = _plain(value)
        return out

    def __repr__(self) -> str:
        fields = ", ".join(f"{k}={_short(v)}" for k, v in self.to_dict().items())
        return f"{type(self).__name__}({fields})"


def _plain(value):
    if isinstance(value, Message):
        return value.to_dict()
    if isinstance(value, (ctypes.Array, list)):
        return [_plain(v) for v in value]
    return value


def _short(value) -> str:
    """A value for ``repr``: long lists shortened to their first items and their length."""
    if isinstance(value, list) and len(value) > 8:
        return "[" + ", ".join(_short(v) for v in value[:4]) + f", … ({len(value)} items)]"
    if isinstance(value, list):
        return "[" + ", ".join(_short(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}={_short(v)}" for k, v in value.items()) + "}"
    return repr(value)


def name_hash(name: str) -> int:
    """64-bit FNV-1a of ``name``: a node's ``source_id`` in headers, a topic in the lockstep
    protocol (``caravan_schemas::lockstep::name_hash``)."""
    h = 0xCBF29CE484222325
    for byte in name.encode("utf-8"):
        h = ((h ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h
"#;

/// The Python module, as checked in at `python/caravan/schemas.py`.
pub fn python_module() -> Result<String> {
    let mut py = String::from(HEADER);
    py.push_str("\nimport ctypes\n\n");
    for (name, value) in [
        ("SCAN_MAX_BEAMS", caravan_schemas::SCAN_MAX_BEAMS),
        ("MAP_MAX_SIDE", caravan_schemas::MAP_MAX_SIDE),
        ("MAP_MAX_CELLS", caravan_schemas::MAP_MAX_CELLS),
        ("PATH_MAX_POSES", caravan_schemas::PATH_MAX_POSES),
        ("SCENE_MAX_SHAPES", caravan_schemas::SCENE_MAX_SHAPES),
        ("NAME_BYTES", caravan_schemas::NAME_BYTES),
        ("MAX_JOINTS", caravan_schemas::MAX_JOINTS),
        ("MAX_LINKS", caravan_schemas::MAX_LINKS),
        ("MAX_CONTACTS", caravan_schemas::MAX_CONTACTS),
        ("MAX_FORCE_TORQUE", caravan_schemas::MAX_FORCE_TORQUE),
        ("WRENCH_WORLD", caravan_schemas::Wrench::WORLD as usize),
        ("WRENCH_LINK", caravan_schemas::Wrench::LINK as usize),
    ] {
        writeln!(py, "{name} = {value}")?;
    }
    py.push_str(HELPERS);

    let layouts = catalog::layouts();
    for (i, layout) in layouts.iter().enumerate() {
        let fields = ctypes_fields(layout, &layouts[..i])?;
        write!(
            py,
            "\n\nclass {}(Message):\n    \"\"\"``{}``: {} bytes, aligned to {}.\"\"\"\n\n    _fields_ = [\n",
            layout.name, layout.type_name, layout.size, layout.align
        )?;
        for (name, ty) in &fields {
            writeln!(py, "        (\"{name}\", {ty}),")?;
        }
        py.push_str("    ]\n");
        // Arrays counted by other fields (a `FixedVec`'s own `_len` needs no entry).
        let counts: Vec<String> = layout
            .fields
            .iter()
            .filter(|f| !f.count.is_empty() && f.count != [format!("{}_len", f.name)])
            .map(|f| format!("\"{}\": (\"{}\",)", f.name, f.count.join("\", \"")))
            .collect();
        if !counts.is_empty() {
            writeln!(py, "    _counts_ = {{{}}}", counts.join(", "))?;
        }
        writeln!(py, "    SIZE = {}", layout.size)?;
        writeln!(py, "    ALIGN = {}", layout.align)?;
        py.push_str("    OFFSETS = {");
        let offsets: Vec<String> = layout
            .fields
            .iter()
            .map(|f| format!("\"{}\": {}", f.name, f.offset))
            .collect();
        if offsets.join(", ").len() + 16 <= 96 {
            py.push_str(&offsets.join(", "));
            py.push_str("}\n");
        } else {
            py.push('\n');
            for o in &offsets {
                writeln!(py, "        {o},")?;
            }
            py.push_str("    }\n");
        }
        write!(
            py,
            "\n    @classmethod\n    def type_name(cls) -> str:\n        \"\"\"The name iceoryx2 matches across languages.\"\"\"\n        return \"{}\"\n",
            layout.type_name
        )?;
    }

    let registry: Vec<&str> = caravan_schemas::message_type_names();
    let class_of = |type_name: &str| {
        layouts
            .iter()
            .find(|l| l.type_name == type_name)
            .map(|l| l.name)
            .with_context(|| format!("{type_name} has no layout description"))
    };
    py.push_str("\n\n# The registry: every type that travels on a topic, by its Rust name.\n");
    py.push_str("MESSAGE_TYPES = (\n");
    for name in &registry {
        writeln!(py, "    {},", class_of(name)?)?;
    }
    py.push_str(")\n");
    py.push_str("BY_TYPE_NAME = {t.type_name(): t for t in MESSAGE_TYPES}\n");
    py.push_str("# Every generated structure, the header and lockstep messages included.\n");
    py.push_str("ALL_TYPES = (\n");
    for l in &layouts {
        writeln!(py, "    {},", l.name)?;
    }
    py.push_str(")\n");

    py.push_str(
        "\n\nclass topics:\n    \"\"\"Topic names, as `caravan_schemas::topics`: scoped by robot, ROS style.\"\"\"\n\n",
    );
    for (name, topic) in TOPIC_CONSTANTS {
        writeln!(py, "    {name} = \"{}\"", topic())?;
    }
    // Learn each helper's pattern from the Rust function itself.
    const SENTINEL: usize = 987_654_321;
    for (name, f) in ROBOT_TOPICS {
        let pattern = f(SENTINEL).replace(&SENTINEL.to_string(), "{i}");
        write!(
            py,
            "\n    @staticmethod\n    def {name}(i: int) -> str:\n        return f\"{pattern}\"\n"
        )?;
    }

    let grant = lockstep::grant_service("{node}");
    write!(
        py,
        "\n\nclass lockstep:\n    \"\"\"The lockstep protocol's constants, as `caravan_schemas::lockstep`.\"\"\"\n\n    MAX_TOPICS = {}\n    HELLO = \"{}\"\n    DONE = \"{}\"\n\n    @staticmethod\n    def grant_service(node: str) -> str:\n        return f\"{grant}\"\n",
        lockstep::MAX_TOPICS,
        lockstep::HELLO,
        lockstep::DONE,
    )?;
    Ok(py)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checked_in_module_is_up_to_date() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(CHECKED_IN);
        let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
        let generated = python_module().unwrap();
        assert!(
            checked_in == generated,
            "{CHECKED_IN} is stale; regenerate it with \
             `cargo run -p caravan-cli -- schemas --python -o {CHECKED_IN}`"
        );
    }

    #[test]
    fn padding_appears_where_c_and_ctypes_differ() {
        let layouts = catalog::layouts();
        let status = layouts.iter().find(|l| l.name == "NodeStatus").unwrap();
        let fields = ctypes_fields(status, &layouts).unwrap();
        // node_len, node, host_len, host, then u64s: C and ctypes agree, no padding needed.
        assert!(
            fields.iter().all(|(n, _)| !n.starts_with("_pad")),
            "{fields:?}"
        );
        let odd = TypeLayout {
            name: "Odd",
            type_name: "caravan::Odd",
            size: 24,
            align: 8,
            fields: vec![
                Field::new("a", 0, 4, Kind::Scalar(Scalar::U32)),
                // A nested FixedVec<u64, 1>: its length sits at 8, not at 4.
                Field::new("v_len", 8, 4, Kind::Scalar(Scalar::U32)),
                Field::new("v", 16, 8, Kind::Array(Element::Scalar(Scalar::U64), 1)),
            ],
        };
        let fields = ctypes_fields(&odd, &[]).unwrap();
        let names: Vec<&str> = fields.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["a", "_pad0", "v_len", "v"]);
        assert_eq!(fields[1].1, "ctypes.c_uint8 * 4");
    }

    #[test]
    fn topic_helpers_follow_the_rust_functions() {
        let py = python_module().unwrap();
        assert!(py.contains(
            "    def wheel_setpoint(i: int) -> str:\n        return f\"robot/{i}/wheel_setpoint\"\n"
        ));
        assert!(py.contains("return f\"caravan/lockstep/grant/{node}\""));
    }
}
