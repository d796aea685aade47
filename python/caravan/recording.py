"""Reading a run's recording (``record.mcap``) back into messages, as Rust's report plugins do.

A Caravan recording is an MCAP file (written by the library ``caravan``) whose chunks are
zstd-compressed. Each Caravan topic is a channel whose schema is named for the message type
(``caravan::Pose2D``, a Rust path), encoded as JSON Schema with the type's descriptor under
``x-caravan-descriptor``; its messages are JSON, the message's fields plus a ``header``
(``seq``, ``stamp_ns``, ``source_id`` as a decimal string). Beside them lie Foxglove's views of
the same messages (``foxglove.*`` schemas, protobuf), which this module leaves out, a ``run``
metadata record and the resolved launch file as the ``launch.toml`` attachment.
docs/recording.md says what a recording holds.

::

    from caravan import recording

    with recording.open("runs/pingpong-…/record.mcap") as rec:
        for t in rec.topics():
            print(t.name, t.type, t.count)
        for topic, log_time_ns, msg in rec.messages(["demo/ping"], start_ns=1_000_000_000):
            print(topic, log_time_ns, msg.x)  # a caravan.schemas.Pose2D

A message of a type that ``caravan.schemas`` has is decoded into its class (``msg.to_dict()``
is the recorded JSON without its header); one of another type into the class its recorded
descriptor describes (``caravan.types.message_class``), else a ``dict`` of its fields. Each
item also has ``.header`` (a ``schemas.Header``: ``seq``, ``stamp_ns``, ``source_id``),
``.type_name`` and ``.json`` (the message as recorded, header included).

Every error is a ``RecordingError`` naming the file: a file that is missing, not MCAP, not a
Caravan recording, cut short (no footer: the recorder did not finish it), or damaged (a chunk
whose CRC does not match). A channel in an encoding this module cannot decode (a later binary
encoding, say) is listed by ``topics()`` and raises ``UnsupportedEncoding`` when its messages
are read.
"""

from __future__ import annotations

import ctypes
import io
import json
import math
import os
from typing import Any, Iterable, Iterator, NamedTuple, Optional, Union

from . import schemas
from .identity import CaravanError

try:
    from mcap.exceptions import McapError
    from mcap.reader import SeekingReader
except ImportError as e:  # pragma: no cover - the venv has them (python/caravan-python)
    raise ImportError(
        "caravan.recording needs the 'mcap' and 'zstandard' packages: pip install ./python, "
        "or run the script with python/caravan-python"
    ) from e

__all__ = [
    "Recorded",
    "Recording",
    "RecordingError",
    "Topic",
    "UnsupportedEncoding",
    "from_dict",
    "open",
]

# What the recorder writes into the MCAP header (runtime/record/src/writer.rs).
LIBRARY = "caravan"
# The attachment holding the launch file after overrides, includes and templates.
LAUNCH_FILE = "launch.toml"
# The schema key carrying the type's descriptor (caravan_record::schema::DESCRIPTOR_KEY).
DESCRIPTOR_KEY = "x-caravan-descriptor"
# Message encodings this module decodes.
ENCODINGS = ("json",)
_MAGIC = b"\x89MCAP0\r\n"


class RecordingError(CaravanError):
    """A recording that cannot be read; the message names the file."""


class UnsupportedEncoding(RecordingError):
    """A channel whose message encoding this module does not decode."""


class Topic(NamedTuple):
    """One Caravan channel of a recording."""

    name: str
    #: The message type's Rust name, e.g. ``caravan::Pose2D``.
    type: str
    #: Messages recorded on it (from the summary's statistics).
    count: int
    #: The channel's message encoding (``json``).
    encoding: str


class Recorded:
    """One recorded message: unpacks as ``(topic, log_time_ns, message)``."""

    __slots__ = ("topic", "log_time_ns", "message", "header", "type_name", "json")

    def __init__(self, topic, log_time_ns, message, header, type_name, view):
        self.topic = topic
        #: The MCAP log time: the simulated stamp in lockstep, the wall clock in realtime.
        self.log_time_ns = log_time_ns
        self.message = message
        self.header = header
        self.type_name = type_name
        self.json = view

    def __iter__(self):
        return iter((self.topic, self.log_time_ns, self.message))

    def __repr__(self) -> str:
        return f"Recorded({self.topic!r}, {self.log_time_ns}, {self.message!r})"


def open(path: Union[str, os.PathLike], *, decode: bool = True) -> "Recording":  # noqa: A001
    """The recording at ``path`` (see ``Recording``)."""
    return Recording(path, decode=decode)


