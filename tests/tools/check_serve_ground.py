"""weaver serve over a mesh under a ground, checked from outside: the tiles
of a vertical section are transparent exactly where no element is (VTK's
PNG reader decodes the alpha, and the server's own point batch says which
pixel centres are in an element), the ground line runs where the test's
own ramp puts it, ?z_mode=elevation moves a z plane to the top's elevation
minus POSITION, and z_mode=depth is refused.
usage: check_serve_ground.py WEAVER WORK_DIR"""
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_ground  # noqa: E402
from picture import pixel, read_png  # noqa: E402
from serve_client import exchange, start_server, stop_server  # noqa: E402

try:  # Debian's python3-vtk9: a PNG reader that is not ours
    import vtk  # noqa: E402
    from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402
except ImportError as e:
    if os.environ.get("WEAVER_REQUIRE_TOOLS"):
        sys.exit(f"check_serve_ground: VTK's Python module ({e}) is not installed "
                 "(WEAVER_REQUIRE_TOOLS is set)")
    print(f"check_serve_ground: VTK's Python module is not installed ({e}): skipped")
    sys.exit(77)

weaver_bin, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
DEADLINE = time.monotonic() + 240


def fail(message):
    sys.exit("check_serve_ground: " + message)


def run(*args):
    r = subprocess.run([weaver_bin, *args], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"weaver {' '.join(args)}: {r.stderr}")
    return r.stdout


def rgba_by_vtk(png_bytes):
    """The tile as VTK reads it: rows from the top, (r, g, b, a) a pixel."""
    path = os.path.join(work, "tile.png")
    with open(path, "wb") as f:
        f.write(png_bytes)
    reader = vtk.vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    w, h, _ = image.GetDimensions()
    scalars = vtk_to_numpy(image.GetPointData().GetScalars())
    if scalars.shape[1] != 4:
        fail(f"VTK reads the tile with {scalars.shape[1]} components, not RGB and alpha")
    # VTK's rows start at the bottom of the picture.
    return lambda i, j: tuple(int(c) for c in scalars[(h - 1 - j) * w + i])


# A ramp along y (the DEM's columns, east) from 0 to 3 km.
dem = os.path.join(work, "ramp.asc")
make_ground.write_asc(dem, 11, 11, 0, 0, 10000, lambda c, r: 300 * c, centre=True)
db = os.path.join(work, "ground")
run("mesh", db, "--model", "loh1", "--freq", "0.15", "--surface", "asc:" + dem, "--quiet")
tables = json.loads(run("stat", db, "--json"))["tables"]
top = float(next(t for t in tables if t["table"] == "octants")["top_elevation_m"])

