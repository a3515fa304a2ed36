"""weaver serve as a client sees it, on 127.0.0.1 only, in loops bounded in
count and time: every JSON route answers what `weaver query --format json`
prints, and a region as vtu what `weaver export --box` writes; tiles are 256 x 256 PNGs whose pixels have the colour of the element
at their centre, in the documented tiling; bad requests get the right status
and one JSON error; clients running while a writer re-meshes the database
see the old mesh or the new one, never a mix, and the new one once it is
committed; SIGTERM stops the server.
usage: check_serve.py WEAVER WORK_DIR"""
import http.client
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from picture import pixel, read_png, viridis  # noqa: E402
from serve_client import exchange, raw, read_to_end, start_server, stop_server  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "src",
                                "api", "python"))
import weaver  # noqa: E402  (its Client needs no library)

weaver_bin, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
# The whole check, whatever happens (three times as long under the sanitizers).
DEADLINE = time.monotonic() + 240 * (3 if os.environ.get("WEAVER_SANITIZED") else 1)


def fail(message):
    sys.exit("check_serve: " + message)


def run(*args, ok=True, stdin=None):
    r = subprocess.run([weaver_bin, *args], input=stdin, capture_output=True, text=True)
    if ok and r.returncode != 0:
        fail(f"weaver {' '.join(args)}: {r.stderr}")
    return r


def descriptors_back_to(descriptors, when, tries):
    """Waits (0.1 s a try) until the server has no more descriptors open than
    `descriptors`, counted `when`."""
    for _ in range(tries):
        if len(os.listdir(f"/proc/{server.pid}/fd")) <= descriptors:
            return
        time.sleep(0.1)
    fail(f"{len(os.listdir(f'/proc/{server.pid}/fd'))} descriptors open, {descriptors} {when}")


