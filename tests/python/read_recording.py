"""Reads a recording with caravan.recording, for tests/tests/python/recording.rs: prints the
topics, the metadata and launch file, then one JSON line per message (topic, log time, header,
type and the decoded message's to_dict(), or the dict when its type has no class). A
RecordingError is printed on stderr with exit status 2. A float that is NaN prints as null.

    read_recording.py FILE [TOPIC...]
"""

import json
import math
import sys

from caravan import recording


def finite(value):
    """NaN as null, as Rust's JSON writes it (Python's json would write NaN, which is not JSON)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite(v) for v in value]
    return value


try:
    with recording.open(sys.argv[1]) as rec:
        print(json.dumps({"topics": [t._asdict() for t in rec.topics()]}))
        print(json.dumps({"metadata": rec.metadata, "launch_file": rec.launch_file,
                          "start_ns": rec.start_ns, "end_ns": rec.end_ns}))
        for item in rec.messages(sys.argv[2:] or None):
            topic, log_time_ns, message = item
            decoded = not isinstance(message, dict)
            print(json.dumps(finite({
                "topic": topic,
                "log_time_ns": log_time_ns,
                "header": item.header.to_dict(),
                "type": item.type_name,
                "class": type(message).__name__ if decoded else None,
                "message": message.to_dict() if decoded else message,
            })))
except recording.RecordingError as e:
    print(f"error: {type(e).__name__}: {e}", file=sys.stderr)
    sys.exit(2)
