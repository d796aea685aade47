"""Checks a live contact run (launch/contact/push.toml) against an independent estimator.

    python/caravan-python --venv contact --requirements examples/contact_independent/requirements.txt \\
        python/examples/contact_independent/check.py RUN_DIR [--sigma S] [--seed N] [--json FILE]

Reads RUN_DIR/record.mcap with ``caravan.recording``, re-estimates every scored instant with
``estimator.py`` (a search over the links' contours, not the perception's analytical method)
and prints a JSON summary, then a Markdown table, of

(a) the independent estimate against the truth,
(b) the live estimate (``robot/0/contact_estimate``) against the truth,
(c) the live estimate against the independent one,

each as force error (N), point error (mm) and direction error (°): mean, median, max.

What is scored, as ``caravan-contact-report`` scores it (``processes/contact/src/report.rs``
and ``live.rs::score``): a push begins at a ``robot/0/wrench`` message in the link's frame
with a non-zero force and ends at the next wrench on the same link; an estimate stamped t is
scored when a push acts (start ≤ t < end) and t ≥ start + ``settle_s`` (the report's param,
read from the run's launch file; 0.75 s), against the push's point and force carried into the
world by the link's pose in the last ``robot/0/link_states`` stamped ≤ t. The live force error
counts every scored estimate with a force; the live point error only those of status 1 (the
point from the line of action), as the report's.

The torques: ``caravan-physics`` publishes as a joint's ``effort`` the torque its position
loop applies (``processes/physics/src/actuator.rs``, ``Actuator::torque``; ``engine/sim.rs``,
``joints``), so at rest the external torque is minus the effort; the perception
(``processes/contact/src/bin/id.rs``) takes τ = −effort + noise (with ``estimator.dynamics``
off, as in push.toml), and adds its noise itself: the recorded efforts are noise-free. The
independent estimator takes τ = −effort plus Gaussian noise of σ drawn here with numpy's
generator (``--sigma``, default the run's ``estimator.torque_sigma``; ``--seed``).
The perception runs on every joint state and publishes one tick later in lockstep, so the
estimate stamped t is paired with the last joint state stamped before t.

With noise the two estimators' errors are compared as distributions: each mean with a
bootstrap 95 % interval, and the difference of the means (live − independent, paired by
instant) with a bootstrap 95 % interval.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tomllib

try:
    import numpy as np
except ImportError:  # the workspace's default .venv has no numpy
    raise SystemExit("check.py needs numpy: run it as python/caravan-python --venv contact "
                     "--requirements examples/contact_independent/requirements.txt "
                     "python/examples/contact_independent/check.py RUN_DIR") from None

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "python"))

from caravan import recording  # noqa: E402
from estimator import Arm, Estimator  # noqa: E402

FOUND = 1  # ContactEstimate.status: force and point from the torques
LINK_FRAME = 1  # Wrench.frame: point and force in the link's frame
CHUNK = 128
BOOTSTRAP = 2000


def yaw(o: dict) -> float:
    w, x, y, z = o["w"], o["x"], o["y"], o["z"]
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def num(v) -> float:
    return math.nan if v is None else float(v)


def toml_1_0(text: str) -> str:
    """Caravan's launch files spread inline tables over lines (TOML 1.1, which the Rust
    parser reads); Python's tomllib reads TOML 1.0: join those lines, dropping comments."""
    out, depth, quote, comment = [], 0, None, False
    for ch in text:
        if comment:
            if ch != "\n":
                continue
            comment = False
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "#" and depth > 0:
            comment = True
            continue
        out.append(" " if ch == "\n" and depth > 0 else ch)
    return "".join(out)


def launch_params(rec) -> dict:
    """The run's resolved launch file: σ, μ, the stadium radius, settle_s, the URDF."""
    launch = tomllib.loads(toml_1_0(rec.launch_file or ""))
    proc = next(p for p in launch.get("process", []) if p.get("name") == "contact-id")
    report = (launch.get("report") or [{}])[0].get("params", {})
    est = proc["params"].get("estimator", {})
    return {
        "sigma": float(est.get("torque_sigma", 0.0)),
        "dynamics": bool(est.get("dynamics", False)),
        "mu": float(est.get("mu", 0.5)),
        "radius": float(proc["params"]["arm"].get("link_radius", 0.05)),
        "urdf": proc["params"]["arm"]["urdf"],
        "settle_s": float(report.get("settle_s", 0.75)),
    }


