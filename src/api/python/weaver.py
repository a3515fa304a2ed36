"""Read a weaver mesh database from Python, through weaver's C API (ctypes).

Only the standard library is needed.  The module finds libweaver.so next to
itself in an installed tree (PREFIX/share/weaver/python -> PREFIX/lib), or
where the WEAVER_LIBRARY environment variable points.

    import weaver
    with weaver.Database("basin.db") as db:
        print(db.element_count, db.node_count)
        for hit in db.locate([(440000, 576000, 1000), (0, 0, 0)]):
            print(hit.inside, hit.element, hit.level, hit.vs)
        hits = numpy.ctypeslib.as_array(db.locate_buffer(xyz))  # xyz: (n, 3) uint32
        for e in db.elements():
            ...

Coordinates are ticks; db.units gives metres per tick and the origin.

A database served by `weaver serve` is read over HTTP by Client, with the
JSON answers of `weaver query --format json` (no library needed there):

    c = weaver.Client("http://127.0.0.1:8080")
    c.stat()["elements"]
    c.locate(40000, 51000, 300, units="m")["vs"]
    c.points([(1000, 2000, 300), (5000, 5000, 10)], query="material", units="m")
    c.element(5), c.node(7), c.neighbors(5, kinds="all"), c.range((0, 0, 0, 99, 99, 99))
    png = c.tile("z", 1000, 2, 1, 3, color="vs")
"""

import ctypes
import ctypes.util
import json
import os
import urllib.error
import urllib.parse
import urllib.request
from collections import namedtuple

__all__ = ["Database", "Client", "WeaverError", "Hit", "Element", "Node", "Neighbor"]


class WeaverError(RuntimeError):
    """An error from the library: a bad id, a damaged file, ..."""


class _Hit(ctypes.Structure):
    _fields_ = [("inside", ctypes.c_int32), ("level", ctypes.c_int32),
                ("element", ctypes.c_uint64), ("corner", ctypes.c_uint32 * 3),
                ("edge", ctypes.c_uint32), ("vp", ctypes.c_float), ("vs", ctypes.c_float),
                ("rho", ctypes.c_float),
                ("pad_", ctypes.c_int32)]  # weaver_hit's tail padding, named for numpy's view


class _Element(ctypes.Structure):
    _fields_ = [("id", ctypes.c_uint64), ("corner", ctypes.c_uint32 * 3),
                ("edge", ctypes.c_uint32), ("level", ctypes.c_int32), ("pad_", ctypes.c_int32),
                ("nodes", ctypes.c_uint64 * 8), ("vp", ctypes.c_float), ("vs", ctypes.c_float),
                ("rho", ctypes.c_float)]


class _Node(ctypes.Structure):
    _fields_ = [("id", ctypes.c_uint64), ("at", ctypes.c_uint32 * 3), ("kind", ctypes.c_int32),
                ("anchor_count", ctypes.c_int32), ("pad_", ctypes.c_int32),
                ("anchors", ctypes.c_uint64 * 4)]


class _Neighbor(ctypes.Structure):
    _fields_ = [("dx", ctypes.c_int32), ("dy", ctypes.c_int32), ("dz", ctypes.c_int32),
                ("pad_", ctypes.c_int32), ("element", ctypes.c_uint64)]


Hit = namedtuple("Hit", "inside element corner level edge vp vs rho")
Element = namedtuple("Element", "id corner level edge nodes vp vs rho")
Node = namedtuple("Node", "id at kind anchors")
Neighbor = namedtuple("Neighbor", "direction element")
NODE_KINDS = ("anchored", "edge", "face")


def _find_library():
    env = os.environ.get("WEAVER_LIBRARY")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    prefix = os.path.dirname(os.path.dirname(here))  # PREFIX/share/weaver/python
    prefix = os.path.dirname(prefix)
    for libdir in ("lib", "lib64", "lib/x86_64-linux-gnu", "lib/aarch64-linux-gnu"):
        candidate = os.path.join(prefix, libdir, "libweaver.so")
        if os.path.exists(candidate):
            return candidate
    found = ctypes.util.find_library("weaver")
    if found:
        return found
    raise WeaverError("cannot find libweaver.so: set WEAVER_LIBRARY to its path")


