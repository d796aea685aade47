"""Caravan for Python: agents that join a Caravan group through the iceoryx2 Python package.

``caravan.schemas`` holds the message types as ctypes structures generated from the Rust
schemas; ``caravan.node`` the runtime (identity, typed ports, realtime and lockstep step loops).
See docs/agents.md, section Python, and examples/python/follower.py.
"""

from . import schemas
from .node import (
    CaravanError,
    Identity,
    Node,
    Publisher,
    Received,
    Step,
    Subscriber,
    main,
    parse_duration,
    parse_rate,
)
from .schemas import topics

__all__ = [
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
]
