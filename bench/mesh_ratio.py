#!/usr/bin/env python3
"""The paper's mesh by this build against another (issue 51: `weaver mesh
--model basin --freq 2 --memory 1G` in at most 0.5x 32f41e8's time for the
stages 32f41e8 runs, construct and extract, and at 1 Hz at most 0.6x; the
octant and node tables byte for byte the same).  Each `weaver mesh` is a
fresh process into a fresh database, the two builds alternating, medians of
--repeat.  The stage times are those each stage's line prints; the boundary
table, which 32f41e8 does not build, is timed apart and left out of the
ratio.  The octant and node tables' md5s must agree between the builds.

  mesh_ratio.py --base OTHER_WEAVER [--weaver build/release/weaver]
                [--work /tmp/mesh-ratio] [--freqs 1,2] [--repeat 3]
                [--memory 1G]

Prints one JSON document, then a table."""
import argparse
import glob
import hashlib
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
STAGE = re.compile(r"^(construct|balance|extract|boundary)\s+\d+ \w+\s+([0-9.]+)s", re.M)


def md5_of(path):
    h = hashlib.md5()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def table_md5(db, table):
    files = glob.glob(os.path.join(db, table + "-*.bt"))
    return md5_of(files[0]) if len(files) == 1 else "missing"


def mesh_once(weaver, db, freq, memory):
    """Seconds of the whole process and of each stage, and the tables' md5s."""
    shutil.rmtree(db, ignore_errors=True)
    t0 = time.monotonic()
    out = subprocess.run([weaver, "mesh", db, "--model", "basin", "--freq", str(freq),
                          "--memory", memory], check=True, capture_output=True, text=True)
    run = {"seconds": time.monotonic() - t0}
    for stage, seconds in STAGE.findall(out.stdout + out.stderr):
        run[stage] = float(seconds)
    run["stages"] = run.get("construct", 0) + run.get("balance", 0) + run.get("extract", 0)
    run["octants_md5"] = table_md5(db, "octants")
    run["nodes_md5"] = table_md5(db, "nodes")
    return run


def median_of(runs, key):
    values = [r[key] for r in runs if key in r]
    return statistics.median(values) if values else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--weaver", default=os.path.join(HERE, "..", "build", "release", "weaver"))
    ap.add_argument("--base", required=True, help="the other build's weaver (32f41e8's)")
    ap.add_argument("--work", default="/tmp/mesh-ratio")
    ap.add_argument("--freqs", default="1,2")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--memory", default="1G")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    builds = {"this": a.weaver, "base": a.base}
    result = {"machine": os.uname().nodename, "memory": a.memory, "freqs": []}
    for freq in [float(x) for x in a.freqs.split(",") if x]:
        runs = {b: [] for b in builds}
        for r in range(a.repeat):
            order = list(builds) if r % 2 == 0 else list(reversed(builds))
            for b in order:
                db = os.path.join(a.work, f"{b}.db")
                runs[b].append(mesh_once(builds[b], db, freq, a.memory))
                print(json.dumps({"freq": freq, "build": b, **runs[b][-1]}), file=sys.stderr)
        # The ratio pair by pair (the runs alternate), then the median.
        pairs = [t["stages"] / b["stages"] for t, b in zip(runs["this"], runs["base"])]
        same = all(t["octants_md5"] == b["octants_md5"] and t["nodes_md5"] == b["nodes_md5"]
                   for t in runs["this"] for b in runs["base"])
        entry = {"freq": freq, "ratio": statistics.median(pairs), "pair_ratios": pairs,
                 "tables_same": same, "runs": runs}
        for b in builds:
            entry[b] = {k: median_of(runs[b], k) for k in
                        ("seconds", "construct", "balance", "extract", "boundary", "stages")}
        result["freqs"].append(entry)
        for b in builds:
            shutil.rmtree(os.path.join(a.work, f"{b}.db"), ignore_errors=True)
    print(json.dumps(result, indent=2))
    print()
    print(" freq  build  construct s  extract s  stages s  boundary s  process s  this/base  tables")
    for e in result["freqs"]:
        for b in builds:
            m = e[b]
            cell = lambda v: f"{v:10.2f}" if v is not None else "         -"
            tail = f"  {e['ratio']:9.3f}  {'same' if e['tables_same'] else 'DIFFER'}" \
                if b == "this" else ""
            print(f"{e['freq']:5.1f}  {b:5}  {cell(m['construct'])}  {cell(m['extract'])}"
                  f"  {cell(m['stages'])}  {cell(m['boundary'])}  {cell(m['seconds'])}{tail}")
    return 0 if all(e["tables_same"] for e in result["freqs"]) else 1


if __name__ == "__main__":
    sys.exit(main())
