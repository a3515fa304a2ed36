#!/usr/bin/env python3
"""weaver-mpi against weaver in one process on the same machine.

For the basin at --freq (default 1 Hz): each stage of the two-pass
pipeline (construct --unbalanced, balance, extract) by `weaver STAGE
--threads T` and by `mpirun -np N weaver-mpi STAGE` (one thread a rank),
then `mesh` (the balanced construct and extract, one commit) both ways, each
a fresh process, --repeat times.  Prints one JSON object per run, then a
table of medians: wall time per stage and of mesh, the ratio MPI / threads,
and per rank: time, records, bytes and messages sent and received (the
exchanged ghost layers, and the one byte a rank that tells whether every
window of balance fitted), bytes written, and their ratio, and peak RSS.

    python3 bench/mpi_bench.py --np 2 --threads 2 --freq 1 --repeat 3
"""
import argparse
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
BUILD = os.path.join(HERE, "..", "build", "release")
RANK = re.compile(r"^rank (\d+)\s+(\d+) (\w+) .*?in ([\d.]+)s.*?sent (\d+) B in (\d+) messages, "
                  r"received (\d+) B, wrote (\d+) B, peak RSS (\d+) B")


def run(cmd, env=None):
    """Runs cmd; returns (seconds, stdout, peak RSS of the children so far)."""
    t0 = time.monotonic()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024
    return time.monotonic() - t0, out, rss


def stage_options(args, stage):
    model = ["--model", "basin", "--freq", str(args.freq)]
    return {"construct": model + ["--unbalanced"], "mesh": model}.get(stage, [])


def serial(args, db, stage):
    opts = stage_options(args, stage)
    cmd = [args.weaver, stage, db] + opts + ["--threads", str(args.threads), "--quiet",
                                             "--memory", args.memory]
    secs, _, _ = run(cmd)
    return {"mode": "threads", "stage": stage, "threads": args.threads, "seconds": secs}


def parallel(args, db, stage):
    opts = stage_options(args, stage)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = ["mpirun", "--oversubscribe", "-np", str(args.np), args.mpi, stage, db] + opts + \
        ["--quiet", "--memory", args.memory]
    secs, out, _ = run(cmd, env)
    ranks = []
    for line in out.splitlines():
        m = RANK.match(line)
        if m:
            r, recs, what, s, sent, msgs, recv, wrote, rss = m.groups()
            ranks.append({"rank": int(r), "records": int(recs), "what": what,
                          "seconds": float(s), "bytes_sent": int(sent), "messages": int(msgs),
                          "bytes_received": int(recv), "bytes_written": int(wrote),
                          "peak_rss": int(rss)})
    return {"mode": "mpi", "stage": stage, "ranks_n": args.np, "seconds": secs, "ranks": ranks}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--np", type=int, default=2)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--freq", type=float, default=1.0)
    p.add_argument("--memory", default="256M")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--dir", default="/tmp/weaver-mpi-bench")
    p.add_argument("--weaver", default=os.path.join(BUILD, "weaver"))
    p.add_argument("--mpi", default=os.path.join(BUILD, "weaver-mpi"))
    args = p.parse_args()
    runs = []
    for _ in range(args.repeat):
        for mode, fn in (("threads", serial), ("mpi", parallel)):
            db = os.path.join(args.dir, mode + ".db")
            shutil.rmtree(db, ignore_errors=True)
            os.makedirs(args.dir, exist_ok=True)
            for stage in ("construct", "balance", "extract", "mesh"):
                if stage == "mesh":
                    shutil.rmtree(db, ignore_errors=True)
                r = fn(args, db, stage)
                r["freq"] = args.freq
                print(json.dumps(r), flush=True)
                runs.append(r)
            shutil.rmtree(db, ignore_errors=True)

    def med(mode, stage):
        return statistics.median(r["seconds"] for r in runs
                                 if r["mode"] == mode and r["stage"] == stage)

    print(f"\nbasin at {args.freq} Hz: medians of {args.repeat}; weaver --threads {args.threads} "
          f"against mpirun -np {args.np} weaver-mpi (1 thread a rank), on this machine")
    print(f"{'stage':10} {'threads s':>10} {'mpi s':>8} {'mpi/threads':>12}")
    total_t = total_m = 0
    for stage in ("construct", "balance", "extract"):
        t, m = med("threads", stage), med("mpi", stage)
        total_t += t
        total_m += m
        print(f"{stage:10} {t:10.2f} {m:8.2f} {m / t:12.2f}")
    print(f"{'3 stages':10} {total_t:10.2f} {total_m:8.2f} {total_m / total_t:12.2f}")
    t, m = med("threads", "mesh"), med("mpi", "mesh")
    print(f"{'mesh':10} {t:10.2f} {m:8.2f} {m / t:12.2f}")
    print(f"\nper rank (last run): records, time, exchanged bytes against written, peak RSS")
    print(f"{'stage':9} {'rank':>4} {'records':>11} {'s':>7} {'sent B':>10} {'msgs':>5} "
          f"{'recv B':>10} {'written B':>11} {'exch/wr':>8} {'RSS MB':>7}")
    for r in runs[-4:-1]:
        for k in r.get("ranks", []):
            ratio = (k["bytes_sent"] + k["bytes_received"]) / max(1, k["bytes_written"])
            print(f"{r['stage']:9} {k['rank']:4} {k['records']:11} {k['seconds']:7.2f} "
                  f"{k['bytes_sent']:10} {k['messages']:5} {k['bytes_received']:10} "
                  f"{k['bytes_written']:11} {100 * ratio:7.2f}% {k['peak_rss'] / 2**20:7.1f}")


if __name__ == "__main__":
    sys.exit(main())
