"""weaver serve against hostile clients, on 127.0.0.1 only, in loops bounded
in count and time: no value a client sends reaches an option or a file
(every route tried with option-like and path-like values answers 400 or 404
and a FIFO that any open would show stays unopened); only the server's own
Host names and pages are answered (421, 403); HEAD, HTTP/1.0 and bytes that
are not UTF-8 are answered as RFC 9110/9112 and JSON say; a tile without a
colour range is the tile with the section's range; and hostile bodies and
whole-mesh ranges keep the server within --memory.
usage: check_serve_hostile.py WEAVER WORK_DIR"""
import errno
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.parse

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from serve_client import exchange, raw  # noqa: E402

weaver_bin, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
DEADLINE = time.monotonic() + 240 * (3 if os.environ.get("WEAVER_SANITIZED") else 1)


def fail(message):
    sys.exit("check_serve_hostile: " + message)


def start(db, *options):
    server = subprocess.Popen([weaver_bin, "serve", db, "--port", "0", "--quiet", *options],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = server.stdout.readline()
    if "http://127.0.0.1:" not in line:
        fail(f"no URL: {line!r}")
    return server, int(line.split("http://127.0.0.1:")[1].split("/")[0])


def stop(server):
    server.send_signal(signal.SIGTERM)
    server.wait(timeout=10)


def request(port, method, path, body=None, headers=None):
    if time.monotonic() > DEADLINE:
        fail("out of time")
    return exchange(port, method, path, body, headers)


def opened(fifo):
    """Whether some process holds the FIFO open for reading: a non-blocking
    open for writing fails with ENXIO when none does."""
    try:
        fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
    except OSError as e:
        if e.errno == errno.ENXIO:
            return False
        raise
    os.close(fd)
    return True


def peak_rss(pid):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    return 0


db = os.path.join(work, "basin.db")
subprocess.run([weaver_bin, "mesh", db, "--model", "basin", "--freq", "0.3", "--quiet"],
               check=True)
fifo = os.path.join(work, "fifo")
os.mkfifo(fifo)
secret = os.path.join(work, "secret.txt")
with open(secret, "w") as f:
    f.write("1 2 3\n")

server, port = start(db, "--threads", "2")
try:
    # 1. Option-like and path-like values in every place a route takes one.
    hostile = ["--points", "--out", "-", "@" + secret, fifo, "/dev/zero", secret,
               "--points=" + fifo, "1e999", "nan", "0x10", " 1", "%00"]
    routes = []
    for v in hostile:
        q = urllib.parse.quote(v, safe="")
        routes += [f"/api/locate?x={q}&y=1&z=1", f"/api/locate?x=1&y=1&z=1&units={q}",
                   f"/api/locate?x=1&y=1&z=1&geo={q}", f"/api/element/{q}",
                   f"/api/neighbors/1?kinds={q}", f"/api/range?box={q},0,0,1,1,1",
                   f"/api/range?box=0,0,0,1,1,1&list={q}", f"/api/range?box=0,0,0,1,1,1&list=1"
                   f"&limit={q}", f"/api/tile/z/100/0/0/0.png?color={q}",
                   f"/api/tile/z/100/0/0/0.png?summary={q}", f"/api/tile/z/{q}/0/0/0.png",
                   f"/api/tile/z/100/0/0/0.png?min={q}&max=1", f"/api/section/z/100?color={q}",
                   f"/api/geo?x={q}&y=1", f"/api/export.vtu?box={q},0,0,1,1,1"]
    for path in routes:
        status, _, data = request(port, "GET", path)
        if status not in (400, 404) or "error" not in json.loads(data):
            fail(f"GET {path}: status {status}: {data[:200]!r}")
    for v in hostile:
        q = urllib.parse.quote(v, safe="")
        status, _, data = request(port, "POST", f"/api/points?query={q}", body="1 2 3\n")
        if status != 400:
            fail(f"POST /api/points?query={v}: status {status}")
        status, _, data = request(port, "POST", f"/api/points?units={q}", body="1 2 3\n")
        if status != 400:
            fail(f"POST /api/points?units={v}: status {status}")
    # The exploit of the old server: x, y, z and units as --points FILE --json.
    q = urllib.parse.quote
    status, _, data = request(port, "GET", f"/api/locate?x=--points&y={q(secret)}&z=--json&units=m")
    if status != 400 or b"1 2 3" in data:
        fail(f"the --points exploit: status {status}: {data[:200]!r}")
    if opened(fifo):
        fail("the server opened the FIFO a client named")
    if request(port, "GET", "/api/stat")[0] != 200:
        fail("the server does not answer after the hostile values")

    # 2. Only this server's names, and only its own pages.
    me = f"127.0.0.1:{port}"
    for headers, want in (({"Host": "evil.example"}, 421), ({"Host": f"evil.example:{port}"}, 421),
                          ({"Host": "127.0.0.1:1"}, 421),
                          ({"Origin": "http://evil.example"}, 403),
                          ({"Origin": "null"}, 403),
                          ({"Sec-Fetch-Site": "cross-site"}, 403),
                          ({"Sec-Fetch-Site": "same-site"}, 403),
                          ({"Sec-Fetch-Site": "same-origin", "Origin": f"http://{me}"}, 200),
                          ({"Host": f"localhost:{port}"}, 200),
                          ({"Sec-Fetch-Site": "none"}, 200)):
        status, _, data = request(port, "GET", "/api/stat", headers=headers)
        if status != want:
            fail(f"/api/stat with {headers}: status {status}, expected {want}: {data[:200]!r}")
    status, head, page = request(port, "GET", "/")
    csp = head.get("Content-Security-Policy", "")
    if status != 200 or "default-src 'self'" not in csp or head.get("X-Frame-Options") != "DENY" \
            or b"<script>" in page or b"<style>" in page or b"style=" in page:
        fail(f"the page's policy: {head}")
    for part, kind in (("/page.js", "text/javascript"), ("/page.css", "text/css")):
        status, head, _ = request(port, "GET", part)
        if status != 200 or not head.get("Content-Type", "").startswith(kind):
            fail(f"{part}: {status} {head}")

    # 3. HEAD, HTTP/1.0, and bytes that are not UTF-8.
    _, get_head, get_body = request(port, "GET", "/api/stat")
    head_answer = raw(port, f"HEAD /api/stat HTTP/1.1\r\nHost: {me}\r\n"
                            f"Connection: close\r\n\r\n".encode())
    top, _, rest = head_answer.partition(b"\r\n\r\n")
    if b" 200 " not in top.split(b"\r\n")[0] or rest != b"" or \
            f"Content-Length: {len(get_body)}".encode() not in top:
        fail(f"HEAD /api/stat: {head_answer[:300]!r}")
    head_post = raw(port, f"HEAD /api/points HTTP/1.1\r\nHost: {me}\r\n"
                          f"Connection: close\r\n\r\n".encode())
    top, _, rest = head_post.partition(b"\r\n\r\n")
    if b" 405 " not in top.split(b"\r\n")[0] or rest != b"":
        fail(f"HEAD of a POST route: {head_post[:300]!r}")
    old = raw(port, b"GET /api/range?box=0,0,0,1048576,1048576,1048576&list=1 HTTP/1.0\r\n\r\n")
    top, _, rest = old.partition(b"\r\n\r\n")
    if b"chunked" in top or json.loads(rest)["count"] != json.loads(get_body)["elements"]:
        fail(f"an HTTP/1.0 client's long answer: {top!r}")
    weird = raw(port, f"GET /api/\xff\xfe/x HTTP/1.1\r\nHost: {me}\r\n"
                      f"Connection: close\r\n\r\n".encode("latin-1"))
    body = weird.partition(b"\r\n\r\n")[2]
    json.loads(body.decode("utf-8"))  # raises (the check fails) unless valid UTF-8 JSON
    for data in (f"POST /api/points HTTP/1.1\r\nHost: {me}\r\nContent-Length : 6\r\n\r\n"
                 f"1 2 3\n", f"POST /api/points HTTP/1.1\r\nHost: {me}\r\nContent-Length: 6\r\n"
                 f"Content-Length: 7\r\n\r\n1 2 3\n", f"GET /api/stat HTTP/1.1\r\nHost: {me}\r\n"
                 f"X: a\r\n b\r\n\r\n", f"GET /api/stat HTTP/1.1\r\n\r\n",
                 f"GET /api/stat HTTP/1.1\r\nHost: {me}\r\nHost: {me}\r\n\r\n"):
        got = raw(port, data.encode())
        if b" 400 " not in got.split(b"\r\n")[0]:
            fail(f"{data[:60]!r}: {got[:200]!r}")

    # 3b. Slow readers hold no worker: eight clients (four times the threads)
    # each reading a 10 MB answer 2 KB at a time, and /api/stat answered at
    # once while every one of them is still connected.
    slow = []
    for _ in range(8):
        so = socket.create_connection(("127.0.0.1", port), timeout=20)
        so.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        so.sendall(f"GET /api/range?box=0,0,0,100000,100000,37500&units=m&list=1&limit=100000 "
                   f"HTTP/1.1\r\nHost: {me}\r\n\r\n".encode())
        slow.append(so)
    for _ in range(3):
        for so in slow:
            if not so.recv(2048):
                fail("a slow reader's answer ended early")
        time.sleep(0.3)
    # Answered while all eight are connected (a server they held would answer
    # only after dropping them).
    if request(port, "GET", "/api/stat")[0] != 200:
        fail("/api/stat beside eight slow readers")
    for so in slow:
        if not so.recv(2048):
            fail("a slow reader was dropped before /api/stat was answered")
        so.close()

    # 4. A tile without a colour range is the tile with the section's.
    section = json.loads(request(port, "GET", "/api/section/z/1000?color=vs")[2])
    plain = request(port, "GET", "/api/tile/z/1000/1/0/1.png?color=vs")[2]
    again = request(port, "GET", "/api/tile/z/1000/1/0/1.png?color=vs")[2]
    ranged = request(port, "GET", f"/api/tile/z/1000/1/0/1.png?color=vs&min={section['min']}"
                                  f"&max={section['max']}")[2]
    if not (plain == again == ranged):
        fail("a tile without min and max differs from the tile with the section's range")
finally:
    stop(server)

# 4b. --scratch: a region's vtu is written where it says, not in DB (a
# directory that does not exist names itself in the 500).
missing = os.path.join(work, "no-such-scratch")
server, port = start(db, "--scratch", missing)
try:
    status, _, data = request(port, "GET", "/api/export.vtu?box=20000,30000,0,21000,31000,500")
    if status != 500 or missing.encode() not in data:
        fail(f"--scratch {missing}: status {status}: {data[:200]!r}")
    os.makedirs(missing)
    status, _, data = request(port, "GET", "/api/export.vtu?box=20000,30000,0,21000,31000,500")
    if status != 200 or b"<VTKFile" not in data[:200] or os.listdir(missing):
        fail(f"--scratch: status {status}, {os.listdir(missing)} left in it")
finally:
    stop(server)

# 5. Hostile bodies and whole-mesh answers within --memory.
BUDGET, ALLOWANCE = 48 << 20, 24 << 20
server, port = start(db, "--threads", "3", "--memory", "48M")
try:
    me = f"127.0.0.1:{port}"
    stat = json.loads(request(port, "GET", "/api/stat")[2])
    request(port, "GET", "/api/element/0")
    before = peak_rss(server.pid)
    problems = []

    def post(body, what, rows):
        try:
            status, _, data = request(port, "POST", "/api/points", body=body)
            got = data.count(b'"status": "bad"')
            if status != 200 or not data.startswith(b'[{"x": null') or got != rows:
                problems.append(f"{what}: status {status}, {got} bad rows of {rows}")
        except Exception as e:  # noqa: BLE001
            problems.append(f"{what}: {e!r}")

    # A million lines that are not points (the old server kept every one's
    # error, 60 MB), and a line without an end just under the largest body
    # --memory 48M takes (a quarter of it).
    bad_lines = b"a\n" * 1000000
    one_line = b"7" * (11 << 20)
    # One after the other: both at once pass the bodies' share (503).
    workers = [threading.Thread(target=lambda: (post(bad_lines, "bad lines", 1000000),
                                                post(one_line, "one long line", 1)))]
    wholes = []

    def whole_range():  # the whole mesh, in metres: past the cap of a page
        s, _, data = request(port, "GET", "/api/range?box=0,0,0,100000,100000,37500&list=1&units=m")
        wholes.append({"status": s, "bytes": len(data), "doc": json.loads(data)})

    workers += [threading.Thread(target=whole_range) for _ in range(2)]
    for t in workers:
        t.start()
    for t in workers:
        t.join(timeout=180)
    if problems:
        fail("; ".join(problems))
    for whole in wholes:
        doc = whole["doc"]
        if whole["status"] != 200 or doc["count"] != stat["elements"] or \
                len(doc["elements"]) != 1000000 or not doc["truncated"] or \
                doc["next"] != doc["elements"][-1]["element"] + 1:
            fail(f"the whole mesh's range: {whole['status']}, count {doc['count']}, "
                 f"{len(doc['elements'])} listed, next {doc['next']}")
    answered = sum(w["bytes"] for w in wholes)
    if len(wholes) != 2 or answered < 3 * BUDGET:
        fail(f"the whole ranges ({answered} bytes) are too small to test the budget")
    peak = peak_rss(server.pid)
    if peak > BUDGET + ALLOWANCE and not os.environ.get("WEAVER_SANITIZED"):
        fail(f"peak {peak >> 20} MiB resident with --memory 48M (before {before >> 20} MiB)")
    if request(port, "GET", "/api/stat")[0] != 200:
        fail("the server does not answer after the hostile bodies")
finally:
    stop(server)
print(f"check_serve_hostile: {len(routes)} hostile GETs and the --points exploit answered 400, "
      f"the FIFO never opened; Host 421, Origin and Sec-Fetch-Site 403, CSP on the page; HEAD, "
      f"HTTP/1.0, non-UTF-8 and smuggling framings as RFC 9112; a tile's range shared; "
      f"{(len(bad_lines) + len(one_line)) >> 20} MiB of hostile bodies and "
      f"{answered >> 20} MiB of ranges within --memory 48M (peak {peak >> 20} MiB)")
