// The page of `weaver serve`, used as a person would: Debian's chromium,
// headless, driven by puppeteer-core against a server on 127.0.0.1.  It
// pans with the mouse, zooms with the wheel, the keys and a two-finger
// pinch, moves the plane, changes the colour and what a pixel of many
// elements shows, goes back in history, clicks an element and one of its
// neighbours, and checks each time what the URL, the tiles and the panels
// say, the panel against `weaver query element ID --format json`.  No page
// error, no failed request.  Screenshots go under the work directory (in
// build/) for a person to look at.
// usage: node check_page_interactive.mjs WEAVER WORK_DIR
import { execFileSync, spawn } from "node:child_process";
import fs from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";

const SKIP = 77;
const [weaver, work] = process.argv.slice(2);
const require = createRequire(import.meta.url);

// What must not outlive the check: the server and the browser.
const children = [];
function fail(message) {
  console.error("check_page_interactive: " + message);
  for (const c of children) c?.kill("SIGKILL");
  process.exit(1);
}

let puppeteer;
try {
  puppeteer = require("puppeteer-core");
} catch {
  if (process.env.WEAVER_REQUIRE_TOOLS) fail("puppeteer-core is not installed (npm ci in tests/tools/browser)");
  console.log("check_page_interactive: puppeteer-core is not installed: skipped");
  process.exit(SKIP);
}
const chromium = ["/usr/bin/chromium", "/usr/bin/chromium-browser"].find((p) => fs.existsSync(p));
if (!chromium) {
  if (process.env.WEAVER_REQUIRE_TOOLS) fail("chromium is not installed");
  console.log("check_page_interactive: chromium is not installed: skipped");
  process.exit(SKIP);
}
// The whole check, whatever happens.
setTimeout(() => fail("took more than 240 s"), 240000).unref();

fs.rmSync(work, { recursive: true, force: true });
fs.mkdirSync(work, { recursive: true });
const run = (...args) => execFileSync(weaver, args, { encoding: "utf8" });
const db = path.join(work, "basin.db");
run("mesh", db, "--model", "basin", "--freq", "0.1", "--quiet");
run("aggregate", db, "--quiet");

const server = spawn(weaver, ["serve", db, "--port", "0"], { stdio: ["ignore", "pipe", "inherit"] });
children.push(server);
const base = await new Promise((resolve, reject) => {
  server.stdout.once("data", (d) => {
    const m = /http:\/\/127\.0\.0\.1:(\d+)\//.exec(String(d));
    m ? resolve(`http://127.0.0.1:${m[1]}`) : reject(new Error(`no URL: ${d}`));
  });
});

