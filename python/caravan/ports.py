"""Typed ports: publishers and subscribers of a topic, the received message, and the node's step
statistics (``caravan::Publisher``, ``caravan::Subscriber``, ``caravan::StepStats``)."""

from __future__ import annotations

import ctypes
import math
import time
from collections import deque
from typing import TYPE_CHECKING, Any, Iterator, Optional, Type

import iceoryx2 as iox

from .identity import CaravanError, T
from .schemas import Header, NodeStatus, name_hash

if TYPE_CHECKING:
    from .node import Node

# --- statistics ----------------------------------------------------------------------------


class _Stats:
    """Steps, deadline misses, period jitter and compute time (``caravan::StepStats``);
    percentiles cover the last 10,000 steps."""

    def __init__(self, period_ns: int) -> None:
        self.period_ns = period_ns
        self.steps = 0
        self.deadline_misses = 0
        self.jitter: deque = deque(maxlen=10_000)
        self.compute: deque = deque(maxlen=10_000)
        self.jitter_max = 0
        self.compute_max = 0
        self.compute_sum = 0
        self.cpu_sum = 0
        self.last_start: Optional[int] = None

    def record(self, start_ns: int, due_ns: int, compute_ns: int, cpu_ns: int) -> None:
        """One step: wall-clock ``compute_ns`` and the stepping thread's ``cpu_ns`` in it."""
        self.steps += 1
        self.cpu_sum += cpu_ns
        self.compute.append(compute_ns)
        self.compute_max = max(self.compute_max, compute_ns)
        self.compute_sum += compute_ns
        if self.period_ns > 0:
            if self.last_start is not None:
                jitter = abs(max(start_ns - self.last_start, 0) - self.period_ns)
                self.jitter.append(jitter)
                self.jitter_max = max(self.jitter_max, jitter)
            late = max(start_ns - due_ns, 0)
            if late > self.period_ns or compute_ns > self.period_ns:
                self.deadline_misses += 1
        self.last_start = start_ns

    @staticmethod
    def _quantile(values: deque, q: float) -> int:
        if not values:
            return 0
        ordered = sorted(values)
        return ordered[min(len(ordered) - 1, max(0, math.ceil(q * len(ordered)) - 1))]

    def fill(self, s: NodeStatus) -> None:
        s.period_ns = self.period_ns
        s.steps = self.steps
        s.deadline_misses = self.deadline_misses
        s.jitter_p50_ns = self._quantile(self.jitter, 0.5)
        s.jitter_p99_ns = self._quantile(self.jitter, 0.99)
        s.jitter_max_ns = self.jitter_max
        s.compute_mean_ns = self.compute_sum // max(self.steps, 1)
        s.compute_p99_ns = self._quantile(self.compute, 0.99)
        s.compute_max_ns = self.compute_max
        s.compute_cpu_mean_ns = self.cpu_sum // max(self.steps, 1)


# --- ports ---------------------------------------------------------------------------------


class Received:
    """A received message: a copy of its ``header`` (``schemas.Header``) and ``payload``."""

    __slots__ = ("header", "payload")

    def __init__(self, header: Header, payload: Any) -> None:
        self.header = header
        self.payload = payload

    @property
    def stamp_s(self) -> float:
        """The simulated time the message was published at, in seconds."""
        return self.header.stamp_ns * 1e-9


def _open(port: Any, node: "Node", msg_type: Type[T], topic: str, depth: int, lossless: bool) -> Any:
    """Binds ``port`` to its node and topic and opens the topic's service."""
    port.topic = topic
    port.msg_type = msg_type
    port._node = node
    return node._open_pubsub(msg_type, topic, depth, lossless)


