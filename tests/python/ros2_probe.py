"""A ROS 2 endpoint on Cyclone DDS that the integration tests use as an independent check.

Caravan's ROS 2 bridge speaks DDS through RustDDS; this probe listens to and publishes ROS 2
topics through another DDS implementation (Cyclone DDS, types from ros2_msgs.py), so that a test
sees what a real ROS 2 node on the same host would see. Run it in .venv-ros2 (created by
``python/caravan-python --venv ros2 --requirements ../tests/requirements-ros2.txt --setup``):

    python ros2_probe.py --domain N [--listen ROS_TOPIC=ROS_TYPE[:QOS]]...
        [--publish ROS_TOPIC=ROS_TYPE[:QOS] [--json '{...}'] [--rate HZ]]
        --duration SECONDS [--count N]

e.g. ``--listen /robot_0/scan=sensor_msgs/msg/LaserScan:best_effort``. The ROS 2 topic
/robot_0/scan is the DDS topic rt/robot_0/scan with the DDS type sensor_msgs::msg::dds_::LaserScan_.
QOS is ``reliable`` or ``best_effort``, optionally followed by ``,transient_local``; the default
is reliable, volatile; history is always keep-last 10. Samples go out as plain CDR (XCDR1), as
rmw_cyclonedds and RustDDS write them.

Every sample received is one JSON line on stdout (flushed at once):
``{"topic": "/robot_0/scan", "type": "sensor_msgs/msg/LaserScan", "data": {...}}``. Non-finite
floats appear as the strings "NaN", "Infinity", "-Infinity" (strict JSON has no literal for
them; --json accepts the same strings, or the bare literals Python's json reads). The published
message is built from --json (fields left out are zero) and written every 1/HZ s (default 10
Hz) from the start. Exits 0 when the duration ends, on SIGTERM (after taking what its readers
still hold) or, with --count, as soon as that many samples were received in total (a summary
goes to stderr); exits 2 on bad arguments.

Discovery is confined to the loopback interface. The Cyclone DDS configuration (set as
CYCLONEDDS_URI for this process before cyclonedds is imported; ROS2_PROBE_CYCLONEDDS_URI
replaces it, ROS2_PROBE_TRACE=config|fine|finest adds Cyclone's trace on stderr) is:

    <CycloneDDS><Domain Id="any">
      <General>
        <Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>
        <AllowMulticast>spdp</AllowMulticast>
      </General>
      <Discovery>
        <ParticipantIndex>auto</ParticipantIndex>
        <MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>
        <Peers><Peer address="127.0.0.1"/></Peers>
      </Discovery>
    </Domain></CycloneDDS>

Why each part (checked on Linux, Cyclone DDS 11.0.1, RustDDS 0.15.1):
- Only 127.0.0.1 is used: tests must not leak onto (or depend on) a real network.
- Unicast discovery is the path that always works. ParticipantIndex auto makes Cyclone take the
  well-known RTPS ports (SPDP unicast 7400 + 250*domain + 10 + 2*index for the first free
  index), which is where RustDDS sends its "localhost peers" SPDP (127.0.0.1, participant ids
  0..11). Peer 127.0.0.1 without a port makes Cyclone send its SPDP to 127.0.0.1 at the ports
  of indices 0..MaxAutoParticipantIndex, where RustDDS (its participant id is the first free
  index from 0) and other probes listen. Default ParticipantIndex (none) would put Cyclone on
  random ports that RustDDS's unicast SPDP never reaches.
- SPDP multicast (239.255.0.1:7400 + 250*domain) is kept as a second path. Linux's lo lacks the
  MULTICAST flag, yet Cyclone 11 still enables SPDP multicast on it and looped-back multicast
  is delivered; RustDDS skips lo for multicast (no flag) and joins the group on the other
  interfaces, but its 0.0.0.0-bound socket still receives Cyclone's lo multicast. RustDDS's own
  multicast (sent on e.g. eth0) reaches Cyclone only when some socket joined the group on that
  interface, so the unicast peers above carry the RustDDS -> Cyclone direction.
"""

import argparse
import json
import math
import os
import signal
import sys
import time

CYCLONEDDS_XML = (
    '<CycloneDDS><Domain Id="any">'
    "<General>"
    '<Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>'
    "<AllowMulticast>spdp</AllowMulticast>"
    "</General>"
    "<Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
    '<Peers><Peer address="127.0.0.1"/></Peers>'
    "</Discovery>"
    "{tracing}"
    "</Domain></CycloneDDS>"
)

