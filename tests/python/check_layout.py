"""Checks python/caravan/schemas.py against the Rust layouts.

Reads the JSON of `caravan schemas --layout` on standard input and compares every Rust type
with the Python class of the same name: iceoryx2 type name, ctypes.sizeof and alignment, the
fields in order with their offsets, sizes and element types, and the SIZE/ALIGN/OFFSETS
constants. The first argument, if given, is JSON with more facts from Rust to compare:
{"registry": [type names], "hashes": {name: hash}, "topics": {helper: [i, name]},
"constants": {name: value}, "grant_service": [node, name]}.

Prints every mismatch and exits 1 if there is any; prints a one-line summary otherwise.
"""

import ctypes
import json
import sys

from caravan import schemas

SCALARS = {
    "f64": ctypes.c_double,
    "f32": ctypes.c_float,
    "u64": ctypes.c_uint64,
    "i64": ctypes.c_int64,
    "u32": ctypes.c_uint32,
    "i32": ctypes.c_int32,
    "u8": ctypes.c_uint8,
    "i8": ctypes.c_int8,
}


def check_type(layout, cls, errors):
    name = layout["name"]

    def expect(what, found, wanted):
        if found != wanted:
            errors.append(f"{name}: {what} is {found!r} in Python, {wanted!r} in Rust")

    expect("type_name()", cls.type_name(), layout["type_name"])
    expect("ctypes.sizeof", ctypes.sizeof(cls), layout["size"])
    expect("ctypes.alignment", ctypes.alignment(cls), layout["align"])
    expect("SIZE", cls.SIZE, layout["size"])
    expect("ALIGN", cls.ALIGN, layout["align"])
    expect("OFFSETS", cls.OFFSETS, {f["name"]: f["offset"] for f in layout["fields"]})
    declared = dict(cls._fields_)
    expect(
        "the field list",
        [n for n, _ in cls._fields_ if not n.startswith("_pad")],
        [f["name"] for f in layout["fields"]],
    )
    for f in layout["fields"]:
        field = f["name"]
        if field not in declared:
            continue
        descriptor = getattr(cls, field)
        expect(f"offset of {field}", descriptor.offset, f["offset"])
        expect(f"size of {field}", descriptor.size, f["size"])
        ctype = declared[field]
        if "len" in f:
            expect(f"length of {field}", getattr(ctype, "_length_", None), f["len"])
            ctype = getattr(ctype, "_type_", None)
        wanted = SCALARS.get(f["type"]) or getattr(schemas, f["type"], None)
        if ctype is not wanted:
            errors.append(
                f"{name}: {field} holds {getattr(ctype, '__name__', ctype)} in Python, "
                f"{f['type']} in Rust"
            )


def main():
    rust = json.load(sys.stdin)
    facts = json.loads(sys.argv[1]) if len(sys.argv) > 1 else {}
    errors = []
    python = {cls.__name__: cls for cls in schemas.ALL_TYPES}
    for layout in rust:
        cls = python.pop(layout["name"], None)
        if cls is None:
            errors.append(f"{layout['name']}: no Python class")
        else:
            check_type(layout, cls, errors)
    errors += [f"{name}: a Python class without a Rust type" for name in python]

    if "registry" in facts:
        found = [t.type_name() for t in schemas.MESSAGE_TYPES]
        if found != facts["registry"]:
            errors.append(f"MESSAGE_TYPES is {found}, the Rust registry {facts['registry']}")
    for name, wanted in facts.get("hashes", {}).items():
        if schemas.name_hash(name) != wanted:
            errors.append(f"name_hash({name!r}) is {schemas.name_hash(name)}, {wanted} in Rust")
    for helper, (i, wanted) in facts.get("topics", {}).items():
        found = getattr(schemas.topics, helper)(i)
        if found != wanted:
            errors.append(f"topics.{helper}({i}) is {found!r}, {wanted!r} in Rust")
    for name, wanted in facts.get("constants", {}).items():
        found = getattr(schemas, name, None)
        if found is None:
            found = getattr(schemas.topics, name, getattr(schemas.lockstep, name, None))
        if found != wanted:
            errors.append(f"{name} is {found!r}, {wanted!r} in Rust")
    if "grant_service" in facts:
        node, wanted = facts["grant_service"]
        if schemas.lockstep.grant_service(node) != wanted:
            errors.append(f"lockstep.grant_service({node!r}) differs from Rust's {wanted!r}")

    for e in errors:
        print(e)
    if errors:
        print(f"layout: {len(errors)} mismatches between python/caravan/schemas.py and Rust")
        sys.exit(1)
    print(f"layout: {len(rust)} types match")


if __name__ == "__main__":
    main()
