"""Every JSON answer of weaver read by real parsers: Python's json (strict:
NaN and Infinity refused) and jq when it is installed.  `--format json` is one
document (an array of rows, or an object where the answer is one thing) at 0,
1 and many rows; `--format jsonl` (and `ndjson`) is one object a line; the
shell's `.mode` follows; paths with a quote and non-ASCII letters come back
as they were given.
usage: check_json.py WEAVER WORK_DIR"""
import json
import os
import shutil
import subprocess
import sys

weaver_bin, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
JQ = shutil.which("jq")
if JQ is None and os.environ.get("WEAVER_REQUIRE_TOOLS"):
    sys.exit("check_json: jq is required (WEAVER_REQUIRE_TOOLS) but not installed")


def fail(message):
    sys.exit("check_json: " + message)


def run(*args, ok=True, stdin=None):
    r = subprocess.run([weaver_bin, *args], input=stdin, capture_output=True, text=True)
    if ok and r.returncode != 0:
        fail(f"weaver {' '.join(args)}: exit {r.returncode}: {r.stderr}")
    return r


def no_constants(name):
    fail(f"{name} is not JSON")


def by_jq(text, what, documents):
    """jq reads text as that many documents."""
    if not JQ:
        return
    r = subprocess.run([JQ, "-c", "type"], input=text, capture_output=True, text=True)
    if r.returncode != 0 or len(r.stdout.splitlines()) != documents:
        fail(f"{what}: jq reads it otherwise (exit {r.returncode}): {r.stderr}{r.stdout[:200]}")


def parse(text, what):
    try:
        return json.loads(text, parse_constant=no_constants)
    except json.JSONDecodeError as e:
        fail(f"{what}: not one JSON document ({e}):\n{text[:400]}")


def strict(text, what):
    """One JSON document, by Python and by jq."""
    doc = parse(text, what)
    by_jq(text, what, 1)
    return doc


def lines(text, what):
    """JSON Lines: every line one object."""
    rows = [parse(line, f"{what}, a line") for line in text.splitlines()]
    if not all(isinstance(r, dict) for r in rows):
        fail(f"{what}: a line that is not an object")
    by_jq(text, what, len(rows))
    return rows


def rows_of(args, what, want=None, stdin=None):
    """The answer as json (an array) and as jsonl and ndjson: the same rows."""
    doc = strict(run(*args, "--format", "json", stdin=stdin).stdout, what)
    if not isinstance(doc, list) or not all(isinstance(r, dict) for r in doc):
        fail(f"{what}: --format json is not an array of objects: {doc!r}"[:400])
    for mode in ("jsonl", "ndjson"):
        if lines(run(*args, "--format", mode, stdin=stdin).stdout, what) != doc:
            fail(f"{what}: --format {mode} holds other rows than --format json")
    if want is not None and len(doc) != want:
        fail(f"{what}: {len(doc)} rows, expected {want}")
    return doc


def one(args, what):
    doc = strict(run(*args, "--format", "json").stdout, what)
    if not isinstance(doc, dict):
        fail(f"{what}: one answer is not one object: {doc!r}"[:400])
    if lines(run(*args, "--format", "jsonl").stdout, what) != [doc]:
        fail(f"{what}: jsonl is not the same one object")
    return doc


# A database in a directory whose name has a quote and non-ASCII letters.
place = os.path.join(work, 'séisme "LA" 地震')
os.makedirs(place)
db = os.path.join(place, "basin.db")
run("mesh", db, "--model", "basin", "--freq", "0.05", "--quiet")

stat = strict(run("stat", db, "--json").stdout, "stat --json")
if stat.get("database") != db:
    fail(f"stat --json: database {stat.get('database')!r}, given {db!r}")
if {t["table"] for t in stat["tables"]} < {"octants", "nodes"}:
    fail(f"stat --json: tables {[t['table'] for t in stat['tables']]}")
octant_stat = next(t for t in stat["tables"] if t["table"] == "octants")
octants = octant_stat["records"]
# The frame: metres a tick and the origin, as the octant table's metadata says.
try:
    tick = float(octant_stat["tick_m"])
    origin = [float(v) for v in octant_stat["origin_m"].split(",")]
except (KeyError, ValueError) as e:
    fail(f"stat --json: no frame in the octant table's entry ({e}): {octant_stat!r}"[:400])
