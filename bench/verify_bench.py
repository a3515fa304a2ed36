#!/usr/bin/env python3
"""weaver verify against weaver mesh of the same mesh (issue 51: verify at
most 1.0x the mesh's time, same build, same --memory): the basin meshed at
each --freqs, then verified, each a fresh process timed whole, alternating,
medians of --repeat runs.  With --independent, `verify --independent` (every
node classified from the leaves around it) is timed beside.  With --cold,
each run also times mesh and verify from a cold page cache: before the mesh
the previous database is gone and the weaver binary is dropped from the
cache; before the verify every file of the database is written back and
dropped (posix_fadvise DONTNEED, checked with fincore where it is).

  verify_bench.py [--weaver build/release/weaver] [--work /tmp/verify-bench]
                  [--freqs 1,2] [--repeat 3] [--memory 1G] [--independent] [--cold]

Prints one JSON document, then a table."""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(cmd):
    t0 = time.monotonic()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - t0


def evict(path):
    """Writes back and drops from the page cache every file under path (a
    file or a directory); returns the bytes still cached after, by fincore
    (0 when fincore is missing)."""
    files = [path] if os.path.isfile(path) else [
        os.path.join(root, f) for root, _, names in os.walk(path) for f in names]
    for f in files:
        fd = os.open(f, os.O_RDONLY)
        try:
            os.fsync(fd)
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        finally:
            os.close(fd)
    if not shutil.which("fincore") or not files:
        return 0
    out = subprocess.run(["fincore", "--bytes", "--noheadings", "--output", "RES", *files],
                         capture_output=True, text=True).stdout
    return sum(int(x) for x in out.split())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--weaver", default=os.path.join(HERE, "..", "build", "release", "weaver"))
    ap.add_argument("--work", default="/tmp/verify-bench")
    ap.add_argument("--freqs", default="1,2")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--memory", default="1G")
    ap.add_argument("--independent", action="store_true")
    ap.add_argument("--cold", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    result = {"machine": os.uname().nodename, "memory": a.memory, "freqs": {}}
    for f in [float(x) for x in a.freqs.split(",") if x]:
        db = os.path.join(a.work, f"basin-{f}")
        runs = {"mesh": [], "verify": [], "independent": [], "mesh_cold": [], "verify_cold": []}
        left_cached = []
        for _ in range(a.repeat):
            shutil.rmtree(db, ignore_errors=True)
            runs["mesh"].append(timed([a.weaver, "mesh", db, "--model", "basin", "--freq", str(f),
                                       "--memory", a.memory, "--quiet"]))
            runs["verify"].append(timed([a.weaver, "verify", db, "--memory", a.memory,
                                         "--quiet"]))
            if a.cold:
                shutil.rmtree(db, ignore_errors=True)
                evict(os.path.realpath(a.weaver))
                runs["mesh_cold"].append(timed([a.weaver, "mesh", db, "--model", "basin", "--freq",
                                                str(f), "--memory", a.memory, "--quiet"]))
                left_cached.append(evict(db))
                runs["verify_cold"].append(timed([a.weaver, "verify", db, "--memory", a.memory,
                                                  "--quiet"]))
            if a.independent:
                runs["independent"].append(timed([a.weaver, "verify", db, "--independent",
                                                  "--memory", a.memory, "--quiet"]))
        row = {k: {"median_s": statistics.median(v), "runs_s": v} for k, v in runs.items() if v}
        row["ratio"] = row["verify"]["median_s"] / row["mesh"]["median_s"]
        if a.cold:
            row["cold_ratio"] = row["verify_cold"]["median_s"] / row["mesh_cold"]["median_s"]
            row["cached_bytes_after_evict"] = left_cached
        result["freqs"][str(f)] = row
        shutil.rmtree(db, ignore_errors=True)
    print(json.dumps(result, indent=2))
    print()
    print(f"{'freq':>5} {'cache':>5} {'mesh s':>8} {'verify s':>9} {'verify/mesh':>12} "
          f"{'--independent s':>16}")
    for f, row in result["freqs"].items():
        ind = f"{row['independent']['median_s']:.1f}" if "independent" in row else "-"
        print(f"{f:>5} {'warm':>5} {row['mesh']['median_s']:>8.1f} "
              f"{row['verify']['median_s']:>9.1f} {row['ratio']:>12.2f} {ind:>16}")
        if "cold_ratio" in row:
            print(f"{f:>5} {'cold':>5} {row['mesh_cold']['median_s']:>8.1f} "
                  f"{row['verify_cold']['median_s']:>9.1f} {row['cold_ratio']:>12.2f} {'-':>16}")


if __name__ == "__main__":
    main()
