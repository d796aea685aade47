"""Caravan's own CPU per simulated tick of a lockstep run (docs/benchmarks.md, "Efficiency").

    python3 python/tools/overhead.py [--bin DIR] [--label L] -- caravan launch FILE [ARGS...]

Runs the command (with `--runs-dir` set to a directory of its own, and DIR first on PATH so
that a copy of another build's binaries can be measured side by side with this one), samples
every process of its tree from /proc twice a second, and prints one JSON line:

- `ticks`: simulated time over the tick (`--tick-ms`, 10 by default); every figure is per
  tick; `advances` and `steps`: the scheduler's (the report's `run.schedule`);
- `cpu_ms_per_tick`: CPU of the launcher and every process of the group (report plugins,
  which run after the simulation, left out);
- `compute_ms_per_tick`: the nodes' CPU inside their step functions (the report's
  `compute_cpu_mean_ms` × `steps`, summed over nodes; that mean is of the steps whose CPU
  clock a node read, one in eight after its first 64); `physics_ms_per_tick` the physics
  process's share of it;
- `overhead`: the first over the second (1 = nothing but the nodes' work);
- `launcher_ms_per_tick` by thread name (`recording write`: JSON, views, compression;
  `driver`: the scheduler and the recorder's taps; `main`: supervision, and after the run the
  report, which reads the recording back);
- `run_cpu_ms_per_tick` and `run_overhead`: the same without the launcher's main thread, i.e.
  what the group costs while it runs;
- `sleeps_per_tick`: voluntary context switches of every thread of the tree (a thread going
  to sleep, to be woken later: the wake-ups), and `preemptions_per_tick` the others;
- `real_time_factor` and `wall_s`.

Processes are read until they exit, at most half a second late, so the last half second of a
process can be missed (CPU and switches a little low, never high).
"""
import argparse
import collections
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from cpu_of_tree import TICK, processes, tree  # noqa: E402


def task_readings(pid):
    """{tid: (thread name, CPU seconds, context switches)} of a process's live threads."""
    out = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tids:
        try:
            stat = open(f"/proc/{pid}/task/{tid}/stat").read()
            status = open(f"/proc/{pid}/task/{tid}/status").read()
        except OSError:
            continue
        name = stat[stat.index("(") + 1 : stat.rindex(")")]
        fields = stat.rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / TICK
        count = lambda key: sum(  # noqa: E731
            int(line.split()[1]) for line in status.splitlines() if line.startswith(key)
        )
        out[tid] = (name, cpu, count("voluntary_ctxt_switches"), count("nonvoluntary_ctxt_switches"))
    return out


def measure(command, bin_dir=None, tick_ms=10.0):
    env = dict(os.environ)
    if bin_dir:
        env["PATH"] = os.path.abspath(bin_dir) + os.pathsep + env["PATH"]
    runs = tempfile.mkdtemp(prefix="overhead-")
    start = time.time()
    child = subprocess.Popen(command + ["--runs-dir", runs], env=env)
    program = {}  # pid -> program name
    threads = {}  # (pid, tid) -> (thread name, CPU s, voluntary and other switches)
    while child.poll() is None:
        procs = processes()
        for pid in tree(child.pid, {p: v[0] for p, v in procs.items()}):
            if pid not in program:
                try:
                    cmd = open(f"/proc/{pid}/cmdline").read().split("\0")[0]
                except OSError:
                    continue
                program[pid] = os.path.basename(cmd)
            for tid, reading in task_readings(pid).items():
                threads[(pid, tid)] = reading
        time.sleep(0.5)
    wall = time.time() - start
    if child.returncode != 0:
        sys.exit(f"the run failed (exit {child.returncode})")
    report_path = next(pathlib.Path(runs).glob("*/report.json"))
    report = json.loads(report_path.read_text())
    advances = report["run"]["schedule"]["advances"]
    ticks = round(report["run"]["sim_time_s"] * 1000 / tick_ms)
    compute = physics = 0.0
    for node in report["nodes"]:
        ms = (node.get("compute_cpu_mean_ms") or 0.0) * (node.get("steps") or 0)
        compute += ms
        if node["name"] == "physics":
            physics += ms
    by_program = collections.Counter()
    sleeps_by = collections.Counter()
    launcher = collections.Counter()
    sleeps = preempted = 0
    after_run = 0.0
    for (pid, tid), (name, cpu, voluntary, other) in threads.items():
        # Report plugins run after the simulation: not part of a tick.
        if program.get(pid, "?").endswith("-report"):
            continue
        by_program[program.get(pid, "?")] += cpu
        sleeps_by[program.get(pid, "?") if pid != child.pid else "launcher: " + name] += voluntary
        sleeps += voluntary
        preempted += other
        if pid == child.pid:
            # The main thread supervises (next to nothing while the group runs) and, after
            # the run, writes the report, reading the whole recording back.
            if int(tid) == pid:
                name = "main"
                after_run += cpu
            launcher[name] += cpu
    total = sum(by_program.values())
    per_tick = lambda seconds: round(1000 * seconds / ticks, 4)  # noqa: E731
    return {
        "ticks": ticks,
        "advances": advances,
        "steps": report["run"]["schedule"]["steps"],
        "wall_s": round(wall, 2),
        "real_time_factor": round(report["run"]["real_time_factor"], 2),
        "cpu_ms_per_tick": per_tick(total),
        "compute_ms_per_tick": round(compute / ticks, 4),
        "physics_ms_per_tick": round(physics / ticks, 4),
        "overhead": round(total * 1000 / compute, 3) if compute else None,
        "run_cpu_ms_per_tick": per_tick(total - after_run),
        "run_overhead": round((total - after_run) * 1000 / compute, 3) if compute else None,
        "launcher_ms_per_tick": {n: per_tick(c) for n, c in launcher.most_common()},
        "sleeps_per_tick": round(sleeps / ticks, 2),
        "preemptions_per_tick": round(preempted / ticks, 2),
        "programs_ms_per_tick": {p: per_tick(c) for p, c in by_program.most_common()},
        "sleeps_per_tick_by": {p: round(n / ticks, 2) for p, n in sleeps_by.most_common()},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", help="a directory of binaries to put first on PATH")
    parser.add_argument("--label", default="", help="a name for the line printed")
    parser.add_argument("--tick-ms", type=float, default=10.0, help="the group's tick")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command given")
    result = measure(command, args.bin, args.tick_ms)
    result = {"label": args.label, **result}
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
