"""CPU used by a process and all its descendants over a span, from /proc/<pid>/stat.

    python3 python/tools/cpu_of_tree.py PID SECONDS

Prints the tree's and the root's CPU time as a percentage of one core (docs/benchmarks.md,
"Idle groups").
"""
import os, sys, time
def tree(root):
    kids={}
    for p in os.listdir('/proc'):
        if p.isdigit():
            try:
                ppid=int(open(f'/proc/{p}/stat').read().rsplit(')',1)[1].split()[1])
                kids.setdefault(ppid,[]).append(int(p))
            except Exception: pass
    out=[root]; i=0
    while i<len(out):
        out+=kids.get(out[i],[]); i+=1
    return out
def cpu(pids):
    t=0
    for p in pids:
        try:
            f=open(f'/proc/{p}/stat').read().rsplit(')',1)[1].split()
            t+=int(f[11])+int(f[12])
        except Exception: pass
    return t/os.sysconf('SC_CLK_TCK')
root=int(sys.argv[1]); span=float(sys.argv[2])
pids=tree(root); a=cpu(pids); launcher_a=cpu([root]); time.sleep(span); b=cpu(pids); launcher_b=cpu([root])
print(f"{len(pids)} processes: {100*(b-a)/span:.2f} % of one core in total, launcher {100*(launcher_b-launcher_a)/span:.2f} %")
