"""The page of `weaver serve` in a real browser: Debian's chromium, headless,
runs the page's script against a server on 127.0.0.1 and gives back the
document it built.  Opened on views given in the URL (axis, plane, colour,
zoom, centre, a selected element), the page must lay out the tiles of that
view (each of which the server answers), show the mesh's counts and the
colour range of the section, and show the selected element as `weaver
query element ID --format json` does.  Screenshots go under the work
directory (in build/) for a person to look at.
usage: check_page.py WEAVER WORK_DIR"""
import html.parser
import json
import os
import shutil
import signal
import subprocess
import sys
import urllib.request

SKIP = 77
weaver_bin, work = sys.argv[1:3]


def fail(message):
    sys.exit("check_page: " + message)


browser = shutil.which("chromium") or shutil.which("chromium-browser")
if browser is None:
    if os.environ.get("WEAVER_REQUIRE_TOOLS"):
        fail("chromium is not installed (WEAVER_REQUIRE_TOOLS is set)")
    print("check_page: chromium is not installed: skipped")
    sys.exit(SKIP)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(*args):
    r = subprocess.run([weaver_bin, *args], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"weaver {' '.join(args)}: {r.stderr}")
    return r.stdout


class Document(html.parser.HTMLParser):
    """The tiles' addresses and the texts of the elements that have ids."""

    def __init__(self):
        super().__init__()
        self.tiles, self.text, self.open = [], {}, []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img" and a.get("data-src", "").startswith("/api/tile/"):
            self.tiles.append(a["data-src"])
        self.open.append(a.get("id"))

    def handle_endtag(self, tag):
        if self.open:
            self.open.pop()

    def handle_data(self, data):
        for i in self.open:
            if i:
                self.text[i] = self.text.get(i, "") + data + " "


def js_number(v):
    """A number as JavaScript prints it (shortest; whole numbers bare)."""
    return str(int(v)) if float(v).is_integer() else repr(float(v))


def chromium(url, *extra):
    args = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            "--virtual-time-budget=15000", "--window-size=1200,800", *extra, url]
    r = subprocess.run(args, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        fail(f"chromium {url}: exit {r.returncode}: {r.stderr[-500:]}")
    return r.stdout


db = os.path.join(work, "basin.db")
run("mesh", db, "--model", "basin", "--freq", "0.05", "--quiet")
server = subprocess.Popen([weaver_bin, "serve", db, "--port", "0", "--quiet"], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
try:
    first = server.stdout.readline()
    if "http://127.0.0.1:" not in first:
        fail(f"no URL: {first!r}")
    base = "http://127.0.0.1:" + first.split("http://127.0.0.1:")[1].split("/")[0]

    def get_json(path):
        with urllib.request.urlopen(base + path, timeout=30) as r:
            return json.loads(r.read())

    stat = get_json("/api/stat")
    element = 123
    want = json.loads(run("query", db, "element", str(element), "--units", "m", "--format",
                          "json"))
    views = [("map", {"axis": "z", "at": "1000", "color": "vs", "zoom": "1", "cu": "0.5",
                      "cv": "0.5"}),
             ("section", {"axis": "y", "at": "40000", "color": "level", "zoom": "2",
                          "cu": "0.4", "cv": "0.3", "sel": str(element)})]
    for name, view in views:
        url = base + "/#" + "&".join(f"{k}={v}" for k, v in view.items())
        doc = Document()
        doc.feed(chromium(url, "--dump-dom"))
        chromium(url, f"--screenshot={os.path.join(work, name + '.png')}")
        prefix = f"/api/tile/{view['axis']}/{view['at']}/{view['zoom']}/"
        if not doc.tiles or not all(t.startswith(prefix) for t in doc.tiles):
            fail(f"{name}: tiles {doc.tiles[:3]}, expected under {prefix}")
        section = get_json(f"/api/section/{view['axis']}/{view['at']}?color={view['color']}")
        for t in doc.tiles:
            if f"color={view['color']}&min={js_number(section['min'])}&max={js_number(section['max'])}" not in \
                    t.replace("&amp;", "&"):
                fail(f"{name}: tile {t} is not coloured by the section's range {section}")
            with urllib.request.urlopen(base + t, timeout=30) as r:
                if r.status != 200 or r.read()[:8] != b"\x89PNG\r\n\x1a\n":
                    fail(f"{name}: tile {t} does not load")
        # A 1200-pixel-wide window at zoom z shows about 4 x 3 tiles there.
        n = 2 ** int(view["zoom"])
        if len(doc.tiles) > n * n or len(doc.tiles) < min(n * n, 2):
            fail(f"{name}: {len(doc.tiles)} tiles at zoom {view['zoom']}")
        info = doc.text.get("info", "")
        if f"{stat['elements']} elements" not in info:
            fail(f"{name}: the panel says {info!r}, not {stat['elements']} elements")
        note = doc.text.get("note", "")
        if f" {view['color']} " not in f" {note} " or f"on the {view['axis']} =" not in note:
            fail(f"{name}: the note says {doc.text.get('note')!r}")
        if "sel" in view:
            shown = doc.text.get("element", "").split()
            if f"element {element}" not in doc.text.get("selected", ""):
                fail(f"{name}: the selected element is not shown: {doc.text.get('sel')!r}")
            for key, value in want.items():
                if key == "element":
                    continue
                words = [str(v) for v in value] if isinstance(value, list) else [str(value)]
                at = shown.index(key) if key in shown else -1
                if at < 0 or shown[at + 1:at + 1 + len(words)] != words:
                    fail(f"{name}: the panel shows {key} as {shown[at + 1:at + 4]}, "
                         f"weaver query says {value}")
        print(f"check_page: {name}: {len(doc.tiles)} tiles of {prefix}, the panel as weaver "
              f"query; {os.path.join(work, name + '.png')}")
    # Opened with no view in the URL, the page fits the domain: the map
    # (1200 x 800 less the header and the panel) holds the 100 x 100 km plane
    # at zoom 1, all four of its tiles, not zoom 0's one tile in a sea of
    # empty axes.
    doc = Document()
    doc.feed(chromium(base + "/", "--dump-dom"))
    chromium(base + "/", f"--screenshot={os.path.join(work, 'first.png')}")
    zooms = {t.split("/")[5] for t in doc.tiles}
    if zooms != {"1"} or len(doc.tiles) != 4:
        fail(f"the first view: tiles {doc.tiles}, expected the four of zoom 1")
    print(f"check_page: the first view fits the domain: {len(doc.tiles)} tiles of zoom 1")
finally:
    server.send_signal(signal.SIGTERM)
    server.wait(timeout=10)