class Publisher:
    """Publishes one message type on one topic, stamping each message's ``Header``."""

    def __init__(
        self, node: "Node", msg_type: Type[T], topic: str, depth: int, lossless: bool
    ) -> None:
        service = _open(self, node, msg_type, topic, depth, lossless)
        self._hash = name_hash(topic)
        strategy = (
            iox.BackpressureStrategy.RetryUntilDelivered
            if lossless
            else iox.BackpressureStrategy.DiscardData
        )
        try:
            self._port = (
                service.publisher_builder()
                .backpressure_strategy(strategy)
                .max_loaned_samples(2)
                .create()
            )
        except Exception as e:
            raise CaravanError(f"topic '{topic}': cannot create publisher: {e}") from None
        self._notifier = node._event(topic).notifier_builder().create()
        node._ports += [self._port, self._notifier]
        self.sequence = 0

    def publish(self, value: Any) -> None:
        """Publishes a copy of ``value`` (an instance of the topic's message type)."""
        sample = self._loan()
        self._send(sample.write_payload(value))

    class _Loan:
        def __init__(self, publisher: "Publisher") -> None:
            self._publisher = publisher
            self._sample = publisher._loan()
            size = ctypes.sizeof(publisher.msg_type)
            ctypes.memset(self._sample.payload_ptr, 0, size)

        def __enter__(self) -> Any:
            return self._sample.payload().contents

        def __exit__(self, kind, value, traceback) -> None:
            if kind is None:
                self._publisher._send(self._sample.assume_init())
            else:
                self._sample.delete()

    def loan(self) -> "Publisher._Loan":
        """``with pub.loan() as msg: …`` fills a zeroed message in shared memory and publishes
        it at the end of the block, without a copy (for scans and maps)."""
        return Publisher._Loan(self)

    def _loan(self) -> Any:
        try:
            return self._port.loan_uninit()
        except Exception as e:
            raise CaravanError(f"topic '{self.topic}': cannot loan a sample: {e}") from None

    def _send(self, sample: Any) -> None:
        self.sequence += 1
        node = self._node
        h = sample.user_header().contents
        h.seq = self.sequence
        h.stamp_ns = node._now_ns
        h.send_wall_ns = time.time_ns()
        h.source_id = node.identity.node_hash
        try:
            sample.send()
        except Exception as e:
            raise CaravanError(f"topic '{self.topic}': cannot send: {e}") from None
        if node.lockstep:
            if self._hash not in node._published:
                node._published.append(self._hash)
        else:
            # Wakes event-driven subscribers; in lockstep the scheduler wakes them instead.
            self._notifier.notify()


class Subscriber:
    """Receives one message type from one topic. In lockstep a message stamped t is visible
    from t + tick on, so a node never sees its own present or future."""

    def __init__(
        self, node: "Node", msg_type: Type[T], topic: str, depth: int, lossless: bool
    ) -> None:
        service = _open(self, node, msg_type, topic, depth, lossless)
        try:
            self._port = service.subscriber_builder().buffer_size(depth).create()
        except Exception as e:
            raise CaravanError(f"topic '{topic}': cannot create subscriber: {e}") from None
        node._ports.append(self._port)
        if not node.lockstep:
            node._listener(topic)
        self._pending: deque = deque()
        self._pending_limit = max(depth, 8) - 1
        self._last_seq: dict = {}
        self.missed = 0
        self.received = 0

    def receive(self) -> Optional[Received]:
        """The next visible message, oldest first, or ``None``."""
        sample = self._next_visible() if self._node.lockstep else self._pull()
        if sample is None:
            return None
        msg = Received(
            Header.from_buffer_copy(sample.user_header().contents),
            self.msg_type.from_buffer_copy(sample.payload().contents),
        )
        sample.delete()
        self._account(msg.header)
        return msg

    def receive_all(self) -> Iterator[Received]:
        """Every visible message, oldest first."""
        while (msg := self.receive()) is not None:
            yield msg

    def latest(self) -> Optional[Received]:
        """The newest visible message, discarding (but counting) older ones; ``None`` if none."""
        newest = None
        for msg in self.receive_all():
            newest = msg
        return newest

    def _pull(self) -> Any:
        try:
            return self._port.receive()
        except Exception as e:
            raise CaravanError(f"topic '{self.topic}': cannot receive: {e}") from None

    def _next_visible(self) -> Any:
        pending = self._pending
        while len(pending) < self._pending_limit:
            sample = self._pull()
            if sample is None:
                break
            pending.append(sample)
        now, tick = self._node._now_ns, self._node._tick_ns
        # Stamps of one publisher only grow, so the first visible one keeps each one's order.
        for i, sample in enumerate(pending):
            if sample.user_header().contents.stamp_ns + tick <= now:
                del pending[i]
                return sample
        return None

    def _account(self, header: Header) -> None:
        self.received += 1
        last = self._last_seq.get(header.source_id)
        if last is not None and header.seq > last + 1:
            gap = header.seq - last - 1
            self.missed += gap
            self._node._missed += gap
        self._last_seq[header.source_id] = header.seq if last is None else max(last, header.seq)