if not tick > 0 or len(origin) != 3:
    fail(f"stat --json: tick_m {tick}, origin_m {origin}")
extract = strict(run("extract", db, "--json", "--quiet").stdout, "extract --json")
if extract["elements"] != octants:
    fail(f"extract --json: {extract['elements']} elements, stat says {octants}")
nodes = extract["nodes"]

# Answers that are one thing: objects.
element = one(["query", db, "element", "0"], "element 0")
if element["element"] != 0 or len(element["nodes"]) != 8:
    fail(f"element 0: {element}")
node = one(["query", db, "node", str(element["nodes"][7])], "node")
if node["node"] != element["nodes"][7]:
    fail(f"node: {node}")
count = one(["query", db, "range", "0", "0", "0", "1048575", "1048575", "0"], "range count")
located = one(["query", db, "locate", "10", "10", "10"], "locate one point")
if located["element"] != 0 or located["status"] != "inside":
    fail(f"locate one point: {located}")

# Answers of rows: arrays at 0, 1 and many rows.
listed = rows_of(["query", db, "range", "0", "0", "0", "1048575", "1048575", "0", "--list"],
                 "range --list", want=count["count"])
if count["count"] < 2:
    fail("range: the plane z = 0 should cut many elements")
rows_of(["query", db, "range", "1", "1", "1", "1", "1", "1", "--list"], "range of a point", 1)
rows_of(["query", db, "neighbors", "0", "--all"], "neighbors")
rows_of(["query", db, "node-elements", str(element["nodes"][7])], "node-elements")
rows_of(["query", db, "depends", "0"], "depends")
rows_of(["query", db, "locate", "--points", "-"], "no points", 0, stdin="")
rows_of(["query", db, "locate", "--points", "-"], "one point", 1, stdin="5 5 5\n")
points = "".join(f"{i * 9000} {i * 7000} {i * 3000}\n" for i in range(200))
rows_of(["query", db, "material", "--points", "-", "--units", "m"], "material batch", 200,
        stdin=points)
# A bad line is a row with nulls, not NaN; the exit status says so.
r = run("query", db, "locate", "--points", "-", "--units", "m", "--format", "json", ok=False,
        stdin="1 2\n1e999 0 0\n0 0 0\n")
bad = strict(r.stdout, "bad points")
if r.returncode != 1 or [b["status"] for b in bad] != ["bad", "bad", "inside"]:
    fail(f"bad points: exit {r.returncode}, rows {bad}")
if bad[0]["x"] is not None or bad[0]["element"] is not None:
    fail(f"bad points: a bad row holds values: {bad[0]}")
rows_of(["query", db, "node-at", "--points", "-"], "node-at batch", 2, stdin="0 0 0\n3 3 3\n")

# The shell: one document a query.
script = ".mode json\nelement 0\nrange 0 0 0 1048575 1048575 0 --list\n" \
         "neighbors 0\n.mode jsonl\nneighbors 0\n.mode ndjson\n.mode\n"
out = run("shell", db, stdin=script).stdout
decoder, at, docs = json.JSONDecoder(parse_constant=no_constants), 0, []
for _ in range(3):
    while at < len(out) and out[at].isspace():
        at += 1
    try:
        doc, at = decoder.raw_decode(out, at)
    except json.JSONDecodeError as e:
        fail(f"shell .mode json: not a JSON document a query ({e}):\n{out[:400]}")
    docs.append(doc)
if docs[0] != element or docs[1] != listed or not isinstance(docs[2], list):
    fail(f"shell .mode json: {docs!r}"[:400])
tail = out[at:].split("\n")
tail = [t for t in tail if t.strip()]
if len(tail) != len(docs[2]) + 1 or tail[-1] != "jsonl":
    fail(f"shell .mode jsonl / ndjson: {tail}")
if [json.loads(t) for t in tail[:-1]] != docs[2]:
    fail("shell .mode jsonl: other rows than .mode json")

# A bad mode is one line and exit 2.
r = run("query", db, "element", "0", "--format", "yaml", ok=False)
if r.returncode != 2 or "jsonl" not in r.stderr or r.stderr.count("\n") != 1:
    fail(f"--format yaml: exit {r.returncode}: {r.stderr}")
print(f"check_json: {count['count']} elements on the plane, {nodes} nodes, "
      f"every answer one JSON document{' (jq too)' if JQ else ''}")
