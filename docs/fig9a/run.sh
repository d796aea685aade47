#!/bin/sh
# Reproduces the follower-deviation experiment of docs/fig9a.md: the autonomous convoy in six
# configurations, {wheel odometry, ideal localisation} × {no delay, WLAN, bad WLAN}, each with
# seeds 1, 2 and 3 (sensor noise and link draws), 120 simulated seconds each in lockstep.
# Writes table.md and the trajectory plots of seed 1 here.
#
#   cargo build --release --workspace --bins && docs/fig9a/run.sh
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
caravan="$root/target/release/caravan"
runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT

run() { # name, launch file, extra args…
    name=$1 file=$2
    shift 2
    for seed in 1 2 3; do
        "$caravan" launch "$root/launch/$file" --quiet --runs-dir "$runs/$name-$seed" \
            --seed "$seed" --set "group.name=fig9a-$name" "$@" >/dev/null 2>&1
        dir=$(ls -d "$runs/$name-$seed"/*/)
        cp "$dir/report.json" "$runs/$name-$seed.json"
        [ "$seed" = 1 ] && cp "$dir/trajectories.svg" "$here/$name.svg"
    done
    echo "$name done"
}

bad="--set args.wlan_latency=50ms --set args.wlan_loss=0.05"
run odometry-no-delay convoy.toml
run ideal-no-delay convoy.toml --set args.localisation=ideal
run odometry-wlan convoy-wlan.toml
run ideal-wlan convoy-wlan.toml --set args.localisation=ideal
# shellcheck disable=SC2086
run odometry-bad-wlan convoy-wlan.toml $bad
# shellcheck disable=SC2086
run ideal-bad-wlan convoy-wlan.toml $bad --set args.localisation=ideal

python3 - "$runs" "$here/table.md" <<'PY'
import json, statistics, sys
runs, out = sys.argv[1], sys.argv[2]
seeds = [1, 2, 3]
cols = [("no-delay", "no delay"), ("wlan", "WLAN"), ("bad-wlan", "bad WLAN (50 ms, 5 % loss)")]
rows = [("odometry", "wheel odometry (+ laser SLAM)"), ("ideal", "ideal localisation")]

def run(r, c, seed):
    conv = json.load(open(f"{runs}/{r}-{c}-{seed}.json"))["convoy"]
    f = conv["followers"]
    mean = lambda key: sum(x[key]["mean"] for x in f) / len(f)
    return {"lead": mean("cross_track_to_leader_m") * 100,
            "pred": mean("cross_track_to_predecessor_m") * 100,
            "gap": conv["min_gap_m"], "goals": conv["goals_reached"],
            "coll": conv["collisions"]}

def cell(r, c):
    rs = [run(r, c, s) for s in seeds]
    m = lambda k: statistics.mean(x[k] for x in rs)
    sd = lambda k: statistics.stdev(x[k] for x in rs)
    return {"lead": m("lead"), "lead_sd": sd("lead"), "pred": m("pred"), "pred_sd": sd("pred"),
            "gap": min(x["gap"] for x in rs), "goals": min(x["goals"] for x in rs),
            "coll": sum(x["coll"] for x in rs)}

cells = {(r, c): cell(r, c) for r, _ in rows for c, _ in cols}
lines = ["Mean follower cross-track deviation to the leader's path / to the predecessor's path (cm,",
         "mean of R1–R4, then mean ± sd over seeds 1–3), their ratio, the smallest gap and the",
         "collisions over the three runs:", "",
         "| localisation | " + " | ".join(c[1] for c in cols) + " |", "|---|" + "---|" * len(cols)]
for r, label in rows:
    row = []
    for c, _ in cols:
        x = cells[(r, c)]
        row.append(f"{x['lead']:.1f} ± {x['lead_sd']:.1f} / {x['pred']:.1f} ± {x['pred_sd']:.1f} "
                   f"({x['lead'] / x['pred']:.1f}×); gap ≥ {x['gap']:.3f} m; {x['coll']} coll.")
    lines.append(f"| {label} | " + " | ".join(row) + " |")
lines += ["", "Effects on the deviation to the leader (cm, differences of the cell means):", ""]
for c, label in cols:
    d = cells[("odometry", c)]["lead"] - cells[("ideal", c)]["lead"]
    lines.append(f"- localisation (odometry − ideal), {label}: {d:+.1f}")
for r, label in rows:
    base = cells[(r, "no-delay")]["lead"]
    for c, clabel in cols[1:]:
        lines.append(f"- {clabel} − no delay, {label}: {cells[(r, c)]['lead'] - base:+.1f}")
open(out, "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
