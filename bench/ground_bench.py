#!/usr/bin/env python3
"""The real-ground benchmark (issue 49): the basin meshed under a synthetic
DEM (mountains up to 2 km, 1000 x 1000 cells over the 100 x 100 km box,
written by tests/tools/make_ground.py) against the same mesh with a flat
top, same --domain (so the same root and tick), alternating the two,
medians of --repeat runs; and a test-made rfile meshed directly.

  ground_bench.py [--weaver build/release/weaver] [--work /tmp/ground-bench]
                  [--freqs 1,2] [--repeat 3] [--memory 1G] [--rfile-mb 0]
                  [--rfile-freq 2] [--rfile-max-elements N] [--base OTHER_WEAVER]

Prints one JSON document, then a table.  Each run's stage times, peak
resident memory (the stage lines' peak) and database size come from
`weaver mesh`'s own output; the ratio is ground / flat of the stages both
run (construct + extract), with the boundary (which every mesh now builds)
reported beside.  Peak disk: the most the database's directory (scratch
files included) held, sampled every 50 ms, against the final database.
The rfile's import runs --repeat times, alternating with --base's if given.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import struct
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "tools"))
import make_ground  # noqa: E402

STAGE = re.compile(r"^(construct|extract|boundary)\s+(\d+) \w+\s+([\d.]+)s.*peak\s+([\d.]+) MB")


def tree_bytes(path):
    """Bytes of the files under path now (files may come and go meanwhile)."""
    size = 0
    for root, _, files in os.walk(path):
        for f in files:
            try:
                size += os.path.getsize(os.path.join(root, f))
            except OSError:
                pass  # removed between the listing and the stat
    return size


class PeakDisk:
    """The most bytes the files under a directory held, sampled every 50 ms
    while a command runs (the scratch files of construct and extract live
    inside the database's directory)."""

    def __init__(self, path):
        self.path, self.peak, self._stop = path, 0, threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _watch(self):
        while not self._stop.wait(0.05):
            self.peak = max(self.peak, tree_bytes(self.path))

    def stop(self):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, tree_bytes(self.path))
        return self.peak


def run_mesh(weaver, db, args, memory):
    shutil.rmtree(db, ignore_errors=True)
    t0 = time.monotonic()
    disk = PeakDisk(db)
    out = subprocess.run([weaver, "mesh", db, "--memory", memory, "--quiet", *args],
                         capture_output=True, text=True, check=True).stdout
    wall = time.monotonic() - t0
    peak_disk = disk.stop()
    r = {"wall_s": wall, "stages": {}}
    for line in out.splitlines():
        m = STAGE.match(line)
        if m:
            r["stages"][m.group(1)] = {"count": int(m.group(2)), "s": float(m.group(3)),
                                       "peak_mb": float(m.group(4))}
    r["db_mb"] = tree_bytes(db) / 1e6
    r["peak_disk_mb"] = peak_disk / 1e6
    r["elements"] = r["stages"]["construct"]["count"]
    r["pipeline_s"] = r["stages"]["construct"]["s"] + r["stages"]["extract"]["s"]
    r["peak_mb"] = max(s["peak_mb"] for s in r["stages"].values())
    return r


def median(runs, key):
    return statistics.median(key(r) for r in runs)


