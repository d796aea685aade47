"""Checks python/caravan/schemas.py against the Rust layouts.

Reads the JSON of `caravan schemas --layout` on standard input and compares every Rust type
with the Python class of the same name: iceoryx2 type name, ctypes.sizeof and alignment, the
fields in order with their offsets, sizes and element types, and the SIZE/ALIGN/OFFSETS
constants. The first argument, if given, is JSON with more facts from Rust to compare:
{"registry": [type names], "hashes": {name: hash}, "topics": {helper: [i, name]},
"constants": {name: value}, "grant_service": [node, name], "descriptors": {type name:
descriptor JSON}}. For each descriptor, the class ``caravan.types.message_class`` builds from it
must have the generated class's size, alignment, fields and offsets, and read the same bytes
into the same ``to_dict()``.

Prints every mismatch and exits 1 if there is any; prints a one-line summary otherwise.
"""

import ctypes
import json
import random
import sys

from caravan import CaravanError, schemas, types

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


def check_descriptor(type_name, descriptor, errors):
    generated = {cls.type_name(): cls for cls in schemas.ALL_TYPES}.get(type_name)
    if generated is None:
        errors.append(f"{type_name}: a descriptor without a generated class")
        return
    try:
        built = types.message_class(descriptor)
    except CaravanError as e:
        errors.append(f"{type_name}: {e}")
        return

    def expect(what, found, wanted):
        if found != wanted:
            errors.append(
                f"{type_name}: {what} is {found!r} from its descriptor, {wanted!r} in schemas.py"
            )

    expect("type_name()", built.type_name(), type_name)
    expect("ctypes.sizeof", ctypes.sizeof(built), ctypes.sizeof(generated))
    expect("ctypes.alignment", ctypes.alignment(built), ctypes.alignment(generated))
    expect("SIZE", built.SIZE, generated.SIZE)
    expect("ALIGN", built.ALIGN, generated.ALIGN)
    expect("OFFSETS", built.OFFSETS, generated.OFFSETS)
    fields = [n for n, _ in generated._fields_ if not n.startswith("_pad")]
    expect("the field list", [n for n, _ in built._fields_ if not n.startswith("_pad")], fields)
    for field in fields:
        if hasattr(built, field):
            slot, wanted = getattr(built, field), getattr(generated, field)
            expect(f"offset of {field}", slot.offset, wanted.offset)
            expect(f"size of {field}", slot.size, wanted.size)
    if ctypes.sizeof(built) != ctypes.sizeof(generated):
        return
    # One to_dict serves both: the same bytes (random, so counts, text and padding vary) must
    # read alike. json.dumps, because a NaN is not equal to itself.
    rng = random.Random(type_name)
    for _ in range(2):
        raw = rng.randbytes(ctypes.sizeof(built))
        a = json.dumps(built.from_buffer_copy(raw).to_dict())
        b = json.dumps(generated.from_buffer_copy(raw).to_dict())
        if a != b:
            errors.append(f"{type_name}: to_dict() differs from the generated class's")
            break


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

    for type_name, descriptor in facts.get("descriptors", {}).items():
        check_descriptor(type_name, descriptor, errors)

    for e in errors:
        print(e)
    if errors:
        print(f"layout: {len(errors)} mismatches between python/caravan/schemas.py and Rust")
        sys.exit(1)
    print(f"layout: {len(rust)} types match")


if __name__ == "__main__":
    main()