def _load():
    lib = ctypes.CDLL(_find_library())
    p, u64, i32, sz = ctypes.c_void_p, ctypes.c_uint64, ctypes.c_int, ctypes.c_size_t
    sigs = {
        "weaver_open_threads": (p, [ctypes.c_char_p, u64, i32, ctypes.c_char_p, sz]),
        "weaver_close": (None, [p]),
        "weaver_last_error": (ctypes.c_char_p, [p]),
        "weaver_element_count": (u64, [p]),
        "weaver_node_count": (u64, [p]),
        "weaver_has_material": (i32, [p]),
        "weaver_units": (ctypes.c_double, [p, ctypes.POINTER(ctypes.c_double)]),
        "weaver_locate": (i32, [p, ctypes.POINTER(ctypes.c_uint32), sz, ctypes.POINTER(_Hit)]),
        "weaver_element_get": (i32, [p, u64, ctypes.POINTER(_Element)]),
        "weaver_node_get": (i32, [p, u64, ctypes.POINTER(_Node)]),
        "weaver_node_at": (i32, [p, ctypes.POINTER(ctypes.c_uint32), ctypes.POINTER(i32),
                                 ctypes.POINTER(u64)]),
        "weaver_neighbors": (i32, [p, u64, i32, ctypes.POINTER(_Neighbor), sz,
                                   ctypes.POINTER(sz)]),
        "weaver_elements": (p, [p, u64]),
        "weaver_element_next": (i32, [p, ctypes.POINTER(_Element)]),
        "weaver_element_iter_free": (None, [p]),
        "weaver_nodes": (p, [p]),
        "weaver_node_next": (i32, [p, ctypes.POINTER(_Node)]),
        "weaver_node_iter_free": (None, [p]),
    }
    for name, (restype, argtypes) in sigs.items():
        f = getattr(lib, name)
        f.restype, f.argtypes = restype, argtypes
    return lib


_lib = None


def _library():
    global _lib
    if _lib is None:
        _lib = _load()
    return _lib


def _element(e):
    return Element(e.id, tuple(e.corner), e.level, e.edge, tuple(e.nodes), e.vp, e.vs, e.rho)


def _node(n):
    return Node(n.id, tuple(n.at), NODE_KINDS[n.kind], tuple(n.anchors[:n.anchor_count]))


class Database:
    """A weaver database, open read-only (the snapshot of its last commit)."""

    def __init__(self, path, memory=0, threads=1):
        """memory: bytes of caches (0: 256 MiB); threads: how many answer a
        locate of 16384 points or more (1: the calling thread; 0: one a
        core), memory shared among them."""
        lib = _library()
        error = ctypes.create_string_buffer(512)
        self._db = lib.weaver_open_threads(os.fsencode(path), memory, threads, error,
                                           len(error))
        if not self._db:
            raise WeaverError(error.value.decode(errors="replace"))
        self._lib = lib

    def close(self):
        if self._db:
            self._lib.weaver_close(self._db)
            self._db = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _check(self, status):
        if status < 0:
            raise WeaverError(self._lib.weaver_last_error(self._db).decode(errors="replace"))
        return status

    @property
    def element_count(self):
        return self._lib.weaver_element_count(self._db)

    @property
    def node_count(self):
        return self._lib.weaver_node_count(self._db)

    @property
    def has_material(self):
        return bool(self._lib.weaver_has_material(self._db))

    @property
    def units(self):
        """(metres per tick, (origin x, y, z) in metres)."""
        origin = (ctypes.c_double * 3)()
        tick = self._lib.weaver_units(self._db, origin)
        return tick, tuple(origin)

    def locate(self, points):
        """The element holding each (x, y, z) tick point: a list of Hit, in order."""
        points = list(points)
        n = len(points)
        xyz = (ctypes.c_uint32 * (3 * n))()
        for i, (x, y, z) in enumerate(points):
            xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2] = int(x), int(y), int(z)
        out = (_Hit * n)()
        self._check(self._lib.weaver_locate(self._db, xyz, n, out))
        return [Hit(bool(h.inside), h.element, tuple(h.corner), h.level, h.edge, h.vp, h.vs,
                    h.rho) for h in out]

    def locate_buffer(self, points):
        """The batch without Python objects: points is any C-contiguous buffer
        of uint32 x, y, z triples (a numpy array of shape (n, 3) and dtype
        uint32, an array.array("I"), ...), read in place when it is writable.
        Returns a ctypes array of n hit records, which
        numpy.ctypeslib.as_array() views as a structured array (fields inside,
        level, element, corner, edge, vp, vs, rho) without copying."""
        view = memoryview(points)
        if view.itemsize != 4 or view.format.lstrip("@=<") not in ("I", "L"):
            raise TypeError(f"points must hold uint32 values, not format {view.format!r}")
        if not view.c_contiguous or view.nbytes % 12 != 0:
            raise ValueError("points must be C-contiguous x, y, z triples")
        n = view.nbytes // 12
        xyz_type = ctypes.c_uint32 * (3 * n)
        xyz = xyz_type.from_buffer_copy(view) if view.readonly else xyz_type.from_buffer(view)
        out = (_Hit * n)()
        self._check(self._lib.weaver_locate(self._db, xyz, n, out))
        return out

    def element(self, element_id):
        e = _Element()
        self._check(self._lib.weaver_element_get(self._db, element_id, ctypes.byref(e)))
        return _element(e)

    def node(self, node_id):
        n = _Node()
        self._check(self._lib.weaver_node_get(self._db, node_id, ctypes.byref(n)))
        return _node(n)

    def node_at(self, x, y, z):
        """The id of the node at a tick point, or None."""
        xyz = (ctypes.c_uint32 * 3)(x, y, z)
        found, node_id = ctypes.c_int(), ctypes.c_uint64()
        self._check(self._lib.weaver_node_at(self._db, xyz, ctypes.byref(found),
                                             ctypes.byref(node_id)))
        return node_id.value if found.value else None

    def neighbors(self, element_id, faces=True, edges=False, corners=False):
        kinds = (1 if faces else 0) | (2 if edges else 0) | (4 if corners else 0)
        count = ctypes.c_size_t()
        cap = 64
        while True:
            out = (_Neighbor * cap)()
            self._check(self._lib.weaver_neighbors(self._db, element_id, kinds, out, cap,
                                                   ctypes.byref(count)))
            if count.value <= cap:
                return [Neighbor((n.dx, n.dy, n.dz), n.element) for n in out[:count.value]]
            cap = count.value

    def elements(self, first=0):
        """Every element from id `first` on, in id order."""
        it = self._lib.weaver_elements(self._db, first)
        try:
            e = _Element()
            while self._check(self._lib.weaver_element_next(it, ctypes.byref(e))) == 1:
                yield _element(e)
        finally:
            self._lib.weaver_element_iter_free(it)

    def nodes(self):
        """Every node in id order."""
        it = self._lib.weaver_nodes(self._db)
        try:
            n = _Node()
            while self._check(self._lib.weaver_node_next(it, ctypes.byref(n))) == 1:
                yield _node(n)
        finally:
            self._lib.weaver_node_iter_free(it)


