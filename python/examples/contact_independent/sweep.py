"""Runs ``check.py`` over every run of a contact sweep and prints the table of docs/contact.md.

    python/caravan-python --venv contact --requirements examples/contact_independent/requirements.txt \\
        python/examples/contact_independent/sweep.py SWEEP_DIR [--out FILE]

SWEEP_DIR is a ``caravan sweep docs/contact/live.toml --out SWEEP_DIR`` output: every directory
under it holding a ``record.mcap`` is a run, checked at its own σ (its ``estimator.torque_sigma``)
with the independent noise seeded by the run's seed. Per σ, each figure is a run's mean,
averaged over the runs (seeds); "live − independent" counts the runs whose bootstrap 95 %
interval of the difference of the mean errors lies above 0, contains 0, or lies below 0.
"""

from __future__ import annotations

import argparse
import json
import os

from check import check, fmt

METRICS = ("force_error_n", "direction_error_deg", "point_error_mm")


def runs(root: str) -> list:
    found = []
    for d, _, files in os.walk(root):
        if "record.mcap" in files:
            found.append(d)
    return sorted(found)


def verdict(diffs: list) -> str:
    above = sum(1 for d in diffs if d and d["bootstrap_ci95"][0] > 0)
    below = sum(1 for d in diffs if d and d["bootstrap_ci95"][1] < 0)
    return f"{above} / {len(diffs) - above - below} / {below}"


def table(results: list) -> str:
    by_sigma = {}
    for r in results:
        by_sigma.setdefault(r["sigma"], []).append(r)
    out = [
        "| σ (N·m) | runs | force error (N): independent / live / live vs independent "
        "| direction error (°) | point error (mm) | live − independent > 0 / ∋ 0 / < 0 (force, direction, point) "
        "| no point (%): independent / live | wrong link (%): independent |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for sigma in sorted(by_sigma):
        rs = by_sigma[sigma]

        def avg(f):
            xs = [f(r) for r in rs]
            xs = [x for x in xs if x is not None]
            return sum(xs) / len(xs) if xs else None

        cells = []
        for m in METRICS:
            # Point errors: the independent one's over the instants the live one had a point.
            ind = (lambda r: (r["independent_point_error_mm_where_live_found"] or {}).get("mean")) if m == "point_error_mm" \
                else (lambda r, m=m: r["independent_vs_truth"][m]["mean"])
            cells.append(f"{fmt(avg(ind))} / {fmt(avg(lambda r, m=m: (r['live_vs_truth'][m] or {}).get('mean')))} / "
                         f"{fmt(avg(lambda r, m=m: (r['live_vs_independent'][m] or {}).get('mean')))}")
        verdicts = ", ".join(verdict([r["live_minus_independent_mean_error"][m] for r in rs]) for m in METRICS)
        out.append(f"| {sigma:g} | {len(rs)} | " + " | ".join(cells) + f" | {verdicts} | "
                   f"{fmt(avg(lambda r: r['independent_no_point_pct']))} / {fmt(avg(lambda r: r['live_no_solution_pct']))} | "
                   f"{fmt(avg(lambda r: r['independent_wrong_link_pct']))} |")
    out += [
        "",
        "| σ (N·m) | live fit beyond the pushed link's joints (%) | live force error (N) there / elsewhere "
        "| independent force error (N) | live noise recovered: std / σ [bootstrap 95 %], skewness, excess kurtosis |",
        "|---|---|---|---|---|",
    ]
    for sigma in sorted(by_sigma):
        rs = by_sigma[sigma]

        def avg(f):
            xs = [f(r) for r in rs]
            xs = [x for x in xs if x is not None]
            return sum(xs) / len(xs) if xs else None

        noise = [r["live_noise"] for r in rs if r.get("live_noise")]
        noise_cell = "; ".join(
            f"{n['std_over_sigma']:.3f} [{n['std_over_sigma_bootstrap_ci95'][0]:.3f}, {n['std_over_sigma_bootstrap_ci95'][1]:.3f}], "
            f"{n['skewness']:+.2f}, {n['excess_kurtosis']:+.2f}" for n in noise) or "–"
        out.append(
            f"| {sigma:g} | {fmt(avg(lambda r: r['live_beyond_pushed_link_pct']))} | "
            f"{fmt(avg(lambda r: (r['live_force_error_n_beyond_pushed_link'] or {}).get('mean')))} / "
            f"{fmt(avg(lambda r: (r['live_force_error_n_up_to_pushed_link'] or {}).get('mean')))} | "
            f"{fmt(avg(lambda r: r['independent_vs_truth']['force_error_n']['mean']))} | {noise_cell} |")
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sweep_dir")
    ap.add_argument("--out", help="write every run's summary here (JSON)")
    args = ap.parse_args()
    results = []
    for d in runs(args.sweep_dir):
        with open(os.path.join(d, "run.json")) as f:
            seed = int(json.load(f)["seed"])
        results.append(check(d, None, seed, None, 0.004))
        print(f"checked {d}", flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)
    print()
    print(table(results))


if __name__ == "__main__":
    main()