# Samples a reader keeps until the probe takes them. ROS 2's default of 10 is too few for a
# logger: a Python probe on a loaded machine falls behind, and on a topic fed by several
# sources (every robot's transforms on /tf, one at 100 Hz) the last ten would all be one
# source's. Writers keep ROS 2's 10.
READER_DEPTH = 1000
WRITER_DEPTH = 10


def cyclone_config():
    """The configuration this process gives Cyclone DDS (see the header comment)."""
    if os.environ.get("ROS2_PROBE_CYCLONEDDS_URI"):
        return os.environ["ROS2_PROBE_CYCLONEDDS_URI"]
    trace = os.environ.get("ROS2_PROBE_TRACE", "")
    tracing = ""
    if trace:
        tracing = (
            f"<Tracing><Verbosity>{trace}</Verbosity><OutputFile>stderr</OutputFile></Tracing>"
        )
    return CYCLONEDDS_XML.format(tracing=tracing)


# Before anything imports cyclonedds: the library reads CYCLONEDDS_URI when the first domain
# is created, and a variable from the caller's environment must not decide where we talk.
os.environ["CYCLONEDDS_URI"] = cyclone_config()

from cyclonedds.core import Policy, Qos, ReadCondition, SampleState, ViewState, InstanceState  # noqa: E402
from cyclonedds.core import WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

from ros2_msgs import TYPES, from_dict, to_dict  # noqa: E402

MIN_WAIT = 0.005  # seconds: the shortest pause of the main loop
# seconds: the longest, so that a SIGTERM (the test's "the group has ended") is seen soon
MAX_WAIT = 0.25

# Set by SIGTERM: take what the readers still hold, then end. A probe behind on a loaded
# machine would otherwise lose the samples Cyclone DDS had already received for it.
stopping = False


def stop(_signum, _frame):
    global stopping
    stopping = True


class UsageError(Exception):
    pass


def parse_endpoint(spec):
    """``/topic=pkg/msg/Type[:qos]`` -> (ros topic, ros type, qos words)."""
    topic, sep, rest = spec.partition("=")
    if not sep or not topic or not rest:
        raise UsageError(f"{spec!r}: expected ROS_TOPIC=ROS_TYPE[:QOS]")
    ros_type, _, qos = rest.partition(":")
    if ros_type not in TYPES:
        raise UsageError(f"{spec!r}: unknown type {ros_type!r}; known: {', '.join(sorted(TYPES))}")
    if not topic.startswith("/"):
        topic = "/" + topic
    if topic.endswith("/") or "//" in topic or any(c.isspace() for c in topic):
        raise UsageError(f"{spec!r}: {topic!r} is not a ROS 2 topic name")
    words = [w.strip() for w in qos.split(",")] if qos else []
    reliability = "reliable"
    durability = "volatile"
    for word in words:
        if word in ("reliable", "best_effort"):
            reliability = word
        elif word in ("volatile", "transient_local"):
            durability = word
        else:
            raise UsageError(
                f"{spec!r}: unknown QoS {word!r} (reliable, best_effort, volatile, transient_local)"
            )
    return topic, ros_type, (reliability, durability)


