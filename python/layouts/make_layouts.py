"""Writes each scenario's Foxglove layout, `launch/<scenario>/foxglove-layout.json`, with the
Foxglove SDK's layout classes (package foxglove-sdk, pinned in requirements.txt).

    python/caravan-python --venv layouts --requirements python/layouts/requirements.txt \
        python/layouts/make_layouts.py [OUT_DIR]

Each layout is a 3D panel in the `map` frame with the scenario's Foxglove channels (the world's
solids, the SLAM map, scans, paths, robots' frames) beside plots of its raw topics. Topic names
in plot paths are quoted because Caravan's topics do not start with a slash. A test regenerates
them and compares (tests/tests/foxglove.rs), and checks that each topic they name is recorded.
"""

from __future__ import annotations

import sys
from pathlib import Path

import foxglove.layouts as fl

ROOT = Path(__file__).resolve().parents[2]


def path(topic: str, field: str) -> str:
    """A message path: the topic quoted, then the field."""
    return f'"{topic}".{field}'


def metric(topic: str, name: str, label: str) -> tuple[str, str, str]:
    """A series of one named value of a caravan::Metrics topic (a message path filter)."""
    return (topic, f'values[:]{{name=="{name}"}}.value', label)


def plot(title: str, series: list[tuple[str, str, str]]) -> fl.PlotPanel:
    """A plot over time of (topic, field, label) series."""
    return fl.PlotPanel(
        title=title,
        config=fl.PlotConfig(
            paths=[
                fl.PlotSeries(value=path(topic, field), label=label, enabled=True)
                for topic, field, label in series
            ],
            show_legend=True,
        ),
    )


def three_d(topics: list[str], follow: str = "map") -> fl.ThreeDeePanel:
    settings = {t: fl.BaseRendererSceneUpdateTopicSettings(visible=True) for t in topics}
    return fl.ThreeDeePanel(
        config=fl.ThreeDeeConfig(follow_tf=follow, topics=settings),
    )


def split(direction: str, *panels, proportions=None) -> fl.SplitContainer:
    proportions = proportions or [1] * len(panels)
    return fl.SplitContainer(
        direction=direction,
        items=[fl.SplitItem(proportion=p, content=c) for p, c in zip(proportions, panels)],
    )


def scene_beside_plots(topics: list[str], *plots: fl.PlotPanel) -> fl.Layout:
    """The 3D panel with `topics`, two thirds of the width, beside a column of `plots`."""
    return fl.Layout(content=split("row", three_d(topics), split("column", *plots), proportions=[2, 1]))


def convoy() -> fl.Layout:
    robots = range(5)
    return scene_beside_plots(
        ["foxglove/scene", "foxglove/map", "foxglove/robot/0/scan", "foxglove/robot/0/path"]
        + [f"foxglove/robot/{i}/pose_true" for i in robots],
        plot("x along the course (m)", [(f"robot/{i}/pose_true", "x", f"robot {i}") for i in robots]),
        plot("gap to predecessor (m)", [metric("convoy/metrics", f"gap_{i}_m", f"R{i}") for i in robots if i]),
        plot(
            "cross-track to predecessor's path (m)",
            [metric("convoy/metrics", f"cross_track_{i}_m", f"R{i}") for i in robots if i],
        ),
        plot(
            "leader command",
            [("robot/0/cmd_vel", "linear.x", "v (m/s)"), ("robot/0/cmd_vel", "angular.z", "ω (rad/s)")],
        ),
    )


def tracked() -> fl.Layout:
    return scene_beside_plots(
        ["foxglove/scene", "foxglove/robot/0/ground_truth", "foxglove/robot/0/odometry"],
        plot(
            "position (m)",
            [("robot/0/ground_truth", "pose.position.x", "x true"), ("robot/0/odometry", "pose.position.x", "x odometry")],
        ),
        plot(
            "speed",
            [("robot/0/cmd_vel", "linear.x", "v command (m/s)"), ("robot/0/ground_truth", "twist.linear.x", "v true (m/s)")],
        ),
    )


def imu() -> fl.Layout:
    return fl.Layout(
        content=split(
            "column",
            plot("acceleration (m/s²)", [("robot/0/imu", f"linear_acceleration.{a}", a) for a in "xyz"]),
            plot("angular velocity (rad/s)", [("robot/0/imu", f"angular_velocity.{a}", a) for a in "xyz"]),
        )
    )


def contact() -> fl.Layout:
    return scene_beside_plots(
        ["foxglove/scene"],
        plot("applied force (N)", [("robot/0/wrench", f"force.{a}", a) for a in "xyz"]),
        plot("estimated force (N)", [("robot/0/contact_estimate", f"force.{a}", a) for a in "xyz"]),
    )


def uav() -> fl.Layout:
    return fl.Layout(
        content=plot(
            "episodes",
            [("agent/episode", "total_reward", "total reward"), ("agent/episode", "steps", "steps")],
        )
    )


def pingpong() -> fl.Layout:
    return fl.Layout(
        content=plot("demo", [("demo/ping", "x", "ping"), ("demo/pong", "x", "pong"), ("demo/sum", "x", "sum")])
    )


LAYOUTS = {
    "convoy": convoy,
    "tracked": tracked,
    "imu": imu,
    "contact": contact,
    "uav": uav,
    "pingpong": pingpong,
}


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "launch"
    for name, make in LAYOUTS.items():
        folder = out if name == "pingpong" else out / name
        folder.mkdir(parents=True, exist_ok=True)
        file = folder / ("pingpong.foxglove-layout.json" if name == "pingpong" else "foxglove-layout.json")
        file.write_text(make().to_json() + "\n")
        print(file)


if __name__ == "__main__":
    main()