class Client:
    """The JSON API of `weaver serve` at url; each method one request, its
    answer as Python values.  A server's error is a WeaverError with its
    message (and .status, the HTTP status)."""

    def __init__(self, url="http://127.0.0.1:8080", timeout=60):
        self.url = url.rstrip("/")
        self.timeout = timeout

    def _get(self, path, params=None, body=None, raw=False):
        query = urllib.parse.urlencode({k: v for k, v in (params or {}).items() if v is not None})
        request = urllib.request.Request(self.url + path + ("?" + query if query else ""),
                                         data=body, method="POST" if body is not None else "GET")
        try:
            with urllib.request.urlopen(request, timeout=self.timeout) as r:
                data = r.read()
        except urllib.error.HTTPError as e:
            try:
                message = json.loads(e.read())["error"]
            except (ValueError, KeyError):
                message = str(e)
            error = WeaverError(message)
            error.status = e.code
            raise error from None
        return data if raw else json.loads(data)

    def stat(self):
        return self._get("/api/stat")

    def locate(self, x, y, z, units=None, geo=False):
        return self._get("/api/locate", {"x": x, "y": y, "z": z, "units": units,
                                         "geo": 1 if geo else None})

    def points(self, points, query="locate", units=None, geo=False):
        """Rows for many points at once, in input order ("status" says
        inside, outside or bad)."""
        body = json.dumps([list(p) for p in points]).encode()
        return self._get("/api/points", {"query": query, "units": units,
                                         "geo": 1 if geo else None}, body)

    def element(self, element_id, units=None):
        return self._get(f"/api/element/{int(element_id)}", {"units": units})

    def node(self, node_id, units=None):
        return self._get(f"/api/node/{int(node_id)}", {"units": units})

    def neighbors(self, element_id, kinds=None, units=None):
        """kinds: "faces" (default), "edges", "corners" or "all", or several
        joined by commas."""
        return self._get(f"/api/neighbors/{int(element_id)}", {"kinds": kinds, "units": units})

    def node_elements(self, node_id, units=None):
        return self._get(f"/api/node-elements/{int(node_id)}", {"units": units})

    def depends(self, node_id, units=None):
        return self._get(f"/api/depends/{int(node_id)}", {"units": units})

    def range(self, box, listed=False, units=None):
        return self._get("/api/range", {"box": ",".join(str(v) for v in box),
                                        "list": 1 if listed else None, "units": units})

    def section(self, axis, position, color="level"):
        return self._get(f"/api/section/{axis}/{position}", {"color": color})

    def tile(self, axis, position, zoom, x, y, color="level", lo=None, hi=None):
        """The PNG bytes of one tile."""
        return self._get(f"/api/tile/{axis}/{position}/{zoom}/{x}/{y}.png",
                         {"color": color, "min": lo, "max": hi}, raw=True)