class Recording:
    """A Caravan recording, opened and checked: its summary read, its header's writer checked.

    ``decode=False`` yields every message as a ``dict`` of its recorded fields (faster for
    large messages such as maps, when only a few fields are needed)."""

    def __init__(self, path: Union[str, os.PathLike], *, decode: bool = True):
        self.path = os.fspath(path)
        self._decode = decode
        try:
            self._file = io.open(self.path, "rb")
        except OSError as e:
            raise RecordingError(f"cannot read {self.path}: {e.strerror or e}") from None
        try:
            self._open()
        except BaseException:
            self._file.close()
            raise

    def _open(self) -> None:
        if self._file.read(len(_MAGIC)) != _MAGIC:
            raise RecordingError(f"{self.path} is not an MCAP file")
        # The recorder ends the file with the magic again after the summary; a file without
        # it was cut short (a run killed before its recorder finished, a partial copy).
        self._file.seek(0, io.SEEK_END)
        size = self._file.tell()
        self._file.seek(max(size - len(_MAGIC), 0))
        if size < 2 * len(_MAGIC) or self._file.read(len(_MAGIC)) != _MAGIC:
            raise RecordingError(
                f"{self.path} is cut short: it does not end as an MCAP file ends (was the run "
                f"interrupted before the recorder finished the file, or the copy partial?)"
            )
        self._file.seek(0)
        try:
            self._reader = SeekingReader(self._file, validate_crcs=True)
            header = self._reader.get_header()
        except (McapError, ValueError, EOFError) as e:
            raise RecordingError(f"{self.path}: cannot read its header: {e}") from None
        if header.library != LIBRARY:
            raise RecordingError(
                f"{self.path} is an MCAP file but not a Caravan recording "
                f"(written by '{header.library}', not '{LIBRARY}')"
            )
        try:
            summary = self._reader.get_summary()
        except (McapError, ValueError, EOFError, KeyError) as e:
            raise RecordingError(
                f"{self.path} is cut short or damaged: it has no readable summary ({e}); was "
                f"the run interrupted before the recorder finished the file?"
            ) from None
        if summary is None:
            raise RecordingError(f"{self.path} has no summary (the recorder always writes one)")
        self._summary = summary
        counts = summary.statistics.channel_message_counts if summary.statistics else {}
        self._topics = {}
        self._types = {}  # type name -> class, or None for a dict
        for cid, channel in sorted(summary.channels.items()):
            schema = summary.schemas.get(channel.schema_id)
            if schema is None or "::" not in schema.name:
                continue  # a Foxglove view or a foreign channel
            self._topics[channel.topic] = Topic(
                channel.topic, schema.name, counts.get(cid, 0), channel.message_encoding
            )
            if schema.name not in self._types:
                self._types[schema.name] = _message_class(schema)

    # -- what the file holds ------------------------------------------------------------------

    def topics(self) -> list:
        """The Caravan topics, sorted by name, each with its type, count and encoding."""
        return sorted(self._topics.values())

    @property
    def start_ns(self) -> int:
        """The first message's log time (0 for a recording without messages)."""
        stats = self._summary.statistics
        return stats.message_start_time if stats and stats.message_count else 0

    @property
    def end_ns(self) -> int:
        """The last message's log time."""
        stats = self._summary.statistics
        return stats.message_end_time if stats and stats.message_count else 0

    @property
    def metadata(self) -> dict:
        """The metadata records by name: ``run`` has ``caravan_version``, ``arguments``,
        ``seed`` (and ``wall_clock_start_ns`` in realtime)."""
        try:
            return {m.name: dict(m.metadata) for m in self._reader.iter_metadata()}
        except (McapError, ValueError, EOFError) as e:
            raise RecordingError(f"{self.path}: cannot read its metadata: {e}") from None

    @property
    def attachments(self) -> dict:
        """The attachments' bytes by name."""
        try:
            return {a.name: a.data for a in self._reader.iter_attachments()}
        except (McapError, ValueError, EOFError) as e:
            raise RecordingError(f"{self.path}: cannot read its attachments: {e}") from None

    @property
    def launch_file(self) -> Optional[str]:
        """The resolved launch file the run was started with (TOML text), if attached."""
        data = self.attachments.get(LAUNCH_FILE)
        return None if data is None else bytes(data).decode("utf-8")

    # -- messages -----------------------------------------------------------------------------

    def messages(
        self,
        topics: Union[str, Iterable[str], None] = None,
        start_ns: Optional[int] = None,
        end_ns: Optional[int] = None,
    ) -> Iterator[Recorded]:
        """The messages of ``topics`` (all Caravan topics when ``None``) logged in
        ``[start_ns, end_ns)``, in file order (log-time order for the recorder's files).
        Every chunk's CRC is checked as it is read. A topic the file has no channel for yields
        nothing (``topics()`` lists those it has)."""
        if isinstance(topics, str):
            topics = [topics]
        wanted = set(self._topics) if topics is None else set(topics)
        for name in wanted & set(self._topics):
            encoding = self._topics[name].encoding
            if encoding not in ENCODINGS:
                raise UnsupportedEncoding(
                    f"{self.path}: topic '{name}' ({self._topics[name].type}) is in the "
                    f"unsupported encoding '{encoding}'; this version of caravan.recording "
                    f"reads {', '.join(ENCODINGS)}"
                )
        try:
            found = self._reader.iter_messages(
                topics=sorted(wanted),
                log_time_order=False,
                starting_at=start_ns,
                ending_before=end_ns,
            )
            for schema, channel, message in found:
                if channel.topic not in self._topics:
                    continue
                yield self._decoded(schema.name, channel.topic, message)
        except (McapError, ValueError, EOFError, KeyError) as e:
            if isinstance(e, RecordingError):
                raise
            raise RecordingError(f"{self.path} is damaged or cut short: {e}") from None

    def _decoded(self, type_name: str, topic: str, message) -> Recorded:
        try:
            view = json.loads(message.data)
        except (ValueError, UnicodeDecodeError) as e:
            raise RecordingError(f"{self.path}: a message on {topic} is not JSON: {e}") from None
        if not isinstance(view, dict):
            raise RecordingError(f"{self.path}: a message on {topic} is not a JSON object")
        header = from_dict(schemas.Header, view.get("header") or {})
        # The header is the envelope the recorder adds (the classes have no such field).
        fields = {k: v for k, v in view.items() if k != "header"}
        cls = self._types.get(type_name) if self._decode else None
        if cls is None:
            decoded = fields
        else:
            try:
                decoded = from_dict(cls, fields)
            except (TypeError, ValueError, KeyError, IndexError) as e:
                raise RecordingError(
                    f"{self.path}: a message on {topic} does not fit {type_name}: {e}"
                ) from None
        return Recorded(topic, message.log_time, decoded, header, type_name, view)

    # -- closing ------------------------------------------------------------------------------

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "Recording":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Recording({self.path!r}, {len(self._topics)} topics)"


