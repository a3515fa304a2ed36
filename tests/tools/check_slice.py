"""weaver slice checked as a person would look at it, by decoding the PNG
with Python's zlib (not weaver's code): the pixel at the centre of every
element the plane cuts (listed by `weaver query range`) has the colour of
its value on the viridis scale, outlines are drawn where elements are large,
the SVG is well-formed XML with one outlined rectangle per element, and bad
requests fail with one line and no file.
usage: check_slice.py WEAVER WORK_DIR"""
import csv
import io
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_ground  # noqa: E402
from picture import pixel, read_png, viridis  # noqa: E402

weaver_bin, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def fail(message):
    sys.exit("check_slice: " + message)


def run(*args, ok=True, stdin=None):
    r = subprocess.run([weaver_bin, *args], input=stdin, capture_output=True, text=True)
    if ok and r.returncode != 0:
        fail(f"weaver {' '.join(args)}: {r.stderr}")
    return r


def close(c, d, tol=1):
    return all(abs(a - b) <= tol for a, b in zip(c, d))


def check_png(db, axis, at, color, width, field_of, extra=()):
    out = os.path.join(work, f"{axis}{at}{color}{len(extra)}.png")
    run("slice", db, "--axis", axis, "--at", str(at), "--color", color, "--width", str(width),
        "--out", out, *extra)
    w, h, rows, text = read_png(out)
    if w != width:
        fail(f"width {w}, asked {width}")
    px0, py0, px1, py1 = map(int, text["weaver.plot"].split())
    u0, v0, u1, v1 = map(float, text["weaver.world"].split())
    lo, hi = map(float, text["weaver.range"].split())
    ua, va = text["weaver.axes"].split()
    scale = (px1 - px0) / (u1 - u0)
    down = va == "z"
    # The elements the plane cuts, from the query layer.
    box = {"x": [0, 1048575], "y": [0, 1048575], "z": [0, 1048575]}
    box[axis] = [at, at]
    if extra:
        r = [int(x) for x in extra[1].split(",")]
        box[ua], box[va] = [r[0], r[2]], [r[1], r[3]]
    listing = run("query", db, "range", str(box["x"][0]), str(box["y"][0]), str(box["z"][0]),
                  str(box["x"][1]), str(box["y"][1]), str(box["z"][1]), "--list",
                  "--format", "csv").stdout
    cut = list(csv.DictReader(io.StringIO(listing)))
    if not cut:
        fail("the plane cuts nothing")
    checked = outlined = 0
    for e in cut:
        edge = int(e["edge"])
        u, v = int(e[ua]), int(e[va])
        if edge * scale < 8:
            continue
        cx = px0 + (u + edge / 2 - u0) * scale
        cy = py0 + ((v + edge / 2 - v0) if down else (v1 - v - edge / 2)) * scale
        if not (px0 + 2 <= cx < px1 - 2 and py0 + 2 <= cy < py1 - 2):
            continue  # beyond a --region
        if extra and not (u0 <= u and u + edge <= u1 and v0 <= v and v + edge <= v1):
            continue  # cut by the region's border: its centre may lie outside
        value = field_of(e)
        want = viridis((value - lo) / (hi - lo) if hi > lo else 0)
        got = pixel(rows, int(cx), int(cy))
        if not close(got, want):
            fail(f"element {e['element']} ({color} {value}) at pixel ({int(cx)}, {int(cy)}): "
                 f"{got}, want {want}")
        checked += 1
        # Its left edge is outlined.
        x_left = int(round(px0 + (u - u0) * scale))
        if edge * scale >= 6 and pixel(rows, x_left, int(cy)) == (40, 40, 40):
            outlined += 1
    if checked < 10:
        fail(f"only {checked} elements large enough to check in {out}")
    if outlined < checked // 2:
        fail(f"{outlined} of {checked} large elements outlined")
    return len(cut), checked


# A graded octree without material, coloured by level.
run("generate", os.path.join(work, "o.txt"), "--kind", "sphere", "--level", "3",
    "--max-level", "6", "--radius", "0.3")
sphere = os.path.join(work, "sphere.db")
run("import", sphere, "--octants", os.path.join(work, "o.txt"))
run("extract", sphere, "--quiet")
n1, c1 = check_png(sphere, "z", 524288, "level", 800, lambda e: float(e["level"]))
n2, c2 = check_png(sphere, "x", 300000, "level", 600, lambda e: float(e["level"]))
# A region of the plane (ticks): only its elements, the plot spans just it.
n4, c4 = check_png(sphere, "z", 524288, "level", 700, lambda e: float(e["level"]),
                   ("--region", "200000,300000,600000,700000"))
if not n4 < n1:
    fail("a region should cut fewer elements than the whole plane")

