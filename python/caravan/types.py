"""Message types learned at run time (``caravan::types`` in Rust).

A topic may carry a type that ``caravan.schemas`` was not generated with: a scenario's or a
user's own, declared in Rust outside Caravan (``examples/beacon``). A process that opens a port
of such a type registers the type's descriptor with its group, a JSON file beside the group's
shared memory (``schemas/src/descriptor.rs`` defines it): its layout, the layouts of the structs
it holds, and its default value. From that file this module builds a ctypes class with the same
size, alignment and offsets and the same JSON view as the generated classes:

- ``message_class(descriptor)``: the class of a descriptor (a dict as the file holds it).
- ``lookup(where, type_name)`` (``Node.message_type(type_name)``): the class of a type that a
  process of the group registered; a catalog type's generated class.
- ``register(where, cls)``: what a Python port does for a class that is not in the catalog,
  as a Rust port does, so that the recorder, ``caravan topic echo`` and Rust processes read it.

``where`` is a ``Node``, an iceoryx2 config or a group name.
"""

from __future__ import annotations

import ctypes
import json
import os
import threading
from typing import Any

from . import schemas
from .identity import CaravanError, group_config

# The descriptor's scalar names (``caravan_schemas::describe::Scalar``).
_SCALARS = {
    "f64": ctypes.c_double,
    "f32": ctypes.c_float,
    "u64": ctypes.c_uint64,
    "i64": ctypes.c_int64,
    "u32": ctypes.c_uint32,
    "i32": ctypes.c_int32,
    "u8": ctypes.c_uint8,
    "i8": ctypes.c_int8,
}
# Scalars that may count an array (``descriptor::check_counts``).
_COUNTERS = ("u8", "u32", "u64", "i32", "i64")


class _Byte(ctypes._SimpleCData):
    """A ``u8`` that is not ``ctypes.c_uint8``: ``Message.to_dict`` shows a ``c_uint8`` array
    counted by its own ``_len`` as text (a ``FixedString``), so a ``FixedVec<u8, N>`` holds these
    and shows as numbers. A direct ``_SimpleCData`` subclass reads as a plain ``int``."""

    _type_ = "B"


# Largest message and descriptor file (Rust's ``descriptor::MAX_MESSAGE_BYTES`` and
# ``types::MAX_FILE_BYTES``): a file of the group cannot make this process allocate without bound.
MAX_MESSAGE_BYTES = 64 << 20
MAX_FILE_BYTES = 1 << 20

_CATALOG = {cls.type_name(): cls for cls in schemas.ALL_TYPES}
# Field names that would hide what every message class has (``type_name()``, ``SIZE`` …).
_TAKEN = {"SIZE", "ALIGN", "OFFSETS", "DESCRIPTOR", "_counts_", "_fields_"}

_lock = threading.RLock()
_built: dict = {}  # canonical descriptor JSON -> class: one class per layout
_registered: set = set()  # (root, prefix, class) registered by this process


# --- classes from descriptors --------------------------------------------------------------


def message_class(descriptor: dict) -> type:
    """The ``schemas.Message`` subclass a descriptor describes, the structs it holds included
    (a held catalog struct is its generated class when the layouts agree, so ``msg.position =
    schemas.Vector3(…)`` works). Raises ``CaravanError`` naming the type and the field if the
    descriptor makes no sense or ctypes cannot reproduce its offsets."""
    canonical = _canonical(descriptor)
    key = json.dumps(canonical, sort_keys=True)
    with _lock:
        cls = _built.get(key)
        if cls is None:
            message = canonical["layouts"][-1]["type_name"]
            built: dict = {}
            for i, layout in enumerate(canonical["layouts"]):
                cls = _struct(layout, built, message)
                generated = _CATALOG.get(layout["type_name"])
                last = i == len(canonical["layouts"]) - 1
                if not last and generated is not None and _same_layout(cls, generated):
                    cls = generated
                built[layout["name"]] = cls
            cls.DESCRIPTOR = canonical
            _built[key] = cls
    return cls


def _refuse(message: str, where: str, why: str) -> CaravanError:
    return CaravanError(f"message type '{message}': {where}: {why}")