def read(run_dir: str, joints: list) -> dict:
    """Pushes, link poses, joint states and live estimates of the run's recording."""
    pushes, poses, states, estimates = [], [], [], []
    topics = ["robot/0/wrench", "robot/0/link_states", "robot/0/joint_states", "robot/0/contact_estimate"]
    with recording.open(os.path.join(run_dir, "record.mcap"), decode=False) as rec:
        params = launch_params(rec)
        seed = rec.metadata.get("run", {}).get("seed")
        for r in rec.messages(topics):
            t, j = r.header.stamp_ns, r.message
            if r.topic == "robot/0/wrench":
                for p in pushes:
                    if p["link"] == j["link"] and p["end"] is None:
                        p["end"] = t
                f = (num(j["force"]["x"]), num(j["force"]["y"]))
                if j["frame"] == LINK_FRAME and math.hypot(*f) > 0:
                    pt = (num(j["point"]["x"]), num(j["point"]["y"]))
                    pushes.append({"start": t, "end": None, "link": j["link"], "point": pt, "force": f})
            elif r.topic == "robot/0/link_states":
                poses.append((t, {l["name"]: (l["pose"]["position"]["x"], l["pose"]["position"]["y"],
                                              yaw(l["pose"]["orientation"])) for l in j["links"]}))
            elif r.topic == "robot/0/joint_states":
                by = {s["name"]: s for s in j["joints"]}
                if all(n in by for n in joints):
                    states.append((t, [num(by[n]["position"]) for n in joints], [num(by[n]["effort"]) for n in joints]))
            else:
                estimates.append((t, int(j["status"]), j["link"], int(j["last_candidate"]),
                                  (num(j["force"]["x"]), num(j["force"]["y"])),
                                  (num(j["point"]["x"]), num(j["point"]["y"]))))
    return {"pushes": pushes, "poses": poses, "states": states, "estimates": estimates, "params": params, "seed": seed}


def scored(data: dict, settle_s: float) -> dict:
    """The estimates the report scores, with their truth and the joint state they came from."""
    settle = round(settle_s * 1e9)
    pose_t = np.array([t for t, _ in data["poses"]])
    state_t = np.array([t for t, _, _ in data["states"]])
    rows = []
    for t, status, link, last, f, p in data["estimates"]:
        push = next((u for u in data["pushes"] if u["start"] <= t and (u["end"] is None or t < u["end"])), None)
        if push is None or t < push["start"] + settle:
            continue
        i = np.searchsorted(pose_t, t, side="right") - 1
        js = np.searchsorted(state_t, t, side="left") - 1
        if i < 0 or js < 0 or push["link"] not in data["poses"][i][1]:
            continue
        x, y, h = data["poses"][i][1][push["link"]]
        c, s = math.cos(h), math.sin(h)
        (lx, ly), (fx, fy) = push["point"], push["force"]
        rows.append({
            "t": t, "status": status, "link": link, "last_candidate": last, "force": f, "point": p, "state": js,
            "true_point": (x + c * lx - s * ly, y + s * lx + c * ly),
            "true_force": (c * fx - s * fy, s * fx + c * fy), "true_link": push["link"],
        })
    return rows


def angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return np.degrees(np.arctan2(np.abs(cross), (a * b).sum(1)))


def errors(f, p, f_ref, p_ref, has_point) -> dict:
    """Force (N), point (mm) and direction (°) errors of (f, p) against (f_ref, p_ref)."""
    has_force = np.isfinite(f).all(1) & np.isfinite(f_ref).all(1)
    has_point = has_point & np.isfinite(p).all(1) & np.isfinite(p_ref).all(1)
    return {
        "force_error_n": np.linalg.norm(f - f_ref, axis=1)[has_force],
        "point_error_mm": 1e3 * np.linalg.norm(p - p_ref, axis=1)[has_point],
        "direction_error_deg": angle_deg(f, f_ref)[has_force],
    }


def describe(x: np.ndarray, rng) -> dict | None:
    if len(x) == 0:
        return None
    means = x[rng.integers(0, len(x), (BOOTSTRAP, len(x)))].mean(1) if len(x) > 1 else np.array([x[0]])
    return {"n": int(len(x)), "mean": float(x.mean()), "median": float(np.median(x)), "max": float(x.max()),
            "bootstrap_ci95": [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]}


def mean_difference(a: np.ndarray, b: np.ndarray, rng) -> dict | None:
    """mean(a) − mean(b) for two samples, each resampled on its own (bootstrap 95 %)."""
    if len(a) < 2 or len(b) < 2:
        return None
    ia, ib = rng.integers(0, len(a), (BOOTSTRAP, len(a))), rng.integers(0, len(b), (BOOTSTRAP, len(b)))
    d = a[ia].mean(1) - b[ib].mean(1)
    return {"diff": float(a.mean() - b.mean()), "bootstrap_ci95": [float(np.quantile(d, 0.025)), float(np.quantile(d, 0.975))],
            "ratio": float(a.mean() / b.mean()) if b.mean() > 0 else None}


