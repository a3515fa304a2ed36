// The first paint of weaver serve's page: from the navigation to the last
// tile of the first view loaded, in Debian's chromium (headless, driven by
// puppeteer-core from tests/tools/browser: npm ci there first), against a
// server started here on the database given.  Each run opens a fresh page
// (the browser's cache emptied); the first runs meet the server's threads
// cold.  Prints a JSON line a run, then the median, the 95th percentile and
// the slowest.
// usage: node bench/page_bench.mjs WEAVER DB [--repeat N] [--view HASH]
//   e.g. node bench/page_bench.mjs build/release/weaver basin-2Hz.db --repeat 10
import { spawn } from "node:child_process";
import fs from "node:fs";
import { createRequire } from "node:module";
import os from "node:os";
import path from "node:path";

const require = createRequire(import.meta.url);
const puppeteer = require("../tests/tools/browser/node_modules/puppeteer-core");
const args = process.argv.slice(2);
const [weaver, db] = args;
const option = (name, fallback) => (args.includes(name) ? args[args.indexOf(name) + 1] : fallback);
const repeat = Number(option("--repeat", "10"));
const view = option("--view", "");  // "" : the page's own first view
if (!weaver || !db) {
  console.error("usage: node bench/page_bench.mjs WEAVER DB [--repeat N] [--view HASH]");
  process.exit(2);
}

const server = spawn(weaver, ["serve", db, "--port", "0"], { stdio: ["ignore", "pipe", "inherit"] });
const base = await new Promise((resolve, reject) => {
  server.stdout.once("data", (d) => {
    const m = /http:\/\/127\.0\.0\.1:(\d+)\//.exec(String(d));
    m ? resolve(`http://127.0.0.1:${m[1]}`) : reject(new Error(`no URL: ${d}`));
  });
});
const profile = fs.mkdtempSync(path.join(os.tmpdir(), "weaver-page-bench-"));
const browser = await puppeteer.launch({
  executablePath: "/usr/bin/chromium",
  headless: true,
  userDataDir: profile,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const times = [];
try {
  for (let r = 0; r < repeat; ++r) {
    const page = await browser.newPage();
    await page.setCacheEnabled(false);
    await page.setViewport({ width: 1200, height: 800 });
    const t0 = performance.now();
    await page.goto(`${base}/${view ? "#" + view : ""}`);
    await page.waitForFunction(() => {
      const imgs = [...document.querySelectorAll("#map img")];
      return imgs.length > 0 && imgs.every((i) => i.complete && i.naturalWidth === 256);
    }, { timeout: 60000, polling: 5 });
    const ms = performance.now() - t0;
    const tiles = await page.evaluate(() => document.querySelectorAll("#map img").length);
    times.push(ms);
    console.log(JSON.stringify({ bench: "page", db, run: r, first_paint_ms: +ms.toFixed(1), tiles }));
    await page.close();
  }
} finally {
  await browser.close();
  server.kill("SIGTERM");
  fs.rmSync(profile, { recursive: true, force: true });
}
times.sort((a, b) => a - b);
const at = (q) => times[Math.min(times.length - 1, Math.floor(times.length * q))];
console.log(`\n${db}: first paint of the page (navigation to the last tile loaded), ${repeat} fresh pages`);
console.log(`median ${at(0.5).toFixed(0)} ms, 95th percentile ${at(0.95).toFixed(0)} ms, ` +
  `slowest ${times[times.length - 1].toFixed(0)} ms`);
