"""A Caravan node in Python: identity from the launcher, typed ports, and the step loop.

This mirrors the Rust ``caravan`` crate (``runtime/src``) so that a Python process is an
ordinary member of a group:

- ``Node.from_env()`` reads the variables the launcher sets (``CARAVAN_GROUP``,
  ``CARAVAN_NODE``, ``CARAVAN_PARAMS``, ``CARAVAN_ICEORYX_CONFIG``, ``CARAVAN_CLOCK``, …) and
  opens an iceoryx2 node on the group's own config.
- ``node.publisher(T, topic)`` and ``node.subscriber(T, topic)`` open the topic's
  publish-subscribe service exactly as the Rust ``Topic::new`` does (same type names, same
  ``Header`` user header, same buffer settings), so Python and Rust ports connect.
- ``node.run(step, rate="20Hz")`` or ``node.run(step, on="robot/0/scan")`` steps the node under
  the group's clock: ``realtime`` sleeps in an iceoryx2 WaitSet (never busy-waits), ``lockstep``
  follows the launcher's scheduler (hello, grant, step, done) and hides a message stamped t
  until t + tick.
"""

from __future__ import annotations

import atexit
import ctypes
import json
import math
import os
import re
import sys
import time
from collections import deque
from fractions import Fraction
from types import SimpleNamespace
from typing import Any, Callable, Iterator, Optional, Type, TypeVar

import iceoryx2 as iox

from . import schemas
from .schemas import Done, Grant, Header, Hello, NodeStatus, lockstep, name_hash, topics

T = TypeVar("T", bound=ctypes.Structure)

# The launcher's environment variables (``caravan::env_vars``).
ENV_GROUP = "CARAVAN_GROUP"
ENV_NODE = "CARAVAN_NODE"
ENV_HOST = "CARAVAN_HOST"
ENV_PARAMS = "CARAVAN_PARAMS"
ENV_ICEORYX_CONFIG = "CARAVAN_ICEORYX_CONFIG"
ENV_CLOCK = "CARAVAN_CLOCK"
ENV_RATE = "CARAVAN_RATE"
ENV_ON = "CARAVAN_ON"
ENV_EPOCH_NS = "CARAVAN_EPOCH_NS"
ENV_SEED = "CARAVAN_SEED"
ENV_LAUNCH_DIR = "CARAVAN_LAUNCH_DIR"
ENV_NETWORK = "CARAVAN_NETWORK"

# Service limits of a group (``caravan::group``), used when no config file is given.
MAX_PUBLISHERS = 80
MAX_SUBSCRIBERS = 80
MAX_NODES_PER_SERVICE = 160

STATUS_PERIOD_NS = 1_000_000_000
_U64 = 0xFFFFFFFFFFFFFFFF


class CaravanError(Exception):
    """Bad input or a transport failure, with a message meant for the person running it."""


# --- durations and rates -------------------------------------------------------------------

_UNITS = {
    "ns": 1e-9,
    "us": 1e-6,
    "µs": 1e-6,
    "ms": 1e-3,
    "s": 1.0,
    "min": 60.0,
    "m": 60.0,
    "h": 3600.0,
}


def _round_ns(seconds: float) -> int:
    # Rust's Duration::from_secs_f64 rounds the exact binary value to the nearest nanosecond.
    return round(Fraction(seconds) * 1_000_000_000)


def parse_duration(text: str) -> int:
    """Nanoseconds in ``"180s"``, ``"20ms"``, ``"1.5s"`` or ``"2min"``, as Rust's
    ``caravan::parse_duration``."""
    match = re.fullmatch(r"([0-9.]*)(.*)", text.strip())
    number, unit = match.group(1), match.group(2).strip()
    try:
        seconds = float(number) * _UNITS[unit]
    except (ValueError, KeyError):
        raise CaravanError(
            f"'{text}' is not a duration; write a number and a unit: ns, us, ms, s, min or h "
            '("20ms", "180s")'
        ) from None
    if not math.isfinite(seconds) or seconds < 0:
        raise CaravanError(f"'{text}' is not a duration")
    return _round_ns(seconds)


