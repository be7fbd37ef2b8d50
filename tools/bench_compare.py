#!/usr/bin/env python3
"""Side-by-side timing of two gseg builds (issue #21): `gseg bench` of each, alternately, same scans
and options, then per build the median / p90 / min ms per scan, the per-step medians, the peak
memory, and the ratio of the medians.

    tools/bench_compare.py NEW_GSEG OTHER_GSEG [--rounds 5] -- BENCH_ARGS...

e.g. tools/bench_compare.py build/bin/gseg /work/ref/build/bin/gseg --rounds 5 -- \\
         ../shared/data/semantickitti/sequences/00/velodyne/*.bin -c config/kitti_hdl64.yaml --repeat 10

Rounds alternate which build runs first (A B, B A, ...), so a slow spell of the machine hits both.
Each build is named by its `--version` and the commit of the source tree its build folder was
configured from (CMakeCache.txt's CMAKE_HOME_DIRECTORY; "+changes" if that tree has uncommitted
changes, Markdown files aside). Per build: "median" is the median over rounds of each run's median (bench's "all scans"
line), "p90" likewise, "min" the minimum over rounds; steps are medians over rounds of each run's
step medians; peak memory the largest of the runs. Exit code: 0 done, 1 a run failed (its output
is shown), 2 bad usage.
"""
import os
import re
import statistics
import subprocess
import sys

STEPS = ["grid", "classification", "plane fit", "expansion", "refinement", "phase total"]


def usage(msg):
    print(f"bench_compare.py: {msg}\nusage: tools/bench_compare.py NEW_GSEG OTHER_GSEG [--rounds N] -- BENCH_ARGS...",
          file=sys.stderr)
    sys.exit(2)


def name_of(gseg):
    try:
        version = subprocess.run([gseg, "--version"], capture_output=True, text=True, timeout=30).stdout.strip()
    except OSError as e:
        usage(f"{gseg}: cannot run: {e}")
    commit = "commit unknown"
    cache = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(gseg))), "CMakeCache.txt")
    if os.path.exists(cache):
        src = next((l.split("=", 1)[1].strip() for l in open(cache) if l.startswith("CMAKE_HOME_DIRECTORY")), None)
        if src:
            rev = subprocess.run(["git", "-C", src, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
            dirty = subprocess.run(["git", "-C", src, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                    ":(exclude)*.md"], capture_output=True, text=True).stdout.strip()
            if rev.returncode == 0:
                commit = f"commit {rev.stdout.strip()}{'+changes' if dirty else ''} ({src})"
    return f"{version}, {commit}"


def run_bench(gseg, args):
    r = subprocess.run([gseg, "bench"] + args, capture_output=True, text=True)
    out = r.stdout + r.stderr
    if r.returncode != 0:
        print(f"bench_compare.py: {gseg} bench failed (exit {r.returncode}):\n{out}", file=sys.stderr)
        sys.exit(1)
    m = re.search(r"^all scans\s+\d+\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)", out, re.M)
    mem = re.search(r"peak memory[^:]*:\s*([\d.]+) MB", out)
    if not m or not mem:
        print(f"bench_compare.py: cannot read {gseg} bench's output:\n{out}", file=sys.stderr)
        sys.exit(1)
    steps = {}
    for s in STEPS:
        sm = re.search(rf"^{s}\s+([\d.]+)\s+([\d.]+)", out, re.M)
        if sm:
            steps[s] = (float(sm.group(1)), float(sm.group(2)))
    return {"median": float(m.group(1)), "p90": float(m.group(2)), "min": float(m.group(3)),
            "mem": float(mem.group(1)), "steps": steps}


def main():
    argv = sys.argv[1:]
    if "--" not in argv:
        usage("give the bench arguments after --")
    cut = argv.index("--")
    mine, bench_args = argv[:cut], argv[cut + 1:]
    rounds = 5
    if "--rounds" in mine:
        i = mine.index("--rounds")
        try:
            rounds = int(mine[i + 1])
        except (IndexError, ValueError):
            usage("--rounds takes a number")
        del mine[i:i + 2]
    if len(mine) != 2 or rounds < 1:
        usage("give two gseg executables and --rounds >= 1")
    builds = [{"gseg": g, "name": name_of(g), "runs": []} for g in mine]
    scans = [a for a in bench_args if os.path.isfile(a) and a.endswith((".bin", ".ply", ".rawlog"))]
    others = [a for a in bench_args if a not in scans]
    print(f"bench_compare: {rounds} round(s) of `gseg bench` on {len(scans)} scan(s) ({' '.join(others)}), "
          "alternating")
    for i, b in enumerate(builds):
        print(f"  build {'AB'[i]}: {b['gseg']}: {b['name']}")
    for r in range(rounds):
        order = builds if r % 2 == 0 else builds[::-1]
        for b in order:
            b["runs"].append(run_bench(b["gseg"], bench_args))
        print(f"round {r + 1}: " + ", ".join(f"{'AB'[builds.index(b)]} {b['runs'][-1]['median']:.2f} ms" for b in order),
              flush=True)
    print(f"\n{'build':<6} {'median ms':>10} {'p90 ms':>10} {'min ms':>10} {'peak MB':>9}")
    summary = []
    for i, b in enumerate(builds):
        med = statistics.median(x["median"] for x in b["runs"])
        p90 = statistics.median(x["p90"] for x in b["runs"])
        mn = min(x["min"] for x in b["runs"])
        mem = max(x["mem"] for x in b["runs"])
        summary.append(med)
        print(f"{'AB'[i]:<6} {med:>10.2f} {p90:>10.2f} {mn:>10.2f} {mem:>9.1f}")
    print(f"\n{'step (median ms)':<18}" + "".join(f"{'AB'[i] + ' phase ' + p:>13}" for i in range(2) for p in ("I", "II")))
    for s in STEPS:
        cols = []
        for b in builds:
            vals = [x["steps"][s] for x in b["runs"] if s in x["steps"]]
            cols += [statistics.median(v[0] for v in vals), statistics.median(v[1] for v in vals)] if vals else [float("nan")] * 2
        print(f"{s:<18}" + "".join(f"{c:>13.3f}" for c in cols))
    print(f"\nratio A / B of the median ms per scan: {summary[0] / summary[1]:.3f}")


if __name__ == "__main__":
    main()