def live_noise(rows, q, tau_true, live_f, live_p, arm, sigma, rng) -> dict | None:
    """The torque noise the perception added, recovered from its output: where it fitted the
    wrench to exactly three joints (``last_candidate`` = 3) and found a point, its force F at
    its point p solves those three equations exactly, so n_i = (p − j_i) × F − τ_i for
    joints 1–3 (τ the noise-free external torque). Their spread against σ checks the
    perception's noise model without the estimator in the way."""
    pick = np.array([r["last_candidate"] == 3 and r["status"] == FOUND for r in rows])
    if sigma <= 0 or pick.sum() < 2:
        return None
    origin, _ = arm.frames(q[pick])
    d = live_p[pick][:, None, :] - origin[:, :3, :]
    f = live_f[pick][:, None, :]
    n = d[..., 0] * f[..., 1] - d[..., 1] * f[..., 0] - tau_true[pick][:, :3]
    x = n.ravel()
    boot = np.array([x[rng.integers(0, len(x), len(x))].std() for _ in range(200)])
    z = (x - x.mean()) / x.std()
    return {"n": int(len(x)), "instants": int(pick.sum()), "mean": float(x.mean()),
            "std_over_sigma": float(x.std() / sigma),
            "std_over_sigma_bootstrap_ci95": [float(np.quantile(boot, 0.025) / sigma), float(np.quantile(boot, 0.975) / sigma)],
            "std_over_sigma_by_joint": [float(v / sigma) for v in n.std(0)],
            "skewness": float((z ** 3).mean()), "excess_kurtosis": float((z ** 4).mean() - 3)}