def parse_rate(rate: Any) -> int:
    """The period in nanoseconds of a rate: a number of Hz, ``"50Hz"``, ``"2.5 kHz"`` or a period
    such as ``"20ms"`` (as ``caravan::parse_rate``)."""
    bad = CaravanError(
        f'\'{rate}\' is not a rate; write a frequency like "50Hz" or a period like "20ms"'
    )
    if isinstance(rate, (int, float)) and not isinstance(rate, bool):
        text, hz = None, float(rate)
    else:
        text = str(rate).strip()
        lower = text.lower()
        scale = 1e3 if lower.endswith("khz") else 1.0 if lower.endswith("hz") else None
        hz = None
        if scale is not None:
            try:
                hz = float(lower[: -3 if scale == 1e3 else -2].strip()) * scale
            except ValueError:
                raise bad from None
    if hz is not None:
        if not (math.isfinite(hz) and hz > 0):
            raise bad
        period = _round_ns(1.0 / hz)
    else:
        try:
            period = parse_duration(text)
        except CaravanError:
            raise bad from None
    if period == 0:
        raise bad
    return period


# --- identity and params -------------------------------------------------------------------


def _warn_unemulated_network(network: Optional[str], name: str, host: str) -> None:
    """Python nodes do not emulate links or CPU budgets yet; say so rather than let a run
    look like it did."""
    try:
        net = json.loads(network) if network else {}
    except json.JSONDecodeError:
        return
    linked = any(l.get("to") == host for l in net.get("links", []))
    slowed = host in net.get("cpu_slowdown", {})
    if linked or slowed:
        what = " and ".join(
            w for w, on in (("network links", linked), ("CPU budgets", slowed)) if on
        )
        print(
            f"caravan (Python node '{name}'): {what} of host '{host}' are not emulated for "
            "Python nodes; it receives messages from other hosts at once and computes in no "
            "simulated time",
            file=sys.stderr,
        )


class Identity(SimpleNamespace):
    """Who the node is, as the launcher tells it (``caravan::NodeIdentity``)."""

    @classmethod
    def from_env(cls) -> "Identity":
        env = os.environ

        def required(var: str) -> str:
            value = env.get(var, "")
            if not value:
                raise CaravanError(
                    f"{var} is not set; start this process with `caravan launch`, or set it by hand"
                )
            return value

        def optional(var: str) -> Optional[str]:
            return env.get(var) or None

        params = optional(ENV_PARAMS)
        try:
            params = json.loads(params) if params else {}
        except json.JSONDecodeError as e:
            raise CaravanError(f"{ENV_PARAMS} is not a JSON object: {e}") from None
        if not isinstance(params, dict):
            raise CaravanError(f"{ENV_PARAMS} is not a JSON object")
        clock = optional(ENV_CLOCK) or "realtime"
        if clock not in ("realtime", "lockstep"):
            raise CaravanError(
                f"{ENV_CLOCK}: unknown clock '{clock}', expected 'realtime' or 'lockstep'"
            )

        def number(var: str, what: str) -> Optional[int]:
            value = optional(var)
            if value is None:
                return None
            try:
                return int(value)
            except ValueError:
                raise CaravanError(f"{var}: '{value}' is not {what}") from None

        host = optional(ENV_HOST) or "localhost"
        _warn_unemulated_network(optional(ENV_NETWORK), required(ENV_NODE), host)
        return cls(
            group=required(ENV_GROUP),
            name=required(ENV_NODE),
            host=host,
            params=params,
            iceoryx_config=optional(ENV_ICEORYX_CONFIG),
            clock=clock,
            rate_override=optional(ENV_RATE),
            on_override=optional(ENV_ON),
            epoch_ns=number(ENV_EPOCH_NS, "a number of nanoseconds"),
            seed=number(ENV_SEED, "an unsigned integer") or 0,
            launch_dir=optional(ENV_LAUNCH_DIR) or ".",
        )

    @property
    def node_hash(self) -> int:
        """Identifies the node in headers (``source_id``) and in the lockstep protocol."""
        return name_hash(self.name)

    @property
    def node_seed(self) -> int:
        """The group seed mixed with the node name, as ``NodeIdentity::node_seed``."""
        h = self.node_hash
        return (self.seed ^ (((h << 17) | (h >> 47)) & _U64)) & _U64

    def resolve_path(self, path: str) -> str:
        """``path`` from the params, relative to the launch file's directory."""
        return os.path.join(self.launch_dir, path)


def _namespace(value: Any) -> Any:
    if isinstance(value, dict):
        return SimpleNamespace(**{k: _namespace(v) for k, v in value.items()})
    return value