# The basin at a low frequency, coloured by vs: values from `weaver query element`.
basin = os.path.join(work, "basin.db")
run("mesh", basin, "--model", "basin", "--freq", "0.05", "--quiet")
vs = {}


def vs_of(e):
    # All the cut elements' vs at once: `weaver query material --points` at
    # their centres, one process (the check runs under the sanitizers too).
    if not vs:
        listing = run("query", basin, "range", "0", "400000", "0", "1048575", "400000", "1048575",
                      "--list", "--format", "csv").stdout
        cut = list(csv.DictReader(io.StringIO(listing)))
        text = "".join(f"{int(c['x']) + int(c['edge']) // 2} {int(c['y']) + int(c['edge']) // 2} "
                       f"{int(c['z']) + int(c['edge']) // 2}\n" for c in cut)
        rows = csv.DictReader(io.StringIO(run("query", basin, "material", "--points", "-",
                                              "--format", "csv", stdin=text).stdout))
        for c, row in zip(cut, rows):
            vs[c["element"]] = float(row["vs"])
    return vs[e["element"]]


n3, c3 = check_png(basin, "y", 400000, "vs", 700, vs_of)

# A mesh under a ground (a ramp along y, from 0 to 3 km): the vertical
# section x = 50 km draws the ground line where the test's own ramp puts it.
dem = os.path.join(work, "ramp.asc")
make_ground.write_asc(dem, 11, 11, 0, 0, 10000, lambda c, r: 300 * c, centre=True)
ground_db = os.path.join(work, "ground")
run("mesh", ground_db, "--model", "loh1", "--freq", "0.15", "--surface", "asc:" + dem, "--quiet")
top = float(run("stat", ground_db, "--json").stdout.split('"top_elevation_m": "')[1].split('"')[0])
out = os.path.join(work, "ground.png")
run("slice", ground_db, "--axis", "x", "--at", "50000", "--units", "m", "--out", out)
w, h, rows, text = read_png(out)
px0, py0, px1, py1 = map(int, text["weaver.plot"].split())
u0, v0, u1, v1 = map(float, text["weaver.world"].split())
scale = (px1 - px0) / (u1 - u0)
tick = 100000 / 1048576
dark = 0
for px in range(px0 + 5, px1 - 5, 37):
    y_m = (u0 + (px + 0.5 - px0) / scale) * tick
    z_ticks = (top - 0.03 * y_m) / tick
    py = py0 + (z_ticks - v0) * scale
    if not (py0 + 2 <= py <= py1 - 2):
        continue
    if not any(close(pixel(rows, px, int(py) + d), (20, 20, 20), 2) for d in (-1, 0, 1)):
        fail(f"no ground line at pixel ({px}, {py:.1f})")
    dark += 1
if dark < 10:
    fail(f"the ground line was checked at {dark} columns only")
# --z elevation: the z plane at the top's elevation minus --at.
by_elevation = os.path.join(work, "elev.png")
by_depth = os.path.join(work, "depth.png")
run("slice", ground_db, "--axis", "z", "--at", "1000", "--z", "elevation", "--out", by_elevation)
run("slice", ground_db, "--axis", "z", "--at", repr(top - 1000), "--units", "m", "--out", by_depth)
if read_png(by_elevation)[3]["weaver.plane"] != read_png(by_depth)[3]["weaver.plane"]:
    fail("slice --z elevation 1000 is not the plane z = top - 1000")

# SVG: well-formed, one outlined rectangle per element cut.
svg = os.path.join(work, "s.svg")
run("slice", sphere, "--axis", "z", "--at", "524288", "--out", svg, "--width", "800")
rects = [r for r in ET.parse(svg).getroot().iter("{http://www.w3.org/2000/svg}rect")
         if r.get("stroke")]
if len(rects) != n1:
    fail(f"{len(rects)} outlined rectangles in the SVG, {n1} elements cut")

# Bad requests: one line, the right status, no file left.
for args, status in [(["--at", "2000000"], 1), (["--at", "5", "--color", "vs"], 1),
                     (["--at", "5", "--width", "50"], 2), (["--at", "5", "--axis", "w"], 2)]:
    out = os.path.join(work, "bad.png")
    r = run("slice", sphere, *args, "--out", out, ok=False)
    if r.returncode != status or r.stderr.count("\n") != 1 or os.path.exists(out):
        fail(f"slice {args}: status {r.returncode}, stderr {r.stderr!r}")
r = run("slice", sphere, "--at", "5", "--out", os.path.join(work, "no-dir", "x.png"), ok=False)
if r.returncode != 1 or r.stderr.count("\n") != 1:
    fail(f"unwritable output: status {r.returncode}, {r.stderr!r}")
print(f"check_slice: ok, {c1} + {c2} + {c3} + {c4} elements' pixels checked")
