"""The installed Python module (ctypes over the C API) against the command
line: it iterates the mesh and answers a batch of locates; every answer is
compared with `weaver query ... --format csv` and `weaver stat`.
usage: check_python_api.py MODULE_DIR WEAVER DB WORK_DIR"""
import array
import csv
import io
import os
import random
import subprocess
import sys
import warnings

module_dir, weaver_bin, db_path, work = sys.argv[1:5]
sys.path.insert(0, module_dir)
import weaver  # noqa: E402


def fail(message):
    sys.exit("check_python_api: " + message)


def cli(*args, stdin=None):
    return subprocess.run([weaver_bin, *args], input=stdin, capture_output=True, text=True,
                          check=True).stdout


with weaver.Database(db_path) as db:
    elements = list(db.elements())
    nodes = list(db.nodes())
    if len(elements) != db.element_count or len(nodes) != db.node_count:
        fail("iteration and counts disagree")
    if [e.id for e in elements] != list(range(len(elements))):
        fail("element ids are not 0..n-1 in order")
    # Every 97th element as the command line prints it.
    for e in elements[::97]:
        row = next(csv.DictReader(io.StringIO(cli("query", db_path, "element", str(e.id),
                                                  "--format", "csv"))))
        want = (int(row["x"]), int(row["y"]), int(row["z"]))
        if e.corner != want or e.level != int(row["level"]) or e.edge != int(row["edge"]):
            fail(f"element {e.id}: {e} against {row}")
        if " ".join(map(str, e.nodes)) != row["nodes"]:
            fail(f"element {e.id} nodes: {e.nodes} against {row['nodes']}")
        if abs(e.vs - float(row["vs"])) > 1e-3 * max(1.0, e.vs):
            fail(f"element {e.id} vs: {e.vs} against {row['vs']}")
    dangling = [n for n in nodes if n.kind != "anchored"]
    for n in dangling[::53]:
        row = next(csv.DictReader(io.StringIO(cli("query", db_path, "node", str(n.id),
                                                  "--format", "csv"))))
        if n.kind != row["kind"] or " ".join(map(str, n.anchors)) != row["anchors"]:
            fail(f"node {n.id}: {n} against {row}")
    # A batch of locates, some outside, against locate --points.
    hi = [max(e.corner[a] + e.edge for e in elements) for a in range(3)]
    rng = random.Random(5)
    points = [tuple(rng.randrange(0, int(h * 1.1) + 1) for h in hi) for _ in range(2000)]
    hits = db.locate(points)
    text = "".join(f"{x} {y} {z}\n" for x, y, z in points)
    rows = list(csv.DictReader(io.StringIO(cli("query", db_path, "locate", "--points", "-",
                                               "--format", "csv", stdin=text))))
    if len(rows) != len(points):
        fail("locate --points lost rows")
    for hit, row in zip(hits, rows):
        if hit.inside != (row["status"] == "inside"):
            fail(f"inside differs: {hit} {row}")
        if hit.inside and (hit.element != int(row["element"]) or hit.level != int(row["level"])):
            fail(f"locate differs: {hit} {row}")
    # The same batch through a buffer, with no Python object per point: an
    # array.array, a read-only view of it, and numpy's arrays when numpy is
    # there (a structured view of the answers, zero-copy both ways).
    flat = array.array("I", [c for p in points for c in p])
    for buf in (flat, memoryview(flat).toreadonly()):
        raw = db.locate_buffer(buf)
        if [(bool(h.inside), h.element, h.level) for h in raw] != \
                [(h.inside, h.element, h.level) for h in hits]:
            fail("locate_buffer differs from locate")
    try:
        db.locate_buffer(array.array("d", [1.0, 2.0, 3.0]))
        fail("locate_buffer took float64 points")
    except TypeError:
        pass
    try:
        import numpy
    except ImportError:
        numpy = None
        if os.environ.get("WEAVER_REQUIRE_TOOLS"):
            fail("numpy is not installed (WEAVER_REQUIRE_TOOLS is set)")
    if numpy is not None:
        xyz = numpy.array(points, dtype=numpy.uint32)
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy must read the records' layout, not guess it
            got = numpy.ctypeslib.as_array(db.locate_buffer(xyz))
        if got.shape != (len(points),) or \
                list(got["element"][got["inside"] != 0]) != [h.element for h in hits if h.inside]:
            fail("locate_buffer through numpy differs from locate")
        try:
            db.locate_buffer(xyz[:, :2].copy())
            fail("locate_buffer took pairs")
        except ValueError:
            pass
    outside = sum(not h.inside for h in hits)
    if outside == 0 or outside == len(hits):
        fail("the points should be partly outside")
    # Neighbours and errors.
    nbrs = db.neighbors(0, faces=True, edges=True, corners=True)
    rows = list(csv.DictReader(io.StringIO(cli("query", db_path, "neighbors", "0", "--all",
                                               "--format", "csv"))))
    if [n.element for n in nbrs] != [int(r["element"]) for r in rows]:
        fail("neighbors differ")
    try:
        db.element(db.element_count)
        fail("an id past the end was answered")
    except weaver.WeaverError as e:
        if "does not exist" not in str(e):
            fail("unexpected error text: " + str(e))
# A batch large enough to be shared among threads (16384 points or more)
# answers as one thread does, point for point.
rng = random.Random(7)
many = array.array("I", [rng.randrange(0, int(h * 1.1) + 1) for _ in range(50000) for h in hi])
with weaver.Database(db_path) as one, weaver.Database(db_path, threads=2) as two:
    a, b = one.locate_buffer(many), two.locate_buffer(many)
    if [(h.inside, h.element, h.level, h.vs) for h in a] != \
            [(h.inside, h.element, h.level, h.vs) for h in b]:
        fail("locate on 2 threads differs from 1")
    if sum(h.inside for h in b) in (0, len(b)):
        fail("the threads' points should be partly outside")
try:
    weaver.Database(db_path, threads=-1)
    fail("threads=-1 opened")
except weaver.WeaverError as e:
    if "threads" not in str(e):
        fail("unexpected error text: " + str(e))
try:
    weaver.Database(work + "/no-such.db")
    fail("a missing database opened")
except weaver.WeaverError:
    pass
print("check_python_api: ok,", len(elements), "elements,", len(nodes), "nodes,",
      len(points), "points")