def parse_params(node: str, given: dict, defaults: dict) -> SimpleNamespace:
    """``defaults`` updated with the launch file's ``given`` params, as attributes
    (``p.follower.k1``). Unknown keys and values of the wrong type are errors naming the key."""

    def merge(defaults: dict, given: dict, prefix: str) -> dict:
        out = dict(defaults)
        for key, value in given.items():
            path = prefix + key
            if key not in defaults:
                raise CaravanError(
                    f"node '{node}': unknown key '{path}'; this node does not take it"
                )
            default = defaults[key]
            if isinstance(default, dict):
                if not isinstance(value, dict):
                    raise CaravanError(f"node '{node}': key '{path}': expected a table")
                out[key] = merge(default, value, path + ".")
            else:
                out[key] = check(default, value, path)
        return out

    def check(default: Any, value: Any, path: str) -> Any:
        def wrong(expected: str) -> CaravanError:
            return CaravanError(
                f"node '{node}': key '{path}': expected {expected}, found {value!r}"
            )

        if default is None:
            return value
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise wrong("true or false")
            return value
        if isinstance(default, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise wrong("a number")
            return float(value)
        if isinstance(default, int):
            if isinstance(value, bool) or not isinstance(value, int):
                raise wrong("an integer")
            return value
        if isinstance(default, str):
            if not isinstance(value, str):
                raise wrong("a string")
            return value
        if isinstance(default, (list, tuple)):
            if not isinstance(value, list):
                raise wrong("a list")
            if default and len(value) != len(default) and not isinstance(default, list):
                raise wrong(f"a list of {len(default)}")
            if default:
                return type(default)(
                    check(default[0], v, f"{path}[{i}]") for i, v in enumerate(value)
                )
            return value
        return value

    return _namespace(merge(defaults, given, ""))


# --- the group's iceoryx2 config -----------------------------------------------------------


def group_prefix(group: str) -> str:
    """File-name prefix of the group's shared memory (``caravan::group::prefix``)."""
    clean = "".join(c if (c.isascii() and c.isalnum()) or c == "-" else "-" for c in group)[:40]
    return f"cvn_{clean}_"


def validate_group(group: str) -> None:
    if not 1 <= len(group) <= 40:
        raise CaravanError(f"group name '{group}' must have 1 to 40 characters")
    for c in group:
        if not ((c.isascii() and c.isalnum()) or c == "-"):
            raise CaravanError(f"group name '{group}' contains '{c}'; use letters, digits and '-'")


def group_config(group: str) -> Any:
    """The group's iceoryx2 config built like ``caravan::group::config``, for a node started
    without the launcher's config file."""
    config = iox.config.default()
    config.global_cfg.prefix = iox.FileName.new(group_prefix(group))
    ps = config.defaults.publish_subscribe
    ps.max_publishers = MAX_PUBLISHERS
    ps.max_subscribers = MAX_SUBSCRIBERS
    ps.max_nodes = MAX_NODES_PER_SERVICE
    ps.subscriber_expired_connection_buffer = 256
    ev = config.defaults.event
    ev.max_notifiers = MAX_PUBLISHERS * 2
    ev.max_listeners = MAX_SUBSCRIBERS
    ev.max_nodes = MAX_NODES_PER_SERVICE
    return config


def load_config(path: str) -> Any:
    """The config file the launcher wrote into the run directory."""
    try:
        return iox.config.from_file(iox.FilePath.new(path))
    except Exception as e:  # iceoryx2 raises its own error types
        raise CaravanError(f"cannot read iceoryx2 config {path}: {e}") from None


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
        self.last_start: Optional[int] = None

    def record(self, start_ns: int, due_ns: int, compute_ns: int) -> None:
        self.steps += 1
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


class Publisher:
    """Publishes one message type on one topic, stamping each message's ``Header``."""

    def __init__(
        self, node: "Node", msg_type: Type[T], topic: str, depth: int, lossless: bool
    ) -> None:
        self.topic = topic
        self.msg_type = msg_type
        self._node = node
        self._hash = name_hash(topic)
        service = node._open_pubsub(msg_type, topic, depth, lossless)
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
        self.topic = topic
        self.msg_type = msg_type
        self._node = node
        service = node._open_pubsub(msg_type, topic, depth, lossless)
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


# --- the step loop -------------------------------------------------------------------------


class Step:
    """What a step function sees of the current step."""

    __slots__ = ("now_ns", "index", "_stop")

    def __init__(self) -> None:
        self.now_ns = 0
        self.index = 0
        self._stop = False

    @property
    def now(self) -> float:
        """Simulated time of this step since the group started, in seconds (computed as Rust's
        ``Duration::as_secs_f64``, so both languages see the same number)."""
        return self.now_ns // 1_000_000_000 + (self.now_ns % 1_000_000_000) / 1e9

    def stop(self) -> None:
        """Ends the run after this step."""
        self._stop = True


def _interrupted(result: Any) -> bool:
    return result in (iox.WaitSetRunResult.TerminationRequest, iox.WaitSetRunResult.Interrupt)


class Node:
    """One process of a group. See the module documentation."""

    def __init__(self, identity: Identity) -> None:
        iox.set_log_level_from_env_or(iox.LogLevel.Warn)
        validate_group(identity.group)
        self.identity = identity
        self.lockstep = identity.clock == "lockstep"
        config = (
            load_config(identity.iceoryx_config)
            if identity.iceoryx_config
            else group_config(identity.group)
        )
        try:
            self._iox = (
                iox.NodeBuilder.new()
                .name(iox.NodeName.new(identity.name))
                .config(config)
                .signal_handling_mode(iox.SignalHandlingMode.HandleTerminationRequests)
                .create(iox.ServiceType.Ipc)
            )
        except Exception as e:
            raise CaravanError(
                f"node '{identity.name}': cannot create iceoryx2 node: {e}"
            ) from None
        self._ports: list = []
        self._events: dict = {}
        self._listeners: dict = {}
        self._published: list = []
        self._missed = 0
        self._now_ns = 0
        self._tick_ns = 0
        self._started = time.monotonic_ns()
        self._epoch_offset_ns = (
            max(time.time_ns() - identity.epoch_ns, 0) if identity.epoch_ns else 0
        )
        self._status = self.publisher(NodeStatus, topics.STATUS)
        atexit.register(self.close)

    @classmethod
    def from_env(cls) -> "Node":
        """The node the launcher described in the environment."""
        return cls(Identity.from_env())

    @property
    def name(self) -> str:
        return self.identity.name

    @property
    def now(self) -> float:
        """Simulated time of the current (or last) step, in seconds."""
        return self._now_ns * 1e-9

    def params(self, defaults: dict) -> SimpleNamespace:
        """The launch file's params over ``defaults``; unknown or mistyped keys are errors."""
        return parse_params(self.identity.name, self.identity.params, defaults)

    def publisher(
        self, msg_type: Type[T], topic: str, depth: Optional[int] = None, lossless: bool = False
    ) -> Publisher:
        """A publisher of ``msg_type`` (a class from ``caravan.schemas``) on ``topic``. The
        defaults match Rust's ``Topic::new`` (keep the newest 8); ``lossless`` matches
        ``Topic::lossless`` (depth 256, publishers wait)."""
        return Publisher(self, msg_type, topic, depth or (256 if lossless else 8), lossless)

    def subscriber(
        self, msg_type: Type[T], topic: str, depth: Optional[int] = None, lossless: bool = False
    ) -> Subscriber:
        """A subscriber of ``msg_type`` on ``topic``; ``publisher`` explains the delivery."""
        return Subscriber(self, msg_type, topic, depth or (256 if lossless else 8), lossless)

    def run(self, step: Callable[[Step], Any], rate: Any = None, on: Optional[str] = None) -> None:
        """Runs ``step(s)`` every period (``rate="20Hz"``, ``"50ms"`` or a number of Hz) or when a
        message arrives on topic ``on``, until SIGTERM/SIGINT, the lockstep scheduler's stop, or
        ``s.stop()``. The launch file's ``rate``/``on`` take precedence. A final status is
        published on exit."""
        if self.identity.rate_override:
            period_ns, trigger = parse_rate(self.identity.rate_override), None
        elif self.identity.on_override:
            period_ns, trigger = 0, self.identity.on_override
        elif rate is not None:
            period_ns, trigger = parse_rate(rate), None
        elif on is not None:
            period_ns, trigger = 0, on
        else:
            raise CaravanError("run() needs a rate or a topic to step on")
        stats = _Stats(period_ns)
        waitset = (
            iox.WaitSetBuilder.new()
            .signal_handling_mode(iox.SignalHandlingMode.HandleTerminationRequests)
            .create(iox.ServiceType.Ipc)
        )
        try:
            if self.lockstep:
                self._run_lockstep(step, stats, waitset, period_ns, trigger)
            else:
                self._run_realtime(step, stats, waitset, period_ns, trigger)
        finally:
            self._publish_status(stats, running=False)

    def close(self) -> None:
        """Releases every port and the iceoryx2 node (also done at exit)."""
        for port in reversed(self._ports):
            port.delete()
        self._ports.clear()
        self._listeners.clear()
        self._events.clear()
        self._iox = None  # the iceoryx2 node goes with its last reference

    # -- internals --------------------------------------------------------------------------

    def _since_epoch_ns(self) -> int:
        return self._epoch_offset_ns + time.monotonic_ns() - self._started

    def _run_step(
        self, step: Callable[[Step], Any], state: Step, stats: _Stats, due_ns: int, start_ns: int
    ) -> None:
        started = time.perf_counter_ns()
        step(state)
        stats.record(start_ns, due_ns, time.perf_counter_ns() - started)
        state.index += 1

    def _run_realtime(
        self, step: Callable, stats: _Stats, waitset: Any, period_ns: int, trigger: Optional[str]
    ) -> None:
        period_guard = (
            waitset.attach_interval(iox.Duration.from_nanos(period_ns)) if period_ns else None
        )
        listener = self._listener(trigger) if trigger else None
        message_guard = waitset.attach_notification(listener) if listener else None
        status_guard = waitset.attach_interval(iox.Duration.from_nanos(STATUS_PERIOD_NS))
        state = Step()
        next_due_ns = self._since_epoch_ns() + period_ns
        while True:
            ids, result = waitset.wait_and_process()
            if _interrupted(result):
                return
            fired = any(
                (period_guard is not None and i.has_event_from(period_guard))
                or (message_guard is not None and i.has_event_from(message_guard))
                for i in ids
            )
            status_due = any(i.has_event_from(status_guard) for i in ids)
            if listener is not None:
                listener.try_wait()  # consume the wake-ups, or the WaitSet fires again at once
            if fired:
                start_ns = self._since_epoch_ns()
                due_ns = next_due_ns if period_ns else start_ns
                state.now_ns = self._now_ns = start_ns
                self._run_step(step, state, stats, due_ns, start_ns)
                # After a long stall, resume the period from now instead of bursting.
                next_due_ns = max(next_due_ns + period_ns, start_ns)
            if status_due:
                self._publish_status(stats, running=True)
            if state._stop:
                return

    def _run_lockstep(
        self, step: Callable, stats: _Stats, waitset: Any, period_ns: int, trigger: Optional[str]
    ) -> None:
        client = _LockstepClient(self, period_ns, [trigger] if trigger else [])
        guard = waitset.attach_notification(client.grant_listener)
        state = Step()
        next_status_ns = 0
        try:
            while True:
                grant = client.wait_for_grant(waitset)
                if grant is None:
                    return
                self._now_ns, self._tick_ns = grant.now_ns, grant.tick_ns
                state.now_ns = grant.now_ns
                self._run_step(step, state, stats, grant.now_ns, grant.now_ns)
                if grant.now_ns >= next_status_ns:
                    self._publish_status(stats, running=True)
                    next_status_ns = grant.now_ns + STATUS_PERIOD_NS
                client.report_done(grant.now_ns)
                if state._stop:
                    return
        finally:
            guard.delete()

    def _publish_status(self, stats: _Stats, running: bool) -> None:
        if self._iox is None:
            return
        s = NodeStatus()
        schemas.set_fixed_str(s, "node", self.identity.name)
        schemas.set_fixed_str(s, "host", self.identity.host)
        stats.fill(s)
        s.messages_missed = self._missed
        s.sim_time_ns = self._now_ns
        s.running = int(running)
        self._status.publish(s)

    def _open_pubsub(self, msg_type: Type[T], topic: str, depth: int, lossless: bool) -> Any:
        """The topic's service, with the settings of Rust's ``transport::open_pubsub``."""
        try:
            return (
                self._iox.service_builder(self._service_name(topic))
                .publish_subscribe(msg_type)
                .user_header(Header)
                .enable_safe_overflow(not lossless)
                .subscriber_max_buffer_size(depth)
                .subscriber_max_borrowed_samples(max(depth, 8))
                .history_size(0)
                .open_or_create()
            )
        except Exception as e:
            raise CaravanError(
                f"topic '{topic}': cannot open as {msg_type.type_name()} ({e}); another process "
                "uses this topic with a different message type or delivery contract"
            ) from None

    @staticmethod
    def _service_name(topic: str) -> Any:
        try:
            return iox.ServiceName.new(topic)
        except Exception as e:
            raise CaravanError(f"topic '{topic}': not a valid name: {e}") from None

    def _event(self, topic: str) -> Any:
        if topic not in self._events:
            try:
                self._events[topic] = (
                    self._iox.service_builder(self._service_name(topic)).event().open_or_create()
                )
            except Exception as e:
                raise CaravanError(f"topic '{topic}': cannot open its event service: {e}") from None
        return self._events[topic]

    def _listener(self, topic: str) -> Any:
        """The listener woken by every message on ``topic``, created on first use."""
        if topic not in self._listeners:
            listener = self._event(topic).listener_builder().create()
            self._listeners[topic] = listener
            self._ports.append(listener)
        return self._listeners[topic]


class _LockstepClient:
    """The node side of the lockstep protocol (``caravan::lockstep::Client``)."""

    def __init__(self, node: Node, period_ns: int, triggers: list) -> None:
        self.node = node
        name = node.identity.name
        grant_name = lockstep.grant_service(name)
        # Control messages are never lost: lossless services, publishers that wait.
        self.hello_port = self._publisher(Hello, lockstep.HELLO)
        self.hello_notifier = node._event(lockstep.HELLO).notifier_builder().create()
        self.grants = (
            self._service(Grant, grant_name).subscriber_builder().buffer_size(256).create()
        )
        self.grant_listener = node._event(grant_name).listener_builder().create()
        self.done_port = self._publisher(Done, lockstep.DONE)
        self.done_notifier = node._event(lockstep.DONE).notifier_builder().create()
        node._ports += [
            self.hello_port,
            self.hello_notifier,
            self.grants,
            self.grant_listener,
            self.done_port,
            self.done_notifier,
        ]
        self.hello = Hello()
        schemas.set_fixed_str(self.hello, "node", name)
        self.hello.period_ns = period_ns
        if schemas.set_fixed_vec(self.hello, "triggers", [name_hash(t) for t in triggers]) < len(
            triggers
        ):
            raise CaravanError(f"node '{name}' triggers on too many topics")
        # The last report, repeated if the scheduler grants the same step again.
        self.last_done: Optional[Done] = None
        self._say_hello()

    def _service(self, msg_type: Type[T], name: str) -> Any:
        return self.node._open_pubsub(msg_type, name, 256, lossless=True)

    def _publisher(self, msg_type: Type[T], name: str) -> Any:
        return (
            self._service(msg_type, name)
            .publisher_builder()
            .backpressure_strategy(iox.BackpressureStrategy.RetryUntilDelivered)
            .create()
        )

    @staticmethod
    def _send(port: Any, msg: Any, notifier: Any) -> None:
        sample = port.loan_uninit()
        ctypes.memset(sample.user_header_ptr, 0, ctypes.sizeof(Header))
        sample.write_payload(msg).send()
        notifier.notify()

    def _say_hello(self) -> None:
        self._send(self.hello_port, self.hello, self.hello_notifier)

    def wait_for_grant(self, waitset: Any) -> Optional[Grant]:
        """Blocks (event-driven) until the scheduler grants a new step; ``None`` when the run
        is over or the process is asked to terminate. As in Rust, the protocol tolerates lost
        samples: the hello is repeated every second until the first grant, and a repeated grant
        of the step already done is answered by repeating its report."""
        while True:
            while (sample := self.grants.receive()) is not None:
                grant = Grant.from_buffer_copy(sample.payload().contents)
                sample.delete()
                if grant.stop:
                    return None
                last = self.last_done
                if last is None or grant.now_ns > last.now_ns:
                    return grant
                if grant.now_ns == last.now_ns:
                    self._send(self.done_port, last, self.done_notifier)
            _, result = waitset.wait_and_process_with_timeout(iox.Duration.from_secs(1))
            self.grant_listener.try_wait()
            if _interrupted(result):
                return None
            if self.last_done is None:
                self._say_hello()

    def report_done(self, now_ns: int) -> None:
        """Reports the step at ``now_ns`` finished, with the topics it published to."""
        done = Done(node_hash=self.node.identity.node_hash, now_ns=now_ns)
        # More topics than fit only delay subscribers: the node is still woken by its period.
        schemas.set_fixed_vec(done, "published", self.node._published)
        self.node._published.clear()
        self.last_done = done
        self._send(self.done_port, done, self.done_notifier)


def main(agent: Callable[[], Any]) -> None:
    """Runs ``agent()`` and exits: status 0 on success, 1 with a one-line message on a
    ``CaravanError`` (bad params, a mismatched topic…), as Rust processes do."""
    try:
        agent()
    except CaravanError as e:
        print(f"{os.path.basename(sys.argv[0])}: {e}", file=sys.stderr)
        sys.exit(1)