def _struct(layout: dict, built: dict, message: str) -> type:
    """One layout as a ctypes structure, padded explicitly where ctypes' natural placement
    differs from the offsets the Rust compiler chose (as the generator pads schemas.py)."""
    name, size, align = layout["name"], layout["size"], layout["align"]
    _check_view(layout, message)
    fields: list = []
    end, widest = 0, 1

    def pad(n: int) -> None:
        fields.append((f"_pad{sum(f[0].startswith('_pad') for f in fields)}", ctypes.c_uint8 * n))

    for f in layout["fields"]:
        element = _SCALARS.get(f["type"]) or built[f["type"]]
        if f["type"] == "u8" and f.get("count") == [f["name"] + "_len"] and not f.get("text"):
            element = _Byte
        item_align = ctypes.alignment(element)
        widest = max(widest, item_align)
        offset = f["offset"]
        if offset % item_align:
            raise _refuse(
                message,
                f"{name}.{f['name']}",
                f"offset {offset} cannot be expressed with ctypes, which aligns "
                f"{f['type']} to {item_align}",
            )
        if _round_up(end, item_align) != offset:
            pad(offset - end)
        fields.append((f["name"], element * f["len"] if "len" in f else element))
        end = offset + f["size"]
    if widest != align:
        raise _refuse(
            message, name, f"ctypes would align it to {widest}, the descriptor aligns it to {align}"
        )
    if _round_up(end, widest) != size:
        pad(size - end)
    attrs = {
        "__doc__": f"``{layout['type_name']}``: {size} bytes, aligned to {align} (from its "
        "descriptor).",
        "__module__": __name__,
        "_fields_": fields,
        "SIZE": size,
        "ALIGN": align,
        "OFFSETS": {f["name"]: f["offset"] for f in layout["fields"]},
        "type_name": classmethod(lambda cls, t=layout["type_name"]: t),
    }
    # The generated classes' convention: arrays counted by fields other than their own `_len`.
    counts = {
        f["name"]: tuple(f["count"])
        for f in layout["fields"]
        if f.get("count") and f["count"] != [f["name"] + "_len"]
    }
    if counts:
        attrs["_counts_"] = counts
    cls = type(name, (schemas.Message,), attrs)
    # What ctypes made of it, checked rather than trusted.
    for f in layout["fields"]:
        if getattr(cls, f["name"]).offset != f["offset"]:
            raise _refuse(
                message,
                f"{name}.{f['name']}",
                f"ctypes places it at {getattr(cls, f['name']).offset}, "
                f"the descriptor at {f['offset']}",
            )
    if ctypes.sizeof(cls) != size:
        raise _refuse(message, name, f"ctypes makes it {ctypes.sizeof(cls)} bytes, not {size}")
    return cls


