"""A convoy follower in Python.

The reference follower law of processes/convoy/src/agent/follower.rs, with the same defaults:
robot i drives toward where its predecessor was tau seconds ago,

    v = k1 (x_p(t - tau) - x) cos(theta) + k2 (y_p(t - tau) - y) sin(theta)
    w = k3 wrap(theta_p(t - tau) - theta)

never reversing, with |w| <= 2 rad/s and v <= 0.25 m/s, holding still until the predecessor's
history reaches back tau, easing off as the gap between the two footprints shrinks, and stopping
before it reaches the 0.15 m safety distance, allowing for how far the robot still rolls at its
measured speed and how old the poses are (their header stamps). It publishes wheel set-points
at 20 Hz.

launch/convoy/convoy-python.toml runs it as follower-2 of the reference convoy:

    caravan launch launch/convoy/convoy-python.toml
"""

import bisect
import math
import tomllib

from caravan import BadInput, Node, main, topics
from caravan.robot import wheel_geometry
from caravan.schemas import Pose2D, WheelSetpoint

# Defaults; the launch file's params table overrides them (unknown keys are errors).
PARAMS = {
    "robot": 0,  # this robot's index: it follows robot - 1
    "mode": "follower",
    "pose_topic": None,  # own pose (Pose2D); default robot/<i>/pose_true
    "predecessor_topic": None,  # the predecessor's pose; default robot/<i-1>/pose_true
    "urdf": None,  # the robot's URDF (required): wheel radius and separation
    "world": None,  # a world file: when it lists [[start]] poses, robot must be one of them
    "follower": {
        "k1": 1.5,
        "k2": 1.5,
        "k3": 1.0,
        "tau_s": 2.0,
        "safety_distance_m": 0.15,
        "stop_margin_m": 0.05,  # extra gap at a standstill
        "brake_time_s": 0.45,  # own speed may still carry the robot this long after a stop, s
        "coast_time_s": 0.2,  # the predecessor's speed carries it at least this long, s
        "rollback_time_s": 0.18,  # a robot stopped from speed V rolls back up to V times this, s
        "rollback_window_s": 1.0,  # the predecessor's peak speed is looked for this far back, s
        "speed_window_s": 0.1,  # speeds are measured over this much pose history, s
        "k_gap": 1.5,  # speed allowed per metre of gap beyond safety distance and margin, 1/s
        "footprint_half_m": (0.10, 0.09),
        "footprint_offset_m": -0.02,
        "v_max": 0.25,
        "omega_max": 2.0,
    },
}

TAU = 2.0 * math.pi


def wrap(a):
    """The angle in (-pi, pi]."""
    w = a % TAU
    return w - TAU if w > math.pi else w


class PoseHistory:
    """Time-stamped poses (x, y, theta) in arrival order, to look up where a robot was."""

    def __init__(self, keep_s):
        self.times, self.poses, self.keep_s = [], [], keep_s

    def push(self, t, pose):
        if self.times and t <= self.times[-1]:
            return
        self.times.append(t)
        self.poses.append(pose)
        old = bisect.bisect_left(self.times, t - self.keep_s)
        if old:
            del self.times[:old], self.poses[:old]

    def latest(self):
        return self.poses[-1] if self.poses else None

    def latest_stamped(self):
        return (self.times[-1], self.poses[-1]) if self.poses else None

    def forward_speed(self, window_s, end=None):
        """Speed along the heading at sample ``end`` (default the newest) over window_s before
        it, m/s: negative rolling back, 0 with fewer than two samples."""
        if not self.times:
            return 0.0
        end = len(self.times) - 1 if end is None else end
        t1, last = self.times[end], self.poses[end]
        t0 = max(t1 - window_s, self.times[0])
        if t1 <= t0:
            return 0.0
        start = self.at(t0)
        dx, dy = last[0] - start[0], last[1] - start[1]
        return (dx * math.cos(last[2]) + dy * math.sin(last[2])) / (t1 - t0)

    def peak_forward_speed(self, window_s, span_s):
        """The highest forward speed measured at any sample of the last span_s (0 if none)."""
        if not self.times:
            return 0.0
        first = bisect.bisect_left(self.times, self.times[-1] - span_s)
        return max([0.0] + [self.forward_speed(window_s, k) for k in range(first, len(self.times))])

    def at(self, t):
        """The pose at time t, interpolated (heading the short way); None before the history."""
        if not self.times or t < self.times[0]:
            return None
        if t >= self.times[-1]:
            return self.poses[-1]
        i = bisect.bisect_right(self.times, t)
        (t0, p0), (t1, p1) = (self.times[i - 1], self.poses[i - 1]), (self.times[i], self.poses[i])
        a = (t - t0) / (t1 - t0)
        return (
            p0[0] + a * (p1[0] - p0[0]),
            p0[1] + a * (p1[1] - p0[1]),
            wrap(p0[2] + a * wrap(p1[2] - p0[2])),
        )


def footprint(pose, half, offset):
    """Corners (counter-clockwise) of a robot's rectangle at pose (x, y, theta)."""
    s, c = math.sin(pose[2]), math.cos(pose[2])
    cx, cy = pose[0] + c * offset, pose[1] + s * offset
    corners = ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
    return [
        (cx + c * (sx * half[0]) - s * (sy * half[1]), cy + s * (sx * half[0]) + c * (sy * half[1]))
        for sx, sy in corners
    ]


