"""Checks caravan.types: message types a Python process learns at run time or registers.

Arguments: a group name and the JSON descriptor of ``test::Gadget``, which the caller (a Rust
test) registered with that group. Checks that the class looked up from the group reads and
writes like the descriptor says, that registering follows Rust's rules (0600, linked whole,
the same layout or a refusal naming the type, never a catalog type) and that bad descriptors
and unknown types are refused with the names a person needs. Registers ``test::Widget`` for the
caller to read back. Prints ``view <bytes> <to_dict>`` of one gadget, every failure, and a
summary; exits 1 on any failure.
"""

import copy
import ctypes
import json
import os
import stat
import sys

from caravan import CaravanError, schemas, types

errors = []


def check(what, ok):
    if not ok:
        errors.append(what)


def refused(what, action, *words):
    """``action()`` raises a CaravanError whose message holds every one of ``words``."""
    try:
        action()
    except CaravanError as e:
        missing = [w for w in words if w not in str(e)]
        check(f"{what}: the error does not name {missing}: {e}", not missing)
        return
    errors.append(f"{what}: not refused")


def main():
    group, gadget = sys.argv[1], json.loads(sys.argv[2])

    # The type Rust registered: the class has its layout and the generated classes' API.
    Gadget = types.lookup(group, "test::Gadget")
    layout = gadget["layouts"][-1]
    check("Gadget's size", (ctypes.sizeof(Gadget), Gadget.SIZE) == (layout["size"],) * 2)
    check("Gadget's alignment", ctypes.alignment(Gadget) == layout["align"] == Gadget.ALIGN)
    check("Gadget's offsets", Gadget.OFFSETS == {f["name"]: f["offset"] for f in layout["fields"]})
    check("Gadget's type name", Gadget.type_name() == "test::Gadget")
    held = dict(Gadget._fields_)["position"]
    check("a held catalog struct is its generated class", held is schemas.Vector3)
    check("one class per descriptor", types.lookup(group, "test::Gadget") is Gadget)
    g = Gadget()
    schemas.set_fixed_str(g, "name", "gizmo")
    g.position = schemas.Vector3(1.5, -2.0, 0.25)
    g.values[:] = [7, -8, 9, 10]
    g.n = 2
    view = g.to_dict()
    check(
        f"Gadget's to_dict(): {view}",
        view == {"name": "gizmo", "position": {"x": 1.5, "y": -2.0, "z": 0.25}, "values": [7, -8]},
    )
    print("view", json.dumps(list(bytes(g))), json.dumps(view))

    # Registering what is registered already: the same descriptor, accepted.
    types.register(group, Gadget)
    # Another layout under its name: refused, naming the type.
    other = copy.deepcopy(gadget)
    other["layouts"][-1]["fields"][3]["type"] = "u32"
    refused(
        "a second layout of test::Gadget",
        lambda: types.register(group, types.message_class(other)),
        "test::Gadget",
        "two layouts",
        group,
    )

    # A class of one's own with a DESCRIPTOR: registered as Rust registers, read back alike.
    class Widget(schemas.Message):
        _fields_ = [
            ("a", ctypes.c_uint32),
            ("_pad0", ctypes.c_uint8 * 4),
            ("b_len", ctypes.c_uint32),
            ("b", ctypes.c_double * 3),
        ]
        DESCRIPTOR = {
            "layouts": [
                {
                    "name": "Widget",
                    "type_name": "test::Widget",
                    "size": 40,
                    "align": 8,
                    "fields": [
                        {"name": "a", "offset": 0, "size": 4, "type": "u32"},
                        {"name": "b_len", "offset": 8, "size": 4, "type": "u32"},
                        {
                            "name": "b",
                            "offset": 16,
                            "size": 24,
                            "type": "f64",
                            "len": 3,
                            "count": ["b_len"],
                        },
                    ],
                }
            ],
            "default": None,
        }

        @classmethod
        def type_name(cls):
            return "test::Widget"

    types.register(group, Widget)
    file = types.path(group, "test::Widget")
    check("the descriptor file is 0600", stat.S_IMODE(os.stat(file).st_mode) == 0o600)
    root = os.path.dirname(file)
    check(
        "no temporary file is left",
        not [n for n in os.listdir(root) if n.endswith(f".{os.getpid()}.tmp")],
    )
    back = types.lookup(group, "test::Widget")
    check("Widget read back", back.OFFSETS == {"a": 0, "b_len": 8, "b": 16} and back.SIZE == 40)

    class Liar(Widget):
        _fields_ = [("extra", ctypes.c_double)]

    refused(
        "a class its DESCRIPTOR does not describe",
        lambda: types.register(group, Liar),
        "test::Widget",
        "DESCRIPTOR",
    )

    # A catalog type is never registered, and looks up as its generated class.
    types.register(group, schemas.Pose2D)
    pose = types.path(group, "caravan::Pose2D")
    check("a catalog type is not registered", not os.path.exists(pose))
    found = types.lookup(group, "caravan::Pose2D")
    check("a catalog type looks up as its generated class", found is schemas.Pose2D)

    # Unknown and malformed types are named, with the group.
    refused(
        "an unregistered type",
        lambda: types.lookup(group, "test::Nothing"),
        "test::Nothing",
        group,
        "no process",
    )
    with open(types.path(group, "test::Broken"), "w") as f:
        f.write('{"layouts": [{"name": "Broken"}]}')
    refused(
        "a malformed descriptor",
        lambda: types.lookup(group, "test::Broken"),
        "test::Broken",
        "malformed",
    )
    os.unlink(types.path(group, "test::Broken"))

    # Descriptors ctypes or to_dict cannot follow are refused, naming the type and field.
    def edited(edit):
        d = copy.deepcopy(gadget)
        edit(d["layouts"][-1])
        return lambda: types.message_class(d)

    def misalign(l):
        l["fields"][3]["offset"] = 42
        l["fields"][4]["offset"] = 60

    refused("a misaligned field", edited(misalign), "test::Gadget", "Gadget.values", "offset 42")

    def untext(l):
        l["fields"][1]["count"] = ["n"]

    refused("text not counted by its _len", edited(untext), "test::Gadget", "Gadget.name")

    def realign(l):
        l["align"] = 16
        l["size"] = 64

    refused("an alignment ctypes cannot give", edited(realign), "test::Gadget", "align")

    # A FixedVec<u8> shows as numbers, a FixedString as text (the same to_dict).
    def bytes_vec(l):
        l["fields"][1].pop("text")

    Bytes = edited(bytes_vec)()
    b = Bytes()
    schemas.set_fixed_vec(b, "name", [104, 105])
    check(f"a u8 vector's to_dict(): {b.to_dict()}", b.to_dict()["name"] == [104, 105])

    for e in errors:
        print(e)
    if errors:
        print(f"types: {len(errors)} failures")
        sys.exit(1)
    print("types: registration and lookup as in Rust")


if __name__ == "__main__":
    main()
