#!/bin/sh
# Reproduces the follower-deviation experiment of docs/fig9a.md: the autonomous convoy in six
# configurations, {wheel odometry, ideal localisation} × {no delay, WLAN, bad WLAN}, 120
# simulated seconds each in lockstep. Writes table.md and the six trajectory plots here.
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
    "$caravan" launch "$root/launch/$file" --quiet --runs-dir "$runs/$name" \
        --set "group.name=fig9a-$name" "$@" >/dev/null
    dir=$(ls -d "$runs/$name"/*/)
    cp "$dir/report.json" "$runs/$name.json"
    cp "$dir/trajectories.svg" "$here/$name.svg"
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
import json, sys
runs, out = sys.argv[1], sys.argv[2]
cols = [("no-delay", "no delay"), ("wlan", "WLAN"), ("bad-wlan", "bad WLAN (50 ms, 5 % loss)")]
rows = [("odometry", "wheel odometry (+ laser SLAM)"), ("ideal", "ideal localisation")]
def cell(r, c):
    rep = json.load(open(f"{runs}/{r}-{c}.json"))
    conv = rep["convoy"]
    f = conv["followers"]
    lead = sum(x["cross_track_to_leader_m"]["mean"] for x in f) / len(f)
    pred = sum(x["cross_track_to_predecessor_m"]["mean"] for x in f) / len(f)
    return lead, pred, conv
lines = ["| localisation | " + " | ".join(c[1] for c in cols) + " |", "|---|" + "---|" * len(cols)]
for r, label in rows:
    cells = []
    for c, _ in cols:
        lead, pred, conv = cell(r, c)
        cells.append(f"{lead*100:.1f} / {pred*100:.1f} cm ({lead/pred:.1f}×), gap {conv['min_gap_m']:.3f} m, {conv['goals_reached']}/4, {conv['collisions']} coll.")
    lines.append(f"| {label} | " + " | ".join(cells) + " |")
detail = ["", "| run | follower | to leader mean / p95 cm | to predecessor mean / p95 cm |", "|---|---|---|---|"]
for r, _ in rows:
    for c, _ in cols:
        _, _, conv = cell(r, c)
        for x in conv["followers"]:
            l, p = x["cross_track_to_leader_m"], x["cross_track_to_predecessor_m"]
            detail.append(f"| {r}-{c} | R{x['robot']} | {l['mean']*100:.1f} / {l['p95']*100:.1f} | {p['mean']*100:.1f} / {p['p95']*100:.1f} |")
open(out, "w").write("\n".join(lines + detail) + "\n")
print("\n".join(lines))
PY
