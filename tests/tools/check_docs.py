"""Every command README.md and docs/*.md show runs as written.

    check_docs.py WEAVER_BINARY SOURCE_DIR WORK_DIR [PAGE.md ...]

Commands live in fenced blocks marked with what the test does with them:

  ```sh run       run, line by line, in order, in a scratch directory of the
                  page's own (pages share nothing); the first non-zero exit
                  fails the test, naming the page and line
  ```sh no-run    not run: the set-up commands (CI runs them anyway) and what
                  needs a cluster or root; their options are still checked
  ```sh server    the first command is `weaver serve ...`, started on
                  --port 0; the lines after it are run against it (each must
                  exit 0, and there must be one), then it is stopped and must
                  exit 0

A block of any other language that holds a command (a line starting with
weaver, ./build/release/weaver, weaver-mpi, mpirun, cmake, ctest, curl,
python3, apt-get or node, with or without a "$ " prompt), and an indented code
block that does, fails the test: unmarked.  In a block where some lines start
with "$ ", only those are commands (the rest is their output), and the lines
"weaver> ..." after a command are its standard input (a shell session).

Before running, commands are made small by one documented rule:
  --freq F with F >= 1          becomes --freq 0.1
  --memory 1G (or more)         becomes --memory 64M
  ./build/release/weaver[-mpi]  is the binary under test (and so is weaver)
  /tmp/, /shared/, /work/runs/  are the page's scratch directory
  python3                       is /usr/bin/python3 (Debian's, with numpy)
  127.0.0.1:8080 / localhost:8080  in a server block, the server's real port
The scratch directory holds `tests` and `examples` (links into the source
tree) and these inputs, which pages may name without making them:
  receivers.txt, points.txt  x y z lines in metres inside the basin's box
  stations.txt               lon lat depth lines around the paper's origin
  labase.e                   a copy of tests/data/etree/cmu.e

Every option a page shows for a command, in a block or in an inline code span
that starts with `weaver CMD`, must appear in `weaver CMD --help`.

The whole run has a budget (WEAVER_DOCS_BUDGET seconds, default 150) so that
.ci/run stays short; past it the test fails, naming the slowest blocks.
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from serve_client import stop_server  # noqa: E402

COMMAND_WORDS = ("weaver", "./build/release/weaver", "weaver-mpi", "./build/release/weaver-mpi",
                 "mpirun", "cmake", "ctest", "curl", "python3", "apt-get", "node")
BUDGET = float(os.environ.get("WEAVER_DOCS_BUDGET", "150"))
COMMAND_TIMEOUT = 120


def fail(msg):
    print("check_docs: " + msg, file=sys.stderr)
    sys.exit(1)


def is_command(line):
    line = line.strip()
    if line.startswith("$ "):
        line = line[2:]
    word = line.split(" ", 1)[0]
    return word in COMMAND_WORDS


class Block:
    def __init__(self, page, line, info, lines):
        self.page, self.line, self.info, self.lines = page, line, info, lines

    def where(self, offset=0):
        return f"{self.page}:{self.line + 1 + offset}"


def read_blocks(page, text):
    """The fenced blocks of a page, and the indented code blocks that hold commands."""
    blocks, lines = [], text.split("\n")
    i, prev_blank = 0, True
    while i < len(lines):
        line = lines[i]
        m = re.match(r"^(\s*)```(.*)$", line)
        if m:
            indent, info, body, start = len(m.group(1)), m.group(2).strip(), [], i
            i += 1
            while i < len(lines) and not re.match(r"^\s*```\s*$", lines[i]):
                body.append(lines[i][indent:] if lines[i][:indent].strip() == "" else lines[i])
                i += 1
            if i == len(lines):
                fail(f"{page}:{start + 1}: a fenced block that never closes")
            blocks.append(Block(page, start, info, body))
            i += 1
            prev_blank = False
            continue
        if line.startswith("    ") and prev_blank and line.strip():
            start, body = i, []
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                body.append(lines[i][4:])
                i += 1
            if any(is_command(b) for b in body):
                blocks.append(Block(page, start - 1, "indented", body))
            prev_blank = False
            continue
        prev_blank = not line.strip()
        i += 1
    return blocks


def commands_of(block):
    """(line offset, command text, stdin text or None) of each command in a block."""
    transcript = any(l.startswith("$ ") for l in block.lines)
    out, i = [], 0
    while i < len(block.lines):
        raw = block.lines[i]
        start = i
        if transcript and not raw.startswith("$ "):
            i += 1
            continue
        text = raw[2:] if transcript else raw
        while text.endswith("\\") and i + 1 < len(block.lines):
            i += 1
            text = text[:-1] + " " + block.lines[i].strip()
        i += 1
        stdin = []
        while i < len(block.lines) and not block.lines[i].startswith("$ "):
            if block.lines[i].startswith("weaver> "):
                stdin.append(block.lines[i][len("weaver> "):])
            i += 1 if transcript else 0
            if not transcript:
                break
        if text.strip() and not text.strip().startswith("#"):
            out.append((start, text, "\n".join(stdin) + "\n" if stdin else None))
    return out


def smaller(cmd, scratch):
    def freq(m):
        return "--freq 0.1" if float(m.group(1)) >= 1 else m.group(0)

    cmd = re.sub(r"--freq[ =]([0-9.]+)", freq, cmd)
    cmd = re.sub(r"--memory[ =]([0-9]+)G\b", "--memory 64M", cmd)
    cmd = re.sub(r"(?<![\w/.])(/tmp|/shared|/work/runs)/", scratch + "/", cmd)
    cmd = re.sub(r"\./build/release/(weaver(-mpi)?)\b", r"\1", cmd)
    return cmd


def option_words(cmd):
    """The weaver command a line runs ('construct', 'model import', ...) and its --options."""
    try:
        words = shlex.split(cmd, comments=True)
    except ValueError:
        words = cmd.split()
    results = []
    for k, w in enumerate(words):
        base = w.rsplit("/", 1)[-1]
        if base not in ("weaver", "weaver-mpi") or k + 1 >= len(words):
            continue
        sub = [words[k + 1]]
        if sub[0] == "model" and k + 2 < len(words):
            sub.append(words[k + 2])
        rest = []
        for v in words[k + 1:]:
            if v in ("|", "&&", ";", ">", "2>", "<") or v.startswith(">"):
                break
            rest.append(v)
        opts = set()
        for v in rest:
            opts.update(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", v))
        # `weaver model import|material`: each alternative is a command of its own
        for alt in sub[-1].split("|"):
            results.append((base, sub[:-1] + [alt], opts))
    return results


def check_options(weaver, mpi, page, line, cmd, helps):
    for base, sub, opts in option_words(cmd):
        if sub[0].startswith("-"):
            continue
        binary = weaver if base == "weaver" else mpi
        if binary is None:
            continue
        key = (base, tuple(sub))
        if key not in helps:
            r = subprocess.run([binary] + sub + ["--help"], capture_output=True, text=True)
            if r.returncode != 0:
                fail(f"{page}:{line}: `{base} {' '.join(sub)}` is not a command "
                     f"({r.stderr.strip() or r.stdout.strip()})")
            helps[key] = r.stdout + r.stderr
        for o in sorted(opts):
            if o in ("--help", "--version"):
                continue
            if not re.search(re.escape(o) + r"(?![a-z0-9-])", helps[key]):
                fail(f"{page}:{line}: `{base} {' '.join(sub)}` shows {o}, "
                     f"which its --help does not name")


def inline_commands(page, text):
    """Inline code spans that start with `weaver CMD`: (line, span)."""
    out = []
    in_fence = False
    for n, line in enumerate(text.split("\n"), 1):
        if re.match(r"^\s*```", line):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        for span in re.findall(r"`([^`]+)`", line):
            if re.match(r"^(weaver|weaver-mpi) [a-z]", span):
                out.append((n, span.replace("\\|", "|")))
    return out


def make_inputs(scratch, source):
    for d in ("tests", "examples"):
        os.symlink(os.path.join(source, d), os.path.join(scratch, d))
    with open(os.path.join(scratch, "receivers.txt"), "w") as f:
        f.write("# x y z in metres\n30000 40000 500\n440 576 10\n51000 62000 1200\n")
    shutil.copy(os.path.join(scratch, "receivers.txt"), os.path.join(scratch, "points.txt"))
    with open(os.path.join(scratch, "stations.txt"), "w") as f:
        f.write("-118.2 34.0 500\n-118.5 33.7 0\n")
    shutil.copy(os.path.join(source, "tests/data/etree/cmu.e"), os.path.join(scratch, "labase.e"))


def shim_path(weaver, scratch):
    shims = os.path.join(scratch, ".bin")
    os.makedirs(shims)
    os.symlink(weaver, os.path.join(shims, "weaver"))
    mpi = os.path.join(os.path.dirname(weaver), "weaver-mpi")
    if os.path.exists(mpi):
        os.symlink(mpi, os.path.join(shims, "weaver-mpi"))
    os.symlink("/usr/bin/python3", os.path.join(shims, "python3"))
    return shims + os.pathsep + os.environ["PATH"]


def run_one(where, cmd, stdin, scratch, env):
    r = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], cwd=scratch, env=env, input=stdin,
                       capture_output=True, text=True, timeout=COMMAND_TIMEOUT)
    if r.returncode != 0:
        fail(f"{where}: exit {r.returncode}: {cmd}\n{r.stderr[-2000:]}")


def run_server_block(block, cmds, scratch, env):
    (off, first, _), rest = cmds[0], cmds[1:]
    if not re.match(r"^weaver serve\b", first):
        fail(f"{block.where(off)}: a server block starts with `weaver serve`, not {first!r}")
    if not rest:
        fail(f"{block.where(off)}: a server block asks at least one request")
    words = re.sub(r"--port[ =]\d+", "", first).split() + ["--port", "0", "--quiet"]
    server = subprocess.Popen(words, cwd=scratch, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)
    try:
        line = server.stdout.readline()
        m = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
        if not m:
            fail(f"{block.where(off)}: the server printed no URL: {line!r}")
        port = m.group(1)
        for o, cmd, stdin in rest:
            cmd = re.sub(r"(127\.0\.0\.1|localhost):8080", "127.0.0.1:" + port, cmd)
            run_one(block.where(o), cmd, stdin, scratch, env)
    finally:
        code = stop_server(server, timeout=30)
    if code is None:
        fail(f"{block.where(off)}: the server did not stop on SIGTERM")
    if code != 0:
        fail(f"{block.where(off)}: the server exited {code} on SIGTERM")


BAD_PAGES = {
    "unmarked.md": "```\nweaver stat x.db\n```\n",
    "indented.md": "Text.\n\n    weaver stat x.db\n",
    "option.md": "```sh no-run\nweaver stat x.db --no-such-option\n```\n",
    "inline.md": "Run `weaver export DB --no-such-option` to see.\n",
    "fails.md": "```sh run\nweaver stat no-such.db\n```\n",
    "server.md": "```sh run\nweaver mesh b.db --model basin --freq 0.05\n```\n\n"
                 "```sh server\nweaver serve b.db\ncurl -fsS http://127.0.0.1:8080/api/no-such\n```\n",
}


def self_test(weaver, source, work):
    """Each page of BAD_PAGES must fail the check, and a good one pass: the check can fail."""
    src = os.path.join(work, "self-test-source")
    os.makedirs(os.path.join(src, "docs"))
    for d in ("tests", "examples"):
        os.symlink(os.path.join(source, d), os.path.join(src, d))
    pages = dict(BAD_PAGES, **{"good.md": "```sh run\nweaver generate o.txt --leaves 100\n```\n"})
    for name, text in pages.items():
        with open(os.path.join(src, "docs", name), "w") as f:
            f.write(text)
        r = subprocess.run([sys.executable, __file__, weaver, src, os.path.join(work, "self-test-" + name),
                            "docs/" + name], capture_output=True, text=True, timeout=120)
        if (r.returncode == 0) != (name == "good.md"):
            fail(f"self-test: docs/{name} gave exit {r.returncode}: {r.stderr.strip() or r.stdout.strip()}")


def main():
    if len(sys.argv) < 4:
        fail("usage: check_docs.py WEAVER_BINARY SOURCE_DIR WORK_DIR [PAGE.md ...]")
    weaver, source, work = (os.path.abspath(a) for a in sys.argv[1:4])
    mpi = os.path.join(os.path.dirname(weaver), "weaver-mpi")
    mpi = mpi if os.path.exists(mpi) else None
    pages = sys.argv[4:] or (["README.md"] + sorted(
        os.path.join("docs", p) for p in os.listdir(os.path.join(source, "docs")) if p.endswith(".md")))
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    if not sys.argv[4:]:
        self_test(weaver, source, work)
    helps, started, timings, ran = {}, time.monotonic(), [], 0
    for page in pages:
        text = open(os.path.join(source, page)).read()
        for n, span in inline_commands(page, text):
            check_options(weaver, mpi, page, n, span, helps)
        blocks = read_blocks(page, text)
        scratch = os.path.join(work, page.replace("/", "_").replace(".md", ""))
        os.makedirs(scratch)
        make_inputs(scratch, source)
        env = dict(os.environ, PATH=shim_path(weaver, scratch), WEAVER_PROGRESS_SECONDS="3600")
        for b in blocks:
            marked = b.info in ("sh run", "sh no-run", "sh server")
            if not marked:
                for k, l in enumerate(b.lines):
                    if is_command(l):
                        kind = b.info or "no language"
                        fail(f"{b.where(k + 1)}: a command in an unmarked block ({kind}): "
                             "mark it ```sh run, ```sh no-run or ```sh server")
                continue
            cmds = commands_of(b)
            for off, cmd, _ in cmds:
                check_options(weaver, mpi, page, b.line + 2 + off, smaller(cmd, scratch)
                              if b.info != "sh no-run" else cmd, helps)
            if b.info == "sh no-run":
                continue
            cmds = [(o, smaller(c, scratch), s) for o, c, s in cmds]
            t0 = time.monotonic()
            if b.info == "sh run":
                for off, cmd, stdin in cmds:
                    run_one(b.where(off + 1), cmd, stdin, scratch, env)
            else:
                run_server_block(b, [(o + 1, c, s) for o, c, s in cmds], scratch, env)
            timings.append((time.monotonic() - t0, b.where()))
            ran += len(cmds)
            if time.monotonic() - started > BUDGET:
                slow = ", ".join(f"{w} {t:.1f} s" for t, w in sorted(timings, reverse=True)[:5])
                fail(f"past the budget of {BUDGET:.0f} s; the slowest blocks: {slow}")
    slow = ", ".join(f"{w} {t:.1f} s" for t, w in sorted(timings, reverse=True)[:5])
    print(f"check_docs: {ran} commands of {len(pages)} pages ran in "
          f"{time.monotonic() - started:.1f} s; the slowest blocks: {slow}")


if __name__ == "__main__":
    main()