def _inside(p, poly):
    return all(
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0.0
        for a, b in zip(poly, poly[1:] + poly[:1], strict=True)
    )


def _point_segment(p, a, b):
    ab = (b[0] - a[0], b[1] - a[1])
    len2 = ab[0] * ab[0] + ab[1] * ab[1]
    t = (
        min(max(((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2, 0.0), 1.0)
        if len2 > 0.0
        else 0.0
    )
    return math.hypot(p[0] - (a[0] + t * ab[0]), p[1] - (a[1] + t * ab[1]))


def rect_distance(a, b):
    """Distance between two convex quadrilaterals; 0 when they overlap."""
    if any(_inside(p, b) for p in a) or any(_inside(p, a) for p in b):
        return 0.0
    return min(
        _point_segment(p, r[i], r[(i + 1) % 4])
        for r, q in ((a, b), (b, a))
        for i in range(4)
        for p in q
    )


def command(own_history, history, now_s, p):
    """(v, w) for a follower given its own and its predecessor's pose histories, at now_s."""
    target, latest = history.at(now_s - p.tau_s), history.latest_stamped()
    if target is None or latest is None:
        return 0.0, 0.0  # waiting for history that reaches back tau
    (own_t, own), (pred_t, current) = own_history.latest_stamped(), latest

    # How much nearer the two can come once both are at rest if both stopped now: the follower
    # drives on from its (older) pose for the longest roll-out, the predecessor coasts for the
    # shortest and then rolls back in proportion to its recent peak speed.
    own_travel = max(own_history.forward_speed(p.speed_window_s), 0.0) * (
        max(now_s - own_t, 0.0) + p.brake_time_s
    )
    pred_speed = history.forward_speed(p.speed_window_s)
    pred_travel = (
        p.coast_time_s * max(pred_speed, 0.0)
        + min(pred_speed, 0.0) * max(now_s - pred_t, 0.0)  # rolling back since its pose
        - p.rollback_time_s * history.peak_forward_speed(p.speed_window_s, p.rollback_window_s)
    )
    closing = max(own_travel - pred_travel, 0.0)
    rect = lambda q: footprint(q, p.footprint_half_m, p.footprint_offset_m)  # noqa: E731
    room = rect_distance(rect(own), rect(current)) - p.safety_distance_m - p.stop_margin_m
    if room <= closing:
        return 0.0, 0.0  # safety stop
    s, c = math.sin(own[2]), math.cos(own[2])
    v = p.k1 * (target[0] - own[0]) * c + p.k2 * (target[1] - own[1]) * s
    omega = p.k3 * wrap(target[2] - own[2])
    v_max = min(p.v_max, p.k_gap * room)  # ease off near the predecessor
    return min(max(v, 0.0), v_max), min(max(omega, -p.omega_max), p.omega_max)


def check_robot(path, name, robot):
    """A world file that lists [[start]] poses names its robots: ``robot`` must be one."""
    try:
        with open(path, "rb") as f:
            starts = len(tomllib.load(f).get("start", []))
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise BadInput(f"key 'world': world file {name}: {e}") from None
    if starts and robot >= starts:
        raise BadInput(
            f"key 'robot': world file {name} lists {starts} [[start]] pose(s), for robots 0 "
            f"to {starts - 1}; robot {robot} is not among them"
        )


def agent():
    node = Node.from_env()
    p = node.params(PARAMS)
    if p.mode != "follower":
        raise BadInput(
            "key 'mode': this Python agent is a follower; use caravan-convoy-agent to lead"
        )
    if p.robot == 0 and p.predecessor_topic is None:
        raise BadInput("key 'robot': robot 0 has no predecessor; set 'predecessor_topic'")
    if p.urdf is None:
        raise BadInput("key 'urdf': give the robot's URDF (its wheel radius and separation)")
    i = p.robot
    if p.world is not None:
        check_robot(node.identity.resolve_path(p.world), p.world, i)
    r, sep = wheel_geometry(node.identity.resolve_path(p.urdf))
    own = node.subscriber(Pose2D, p.pose_topic or topics.pose_true(i))
    predecessor = node.subscriber(Pose2D, p.predecessor_topic or topics.pose_true(i - 1))
    setpoint = node.publisher(WheelSetpoint, topics.wheel_setpoint(i))
    history = PoseHistory(p.follower.tau_s + 2.0)
    own_history = PoseHistory(p.follower.speed_window_s + 1.0)  # for the robot's own speed

    def step(s):
        for msg in predecessor.receive_all():
            history.push(msg.stamp_s, (msg.payload.x, msg.payload.y, msg.payload.theta))
        if (msg := own.latest()) is not None:
            own_history.push(msg.stamp_s, (msg.payload.x, msg.payload.y, msg.payload.theta))
        if own_history.latest() is None:
            return
        v, omega = command(own_history, history, s.now, p.follower)
        setpoint.publish(
            WheelSetpoint((2 * v - sep * omega) / (2 * r), (2 * v + sep * omega) / (2 * r))
        )

    node.run(step, rate="20Hz")


if __name__ == "__main__":
    main(agent)
