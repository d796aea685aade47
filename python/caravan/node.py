"""A Caravan node in Python: identity from the launcher, typed ports, and the step loop.

This mirrors the Rust ``caravan`` crate (``runtime/src``) so that a Python process is an
ordinary member of a group:

- ``Node.from_env()`` reads the variables the launcher sets (``CARAVAN_GROUP``,
  ``CARAVAN_NODE``, ``CARAVAN_PARAMS``, ``CARAVAN_ICEORYX_CONFIG``, ``CARAVAN_CLOCK``, …) and
  opens an iceoryx2 node on the group's own config.
- ``node.publisher(T, topic)`` and ``node.subscriber(T, topic)`` open the topic's
  publish-subscribe service exactly as the Rust ``Topic::new`` does (same type names, same
  ``Header`` user header, same buffer settings), so Python and Rust ports connect.
- ``node.message_type("beacon::Beacon")`` is the class of a type outside ``caravan.schemas``,
  learned from the descriptor a process of the group registered (``caravan.types``).
- ``node.run(step, rate="20Hz")`` or ``node.run(step, on="robot/0/scan")`` steps the node under
  the group's clock: ``realtime`` sleeps in an iceoryx2 WaitSet (never busy-waits), ``lockstep``
  follows the launcher's scheduler (hello, grant, step, done) and hides a message stamped t
  until t + tick.
"""

from __future__ import annotations

import atexit
import ctypes
import os
import sys
import time
from types import SimpleNamespace
from typing import Any, Callable, Optional, Type

import iceoryx2 as iox

from . import schemas
from .schemas import Done, Grant, Header, Hello, NodeStatus, lockstep, name_hash, topics

from .identity import (
    BadInput,
    CaravanError,
    CheckPassed,
    Identity,
    STATUS_PERIOD_NS,
    T,
    check_only,
    group_config,
    load_config,
    parse_params,
    parse_rate,
    validate_group,
)
from .types import lookup as lookup_type, register as register_type
from .ports import (
    Publisher,
    Subscriber,
    _Stats,
)

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
        if check_only():
            # The launcher only checks this node's input: read params and files, join nothing.
            # Opening a port or running is where the check ends (``CheckPassed``).
            return
        self.lockstep = identity.clock == "lockstep"
        config = (
            load_config(identity.iceoryx_config)
            if identity.iceoryx_config
            else group_config(identity.group)
        )
        self._config = config
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
        """A publisher of ``msg_type`` (a class from ``caravan.schemas`` or ``message_type``) on
        ``topic``. The defaults match Rust's ``Topic::new`` (keep the newest 8); ``lossless``
        matches ``Topic::lossless`` (depth 256, publishers wait)."""
        _end_of_check()
        return Publisher(self, msg_type, topic, depth or (256 if lossless else 8), lossless)

    def subscriber(
        self, msg_type: Type[T], topic: str, depth: Optional[int] = None, lossless: bool = False
    ) -> Subscriber:
        """A subscriber of ``msg_type`` on ``topic``; ``publisher`` explains the delivery."""
        _end_of_check()
        return Subscriber(self, msg_type, topic, depth or (256 if lossless else 8), lossless)

    def message_type(self, type_name: str) -> type:
        """The message class of ``type_name`` (``"beacon::Beacon"``): a catalog type's class
        from ``caravan.schemas``, or a class built from the descriptor that a process of the group
        registered when it opened a port of the type (``caravan.types``). A ``CaravanError`` if no
        process of the group has yet."""
        # The type is known only once the group runs: a check of this node's input ends here.
        _end_of_check()
        return lookup_type(self, type_name)

    def run(self, step: Callable[[Step], Any], rate: Any = None, on: Optional[str] = None) -> None:
        """Runs ``step(s)`` every period (``rate="20Hz"``, ``"50ms"`` or a number of Hz) or when a
        message arrives on topic ``on``, until SIGTERM/SIGINT, the lockstep scheduler's stop, or
        ``s.stop()``. The launch file's ``rate``/``on`` take precedence. A final status is
        published on exit."""
        _end_of_check()
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
        cpu_started = time.thread_time_ns()
        step(state)
        stats.record(
            start_ns,
            due_ns,
            time.perf_counter_ns() - started,
            time.thread_time_ns() - cpu_started,
        )
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
        s.rss_kib = _resident_kib()
        self._status.publish(s)

    def _open_pubsub(self, msg_type: Type[T], topic: str, depth: int, lossless: bool) -> Any:
        """The topic's service, with the settings of Rust's ``transport::open_pubsub``."""
        try:
            # As a Rust port does: the group's tools then read a type outside the catalog.
            register_type(self, msg_type)
        except CaravanError as e:
            raise CaravanError(f"topic '{topic}': {e}") from None
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


def _resident_kib() -> int:
    """Resident memory of this process, KiB (``caravan::stats::resident_kib``)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024
    except (OSError, ValueError, IndexError):
        return 0


def _end_of_check() -> None:
    if check_only():
        raise CheckPassed()


def main(agent: Callable[[], Any]) -> None:
    """Runs ``agent()`` and exits as Rust nodes do: status 0 on success; with a one-line
    message, 2 on ``BadInput`` (bad params or input files: nothing ran) and 1 on any other
    ``CaravanError`` (a mismatched topic, a transport failure…).

    Before the group starts, ``caravan launch`` runs the agent once with ``CARAVAN_CHECK`` set:
    ``Node.from_env()`` then joins nothing, and the agent's first port or ``run`` ends the
    check with status 0, so its params and files are checked before anything starts."""
    try:
        agent()
    except CaravanError as e:
        print(f"{os.path.basename(sys.argv[0])}: {e}", file=sys.stderr)
        sys.exit(2 if isinstance(e, BadInput) else 1)