def make_qos(reliability, durability, depth):
    return Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100))
        if reliability == "reliable"
        else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal
        if durability == "transient_local"
        else Policy.Durability.Volatile,
        Policy.History.KeepLast(depth),
        # Plain CDR (XCDR1) like every ROS 2 middleware; Cyclone would also offer XCDR2.
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def json_safe(value):
    """Non-finite floats as the strings "NaN" / "Infinity" / "-Infinity", so lines stay JSON."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_safe(v) for v in value]
    return value


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="ros2_probe.py",
        description="Listen to / publish ROS 2 topics through Cyclone DDS on loopback.",
    )
    parser.add_argument("--domain", type=int, required=True, help="DDS domain id (0..232)")
    parser.add_argument(
        "--listen", action="append", default=[], metavar="ROS_TOPIC=ROS_TYPE[:QOS]"
    )
    parser.add_argument("--publish", metavar="ROS_TOPIC=ROS_TYPE[:QOS]")
    parser.add_argument("--json", metavar="OBJECT", help="the published message (default {})")
    parser.add_argument("--rate", type=float, help="publications per second (default 10)")
    parser.add_argument("--duration", type=float, required=True, metavar="SECONDS")
    parser.add_argument("--count", type=int, help="exit after this many received samples")
    args = parser.parse_args(argv)  # exits 2 itself on a malformed command line

    if not 0 <= args.domain <= 232:
        raise UsageError(f"--domain {args.domain}: must be 0..232")
    if not (args.duration > 0 and math.isfinite(args.duration)):
        raise UsageError("--duration must be a positive number of seconds")
    if args.count is not None and args.count <= 0:
        raise UsageError("--count must be positive")
    if args.count is not None and not args.listen:
        raise UsageError("--count needs at least one --listen")
    if args.publish is None and (args.json is not None or args.rate is not None):
        raise UsageError("--json and --rate need --publish")
    if not args.listen and args.publish is None:
        raise UsageError("nothing to do: give --listen and/or --publish")
    if args.rate is None:
        args.rate = 10.0
    if not (args.rate > 0 and math.isfinite(args.rate)):
        raise UsageError("--rate must be a positive number")

    args.listen = [parse_endpoint(spec) for spec in args.listen]
    if args.publish is not None:
        args.publish = parse_endpoint(args.publish)
        _, ros_type, _ = args.publish
        try:
            data = json.loads(args.json) if args.json is not None else {}
            args.message = from_dict(TYPES[ros_type], data)
            args.message.serialize()  # out-of-range integers and the like fail here
        except Exception as e:  # bad JSON, wrong shapes, values out of range
            raise UsageError(f"--json for {ros_type}: {e}") from None
    types_by_topic = {}
    for topic, ros_type, _ in args.listen + ([args.publish] if args.publish else []):
        if types_by_topic.setdefault(topic, ros_type) != ros_type:
            raise UsageError(f"{topic} given with two types: {types_by_topic[topic]} and {ros_type}")
    return args


def emit(line):
    try:
        sys.stdout.write(line + "\n")
        sys.stdout.flush()
    except BrokenPipeError:
        # Whoever read us has gone; nothing left to report to.
        os._exit(0)


def run(args):
    participant = DomainParticipant(args.domain)
    topics = {}

    def dds_topic(ros_topic, ros_type):
        if ros_topic not in topics:
            topics[ros_topic] = Topic(participant, "rt" + ros_topic, TYPES[ros_type])
        return topics[ros_topic]

    waitset = WaitSet(participant)
    readers = []
    for ros_topic, ros_type, qos in args.listen:
        reader = DataReader(
            participant, dds_topic(ros_topic, ros_type), qos=make_qos(*qos, READER_DEPTH)
        )
        condition = ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any)
        waitset.attach(condition)
        readers.append((ros_topic, ros_type, reader, condition))

    writer = None
    if args.publish is not None:
        ros_topic, ros_type, qos = args.publish
        writer = DataWriter(
            participant, dds_topic(ros_topic, ros_type), qos=make_qos(*qos, WRITER_DEPTH)
        )

    # Tests wait for this line before they start the group, so that a slow start of Python
    # and Cyclone DDS does not miss the run.
    print("ros2_probe: ready", file=sys.stderr, flush=True)
    start = time.monotonic()
    end = start + args.duration
    period = 1.0 / args.rate
    next_publish = start
    received = 0
    published = 0
    while True:
        now = time.monotonic()
        if writer is not None and now >= next_publish:
            writer.write(args.message)
            published += 1
            # Keep the cadence, but never try to catch up a backlog in a burst.
            next_publish = max(next_publish + period, now)
        for ros_topic, ros_type, reader, condition in readers:
            while True:
                samples = reader.take(N=64, condition=condition)
                if not samples:
                    break
                for sample in samples:
                    if not getattr(sample.sample_info, "valid_data", True) or not hasattr(
                        sample, "__dataclass_fields__"
                    ):
                        continue  # an unregister/dispose notice, no data
                    line = {"topic": ros_topic, "type": ros_type, "data": to_dict(sample)}
                    emit(json.dumps(json_safe(line), allow_nan=False))
                    received += 1
                    if args.count is not None and received >= args.count:
                        return received, published
        now = time.monotonic()
        if now >= end or stopping:
            return received, published
        wake = end if writer is None else min(end, next_publish)
        pause = min(max(wake - now, MIN_WAIT), MAX_WAIT)
        if readers:
            waitset.wait(duration(seconds=pause))
            # A sample that arrives while we are still in the previous batch keeps the waitset
            # triggered; the floor keeps a flood from turning the loop into a spin.
            if time.monotonic() - now < MIN_WAIT:
                time.sleep(MIN_WAIT)
        else:
            time.sleep(pause)


def main(argv):
    try:
        args = parse_args(argv)
    except UsageError as e:
        print(f"ros2_probe: {e}", file=sys.stderr)
        return 2
    signal.signal(signal.SIGTERM, stop)
    try:
        received, published = run(args)
    except KeyboardInterrupt:
        return 130
    print(f"ros2_probe: received {received} samples, published {published}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