def _round_up(n: int, align: int) -> int:
    return -(-n // align) * align


def _check_view(layout: dict, message: str) -> None:
    """Refuses a layout that ``Message.to_dict`` would show otherwise than Rust's JSON view
    (``schemas/src/view.rs``): to_dict finds a ``FixedString``'s or ``FixedVec``'s count by the
    name ``<field>_len`` and pads by the name ``_pad…``; Rust's derive names them so."""
    names = {f["name"] for f in layout["fields"]}
    for f in layout["fields"]:
        field, where = f["name"], f"{layout['name']}.{f['name']}"
        own = [field + "_len"]
        if field.startswith("_pad") or field in _TAKEN or hasattr(schemas.Message, field):
            raise _refuse(message, where, "the name is taken by the Python class itself")
        if own[0] in names and ("len" not in f or f.get("count") != own):
            raise _refuse(
                message, where, f"'{own[0]}' beside it is read as its count, but does not count it"
            )
        if f.get("text") and f.get("count") != own:
            raise _refuse(message, where, f"text is counted by '{own[0]}' only")


def _same_layout(a: type, b: type) -> bool:
    """Whether two classes lay out the same fields alike (a descriptor's catalog struct and
    its generated class)."""

    def shape(cls: type) -> list:
        return [
            (n, ctypes.sizeof(t), getattr(t, "_length_", None), getattr(t, "_type_", t))
            for n, t in cls._fields_
        ]

    def facts(cls: type) -> tuple:
        return (cls.type_name(), ctypes.sizeof(cls), ctypes.alignment(cls), cls.OFFSETS)

    return facts(a) == facts(b) and a._counts_ == b._counts_ and shape(a) == shape(b)


def _check_describes(cls: type, descriptor: dict) -> None:
    """Refuses a class whose ``DESCRIPTOR`` (checked, ``descriptor``) is not its own layout:
    other processes would read its bytes by the descriptor."""
    layout = descriptor["layouts"][-1]
    found = (cls.type_name(), ctypes.sizeof(cls), ctypes.alignment(cls))
    wanted = (layout["type_name"], layout["size"], layout["align"])
    for f in layout["fields"]:
        slot = getattr(cls, f["name"], None)
        found += (getattr(slot, "offset", None), getattr(slot, "size", None))
        wanted += (f["offset"], f["size"])
    if found != wanted:
        raise CaravanError(
            f"message type '{layout['type_name']}': the class {cls.__name__} is not laid out as "
            f"its DESCRIPTOR says (type name, size, alignment, field offsets and sizes: "
            f"{list(found)} against {list(wanted)})"
        )


# --- checking a descriptor -----------------------------------------------------------------


def _canonical(descriptor: Any) -> dict:
    """``descriptor`` checked as ``Descriptor::from_json`` checks it, in the shape
    ``Descriptor::to_json`` writes (no ``len`` but for arrays, ``count`` and ``text`` only when
    set): the form registered and compared."""
    items = descriptor.get("layouts") if isinstance(descriptor, dict) else None
    if not isinstance(items, list) or not items:
        raise CaravanError('a descriptor is {"layouts": [...], "default": ...}, with a layout')
    last = items[-1] if isinstance(items[-1], dict) else {}
    check = _Checker(last.get("type_name") if isinstance(last.get("type_name"), str) else "?")
    known: dict = {}
    for i, item in enumerate(items):
        layout = check.layout(item, known, f"layout {i}")
        known[layout["name"]] = layout
    return {"layouts": list(known.values()), "default": descriptor.get("default")}


class _Checker:
    """Reads the layouts of one message type's descriptor, naming the type in every refusal."""

    def __init__(self, message: str) -> None:
        self.message = message

    def bad(self, where: str, why: str) -> CaravanError:
        return _refuse(self.message, where, why)

    def name(self, v: Any, key: str, where: str) -> str:
        s = v.get(key) if isinstance(v, dict) else None
        if not isinstance(s, str) or not 1 <= len(s.encode()) <= 256:
            raise self.bad(where, f"'{key}' must be a name of 1 to 256 bytes")
        return s

    def whole(self, v: dict, key: str, where: str) -> int:
        n = v.get(key)
        if not isinstance(n, int) or isinstance(n, bool) or n < 0:
            raise self.bad(where, f"'{key}' must be a whole number")
        return n

    def layout(self, item: Any, known: dict, where: str) -> dict:
        name = self.name(item, "name", where)
        size, align = self.whole(item, "size", name), self.whole(item, "align", name)
        if name in known:
            raise self.bad(name, "described twice")
        if align == 0 or align & (align - 1) or align > 4096:
            raise self.bad(name, f"alignment {align} is not a power of two up to 4096")
        if size > MAX_MESSAGE_BYTES:
            raise self.bad(name, f"{size} bytes, more than the {MAX_MESSAGE_BYTES} a message takes")
        if not isinstance(item.get("fields"), list):
            raise self.bad(name, "'fields' must be a list")
        fields, end = [], 0
        for f in item["fields"]:
            field = self.field(f, known, name)
            where = f"{name}.{field['name']}"
            if field["offset"] < end or field["offset"] + field["size"] > size:
                raise self.bad(where, f"at {field['offset']}, over the one before or past the end")
            end = field["offset"] + field["size"]
            fields.append(field)
        for f in fields:
            for c in f.get("count", []):
                counter = [o for o in fields if o["name"] == c and "len" not in o]
                if not counter or counter[0]["type"] not in _COUNTERS:
                    raise self.bad(
                        f"{name}.{f['name']}",
                        f"counted by '{c}', which is not an integer field of {name}",
                    )
        type_name = self.name(item, "type_name", name)
        return dict(name=name, type_name=type_name, size=size, align=align, fields=fields)

    def field(self, f: Any, known: dict, struct: str) -> dict:
        where = f"{struct}.{self.name(f, 'name', struct)}"
        kind = f.get("type")
        if kind in _SCALARS:
            item_size = ctypes.sizeof(_SCALARS[kind])
        elif isinstance(kind, str) and kind in known:
            item_size = known[kind]["size"]
        else:
            raise self.bad(where, f"'{kind}' is not described before it")
        out = {
            "name": f["name"],
            "offset": self.whole(f, "offset", where),
            "size": self.whole(f, "size", where),
            "type": kind,
        }
        if "len" in f:
            out["len"] = self.whole(f, "len", where)
        expected = item_size * out.get("len", 1)
        if expected != out["size"]:
            raise self.bad(where, f"{out['size']} bytes, but its type takes {expected}")
        count = f.get("count", [])
        if not isinstance(count, list) or not all(isinstance(c, str) for c in count):
            raise self.bad(where, "'count' must name fields")
        if count and "len" not in out:
            raise self.bad(where, "only an array is counted")
        if count:
            out["count"] = list(count)
        if f.get("text", False) is not False:
            if f["text"] is not True or kind != "u8" or "len" not in out:
                raise self.bad(where, "text must be an array of u8")
            out["text"] = True
        return out


# --- the group's registered types ----------------------------------------------------------


def _place(where: Any) -> tuple:
    """(root path, file prefix, group) of a Node, an iceoryx2 config or a group name."""
    group = None
    if isinstance(where, str):
        group, config = where, group_config(where)
    elif hasattr(where, "identity"):
        group, config = where.identity.group, getattr(where, "_config", None)
        if config is None:
            raise CaravanError(f"node '{where.identity.name}' has not joined its group")
    else:
        config = where
    root = config.global_cfg.root_path.to_string()
    prefix = config.global_cfg.prefix.to_string()
    if group is None:
        group = prefix[4:-1] if prefix.startswith("cvn_") else prefix
    return root, prefix, group


def path(where: Any, type_name: str) -> str:
    """Where the descriptor of ``type_name`` is registered (``types::path`` in Rust)."""
    root, prefix, _ = _place(where)
    return os.path.join(root, f"{prefix}type_{schemas.name_hash(type_name):016x}.json")


def lookup(where: Any, type_name: str) -> type:
    """The class of the type named ``type_name`` in the group: a catalog type's generated
    class, or the class of the descriptor a process of the group registered."""
    if type_name in _CATALOG:
        return _CATALOG[type_name]
    return message_class(_read(where, type_name))


def _read(where: Any, type_name: str) -> dict:
    file = path(where, type_name)
    group = _place(where)[2]

    def unknown(why: str) -> CaravanError:
        return CaravanError(
            f"unknown message type '{type_name}': no process of group '{group}' registered "
            f"it ({why})"
        )

    try:
        with open(file, "rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise unknown(f"no {file}; a process registers it when it opens a port of it") from None
    except OSError as e:
        raise unknown(str(e)) from None
    if len(raw) > MAX_FILE_BYTES:
        raise unknown(f"{file} takes more than {MAX_FILE_BYTES} bytes")
    try:
        descriptor = json.loads(raw)
        described = _canonical(descriptor)["layouts"][-1]["type_name"]
    except (ValueError, CaravanError) as e:
        raise CaravanError(
            f"message type '{type_name}' of group '{group}': malformed descriptor {file}: {e}"
        ) from None
    if described != type_name:
        raise unknown(f"{file} describes '{described}'")
    return descriptor


def register(where: Any, cls: type) -> None:
    """Registers the descriptor of ``cls`` with the group, as a Rust port does: nothing for a
    catalog type or a class without a ``DESCRIPTOR``; a type registered before under the same
    name must have the same descriptor, or ``CaravanError`` names it."""
    if not hasattr(cls, "type_name"):
        return  # a plain ctypes type, which iceoryx2 names by itself
    type_name = cls.type_name()
    generated = _CATALOG.get(type_name)
    if generated is not None:
        if cls is not generated and not _same_layout(cls, generated):
            raise CaravanError(
                f"message type '{type_name}' is Caravan's, laid out otherwise than this class"
            )
        return
    descriptor = getattr(cls, "DESCRIPTOR", None)
    if descriptor is None:
        return
    root, prefix, group = _place(where)
    with _lock:
        if (root, prefix, cls) in _registered:
            return
    ours = _canonical(descriptor)
    _check_describes(cls, ours)
    target = path(where, type_name)
    # Written whole under a name of its own, then linked into place: a reader never sees half
    # a file, and of two processes registering at once, one links and the other compares.
    temp = f"{target[: -len('.json')]}.{os.getpid()}.tmp"
    with _lock:
        try:
            fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            with os.fdopen(fd, "w") as f:
                f.write(json.dumps(ours, separators=(",", ":")))
            os.link(temp, target)
            linked = True
        except FileExistsError:
            linked = False
        except OSError as e:
            raise CaravanError(
                f"cannot register message type '{type_name}' at {target}: {e}"
            ) from None
        finally:
            try:
                os.unlink(temp)
            except OSError:
                pass
        if not linked:
            known = _canonical(_read(where, type_name))
            if known != ours:
                raise CaravanError(
                    f"message type '{type_name}' is declared with two layouts in group "
                    f"'{group}': {json.dumps(known)} and {json.dumps(ours)}; the processes that "
                    "use it were built from different declarations"
                )
        _registered.add((root, prefix, cls))