def check(run_dir: str, sigma: float | None, seed: int, urdf: str | None, spacing: float) -> dict:
    # The URDF named by the run's launch file, relative to launch/contact/ (push.toml's place).
    with recording.open(os.path.join(run_dir, "record.mcap")) as rec:
        params = launch_params(rec)
    urdf = urdf or os.path.join(ROOT, "launch", "contact", params["urdf"])
    probe = Arm(urdf, params["radius"])
    data = read(run_dir, probe.joints)
    if not data["pushes"] or not data["estimates"]:
        raise SystemExit(f"{run_dir}: the recording has no pushes or no estimates")
    if params["dynamics"]:
        raise SystemExit(f"{run_dir}: the perception subtracted the arm's dynamics; this compares the static method")
    # The robot's mounting in the plane: its root link's pose, fixed.
    base = data["poses"][0][1].get("base", (0.0, 0.0, 0.0))
    arm = Arm(urdf, params["radius"], base=base)
    est = Estimator(arm, params["mu"], spacing=spacing)
    sigma = params["sigma"] if sigma is None else sigma
    rows = scored(data, params["settle_s"])
    if not rows:
        raise SystemExit(f"{run_dir}: no estimate was scored")
    q = np.array([data["states"][r["state"]][1] for r in rows])
    tau_true = -np.array([data["states"][r["state"]][2] for r in rows])
    noise_rng = np.random.default_rng(seed)
    tau = tau_true + (noise_rng.normal(0.0, sigma, tau_true.shape) if sigma > 0 else 0.0)
    out = {k: [] for k in ("force", "point", "link", "residual")}
    for i in range(0, len(rows), CHUNK):
        e = est.estimate(q[i:i + CHUNK], tau[i:i + CHUNK])
        for k in out:
            out[k].append(e[k])
    ind = {k: np.concatenate(v) for k, v in out.items()}
    true_f = np.array([r["true_force"] for r in rows])
    true_p = np.array([r["true_point"] for r in rows])
    live_f = np.array([r["force"] for r in rows])
    live_p = np.array([r["point"] for r in rows])
    live_found = np.array([r["status"] == FOUND for r in rows])
    ind_found = np.isfinite(ind["residual"])
    # Forward kinematics from the joint angles against the links' true poses at the same
    # stamp (the frames the truth is carried by): a check of the geometry read from the URDF.
    origin, _ = arm.frames(q)
    pose_t = [t for t, _ in data["poses"]]
    fk = 0.0
    for n in range(0, len(rows), max(1, len(rows) // 50)):
        t_state = data["states"][rows[n]["state"]][0]
        links = data["poses"][np.searchsorted(pose_t, t_state, "right") - 1][1]
        for k in range(arm.n):
            x, y, _ = links[arm.links[k]]
            fk = max(fk, math.hypot(origin[n, k, 0] - x, origin[n, k, 1] - y))
    stats_rng = np.random.default_rng(0)
    a = errors(ind["force"], ind["point"], true_f, true_p, ind_found)
    b = errors(live_f, live_p, true_f, true_p, live_found)
    c = errors(live_f, live_p, ind["force"], ind["point"], live_found & ind_found)
    # The live point error counts only the instants with a point from the line (status 1);
    # the independent one's, over the same instants, for a like-for-like comparison.
    a_matched = dict(a, point_error_mm=errors(ind["force"], ind["point"], true_f, true_p, ind_found & live_found)["point_error_mm"])
    links = np.array([arm.links[k] if k >= 0 else "" for k in ind["link"]])
    beyond = np.array([r["last_candidate"] > arm.links.index(r["true_link"]) + 1 for r in rows])
    live_err = np.linalg.norm(live_f - true_f, axis=1)
    true_links = np.array([r["true_link"] for r in rows])
    summary = {
        "run_dir": run_dir, "seed": data["seed"], "sigma": sigma, "noise_seed": seed, "settle_s": params["settle_s"],
        "mu": params["mu"], "link_radius": params["radius"], "spacing_m": spacing,
        "pushes": len(data["pushes"]), "scored": len(rows),
        "fk_vs_link_states_max_m": fk,
        "independent_vs_truth": {k: describe(v, stats_rng) for k, v in a.items()},
        "live_vs_truth": {k: describe(v, stats_rng) for k, v in b.items()},
        "live_vs_independent": {k: describe(v, stats_rng) for k, v in c.items()},
        "independent_point_error_mm_where_live_found": describe(a_matched["point_error_mm"], stats_rng),
        "live_minus_independent_mean_error": {k: mean_difference(b[k], a_matched[k], stats_rng) for k in a},
        "independent_no_point_pct": 100.0 * float((~ind_found).mean()),
        "independent_wrong_link_pct": 100.0 * float((links[ind_found] != true_links[ind_found]).mean()) if ind_found.any() else None,
        "live_no_solution_pct": 100.0 * float((~live_found).mean()),
        "independent_residual_n_m": describe(ind["residual"][ind_found], stats_rng),
        # The live fit on more joints than the pushed link's (its thresholds let a wrong
        # model through): how often, and its force error then and otherwise.
        "live_beyond_pushed_link_pct": 100.0 * float(beyond.mean()),
        "live_force_error_n_beyond_pushed_link": describe(live_err[beyond & np.isfinite(live_err)], stats_rng),
        "live_force_error_n_up_to_pushed_link": describe(live_err[~beyond & np.isfinite(live_err)], stats_rng),
        "live_noise": live_noise(rows, q, tau_true, live_f, live_p, arm, sigma, stats_rng),
    }
    report = os.path.join(run_dir, "report.json")
    if os.path.exists(report):
        with open(report) as f:
            live = json.load(f).get("contact", {}).get("live", {})
        summary["report"] = {k: {"n": (live.get(k) or {}).get("n"), "mean": (live.get(k) or {}).get("mean")}
                             for k in ("force_error_n", "point_error_mm", "direction_error_deg")}
        summary["report"]["scored"] = live.get("scored")
    return summary


def fmt(x) -> str:
    if x is None:
        return "–"
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def markdown(s: dict) -> str:
    head = (f"σ = {s['sigma']} N·m, {s['pushes']} pushes, {s['scored']} scored estimates\n\n"
            "| | force error (N) mean / median / max | point error (mm) mean / median / max "
            "| direction error (°) mean / median / max |\n|---|---|---|---|\n")
    lines = []
    for name, key in (("(a) independent vs truth", "independent_vs_truth"), ("(b) live vs truth", "live_vs_truth"),
                      ("(c) live vs independent", "live_vs_independent")):
        cells = []
        for m in ("force_error_n", "point_error_mm", "direction_error_deg"):
            d = s[key][m]
            cells.append("–" if d is None else f"{fmt(d['mean'])} / {fmt(d['median'])} / {fmt(d['max'])}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return head + "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--sigma", type=float, help="torque noise σ, N·m (default: the run's estimator.torque_sigma)")
    ap.add_argument("--seed", type=int, default=1, help="the independent noise's seed (numpy default_rng)")
    ap.add_argument("--urdf", help="the arm's URDF (default: the run's, from launch/contact/)")
    ap.add_argument("--spacing", type=float, default=0.004, help="coarse sampling of the contours, m")
    ap.add_argument("--json", help="also write the JSON summary to this file")
    args = ap.parse_args()
    if args.sigma is not None and not 0 <= args.sigma <= 20:
        ap.error("--sigma must be within 0 to 20 N·m")
    s = check(args.run_dir, args.sigma, args.seed, args.urdf, args.spacing)
    text = json.dumps(s, indent=1)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")
    print(text)
    print()
    print(markdown(s))


if __name__ == "__main__":
    main()