db = os.path.join(work, "basin.db")
run("mesh", db, "--model", "basin", "--freq", "0.05", "--quiet")
log_path = os.path.join(work, "serve.log")
server, port = start_server(weaver_bin, db, log_path, "--threads", "3")
try:

    def request(method, path, body=None, headers=None):
        if time.monotonic() > DEADLINE:
            fail("out of time")
        status, head, data = exchange(port, method, path, body, headers, timeout=30)
        return status, head.get("Content-Type"), data

    def api(path, method="GET", body=None, status=200):
        got, kind, data = request(method, path, body)
        if got != status:
            fail(f"{method} {path}: status {got}, expected {status}: {data[:300]!r}")
        if kind != "application/json":
            fail(f"{method} {path}: Content-Type {kind}")
        return json.loads(data, parse_constant=lambda c: fail(f"{path}: {c} in JSON"))

    def same_as_query(path, *words, method="GET", body=None, stdin=None):
        want = json.loads(run("query", db, *words, "--format", "json", stdin=stdin,
                              ok=False).stdout)
        got = api(path, method, body)
        if got != want:
            fail(f"{path}: {json.dumps(got)[:300]}\n  weaver query {' '.join(words)}: "
                 f"{json.dumps(want)[:300]}")
        return got

    # The JSON routes are the query answers.
    stat = api("/api/stat")
    counts = json.loads(run("stat", db, "--json").stdout)
    records = {t["table"]: t["records"] for t in counts["tables"]}
    if (stat["elements"], stat["nodes"]) != (records["octants"], records["nodes"]):
        fail(f"/api/stat: {stat} against weaver stat {records}")
    if stat["extent_m"] != [100000, 100000, 37500] or "vs" not in stat["fields"]:
        fail(f"/api/stat: extent or fields: {stat}")
    for i in (0, 7, stat["elements"] - 1):
        e = same_as_query(f"/api/element/{i}", "element", str(i))
        same_as_query(f"/api/neighbors/{i}", "neighbors", str(i))
        same_as_query(f"/api/neighbors/{i}?kinds=all&units=m", "neighbors", str(i), "--all",
                      "--units", "m")
        same_as_query(f"/api/node/{e['nodes'][6]}", "node", str(e["nodes"][6]))
        same_as_query(f"/api/node-elements/{e['nodes'][6]}", "node-elements",
                      str(e["nodes"][6]))
        same_as_query(f"/api/depends/{e['nodes'][0]}", "depends", str(e["nodes"][0]))
    same_as_query("/api/locate?x=40000.5&y=51000&z=300&units=m", "locate", "40000.5", "51000",
                  "300", "--units", "m")
    same_as_query("/api/range?box=0,0,100,1048575,1048575,100", "range", "0", "0", "100",
                  "1048575", "1048575", "100")
    # A range's list comes in pages: the whole of it, and pages of 1000
    # following "next" to the end, are weaver query's rows.
    want_list = json.loads(run("query", db, "range", "0", "0", "100", "1048575", "1048575", "100",
                               "--list", "--format", "json").stdout)
    whole = api("/api/range?box=0,0,100,1048575,1048575,100&list=1")
    if (whole["elements"], whole["count"], whole["truncated"], whole["next"]) != \
            (want_list, len(want_list), False, None):
        fail(f"/api/range list=1: {json.dumps(whole)[:300]}")
    paged, at = [], 0
    for _ in range(1000):
        page = api(f"/api/range?box=0,0,100,1048575,1048575,100&list=1&limit=1000&from={at}")
        paged += page["elements"]
        if page["next"] is None:
            break
        if not page["truncated"] or len(page["elements"]) != 1000 or page["next"] <= at:
            fail(f"a page of a range: {json.dumps(page)[:300]}")
        at = page["next"]
    if paged != want_list or len(want_list) <= 1000:
        fail(f"the pages of a range ({len(paged)} rows) are not weaver query's {len(want_list)}")
    lines = "".join(f"{i * 997} {i * 1231} {i * 89}\n" for i in range(300)) + "not a point\n"
    same_as_query("/api/points?query=material&units=m", "material", "--points", "-",
                  "--units", "m", method="POST", body=lines, stdin=lines)
    array = json.dumps([[i * 5000, i * 3000, 700] for i in range(20)])
    as_lines = "".join(f"{i * 5000} {i * 3000} 700\n" for i in range(20))
    same_as_query("/api/points?units=m", "locate", "--points", "-", "--units", "m",
                  method="POST", body=array, stdin=as_lines)

    # A tile: each pixel the colour of the element at its centre (or the
    # outline), north up, the whole section at zoom 0.
    section = api("/api/section/z/1000?color=vs")
    lo, hi, side = section["min"], section["max"], section["side_m"]
    if not (section["u"], section["v"], section["down"]) == ("x", "y", False) or lo >= hi:
        fail(f"/api/section: {section}")
    for zoom, tx, ty in ((0, 0, 0), (2, 1, 2)):
        status, kind, png = request("GET", f"/api/tile/z/1000/{zoom}/{tx}/{ty}.png?color=vs"
                                    f"&min={lo}&max={hi}")
        if status != 200 or kind != "image/png":
            fail(f"tile {zoom}/{tx}/{ty}: status {status}, {kind}")
        w, h, rows, _ = read_png(png)
        if (w, h) != (256, 256):
            fail(f"tile {zoom}/{tx}/{ty} is {w} x {h}")
        span = side / 2 ** zoom
        samples = [(i, j) for j in range(3, 256, 23) for i in range(5, 256, 19)]
        points = "".join(f"{tx * span + (i + 0.5) * span / 256} "
                         f"{side - ty * span - (j + 0.5) * span / 256} {section['at_m']}\n"
                         for i, j in samples)
        hits = api("/api/points?query=material&units=m", "POST", points)
        matched = 0
        for (i, j), hit in zip(samples, hits):
            got = pixel(rows, i, j)
            if hit["status"] != "inside":
                continue
            want = viridis((hit["vs"] - lo) / (hi - lo))
            if got == (40, 40, 40):  # an outline
                continue
            if max(abs(a - b) for a, b in zip(got, want)) > 2:
                fail(f"tile {zoom}/{tx}/{ty} pixel ({i}, {j}): {got}, vs {hit['vs']} is {want}")
            matched += 1
        if matched < len(samples) // 2:
            fail(f"tile {zoom}/{tx}/{ty}: only {matched} of {len(samples)} pixels checked")

    # Dangling nodes on request: on the z = 0 plane (the elements' top
    # faces), in a tile at zoom 5, where every element is over 6 pixels wide,
    # every edge- or face-dangling node is marked at its pixel, red or white,
    # as weaver export's nodes.csv says.
    csv_dir = os.path.join(work, "csv")
    run("export", db, "--format", "csv", "--out", csv_dir)
    side_ticks = api("/api/section/z/0?color=vs")["side_m"] / stat["tick_m"]
    with open(os.path.join(csv_dir, "nodes.csv")) as f:
        next(f)
        top = [(int(x), int(y), k) for _, x, y, z, k, *_ in (line.split(",") for line in f)
               if int(z) == 0 and k != "anchored"]
    zoom = 5
    span = side_ticks / 2 ** zoom
    px = span / 256
    # The tile with the most such nodes off its edges (nodes lie on octant
    # boundaries, and so do tiles' edges).
    counts = {}
    for x, y, _ in top:
        t = (int(x // span), int((side_ticks - y) // span))
        if 2 <= (x - t[0] * span) / px < 254 and 2 <= (side_ticks - t[1] * span - y) / px < 254:
            counts[t] = counts.get(t, 0) + 1
    tx, ty = max(counts, key=counts.get)
    u0, v0 = tx * span, side_ticks - ty * span
    status, kind, png = request("GET", f"/api/tile/z/0/{zoom}/{tx}/{ty}.png?color=vs"
                                f"&min=0&max=5000&danglings=1")
    _, _, rows, _ = read_png(png)
    marked = 0
    for x, y, node_kind in top:
        i, j = int((x - u0) // px), int((v0 - y) // px)
        if not (2 <= i < 254 and 2 <= j < 254):
            continue
        want = (220, 30, 30) if node_kind == "edge" else (255, 255, 255)
        if pixel(rows, i, j) != want:
            fail(f"the {node_kind}-dangling node ({x}, {y}, 0) is not marked at pixel ({i}, {j}) "
                 f"of tile 5/{tx}/{ty}: {pixel(rows, i, j)}")
        marked += 1
    if marked < 3:
        fail(f"only {marked} dangling nodes in tile 5/{tx}/{ty} to check")

    api("/api/geo?x=1&y=2", status=404)  # not georeferenced

    # A region as vtu: what weaver export --box writes, byte for byte.
    box = "20000,30000,0,35000,41000,1500"
    status, kind, vtu = request("GET", f"/api/export.vtu?box={box}")
    mine = os.path.join(work, "region.vtu")
    run("export", db, "--format", "vtu", "--box", box, "--out", mine)
    if status != 200 or kind != "application/xml" or vtu != open(mine, "rb").read():
        fail(f"/api/export.vtu: status {status}, {kind}, {len(vtu)} bytes against "
             f"{os.path.getsize(mine)} from weaver export")
    api("/api/export.vtu?box=1,2,3", status=400)

    # Bad requests: a status and one JSON error each; never a crash.
    for path, status in (("/api/element/99999999", 404), ("/api/element/x", 400),
                         ("/api/nothing", 404), ("/../../etc/passwd", 404),
                         ("/api/tile/q/1000/0/0/0.png", 400), ("/api/tile/z/1000/1/2/0.png", 404),
                         ("/api/tile/z/99999999/0/0/0.png", 400),
                         ("/api/tile/z/1000/0/0/0.png?color=mood", 400),
                         ("/api/section/z/1000?color=qs", 400),
                         ("/api/locate?x=1&y=2", 400), ("/api/range?box=1,2,3", 400),
                         ("/api/locate?x=1&y=2&z=3&geo=1", 404)):
        e = api(path, status=status)
        if set(e) != {"error"}:
            fail(f"{path}: {e}")
    api("/api/stat", method="POST", body="x", status=405)
    status, _, _ = request("POST", "/api/points", body="", headers={"Content-Length": "999999999999"})
    if status != 413:
        fail(f"an oversized body: status {status}")
    status, kind, page = request("GET", "/")
    page += request("GET", "/page.js")[2] + request("GET", "/page.css")[2]
    if status != 200 or not kind.startswith("text/html") or b"/api/tile/" not in page \
            or b"http://" in page.replace(b"http://127", b""):
        fail(f"the page: status {status}, {kind}, or it fetches from elsewhere")

    # The raw protocol: keep-alive, pipelining, limits, malformed heads, and
    # a client that sends nothing never holds up the others.
    # An idle connection holds up no other client: /api/stat is answered
    # while the idle one is still open (a server that gave it a thread would
    # answer only once its idle timeout closed it).
    idle = socket.create_connection(("127.0.0.1", port), timeout=20)
    api("/api/stat")
    idle.setblocking(False)
    try:
        if idle.recv(1) == b"":
            fail("an idle connection held up another client until it was closed")
    except BlockingIOError:
        pass  # open, nothing to read: as it should be
    host = f"Host: 127.0.0.1:{port}\r\n".encode()
    two = raw(port, b"GET /api/element/1 HTTP/1.1\r\n" + host + b"\r\n"
              b"GET /api/element/2 HTTP/1.1\r\n" + host + b"Connection: close\r\n\r\n")
    if two.count(b"HTTP/1.1 200 OK") != 2 or b"Connection: keep-alive" not in two:
        fail(f"two pipelined requests: {two[:300]!r}")
    for data, want in ((b"GARBAGE\r\n\r\n", b" 400 "),
                       (b" /api/stat HTTP/1.1\r\n\r\n", b" 400 "),  # found by the fuzzer
                       (b"GET /api/st at HTTP/1.1\r\n\r\n", b" 400 "),
                       (b"GET /api/stat HTTP/2.0\r\n\r\n", b" 400 "),
                       (b"GET " + b"/a" * 5000 + b" HTTP/1.1\r\n\r\n", b" 431 "),
                       (b"GET / HTTP/1.1\r\n" + b"X-Long: " + b"y" * 40000 + b"\r\n\r\n",
                        b" 431 "),
                       (b"GET / HTTP/1.1\r\nno colon here\r\n\r\n", b" 400 "),
                       (b"POST /api/points HTTP/1.1\r\n" + host + b"Content-Length: -5\r\n\r\n",
                        b" 400 "),
                       (b"POST /api/points HTTP/1.1\r\n" + host +
                        b"Transfer-Encoding: chunked\r\n\r\n", b" 400 ")):
        got = raw(port, data)
        if want not in got.split(b"\r\n")[0] or b'{"error": ' not in got:
            fail(f"{data[:40]!r}: {got[:200]!r}")
    idle.close()
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    for i in range(50):
        conn.request("GET", f"/api/element/{i}")
        r = conn.getresponse()
        r.read()
        if r.status != 200 or r.getheader("Connection") != "keep-alive":
            fail(f"keep-alive request {i}: {r.status} {r.getheader('Connection')}")
    conn.close()

    # The Python module's client: the same answers, errors as WeaverError.
    client = weaver.Client(f"http://127.0.0.1:{port}")
    if client.element(7) != api("/api/element/7") or client.stat() != api("/api/stat"):
        fail("weaver.Client answers otherwise")
    if client.points([(5000, 5000, 10)], query="material", units="m")[0]["status"] != "inside":
        fail("weaver.Client.points")
    if read_png(client.tile("z", 1000, 0, 0, 0, color="vs"))[:2] != (256, 256):
        fail("weaver.Client.tile")
    try:
        client.element(10 ** 9)
        fail("weaver.Client.element past the end did not raise")
    except weaver.WeaverError as e:
        if e.status != 404 or "does not exist" not in str(e):
            fail(f"weaver.Client's error: {e.status} {e}")

    # Clients while a writer re-meshes the served database: each answer is
    # the old mesh's or the new one's, and after the commit the new one's.
    old = (stat["elements"], stat["nodes"])
    # Element 100 of the old mesh and of the new one (built the same way in
    # a twin database first), as weaver query prints them: its octant comes
    # from one table and its corners' node ids from the other, so an answer
    # that mixed two states would be neither.
    probe = 100
    want_old = json.loads(run("query", db, "element", str(probe), "--format", "json").stdout)
    twin = os.path.join(work, "twin.db")
    run("mesh", twin, "--model", "basin", "--freq", "0.08", "--quiet")
    want_new = json.loads(run("query", twin, "element", str(probe), "--format", "json").stdout)
    if want_old == want_new:
        fail(f"element {probe} is the same in both meshes: it cannot tell them apart")
    seen, mixed, errors, answers = set(), [], [], set()
    stop = threading.Event()

    def client():
        # Bounded in time: until a moment after the writer's commit (or the
        # check's deadline), so that the clients overlap the commit.
        while not stop.is_set() and time.monotonic() < DEADLINE:
            try:
                s = api("/api/stat")
                e = api(f"/api/element/{probe}")
                seen.add((s["elements"], s["nodes"]))
                if e == want_old:
                    answers.add("old")
                elif e == want_new:
                    answers.add("new")
                else:
                    mixed.append(e)
            except SystemExit as x:
                errors.append(str(x))
                return

    # Slow clients (a request a few bytes at a time) and malformed ones mixed
    # in: each gets its own answer, and none holds up the others.
    slow_errors = []

    def slow_client(i):
        request = (f"GET /api/element/{i} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                   f"Connection: close\r\n\r\n").encode()
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=20) as so:
                for k in range(0, len(request), 7):
                    so.sendall(request[k:k + 7])
                    time.sleep(0.02)
                got = read_to_end(so)
            if b" 200 " not in got.split(b"\r\n")[0] or f'"element": {i},'.encode() not in got:
                slow_errors.append(got[:200])
        except OSError as e:
            slow_errors.append(str(e))

    def malformed_client():
        for _ in range(20):
            if b" 400 " not in raw(port, b"NOT HTTP AT ALL\r\n\r\n").split(b"\r\n")[0]:
                slow_errors.append("malformed request not answered 400")

    descriptors = len(os.listdir(f"/proc/{server.pid}/fd"))
    clients = [threading.Thread(target=client) for _ in range(3)]
    clients += [threading.Thread(target=slow_client, args=(i,)) for i in range(6)]
    clients += [threading.Thread(target=malformed_client) for _ in range(2)]
    for t in clients:
        t.start()
    run("mesh", db, "--model", "basin", "--freq", "0.08", "--quiet")
    time.sleep(0.3)
    stop.set()
    for t in clients:
        t.join(timeout=60)
    new = tuple(api("/api/stat")[k] for k in ("elements", "nodes"))
    if api(f"/api/element/{probe}") != want_new:
        fail(f"after the re-mesh, element {probe} is not the new mesh's")
    if new == old or errors or mixed or seen != {old, new} or answers != {"old", "new"}:
        fail(f"re-mesh while serving: old {old}, new {new}, seen {seen}, answers {answers}, "
             f"errors {errors[:2]}, mixed {mixed[:2]}")
    if slow_errors:
        fail(f"slow or malformed clients beside the others: {slow_errors[:2]}")
    # Every connection closed by its client is closed by the server: as many
    # descriptors as before the clients (waiting out the idle timeout).
    descriptors_back_to(descriptors, "before the clients came", tries=100)
finally:
    code = stop_server(server)
if code is None:
    fail("the server did not stop on SIGTERM")
if code != 0:
    fail(f"the server exited {code}: {open(log_path).read()[-2000:]}")
# The log: a line a request, with its status.
log_lines = open(log_path).read().splitlines()
if not any(" GET /api/stat 200 " in line for line in log_lines) or \
        not any(" 400 " in line for line in log_lines):
    fail(f"the request log: {log_lines[:3]}")

# A model database (weaver model import of the etree fixture): its cells as
# the octree, the material of a point as `weaver model material` gives it,
# its tiles, and no nodes.
model = os.path.join(work, "model.db")
fixture = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "etree", "cmu.e")
run("model", "import", model, "--from", "etree:" + fixture)
server, port = start_server(weaver_bin, model, os.path.join(work, "model-serve.log"), "--quiet")
try:
    stat = api("/api/stat")
    if stat["kind"] != "model" or stat["nodes"] != 0 or "vs" not in stat["fields"]:
        fail(f"a model database's /api/stat: {stat}")
    points = [(1000 + 7919 * i % 90000, 500 + 3571 * i % 90000, 100 + 997 * i % 9000)
              for i in range(20)]
    hits = api("/api/points?query=material&units=m", "POST",
               "".join(f"{x} {y} {z}\n" for x, y, z in points))
    for (x, y, z), hit in zip(points, hits):
        want = run("model", "material", model, str(x), str(y), str(z)).stdout.split()
        if hit["status"] != "inside" or \
                any(abs(hit[k] - float(want[3 + i])) > 1e-3 * abs(float(want[3 + i]))
                    for i, k in enumerate(("vp", "vs", "rho"))):
            fail(f"a model's material at ({x}, {y}, {z}): {hit}, weaver model material {want}")
    status, kind, png = request("GET", "/api/tile/z/1000/1/0/0.png?color=vs")
    if status != 200 or read_png(png)[:2] != (256, 256):
        fail(f"a model's tile: {status}")
    api("/api/node/0", status=404)
finally:
    server.send_signal(signal.SIGTERM)
    server.wait(timeout=10)

# A georeferenced mesh: /api/geo's longitude and latitude (the page's hover)
# are where `weaver query --geo` puts the same point back.
geo_db = os.path.join(work, "geo.db")
run("mesh", geo_db, "--model", "basin", "--freq", "0.05", "--origin-geo", "-118.7,33.58",
    "--azimuth", "30", "--quiet")
server = subprocess.Popen([weaver_bin, "serve", geo_db, "--port", "0", "--quiet"], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
try:
    port = int(server.stdout.readline().split("http://127.0.0.1:")[1].split("/")[0])
    for x, y in ((40000, 51000), (1000, 99000), (75500.5, 20000)):
        g = api(f"/api/geo?x={x}&y={y}")
        back = json.loads(run("query", geo_db, "locate", repr(g["lon"]), repr(g["lat"]), "100",
                              "--geo", "--format", "json").stdout)
        if abs(back["x"] - x) > 1e-3 or abs(back["y"] - y) > 1e-3:
            fail(f"/api/geo?x={x}&y={y} gave {g}; weaver query --geo puts it at {back}")
    api("/api/geo?x=1&y=oops", status=400)
finally:
    server.send_signal(signal.SIGTERM)
    server.wait(timeout=10)
# The server's memory stays within --memory whatever the clients ask: four
# clients post batches whose answers (about 20 MB of JSON each) together
# are several times the budget, one leaves in the middle of its answer, and
# one downloads a region; the answers come streamed (chunked) and whole,
# and the peak resident size stays within the budget plus a fixed allowance
# for the program itself (its code, libraries and thread stacks).
BUDGET, ALLOWANCE = 48 << 20, 24 << 20
server = subprocess.Popen([weaver_bin, "serve", db, "--port", "0", "--threads", "3",
                           "--memory", "48M", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)
try:
    port = int(server.stdout.readline().split("http://127.0.0.1:")[1].split("/")[0])
    n_points = 100000
    batch = "".join(f"{(i * 7919) % 100000} {(i * 3571) % 100000} {(i * 997) % 37500}\n"
                    for i in range(n_points))
    # One batch first: it opens the helper that large batches share their
    # work with (its table files stay open).
    api("/api/points?units=m", "POST", batch)
    descriptors = len(os.listdir(f"/proc/{server.pid}/fd"))
    want_rows = json.loads(run("query", db, "locate", "--points", "-", "--units", "m",
                               "--format", "json", stdin=batch).stdout)
    answered, streamed, problems = [], [], []

    def poster(k):
        try:
            for _ in range(2):
                c = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                c.request("POST", "/api/points?units=m", body=batch)
                r = c.getresponse()
                data = r.read()
                c.close()
                if r.status != 200:
                    problems.append(f"client {k}: status {r.status}: {data[:200]!r}")
                    return
                streamed.append(r.getheader("Transfer-Encoding") == "chunked")
                answered.append(len(data))
                if json.loads(data) != want_rows:  # every client's: they share the helper
                    problems.append(f"client {k}'s batch differs from weaver query's answer")
        except Exception as e:  # noqa: BLE001  (any failure is the check's)
            problems.append(f"client {k}: {e!r}")

    def leaver():
        s = socket.create_connection(("127.0.0.1", port), timeout=30)
        s.sendall(f"POST /api/points?units=m HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                  f"Content-Length: {len(batch)}\r\n\r\n{batch}".encode())
        s.recv(100000)  # a little of the answer, then gone
        s.close()

    threads = [threading.Thread(target=poster, args=(k,)) for k in range(4)]
    threads.append(threading.Thread(target=leaver))
    for t in threads:
        t.start()
    status, kind, vtu = request("GET", "/api/export.vtu?box=0,0,0,100000,100000,37500")
    for t in threads:
        t.join(timeout=120)
    if problems:
        fail("; ".join(problems))
    if status != 200 or b"<VTKFile" not in vtu[:200] or not vtu.rstrip().endswith(b"</VTKFile>"):
        fail(f"/api/export.vtu of the whole domain: status {status}, {len(vtu)} bytes")
    if len(answered) != 8:
        fail(f"{len(answered)} of 8 batches answered")
    if sum(answered) < 3 * BUDGET:
        fail(f"the answers ({sum(answered)} bytes) are too small to test the budget")
    peak = 0
    for line in open(f"/proc/{server.pid}/status"):
        if line.startswith("VmHWM:"):
            peak = int(line.split()[1]) * 1024
    if peak > BUDGET + ALLOWANCE and not os.environ.get("WEAVER_SANITIZED"):
        fail(f"the server peaked at {peak >> 20} MiB resident with --memory 48M "
             f"({sum(answered) >> 20} MiB answered)")
    if not all(streamed):
        fail(f"batches streamed (chunked): {streamed}")
    # The leaver's connection is closed by the server too.
    descriptors_back_to(descriptors, "before the batches", tries=50)
finally:
    server.send_signal(signal.SIGTERM)
    server.wait(timeout=10)
print(f"check_serve: JSON routes as weaver query, tiles by pixel, {marked} dangling nodes "
      f"marked, bad requests, a model "
      f"database, /api/geo as weaver query --geo, a re-mesh "
      f"seen whole ({len(seen)} states, element {probe} as the {' or the '.join(sorted(answers))} mesh has it), stopped by SIGTERM; "
      f"{sum(answered) >> 20} MiB of batches streamed within --memory 48M (peak {peak >> 20} MiB)")