def _message_class(schema) -> Optional[type]:
    """The class messages of ``schema`` decode into: the generated one, else the one its
    recorded descriptor describes, else ``None`` (they stay dicts)."""
    cls = schemas.BY_TYPE_NAME.get(schema.name)
    if cls is not None:
        return cls
    try:
        descriptor = json.loads(schema.data).get(DESCRIPTOR_KEY)
    except (ValueError, UnicodeDecodeError, AttributeError):
        return None
    if not isinstance(descriptor, dict):
        return None
    from . import types  # only for types outside the catalog

    try:
        return types.message_class(descriptor)
    except (CaravanError, KeyError, TypeError, ValueError):
        return None


# --- from the JSON view back to a message ----------------------------------------------------

_FLOATS = (ctypes.c_double, ctypes.c_float)


def from_dict(cls: type, view: dict) -> Any:
    """A ``cls`` filled from its JSON view (what ``to_dict()`` gives and recordings hold): the
    inverse of ``schemas.Message.to_dict``. A float recorded as ``null`` (Rust's JSON for NaN)
    reads as NaN; a ``u64`` written as a decimal string reads as an integer."""
    msg = cls()
    _fill(msg, view)
    return msg


def _fill(msg: ctypes.Structure, view: dict) -> None:
    fields = dict(msg._fields_)
    counts = getattr(type(msg), "_counts_", {})
    for name, ctype in msg._fields_:
        if name not in view:
            continue  # padding, a length or count implied by its array, or not recorded
        value = view[name]
        if name + "_len" in fields:
            if isinstance(value, str):
                schemas.set_fixed_str(msg, name, value)
                continue
            items = getattr(msg, name)
            n = min(len(value), len(items))
            _fill_array(items, ctype._type_, value[:n])
            setattr(msg, name + "_len", n)
        elif issubclass(ctype, ctypes.Array):
            items = getattr(msg, name)
            n = min(len(value), len(items))
            _fill_array(items, ctype._type_, value[:n])
            by = counts.get(name, ())
            # A count that alone counts its array is not recorded: the array's length is it.
            if len(by) == 1 and by[0] not in view:
                setattr(msg, by[0], n)
        elif issubclass(ctype, ctypes.Structure):
            _fill(getattr(msg, name), value)
        else:
            setattr(msg, name, _scalar(ctype, value))


def _fill_array(items, element, values: list) -> None:
    if issubclass(element, ctypes.Structure):
        for i, v in enumerate(values):
            _fill(items[i], v)
    elif issubclass(element, ctypes.Array):
        for i, v in enumerate(values):
            _fill_array(items[i], element._type_, v[: len(items[i])])
    elif values:
        items[: len(values)] = [_scalar(element, v) for v in values]


def _scalar(ctype, value):
    if issubclass(ctype, _FLOATS):
        return math.nan if value is None else float(value)
    if isinstance(value, str):
        return int(value)
    return value