def rfile_grid_points(path):
    """The grid points of an rfile's material blocks (blocks 2 on)."""
    with open(path, "rb") as f:
        head = f.read(4096)
    e = "<" if struct.unpack("<i", head[:4])[0] == 1 else ">"
    at = 12 + 24
    (n,) = struct.unpack(e + "i", head[at:at + 4])
    at += 4 + n
    (blocks,) = struct.unpack(e + "i", head[at:at + 4])
    at += 4
    total = 0
    for b in range(blocks):
        _, _, _, _, ni, nj, nk = struct.unpack(e + "dddiiii", head[at:at + 40])
        at += 40
        if b > 0:
            total += ni * nj * nk
    return total


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--weaver", default=os.path.join(HERE, "..", "build", "release", "weaver"))
    ap.add_argument("--work", default="/tmp/ground-bench")
    ap.add_argument("--freqs", default="1,2")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--memory", default="1G")
    ap.add_argument("--rfile-mb", type=float, default=0)
    ap.add_argument("--rfile-freq", type=float, default=2,
                    help="the rfile's mesh (0: import only)")
    ap.add_argument("--rfile-max-elements", default="",
                    help="--max-elements for the rfile's mesh (default: weaver's)")
    ap.add_argument("--base", default="",
                    help="another weaver build whose rfile import runs alternating with --weaver's")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    dem = os.path.join(a.work, "dem.asc")
    if not os.path.exists(dem):
        ground = make_ground.hills(100000, 2000)
        cell = 100.0
        make_ground.write_asc(dem, 1001, 1001, -cell / 2, -cell / 2, cell,
                              lambda c, r: ground(r * cell, c * cell))
    result = {"machine": os.uname().nodename, "memory": a.memory, "freqs": {}}
    for f in [float(x) for x in a.freqs.split(",") if x]:
        common = ["--model", "basin", "--freq", str(f), "--domain", "100000,100000,37500"]
        flat, carved = [], []
        for _ in range(a.repeat):
            flat.append(run_mesh(a.weaver, os.path.join(a.work, "flat.db"), common, a.memory))
            carved.append(run_mesh(a.weaver, os.path.join(a.work, "ground.db"),
                                   common + ["--surface", "asc:" + dem], a.memory))
        row = {}
        for name, runs in (("flat", flat), ("ground", carved)):
            row[name] = {
                "elements": runs[0]["elements"],
                "construct_s": median(runs, lambda r: r["stages"]["construct"]["s"]),
                "extract_s": median(runs, lambda r: r["stages"]["extract"]["s"]),
                "boundary_s": median(runs, lambda r: r["stages"]["boundary"]["s"]),
                "pipeline_s": median(runs, lambda r: r["pipeline_s"]),
                "peak_mb": max(r["peak_mb"] for r in runs),
                "db_mb": runs[0]["db_mb"],
                "peak_disk_mb": max(r["peak_disk_mb"] for r in runs),
            }
        row["ratio"] = row["ground"]["pipeline_s"] / row["flat"]["pipeline_s"]
        result["freqs"][str(f)] = row
    if a.rfile_mb > 0:
        rfile = os.path.join(a.work, "model.rfile")
        if not os.path.exists(rfile):
            ground = make_ground.hills(100000, 2000)
            make_ground.write_rfile_benchmark(rfile, 100000, 37500, 2000, a.rfile_mb, ground)
        points = rfile_grid_points(rfile)
        builds = {"this": a.weaver, **({"base": a.base} if a.base else {})}
        times = {name: [] for name in builds}
        for _ in range(a.repeat):
            for name, weaver in builds.items():  # alternating, page cache warm after the first
                db = os.path.join(a.work, "rfile-model.db")
                shutil.rmtree(db, ignore_errors=True)
                t0 = time.monotonic()
                subprocess.run([weaver, "model", "import", db, "--from", "rfile:" + rfile,
                                "--memory", a.memory], check=True, stdout=subprocess.DEVNULL)
                times[name].append(time.monotonic() - t0)
        result["rfile_import"] = {
            name: {"grid_points": points, "s": statistics.median(t), "runs_s": t,
                   "points_per_s": points / statistics.median(t)} for name, t in times.items()}
        if a.rfile_freq > 0:
            extra = ["--max-elements", a.rfile_max_elements] if a.rfile_max_elements else []
            r = run_mesh(a.weaver, os.path.join(a.work, "rfile.db"),
                         ["--model", "rfile:" + rfile, "--freq", str(a.rfile_freq), "--domain",
                          "100000,100000,37500", *extra], a.memory)
            result["rfile"] = {"file_mb": os.path.getsize(rfile) / 1e6, "freq": a.rfile_freq,
                               "elements": r["elements"], "pipeline_s": r["pipeline_s"],
                               "construct_s": r["stages"]["construct"]["s"],
                               "extract_s": r["stages"]["extract"]["s"],
                               "wall_s": r["wall_s"], "peak_mb": r["peak_mb"],
                               "db_mb": r["db_mb"], "peak_disk_mb": r["peak_disk_mb"]}
    print(json.dumps(result, indent=2))
    print()
    print(f"{'freq':>5} {'mesh':>7} {'elements':>12} {'construct':>10} {'extract':>8} "
          f"{'boundary':>9} {'peak MB':>8} {'db MB':>8} {'disk peak':>9} {'ratio':>6}")
    for f, row in result["freqs"].items():
        for name in ("flat", "ground"):
            x = row[name]
            ratio = f"{row['ratio']:.2f}" if name == "ground" else ""
            print(f"{f:>5} {name:>7} {x['elements']:>12} {x['construct_s']:>10.2f} "
                  f"{x['extract_s']:>8.2f} {x['boundary_s']:>9.2f} {x['peak_mb']:>8.1f} "
                  f"{x['db_mb']:>8.1f} {x['peak_disk_mb'] / x['db_mb']:>8.2f}x {ratio:>6}")
    for name, x in result.get("rfile_import", {}).items():
        print(f"rfile import ({name}): {x['grid_points']} grid points in {x['s']:.2f} s (median "
              f"of {len(x['runs_s'])}, whole process): {x['points_per_s'] / 1e6:.1f}M points/s")
    if "base" in result.get("rfile_import", {}):
        x = result["rfile_import"]
        print(f"rfile import time ratio this / base: {x['this']['s'] / x['base']['s']:.2f}")
    if "rfile" in result:
        x = result["rfile"]
        print(f"rfile {x['file_mb']:.0f} MB at {x['freq']} Hz: {x['elements']} elements, "
              f"construct {x['construct_s']:.1f} s, construct + extract {x['pipeline_s']:.1f} s, "
              f"peak {x['peak_mb']:.0f} MB, database {x['db_mb']:.0f} MB, disk at most "
              f"{x['peak_disk_mb'] / x['db_mb']:.2f}x the database")


if __name__ == "__main__":
    main()
