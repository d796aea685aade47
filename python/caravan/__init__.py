"""Caravan for Python: agents that join a Caravan group through the iceoryx2 Python package.

``caravan.schemas`` holds the message types as ctypes structures generated from the Rust
schemas, ``caravan.types`` builds those of types learned at run time (``node.message_type``);
``caravan.identity`` the node's identity and params, ``caravan.ports`` typed publishers and
subscribers, ``caravan.node`` the node and its realtime and lockstep step loops.
See docs/agents.md, section Python, and examples/python/follower.py.

``caravan.recording`` reads a run's ``record.mcap`` back into those classes and
``caravan.report`` makes a script a report plugin (docs/scenarios.md, and
python/examples/travelled_distance/); import them by name (``from caravan import report``).
"""

from . import schemas, types
from .identity import BadInput, CaravanError, Identity, parse_duration, parse_rate
from .node import Node, Step, main
from .ports import Publisher, Received, Subscriber
from .schemas import topics

__all__ = [
    "BadInput",
    "CaravanError",
    "Identity",
    "Node",
    "Publisher",
    "Received",
    "Step",
    "Subscriber",
    "main",
    "parse_duration",
    "parse_rate",
    "schemas",
    "topics",
    "types",
]
