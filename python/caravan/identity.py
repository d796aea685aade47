"""A Caravan node's identity from the launcher's environment, its typed params, durations and
rates, and the group's iceoryx2 config (``caravan::NodeIdentity``, ``caravan::parse_params``,
``caravan::group``)."""

from __future__ import annotations

import ctypes
import json
import math
import os
import re
import sys
from fractions import Fraction
from types import SimpleNamespace
from typing import Any, Optional, TypeVar

import iceoryx2 as iox

from .schemas import name_hash

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
ENV_CHECK = "CARAVAN_CHECK"

# Service limits of a group (``caravan::group``), used when no config file is given.
MAX_PUBLISHERS = 80
MAX_SUBSCRIBERS = 80
MAX_NODES_PER_SERVICE = 160

STATUS_PERIOD_NS = 1_000_000_000
_U64 = 0xFFFFFFFFFFFFFFFF


class CaravanError(Exception):
    """Bad input or a transport failure, with a message meant for the person running it."""


class BadInput(CaravanError):
    """Bad params, environment or input files: the node did nothing (exit status 2, as
    ``caravan::node_main``)."""


class CheckPassed(SystemExit):
    """Raised when a node that only checks its input (``CARAVAN_CHECK``) reaches the point
    where it would join the group: everything it read so far was good. A ``SystemExit`` with
    status 0, so a script ends cleanly there with or without ``caravan.main``."""

    def __init__(self) -> None:
        super().__init__(0)


def check_only() -> bool:
    """True when the launcher started this process only to check its params and inputs
    before the group starts (``CARAVAN_CHECK``, as ``caravan::check_only``)."""
    return os.environ.get(ENV_CHECK, "") not in ("", "0")


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
        raise BadInput(
            f"'{text}' is not a duration; write a number and a unit: ns, us, ms, s, min or h "
            '("20ms", "180s")'
        ) from None
    if not math.isfinite(seconds) or seconds < 0:
        raise BadInput(f"'{text}' is not a duration")
    return _round_ns(seconds)


def parse_rate(rate: Any) -> int:
    """The period in nanoseconds of a rate: a number of Hz, ``"50Hz"``, ``"2.5 kHz"`` or a period
    such as ``"20ms"`` (as ``caravan::parse_rate``)."""
    bad = BadInput(
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
                raise BadInput(
                    f"{var} is not set; start this process with `caravan launch`, or set it by hand"
                )
            return value

        def optional(var: str) -> Optional[str]:
            return env.get(var) or None

        params = optional(ENV_PARAMS)
        try:
            params = json.loads(params) if params else {}
        except json.JSONDecodeError as e:
            raise BadInput(f"{ENV_PARAMS} is not a JSON object: {e}") from None
        if not isinstance(params, dict):
            raise BadInput(f"{ENV_PARAMS} is not a JSON object")
        clock = optional(ENV_CLOCK) or "realtime"
        if clock not in ("realtime", "lockstep"):
            raise BadInput(
                f"{ENV_CLOCK}: unknown clock '{clock}', expected 'realtime' or 'lockstep'"
            )

        def number(var: str, what: str) -> Optional[int]:
            value = optional(var)
            if value is None:
                return None
            try:
                return int(value)
            except ValueError:
                raise BadInput(f"{var}: '{value}' is not {what}") from None

        host = optional(ENV_HOST) or "localhost"
        if not check_only():
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
                raise BadInput(
                    f"node '{node}': unknown key '{path}'; this node does not take it"
                )
            default = defaults[key]
            if isinstance(default, dict):
                if not isinstance(value, dict):
                    raise BadInput(f"node '{node}': key '{path}': expected a table")
                out[key] = merge(default, value, path + ".")
            else:
                out[key] = check(default, value, path)
        return out

    def check(default: Any, value: Any, path: str) -> Any:
        def wrong(expected: str) -> CaravanError:
            return BadInput(
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
        raise BadInput(f"group name '{group}' must have 1 to 40 characters")
    for c in group:
        if not ((c.isascii() and c.isalnum()) or c == "-"):
            raise BadInput(f"group name '{group}' contains '{c}'; use letters, digits and '-'")


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
        raise BadInput(f"cannot read iceoryx2 config {path}: {e}") from None
