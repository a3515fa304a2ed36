#!/usr/bin/env python3
"""Writers of the ground's inputs, independent of weaver's readers: an ESRI
ASCII raster (the DEM GDAL and GMT write) and an SW4 rfile (the layout SW4's
MaterialRfile reads and pySW4's rfileIO writes).  Used by the tests and the
benchmarks; run as a script it writes the benchmark's DEM or rfile.

  make_ground.py dem OUT.asc [--cells 1000] [--size 100000] [--height 2000]
      Mountains up to --height m (a sum of Gaussian hills, seeded) over a
      --size x --size m box, --cells x --cells cells, xllcorner = yllcorner = 0.
  make_ground.py rfile OUT.rfile [--size 100000] [--depth 37500] [--mb 1000]
      A five-component rfile with blocks of 50 m to 400 m spacing (the top
      block finest), about --mb megabytes, with the DEM above as block 1.
"""
import argparse
import math
import random
import struct
import sys


def hills(size_m, height_m, seed=7, count=12):
    """A smooth ground: elevation(x_north, y_east) in metres, 0..height."""
    rnd = random.Random(seed)
    bumps = []
    for _ in range(count):
        bumps.append((rnd.uniform(0, size_m), rnd.uniform(0, size_m),
                      rnd.uniform(0.05, 0.15) * size_m, rnd.uniform(0.3, 1.0)))
    peak = max(b[3] for b in bumps)

    def elevation(x, y):
        z = 0.0
        for (bx, by, w, a) in bumps:
            z += a * math.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * w * w))
        return height_m * min(z, peak) / peak
    return elevation


def write_asc(path, ncols, nrows, xll, yll, cellsize, value, nodata=None, centre=False,
              keyword_case=str.lower):
    """value(col, row_from_south) -> metres, or None for NODATA.  Columns
    are east (the raster's x), rows north; the file lists rows from the north."""
    with open(path, "w") as f:
        f.write("%s %d\n" % (keyword_case("ncols"), ncols))
        f.write("%s %d\n" % (keyword_case("nrows"), nrows))
        f.write("%s %.17g\n" % (keyword_case("xllcenter" if centre else "xllcorner"), xll))
        f.write("%s %.17g\n" % (keyword_case("yllcenter" if centre else "yllcorner"), yll))
        f.write("%s %.17g\n" % (keyword_case("cellsize"), cellsize))
        if nodata is not None:
            f.write("%s %.17g\n" % (keyword_case("NODATA_value"), nodata))
        for r in range(nrows - 1, -1, -1):
            row = []
            for c in range(ncols):
                v = value(c, r)
                row.append("%.6f" % (nodata if v is None else v))
            f.write(" ".join(row) + "\n")


def write_rfile(path, blocks, azimuth=0.0, lon0=-118.0, lat0=34.0, proj="+proj=utm +zone=11",
                precision=4, big_endian=False):
    """blocks: [(hh, hv, z0, nc, ni, nj, nk, value)], block 0 the topography;
    value(i, j, k) -> list of nc numbers (rho, vp, vs[, qp, qs]).  Written in
    C order over (i, j, k, component)."""
    e = ">" if big_endian else "<"
    fl = "d" if precision == 8 else "f"
    attenuation = 1 if blocks[1][3] == 5 else 0
    with open(path, "wb") as f:
        f.write(struct.pack(e + "iii", 1, precision, attenuation))
        f.write(struct.pack(e + "ddd", azimuth, lon0, lat0))
        p = proj.encode()
        f.write(struct.pack(e + "i", len(p)) + p)
        f.write(struct.pack(e + "i", len(blocks)))
        for (hh, hv, z0, nc, ni, nj, nk, _) in blocks:
            f.write(struct.pack(e + "dddiiii", hh, hv, z0, nc, ni, nj, nk))
        for (hh, hv, z0, nc, ni, nj, nk, value) in blocks:
            fmt = e + fl * (nc * nk)
            for i in range(ni):
                for j in range(nj):
                    col = []
                    for k in range(nk):
                        col.extend(value(i, j, k))
                    f.write(struct.pack(fmt, *col))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("kind", choices=["dem", "rfile"])
    ap.add_argument("out")
    ap.add_argument("--cells", type=int, default=1000)
    ap.add_argument("--size", type=float, default=100000)
    ap.add_argument("--height", type=float, default=2000)
    ap.add_argument("--depth", type=float, default=37500)
    ap.add_argument("--mb", type=float, default=1000)
    a = ap.parse_args()
    ground = hills(a.size, a.height)
    if a.kind == "dem":
        cell = a.size / a.cells
        # Cell centres from cell/2: columns east (y), rows north (x).
        write_asc(a.out, a.cells + 1, a.cells + 1, -cell / 2, -cell / 2, cell,
                  lambda c, r: ground(r * cell, c * cell))
        return 0
    write_rfile_benchmark(a.out, a.size, a.depth, a.height, a.mb, ground)
    return 0