server, port = start_server(weaver_bin, db, os.path.join(work, "serve.log"), "--threads", "2")
try:
    def request(path, method="GET", body=None):
        if time.monotonic() > DEADLINE:
            fail("out of time")
        status, head, data = exchange(port, method, path, body, timeout=30)
        return status, data

    def api(path, method="GET", body=None):
        status, data = request(path, method, body)
        if status != 200:
            fail(f"{path}: status {status}: {data[:300]!r}")
        return json.loads(data)

    served = api("/api/stat")
    if abs(served["top_elevation_m"] - top) > 1e-6 * max(1.0, abs(top)):
        fail(f"/api/stat top_elevation_m {served['top_elevation_m']}, weaver stat {top}")
    origin, tick = served["origin_m"], served["tick_m"]

    # The vertical section x = 50 km at zoom 0, and one tile of zoom 1.
    section = api("/api/section/x/50000?color=vs")
    side = section["side_m"]
    if (section["u"], section["v"], section["down"]) != ("y", "z", True):
        fail(f"/api/section/x: {section}")
    clear = opaque = ground_checked = 0
    for zoom, tx, ty in ((0, 0, 0), (1, 0, 0), (1, 1, 0)):
        status, png = request(f"/api/tile/x/50000/{zoom}/{tx}/{ty}.png?color=vs")
        if status != 200:
            fail(f"tile {zoom}/{tx}/{ty}: status {status}")
        at = rgba_by_vtk(png)
        _, _, rows, _ = read_png(png)
        span = side / 2 ** zoom
        px = span / 256

        def centre(i, j):  # metres: y across, z down
            return (origin[1] + tx * span + (i + 0.5) * px,
                    origin[2] + ty * span + (j + 0.5) * px)
        samples = [(i, j) for j in range(2, 256, 9) for i in range(3, 256, 11)]
        points = "".join(f"50000 {centre(i, j)[0]} {centre(i, j)[1]}\n" for i, j in samples)
        hits = api("/api/points?units=m", "POST", points)
        for (i, j), hit in zip(samples, hits):
            rgba = at(i, j)
            if rgba[:3] != pixel(rows, i, j):
                fail(f"tile {zoom}/{tx}/{ty} ({i}, {j}): VTK reads {rgba}, "
                     f"the PNG holds {pixel(rows, i, j)}")
            y_m, z_m = centre(i, j)
            # The ground line's two rows are drawn over whatever is there.
            z_ground = top - 0.03 * y_m
            if abs(z_m - z_ground) <= 2.5 * px:
                continue
            inside = hit["status"] == "inside"
            if inside != (rgba[3] == 255) or (not inside and rgba[3] != 0):
                fail(f"tile {zoom}/{tx}/{ty} pixel ({i}, {j}) at y {y_m:.0f} m, z {z_m:.0f} m: "
                     f"alpha {rgba[3]}, the point is {hit['status']}")
            clear += not inside
            opaque += inside
        # The ground line where the ramp crosses each pixel column.
        for i in range(4, 256, 13):
            y_m = origin[1] + tx * span + (i + 0.5) * px
            row = (top - 0.03 * y_m - origin[2] - ty * span) / px
            if not (2 <= row < 254) or y_m > origin[1] + served["extent_m"][1]:
                continue
            near = [at(i, int(row) + d) for d in (-2, -1, 0, 1)]
            if not any(c == (20, 20, 20, 255) for c in near):
                fail(f"tile {zoom}/{tx}/{ty}: no ground line in column {i} near row {row:.1f}: "
                     f"{near}")
            ground_checked += 1
    if clear < 20 or opaque < 20 or ground_checked < 10:
        fail(f"too little checked: {clear} clear, {opaque} opaque pixels, "
             f"{ground_checked} ground columns")

    # z_mode=elevation: the z plane at the top's elevation minus POSITION,
    # the same tile and section as the domain's z = 1000 m.
    plain = api(f"/api/section/z/{origin[2] + 1000}?color=vs")
    by_elevation = api(f"/api/section/z/{top - 1000}?color=vs&z_mode=elevation")
    if by_elevation["at_ticks"] != plain["at_ticks"]:
        fail(f"z_mode=elevation: plane {by_elevation['at_ticks']}, want {plain['at_ticks']}")
    _, a = request(f"/api/tile/z/{origin[2] + 1000}/0/0/0.png?color=vs")
    _, b = request(f"/api/tile/z/{top - 1000}/0/0/0.png?color=vs&z_mode=elevation")
    if a != b:
        fail("the tile at z_mode=elevation is not the domain's tile of the same plane")
    for bad in ("z_mode=depth", "z_mode=sideways"):
        status, data = request(f"/api/tile/z/100/0/0/0.png?{bad}")
        if status != 400:
            fail(f"{bad}: status {status}")
    status, data = request("/api/section/z/100?z_mode=depth")
    if status != 400 or b"curved" not in data:
        fail(f"a depth section: {status} {data[:200]!r}")
finally:
    code = stop_server(server)
if code != 0:
    fail(f"weaver serve exited {code} on SIGTERM")
print(f"check_serve_ground: {clear} transparent and {opaque} opaque pixels as the points say, "
      f"the ground line in {ground_checked} columns, z_mode")
