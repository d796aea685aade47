"""Reads a rosbag2 directory with the `rosbags` library: an independent check of Caravan's bags.

Caravan's rosbag2 exporter is Rust; this reads what it wrote the way ROS 2 tooling would
(metadata.yaml plus MCAP storage, CDR messages, ros2msg schemas) through a separate
implementation. Run it in .venv-ros2 (``python/caravan-python --venv ros2 --requirements
../tests/requirements-ros2.txt --setup``)::

    python read_bag.py BAG_DIR

prints one JSON line per message, in log-time order:
``{"topic": "/robot_0/scan", "type": "sensor_msgs/msg/LaserScan", "log_time_ns": 1700000000000,
"data": {...}}``; arrays become lists, non-finite floats the strings "NaN", "Infinity",
"-Infinity" (as ros2_probe.py prints them).

Messages of the ROS 2 Jazzy standard types are decoded with Jazzy's own definitions (rosbags'
ROS2_JAZZY store), not with what the bag says, and the bag's definition of such a type must
agree with Jazzy's; any other type is decoded with the definition the bag carries. Exits 1 with
a message on stderr when the bag cannot be read: a missing or malformed metadata.yaml or MCAP
file, a message that does not decode (or leaves bytes over), a schema that disagrees with
Jazzy's, or per-topic message counts in metadata.yaml that differ from the storage's.
"""

import json
import math
import sys
from dataclasses import fields, is_dataclass
from pathlib import Path


def fail(message):
    print(f"read_bag: {message}", file=sys.stderr)
    sys.exit(1)


try:
    from rosbags.interfaces import MessageDefinitionFormat
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
except ImportError as e:
    fail(f"{e}: run this in .venv-ros2 (python/caravan-python --venv ros2 ... --setup)")


def plain(value):
    """A decoded message (or a value in one) as JSON-able dicts, lists, numbers, strings."""
    if is_dataclass(value) and not isinstance(value, type):
        # rosbags classes carry their type name as a field, __msgtype__: not message data.
        return {
            f.name: plain(getattr(value, f.name)) for f in fields(value) if not f.name.startswith("__")
        }
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    return value


def bag_types(connection):
    """The types the connection's own message definition declares ({} if it carries none)."""
    msgdef = connection.msgdef
    if msgdef.format == MessageDefinitionFormat.MSG and msgdef.data.strip():
        return get_types_from_msg(msgdef.data, connection.msgtype)
    if msgdef.format == MessageDefinitionFormat.IDL and msgdef.data.strip():
        return get_types_from_idl(msgdef.data)
    return {}


def check_against_jazzy(connection, declared, jazzy):
    """Refuses a bag whose definition of a standard type differs from Jazzy's."""
    for name, definition in declared.items():
        if name not in jazzy.fielddefs:
            continue
        mine = get_typestore(Stores.EMPTY)
        mine.register({name: definition})
        # Compare the shapes (field names, base types, lengths) rather than the parse trees'
        # incidental details; nested names are compared by name, and checked in their turn.
        if _shape(mine.fielddefs[name]) != _shape(jazzy.fielddefs[name]):
            fail(
                f"{connection.topic}: the bag's definition of {name} differs from ROS 2 Jazzy's\n"
                f"  bag:   {_shape(mine.fielddefs[name])}\n"
                f"  Jazzy: {_shape(jazzy.fielddefs[name])}"
            )


def _shape(fielddef):
    consts, members = fielddef
    return (
        sorted((c[0], c[1], c[2]) for c in consts),
        [(fname, _type_shape(ftype)) for fname, ftype in members],
    )


def _type_shape(ftype):
    kind, rest = ftype
    if kind.name == "BASE":
        return ("BASE", rest[0], rest[1])
    if kind.name == "NAME":
        return ("NAME", rest)
    return (kind.name, _type_shape(rest[0]), rest[1])


def main(argv):
    if len(argv) != 1 or argv[0].startswith("-"):
        print("usage: read_bag.py BAG_DIR", file=sys.stderr)
        return 2
    path = Path(argv[0])
    if not path.is_dir():
        fail(f"{path}: not a directory (a rosbag2 bag is a directory with metadata.yaml)")
    if not (path / "metadata.yaml").is_file():
        fail(f"{path}: no metadata.yaml")

    jazzy = get_typestore(Stores.ROS2_JAZZY)
    counts = {}
    try:
        with Reader(path) as reader:
            extra = {}
            for connection in reader.connections:
                if connection.ext.serialization_format != "cdr":
                    fail(
                        f"{connection.topic}: serialization format "
                        f"{connection.ext.serialization_format!r}, expected 'cdr'"
                    )
                declared = bag_types(connection)
                check_against_jazzy(connection, declared, jazzy)
                if connection.msgtype not in jazzy.fielddefs:
                    if connection.msgtype not in declared:
                        fail(
                            f"{connection.topic}: type {connection.msgtype} is neither a ROS 2 "
                            "Jazzy type nor defined in the bag"
                        )
                    extra.update({k: v for k, v in declared.items() if k not in jazzy.fielddefs})
            if extra:
                jazzy.register(extra)

            for connection, timestamp, rawdata in reader.messages():
                try:
                    message = jazzy.deserialize_cdr(rawdata, connection.msgtype)
                except Exception as e:  # rosbags raises plain exceptions on malformed CDR
                    fail(
                        f"{connection.topic}: message {counts.get(connection.id, 0)} "
                        f"({connection.msgtype}, {len(rawdata)} bytes) does not decode: {e!r}"
                    )
                counts[connection.id] = counts.get(connection.id, 0) + 1
                line = {
                    "topic": connection.topic,
                    "type": connection.msgtype,
                    "log_time_ns": timestamp,
                    "data": plain(message),
                }
                try:
                    sys.stdout.write(json.dumps(line, allow_nan=False) + "\n")
                except BrokenPipeError:
                    return 0
            sys.stdout.flush()

            for connection in reader.connections:
                found = counts.get(connection.id, 0)
                if connection.msgcount != found:
                    fail(
                        f"{connection.topic}: metadata.yaml says {connection.msgcount} messages, "
                        f"the storage holds {found}"
                    )
    except SystemExit:
        raise
    except Exception as e:  # ReaderError, YAML and MCAP errors, missing files
        fail(f"{path}: cannot read the bag: {type(e).__name__}: {e}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