def write_rfile_benchmark(path, size, depth, height, mb, ground):
    """Blocks of 50, 100, 200, 400 m (hv = hh), the finest on top from the
    highest ground down, five components, about mb megabytes: the top
    blocks' thicknesses scale to fit, the last reaches down to --depth.
    Each block starts where the one above ends (SW4 stacks them so)."""
    import numpy as np  # the benchmark's writer: numpy for speed
    spacings = [50.0, 100.0, 200.0, 400.0]
    n = [int(size // h) + 1 for h in spacings]
    target = mb * 1e6 / 20  # grid points of five float32 values
    thick = np.array([1000.0, 2000.0, 6000.0])
    per_m = sum(n[b] ** 2 / spacings[b] * thick[b] for b in range(3)) / thick.sum()
    last = n[3] ** 2 * max(2, (depth - (thick.sum() - height)) / 400 + 1)
    thick *= max(0.05, (target - last) / per_m / thick.sum())
    nks, tops = [], [-height]
    for b, h in enumerate(spacings):
        bottom = tops[b] + thick[b] if b < 3 else depth
        nk = max(2, int(round((bottom - tops[b]) / h)) + 1)
        nks.append(nk)
        tops.append(tops[b] + (nk - 1) * h)
    e = "<"
    with open(path, "wb") as f:
        f.write(struct.pack(e + "iii", 1, 4, 1))
        f.write(struct.pack(e + "ddd", 0.0, -118.0, 34.0))
        p = b"+proj=utm +zone=11 +datum=WGS84"
        f.write(struct.pack(e + "i", len(p)) + p)
        f.write(struct.pack(e + "i", 5))
        nt = int(size // 100) + 1
        f.write(struct.pack(e + "dddiiii", 100.0, 100.0, 0.0, 1, nt, nt, 1))
        for b, h in enumerate(spacings):
            f.write(struct.pack(e + "dddiiii", h, h, tops[b], 5, n[b], n[b], nks[b]))
        xs = np.arange(nt) * 100.0
        topo = np.array([[ground(x, y) for y in xs] for x in xs], dtype="<f4")
        f.write(topo.tobytes())
        for b, h in enumerate(spacings):
            z = tops[b] + np.arange(nks[b]) * h
            # Air above the ground is -999 in SW4's files; here the values
            # grow with depth below sea level, the same in every column.
            below = np.maximum(z, 0.0)
            vs = np.minimum(500 + 0.1 * below, 3500)
            vals = np.stack([2000 + 0.02 * below, vs * 1.8, vs,
                             np.full_like(vs, 100.0), np.full_like(vs, 50.0)], axis=1)
            row = vals.astype("<f4").tobytes() * n[b]
            for _ in range(n[b]):
                f.write(row)


if __name__ == "__main__":
    sys.exit(main())