const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  userDataDir: path.join(work, "profile"),
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
children.push(browser.process());
const problems = [];
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 800, hasTouch: true });
  page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
  page.on("console", (m) => m.type() === "error" && problems.push(`console: ${m.text()}`));
  page.on("response", (r) => r.status() >= 400 && problems.push(`${r.status()} for ${r.url()}`));

  const hash = () => page.evaluate(() => Object.fromEntries(new URLSearchParams(location.hash.slice(1))));
  const tiles = () => page.evaluate(() => [...document.querySelectorAll("#map img")].map((i) => i.dataset.src));
  const text = (id) => page.$eval(`#${id}`, (e) => e.textContent);
  // Every tile of the view laid out and loaded, 256 x 256.
  const loaded = () => page.waitForFunction(() => {
    const imgs = [...document.querySelectorAll("#map img")];
    return imgs.length > 0 && imgs.every((i) => i.complete && i.naturalWidth === 256);
  }, { timeout: 30000 });
  let shot = 0;
  // After an action the page fetches and draws on its own time (slowly under
  // the sanitizers): the check is asked again until it holds, for 20 s.
  const step = async (name, check) => {
    const until = Date.now() + 20000;
    for (;;) {
      await loaded();
      const h = await hash(), t = await tiles();
      const wrong = await check(h, t);
      if (!wrong) {
        console.log(`check_page_interactive: ${name}: ${t.length} tiles, ok`);
        break;
      }
      if (Date.now() > until) fail(`${name}: ${wrong}; URL ${JSON.stringify(h)}, tiles ${t.slice(0, 2)}`);
      await new Promise((r) => setTimeout(r, 50));
    }
    await page.screenshot({ path: path.join(work, `${String(++shot).padStart(2, "0")}-${name}.png`) });
  };
  const close = (a, b) => Math.abs(Number(a) - b) < 1e-6;

  await page.goto(`${base}/#axis=z&at=1000&color=vs&zoom=1&cu=0.5&cv=0.5`);
  await step("opened", async (h, t) => {
    if (await page.$eval("#sumlabel", (e) => e.hidden)) return "no choice of summary with an aggregate table";
    if (!(await text("note")).includes("least vs of the elements in each pixel")) return "the note";
    if (!t.every((s) => s.startsWith("/api/tile/z/1000/1/") && s.includes("color=vs"))) return "tiles";
  });

  const box = await (await page.$("#map")).boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx - 128, cy + 64, { steps: 8 });
  await page.mouse.up();
  // The map follows the pointer: 128 pixels left of 512 at zoom 1 puts the
  // centre a quarter further right, 64 down an eighth further up.
  await step("dragged", (h) => (!close(h.cu, 0.75) || !close(h.cv, 0.375) ? "the centre did not move so" : ""));

  await page.mouse.move(cx, cy);
  await page.mouse.wheel({ deltaY: -100 });
  await step("wheel", (h, t) => (h.zoom !== "2" || !t.every((s) => s.includes("/z/1000/2/")) ? "zoom 2" : ""));
  await page.keyboard.press("+");
  await step("plus", (h) => (h.zoom !== "3" ? "zoom 3" : ""));
  await page.keyboard.press("-");
  const before = Number((await hash()).cu);
  await page.keyboard.press("ArrowRight");
  await step("keys", (h) => (h.zoom !== "2" || !close(h.cu, before + 64 / 1024) ? "minus and the right arrow" : ""));

  await page.$eval("#atn", (e) => { e.value = "2000"; e.dispatchEvent(new Event("change")); });
  await step("plane", (h, t) => (h.at !== "2000" || !t.every((s) => s.startsWith("/api/tile/z/2000/")) ? "the plane" : ""));
  await page.select("#color", "level");
  await step("colour", async (h, t) => {
    if (h.color !== "level" || !t.every((s) => s.includes("color=level"))) return "colour by level";
    if (!(await text("note")).includes("finest level of the elements in each pixel")) return "the note";
  });
  await page.select("#summary", "centre");
  await step("summary", async (h, t) => {
    if (h.summary !== "centre" || !t.every((s) => s.includes("summary=centre"))) return "summary=centre";
    if (!(await text("note")).includes("level of the element at each pixel's centre")) return "the note";
  });
  await page.goBack();
  await step("back", async (h, t) => {
    if (h.summary || t.some((s) => s.includes("summary="))) return "back to the level's own summary";
    if (!(await text("note")).includes("finest level")) return "the note";
  });
  await page.goForward();
  await step("forward", (h) => (h.summary !== "centre" ? "forward to summary=centre" : ""));
  await page.click("#dang");
  await step("danglings", async (h, t) => {
    if (h.dang !== "1" || !t.every((s) => s.includes("&danglings=1"))) return "tiles with the dangling nodes";
    if (!(await text("note")).includes("dangling nodes on the plane")) return "the note";
  });

  // A click selects the element there: the one `weaver query locate`
  // finds, shown as `weaver query element` says.
  // The point under the click, from the URL's view and /api/section alone,
  // not from the page's own worldAt (a wrong transform would agree with
  // itself): the map's centre is the point (cu, cv) of the section's square,
  // u across from its left, v down from its top.
  const view = await hash();
  const section = await (await fetch(`${base}/api/section/${view.axis}/${view.at}?color=${view.color}`)).json();
  const along = (a) => "xyz".indexOf(a);
  const p = [0, 0, 0];
  p[along(view.axis)] = section.at_m;
  p[along(section.u)] = section.origin_m[0] + Number(view.cu) * section.side_m;
  p[along(section.v)] = section.down ? section.origin_m[1] + Number(view.cv) * section.side_m
    : section.origin_m[1] + (1 - Number(view.cv)) * section.side_m;
  await page.mouse.click(cx, cy);
  await page.waitForSelector("#selected", { timeout: 10000 });
  const hit = JSON.parse(run("query", db, "locate", ...p.map(String), "--units", "m", "--format", "json"));
  const expectElement = async (id) => {
    await page.waitForFunction((id) => document.querySelector("#selected")?.textContent === `element ${id}`,
      { timeout: 10000 }, id);
    const want = JSON.parse(run("query", db, "element", String(id), "--units", "m", "--format", "json"));
    const shown = await page.$$eval("#element tr", (rows) =>
      Object.fromEntries(rows.map((r) => [r.cells[0].textContent, r.cells[1].textContent])));
    for (const [k, v] of Object.entries(want)) {
      if (k !== "element" && shown[k] !== (Array.isArray(v) ? v.join(" ") : String(v))) {
        fail(`element ${id}: the panel shows ${k} = ${shown[k]}, weaver query says ${v}`);
      }
    }
  };
  await expectElement(hit.element);
  // The selected element is outlined on the map, around the point clicked.
  const around = () => page.$eval("#mark", (m, x, y) => {
    const r = m.getBoundingClientRect();
    return getComputedStyle(m).display !== "none" && r.left <= x + 1 && x <= r.right + 1 && r.top <= y + 1 && y <= r.bottom + 1;
  }, cx, cy);
  await step("clicked", async (h) => {
    if (h.sel !== String(hit.element)) return "the selection in the URL";
    if (!(await around())) return "the selected element's outline around the point clicked";
  });
  const neighbour = await page.$eval("#sel .id", (e) => e.dataset.id);
  await page.click("#sel .id");
  await expectElement(neighbour);
  await step("neighbour", (h) => (h.sel !== neighbour ? "the neighbour in the URL" : ""));

  // Two fingers apart, from 100 to 220 pixels: one zoom step in.
  const zoom = Number((await hash()).zoom);
  const cdp = await page.createCDPSession();
  const touch = (type, d) => cdp.send("Input.dispatchTouchEvent", {
    type, touchPoints: d === null ? [] : [{ x: cx - d, y: cy, id: 1 }, { x: cx + d, y: cy, id: 2 }],
  });
  await touch("touchStart", 50);
  for (const d of [70, 90, 110]) await touch("touchMove", d);
  await touch("touchEnd", null);
  await step("pinch", (h) => (Number(h.zoom) !== zoom + 1 ? `zoom ${h.zoom} after a pinch from ${zoom}` : ""));

  if (problems.length) fail(problems.slice(0, 5).join("; "));
  console.log(`check_page_interactive: panned, zoomed, moved the plane, recoloured, went back and forth, ` +
    `selected ${hit.element} and ${neighbour}, pinched; screenshots in ${work}`);
} finally {
  await browser.close();
  server.kill("SIGTERM");
}
