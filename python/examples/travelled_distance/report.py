"""A report plugin in Python: how far each robot (or anything publishing poses) travelled.

For every recorded topic that ``topics`` selects (names or patterns with ``*``) whose messages
have ``x`` and ``y`` (``caravan::Pose2D``, say ``robot/*/pose_true``), the section holds:

- ``messages``: how many were recorded;
- ``distance_m``: the length of the polyline through their (x, y), m;
- ``displacement_m``: the straight distance from the first to the last, m;
- ``duration_s``: from the first message's stamp to the last's, simulated s.

and ``total_distance_m``, their sum. ``plot`` names an SVG of the paths written into the run
directory ("" for none). Run by the launcher through ``python/caravan-python`` (see
pingpong.toml beside this file, and docs/scenarios.md).
"""

import fnmatch
import math

from caravan import report


def setup(p, inputs):
    if not p["topics"] or not all(isinstance(t, str) and t for t in p["topics"]):
        raise report.BadParams("key 'topics': name at least one topic or pattern")
    report.check_name(p["section"])
    return p


@report.plugin(
    "travelled-distance-report",
    params={"topics": list, "section": "distance", "plot": "distance.svg"},
    setup=setup,
)
def distance(run, p):
    rec = run.recording
    chosen = [t.name for t in rec.topics()
              if any(fnmatch.fnmatchcase(t.name, pattern) for pattern in p["topics"])]
    paths = {name: [] for name in chosen}
    stamps = {name: [] for name in chosen}
    for item in rec.messages(chosen):
        paths[item.topic].append((item.message.x, item.message.y))
        stamps[item.topic].append(item.header.stamp_ns)
    rows = {}
    for name, path in paths.items():
        if not path:
            continue
        rows[name] = {
            "messages": len(path),
            "distance_m": sum(math.dist(a, b) for a, b in zip(path, path[1:])),
            "displacement_m": math.dist(path[0], path[-1]),
            "duration_s": (stamps[name][-1] - stamps[name][0]) / 1e9,
        }
    total = sum(r["distance_m"] for r in rows.values())
    lines = [f"## Travelled distance\n\n{total:.3f} m over {len(rows)} topics.\n",
             "| topic | messages | distance (m) | displacement (m) | duration (s) |",
             "|---|---|---|---|---|"]
    lines += [f"| `{n}` | {r['messages']} | {r['distance_m']:.3f} | {r['displacement_m']:.3f} "
              f"| {r['duration_s']:.3f} |" for n, r in rows.items()]
    if p["plot"]:
        report.line_plot(run.path(p["plot"]), {n: paths[n] for n in rows},
                         title="Paths", x_label="x (m)", y_label="y (m)", equal_axes=True)
        lines.append(f"\n![paths]({p['plot']})")
    return report.Section(p["section"], {"topics": rows, "total_distance_m": total},
                          "\n".join(lines) + "\n")


if __name__ == "__main__":
    distance.main()
