"""CPU used by a process and all its descendants, from /proc/<pid>/stat (utime + stime).

    python3 python/tools/cpu_of_tree.py PID SECONDS
        the tree's and the root's CPU over a span, as a percentage of one core
        (docs/benchmarks.md, "Idle groups");
    python3 python/tools/cpu_of_tree.py run COMMAND...
        runs COMMAND and prints the CPU seconds each program of its tree used, summed by
        program name, and the root's threads by name (docs/benchmarks.md, "Why the lockstep
        targets do not fit on two cores").

`run` samples /proc every half second and keeps each process's last reading, so a process
that lived under half a second, or the last half second of one, can be missed; the root
(the launcher) is read until it exits.
"""
import collections
import os
import subprocess
import sys
import time

TICK = os.sysconf("SC_CLK_TCK")


def stat(path):
    """(name in the kernel, parent pid, CPU seconds) of a /proc/.../stat file."""
    s = open(path).read()
    fields = s.rsplit(")", 1)[1].split()
    return s[s.index("(") + 1 : s.rindex(")")], int(fields[1]), (int(fields[11]) + int(fields[12])) / TICK


def processes():
    """{pid: (parent pid, CPU seconds)} of every process readable now."""
    out = {}
    for p in os.listdir("/proc"):
        if p.isdigit():
            try:
                _, ppid, cpu = stat(f"/proc/{p}/stat")
                out[int(p)] = (ppid, cpu)
            except (OSError, ValueError, IndexError):
                pass
    return out


def tree(root, parents):
    """root and its descendants, from {pid: parent pid}."""
    kids = collections.defaultdict(list)
    for pid, ppid in parents.items():
        kids[ppid].append(pid)
    out = [root]
    i = 0
    while i < len(out):
        out += kids.get(out[i], [])
        i += 1
    return out


def span(root, seconds):
    def cpu_now():
        procs = processes()
        pids = tree(root, {p: v[0] for p, v in procs.items()})
        return sum(procs[p][1] for p in pids if p in procs), procs.get(root, (0, 0.0))[1], len(pids)

    a, root_a, _ = cpu_now()
    time.sleep(seconds)
    b, root_b, n = cpu_now()
    print(f"{n} processes: {100 * (b - a) / seconds:.2f} % of one core in total, "
          f"launcher {100 * (root_b - root_a) / seconds:.2f} %")


def run(command):
    start = time.time()
    child = subprocess.Popen(command)
    seen = {}  # pid -> [program, parent pid, CPU seconds]
    threads = {}
    while child.poll() is None:
        for pid, (ppid, cpu) in processes().items():
            if pid not in seen:
                try:
                    program = os.path.basename(open(f"/proc/{pid}/cmdline").read().split("\0")[0])
                except OSError:
                    continue
                seen[pid] = [program, ppid, cpu]
            seen[pid][1:] = [ppid, cpu]
        try:
            for t in os.listdir(f"/proc/{child.pid}/task"):
                name, _, cpu = stat(f"/proc/{child.pid}/task/{t}/stat")
                threads[t] = (name, cpu)
        except OSError:
            pass
        time.sleep(0.5)
    wall = time.time() - start
    by_program = collections.Counter()
    for pid in tree(child.pid, {p: v[1] for p, v in seen.items()}):
        if pid in seen:
            by_program[seen[pid][0]] += seen[pid][2]
    print(f"wall {wall:.1f} s, CPU {sum(by_program.values()):.2f} s")
    for program, cpu in by_program.most_common():
        print(f"  {program:28s} {cpu:8.2f}")
    by_thread = collections.Counter()
    for name, cpu in threads.values():
        by_thread[name] += cpu
    print("  root's threads: " + ", ".join(f"{n} {c:.2f}" for n, c in by_thread.most_common()))
    return child.returncode


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "run":
        sys.exit(run(sys.argv[2:]))
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    span(int(sys.argv[1]), float(sys.argv[2]))
