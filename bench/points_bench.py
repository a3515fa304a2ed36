#!/usr/bin/env python3
"""Points a second, end to end (issue 51: at least 2M points/s at 0.5, 1 and
2 Hz): `weaver query DB locate|material --points FILE --format csv|text` of
a million random points in the mesh's box, each a fresh process timed whole
(process start, reading the points, answering, writing the rows to a file),
at the default --threads and --memory, page cache warm (a run first, not
counted).  With --base, the same commands by another build (32f41e8's),
alternating, and the ratio of their times.

  points_bench.py [--weaver build/release/weaver] [--base OTHER_WEAVER]
                  [--work /tmp/points-bench] [--freqs 0.5,1,2] [--repeat 5]
                  [--points 1000000]

The meshes are built once into --work by --weaver (`weaver mesh --model basin
--freq F --memory 1G`) and kept for the next run.  Prints one JSON document,
then a table."""
import argparse
import json
import os
import random
import statistics
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(cmd, out):
    with open(out, "wb") as sink:
        t0 = time.monotonic()
        subprocess.run(cmd, check=True, stdout=sink, stderr=subprocess.DEVNULL)
        return time.monotonic() - t0


def mesh_box(weaver, db):
    """The far corner of the box the leaves span, in metres: the last leaf
    in key order holds it (a box domain)."""
    tables = json.loads(subprocess.run([weaver, "stat", db, "--json"], check=True,
                                       capture_output=True, text=True).stdout)["tables"]
    last = [t["records"] for t in tables if t["table"] == "octants"][0] - 1
    e = json.loads(subprocess.run([weaver, "query", db, "element", str(last), "--units", "m",
                                   "--format", "json"], check=True, capture_output=True,
                                  text=True).stdout)
    return [e[a] + e["edge"] for a in "xyz"]


def write_points(path, n, lo, hi, seed):
    rng = random.Random(seed)
    with open(path, "w") as f:
        for _ in range(n):
            f.write("%.2f %.2f %.2f\n" % tuple(rng.uniform(lo[a], hi[a]) for a in range(3)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--weaver", default=os.path.join(HERE, "..", "build", "release", "weaver"))
    ap.add_argument("--base", default="")
    ap.add_argument("--work", default="/tmp/points-bench")
    ap.add_argument("--freqs", default="0.5,1,2")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--points", type=int, default=1000000)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    builds = {"this": a.weaver}
    if a.base:
        builds["base"] = a.base
    result = {"machine": os.uname().nodename, "points": a.points, "runs": []}
    for f in [float(x) for x in a.freqs.split(",") if x]:
        db = os.path.join(a.work, f"basin-{f}.db")
        if not os.path.isdir(db):
            subprocess.run([a.weaver, "mesh", db, "--model", "basin", "--freq", str(f),
                            "--memory", "1G", "--quiet"], check=True)
        domain = mesh_box(a.weaver, db)
        points = os.path.join(a.work, f"points-{f}.txt")
        if not os.path.exists(points):
            write_points(points, a.points, [0, 0, 0], domain, 51)
        for query in ("locate", "material"):
            for fmt in ("csv", "text"):
                cmds = {b: [w, "query", db, query, "--points", points, "--units", "m",
                            "--format", fmt] for b, w in builds.items()}
                out = os.path.join(a.work, "rows.out")
                for w in cmds.values():
                    timed(w, out)  # the page cache warm
                times = {b: [] for b in builds}
                for _ in range(a.repeat):
                    for b, cmd in cmds.items():
                        times[b].append(timed(cmd, out))
                row = {"freq": f, "query": query, "format": fmt}
                for b, t in times.items():
                    row[b] = {"median_s": statistics.median(t), "runs_s": t,
                              "points_per_s": a.points / statistics.median(t)}
                if "base" in times:
                    row["ratio"] = statistics.median(
                        [x / y for x, y in zip(times["this"], times["base"])])
                result["runs"].append(row)
                print(json.dumps(row), flush=True)
    print(json.dumps(result, indent=2))
    print()
    print(f"medians of {a.repeat} runs, {a.points} random points, page cache warm")
    head = f"{'freq':>5} {'query':>9} {'format':>6} {'this M/s':>9} {'this s':>7}"
    if a.base:
        head += f" {'base M/s':>9} {'base s':>7} {'this/base':>10}"
    print(head)
    for r in result["runs"]:
        line = (f"{r['freq']:>5} {r['query']:>9} {r['format']:>6} "
                f"{r['this']['points_per_s'] / 1e6:>9.2f} {r['this']['median_s']:>7.3f}")
        if a.base:
            line += (f" {r['base']['points_per_s'] / 1e6:>9.2f} {r['base']['median_s']:>7.3f}"
                     f" {r['ratio']:>10.2f}")
        print(line)


if __name__ == "__main__":
    main()
