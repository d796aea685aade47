"""One-way latency of Caravan's ROS 2 bridge, Caravan topic -> DDS -> a Cyclone DDS subscriber.

Starts launch/bench/ros2-latency.toml (caravan-demo clock publishes the wall clock as x at
100 Hz; caravan-ros2 steps on each message and publishes it as geometry_msgs/Pose2D on
/demo/clock) and subscribes to /demo/clock with Cyclone DDS. Each sample's latency is the
subscriber's wall clock when it takes the sample minus x: Caravan's publish, the bridge's
wake-up and CDR encoding, RustDDS, the loopback network, Cyclone DDS and the Python binding.
Prints the count and p50 / p90 / p99 / max in microseconds. Run from the workspace root after
a release build, in .venv-ros2 (python/caravan-python --venv ros2 --requirements
../tests/requirements-ros2.txt --setup):

    .venv-ros2/bin/python tests/python/ros2_latency.py [--duration 30] [--domain 42]
        [--caravan target/release/caravan]

The first 2 s (discovery) are left out.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros2_probe  # noqa: E402,F401  (configures Cyclone DDS for loopback before it loads)
from cyclonedds.core import ReadCondition, SampleState, ViewState, InstanceState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402
from ros2_msgs import TYPES  # noqa: E402


def percentile(sorted_values, p):
    return sorted_values[min(len(sorted_values) - 1, int(p / 100 * len(sorted_values)))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--domain", type=int, default=42)
    parser.add_argument("--caravan", default="target/release/caravan")
    args = parser.parse_args()
    participant = DomainParticipant(args.domain)
    topic = Topic(participant, "rt/demo/clock", TYPES["geometry_msgs/msg/Pose2D"])
    reader = DataReader(participant, topic, qos=ros2_probe.make_qos("best_effort", "volatile", ros2_probe.READER_DEPTH)
    )
    condition = ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any)
    waitset = WaitSet(participant)
    waitset.attach(condition)
    runs = tempfile.mkdtemp(prefix="ros2-latency-")
    group = subprocess.Popen(
        [args.caravan, "launch", "launch/bench/ros2-latency.toml", "--quiet",
         "--duration", f"{args.duration}s", "--runs-dir", runs,
         "--set", f"process.ros2.params.domain={args.domain}"],
    )
    start = time.time()
    latencies = []
    while group.poll() is None:
        waitset.wait(duration(seconds=0.5))
        for sample in reader.take(N=64, condition=condition):
            now = time.time()
            if hasattr(sample, "x") and now - start > 2.0:
                latencies.append((now - sample.x) * 1e6)
    if group.returncode != 0 or not latencies:
        print(f"ros2_latency: the group exited {group.returncode}, {len(latencies)} samples", file=sys.stderr)
        return 1
    latencies.sort()
    print(f"samples {len(latencies)}  p50 {percentile(latencies, 50):.1f} µs  "
          f"p90 {percentile(latencies, 90):.1f} µs  p99 {percentile(latencies, 99):.1f} µs  "
          f"max {latencies[-1]:.1f} µs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
