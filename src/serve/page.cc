// The page of `weaver serve`: a map of a cross-section made of the server's
// tiles, pannable and zoomable with the mouse, the wheel, touch and the
// keyboard, coloured by a field with its colour bar, with the coordinate
// under the pointer, the element under a click (and its neighbours, which
// are clickable), and the view kept in the URL.  Nothing is fetched from
// elsewhere, and nothing inline: the page, its style and its script are
// three answers, so that the Content-Security-Policy allows only this
// origin (Service::handle).
#include "serve/service.h"

namespace weaver::serve {

const char kPage[] = R"PAGE(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>weaver serve</title><link rel="icon" href="data:,">
<link rel="stylesheet" href="/page.css"></head><body>
<header>
<b>weaver</b>
<label>axis <select id="axis"><option>x</option><option>y</option><option selected>z</option></select></label>
<label>at <input id="at" type="range" step="any"> <input id="atn" type="number" step="any"> m</label>
<label>colour <select id="color"></select></label>
<label id="sumlabel" hidden>pixel <select id="summary"><option value="">own</option><option value="min">least</option><option value="max">greatest</option><option value="mean">mean</option><option value="centre">centre</option></select></label>
<label id="danglabel" title="the dangling nodes on the plane: red edge-dangling, white face-dangling; only a plane on element faces (z = 0, say) has nodes on it"><input type="checkbox" id="dang"> dangling nodes</label>
<span id="where"></span>
</header>
<main><div id="map"><canvas id="axes"></canvas></div>
<aside><div id="info"></div><canvas id="bar" width="300" height="46"></canvas><div id="note"></div><div id="sel">Click the map to select an element; shift and drag to download a region as vtu.</div></aside></main>
<script src="/page.js"></script></body></html>
)PAGE";

const char kPageCss[] =
    R"PAGE(body{margin:0;font:14px system-ui,sans-serif;display:flex;flex-direction:column;height:100vh}
header{display:flex;gap:12px;align-items:center;padding:6px 10px;background:#f3f3f3;flex-wrap:wrap}
main{flex:1;display:flex;min-height:0}
#map{flex:1;position:relative;overflow:hidden;background:#fff;cursor:grab;touch-action:none}
#map img{position:absolute;width:256px;height:256px;image-rendering:pixelated;user-select:none}
#axes{position:absolute;left:0;top:0;pointer-events:none}
aside{width:320px;overflow:auto;padding:8px 10px;border-left:1px solid #ddd}
#bar{display:block;margin:6px 0}
.id{color:#0645ad;cursor:pointer;text-decoration:underline}
table{border-collapse:collapse}td{padding:1px 6px 1px 0;vertical-align:top}
#where{font-family:monospace}
#at{width:220px}
#atn{width:90px}
)PAGE";

const char kPageJs[] = R"PAGE("use strict";
const $ = id => document.getElementById(id);
const map = $("map"), axesCanvas = $("axes");
let stat = null, sec = null;
const view = {axis: "z", at: 0, color: "level", summary: "", dang: "", zoom: 0, cu: 0.5, cv: 0.5, sel: ""};
const DEFAULTS = {...view};
const VIRIDIS = [[68,1,84],[72,40,120],[62,74,137],[49,104,142],[38,130,142],[31,158,137],[53,183,121],[110,206,88],[181,222,43],[253,231,37]];
const units = {level: "", edge: "m", vp: "m/s", vs: "m/s", rho: "kg/m^3", qp: "", qs: ""};

async function json(url) {
  const r = await fetch(url);
  const j = await r.json();
  if (!r.ok) throw new Error(j.error || r.statusText);
  return j;
}
function readHash() {
  const h = new URLSearchParams(location.hash.slice(1));
  // A key the URL leaves out has its default (writeHash leaves out the empty ones).
  for (const k of Object.keys(view)) view[k] = !h.has(k) ? DEFAULTS[k] : typeof DEFAULTS[k] === "number" ? Number(h.get(k)) : h.get(k);
}
function writeHash(push) {
  const h = new URLSearchParams();
  for (const [k, v] of Object.entries(view)) if (v !== "") h.set(k, typeof v === "number" ? +v.toPrecision(8) : v);
  const url = "#" + h.toString();
  if (url !== location.hash) (push ? history.pushState : history.replaceState).call(history, null, "", url);
}
function axisIndex(a) { return "xyz".indexOf(a); }
// The view that shows the section's part of the domain whole, as large as a
// whole zoom allows, in the middle of the map.
function fitView() {
  const fu = sec.extent_m[0] / sec.side_m, fv = sec.extent_m[1] / sec.side_m;
  const across = Math.min(map.clientWidth / (256 * fu), map.clientHeight / (256 * fv));
  view.zoom = Math.max(0, Math.min(24, Math.floor(Math.log2(across))));
  view.cu = fu / 2;
  view.cv = sec.down ? fv / 2 : 1 - fv / 2;
}
async function loadSection(push, fit) {
  const i = axisIndex(view.axis);
  const lo = stat.origin_m[i], hi = lo + stat.extent_m[i];
  $("at").min = $("atn").min = lo; $("at").max = $("atn").max = hi;
  if (!(view.at >= lo && view.at < hi)) view.at = lo + (hi - lo) / (view.axis === "z" ? 20 : 2);
  $("at").value = $("atn").value = view.at;
  $("axis").value = view.axis; $("color").value = view.color; $("summary").value = view.summary;
  $("dang").checked = view.dang !== "";
  try { sec = await json(`/api/section/${view.axis}/${view.at}?${paintQuery()}`); }
  catch (e) { $("note").textContent = e.message; return; }
  if (fit) fitView();
  writeHash(push);
  drawBar(); draw();
}
// The colour and what a pixel of many elements shows, as the API takes them.
function paintQuery() { return `color=${view.color}` + (view.summary ? `&summary=${view.summary}` : ""); }
function tileQuery() { return paintQuery() + `&min=${sec.min}&max=${sec.max}` + (view.dang ? "&danglings=1" : ""); }
function tileSize() { return 256; }
function worldPerPixel() { return sec.side_m / (256 * 2 ** view.zoom); }
function draw() {
  if (!sec) return;
  const w = map.clientWidth, h = map.clientHeight, z = view.zoom, n = 2 ** z;
  const full = 256 * n;  // pixels across the whole section at this zoom
  const left = w / 2 - view.cu * full, top = h / 2 - view.cv * full;
  const want = new Set();
  for (let ty = Math.max(0, Math.floor(-top / 256)); ty < Math.min(n, Math.ceil((h - top) / 256)); ty++)
    for (let tx = Math.max(0, Math.floor(-left / 256)); tx < Math.min(n, Math.ceil((w - left) / 256)); tx++) {
      const src = `/api/tile/${view.axis}/${view.at}/${z}/${tx}/${ty}.png?${tileQuery()}`;
      want.add(src);
      let img = map.querySelector(`img[data-src="${CSS.escape(src)}"]`);
      if (!img) { img = new Image(); img.dataset.src = src; img.src = src; img.draggable = false; map.insertBefore(img, axesCanvas); }
      img.style.left = (left + tx * 256) + "px"; img.style.top = (top + ty * 256) + "px";
    }
  for (const img of [...map.querySelectorAll("img")]) if (!want.has(img.dataset.src)) img.remove();
  drawAxes(left, top, full);
  drawMark(left, top, full);
}
// The selected element's outline, where it meets the plane.
let selected = null;  // its corner and edge, metres: {x, y, z, edge}
const mark = document.createElement("div");
mark.id = "mark";
mark.style.cssText = "position:absolute;border:2px solid #e00;pointer-events:none;display:none;box-sizing:border-box";
map.appendChild(mark);
function drawMark(left, top, full) {
  const e = selected, a = view.axis;
  if (!e || !sec || !(sec.at_m >= e[a] && sec.at_m < e[a] + e.edge)) return void (mark.style.display = "none");
  const px = full / sec.side_m;  // pixels a metre
  const x = left + (e[sec.u] - sec.origin_m[0]) * px;
  const v0 = sec.down ? e[sec.v] - sec.origin_m[1] : sec.origin_m[1] + sec.side_m - e[sec.v] - e.edge;
  const size = Math.max(e.edge * px, 4);
  Object.assign(mark.style, {display: "block", left: x + "px", top: top + v0 * px + "px", width: size + "px", height: size + "px"});
}
function niceStep(span, n) {
  const raw = span / n, p = 10 ** Math.floor(Math.log10(raw));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}
function drawAxes(left, top, full) {
  const w = map.clientWidth, h = map.clientHeight, c = axesCanvas;
  c.width = w; c.height = h;
  const g = c.getContext("2d");
  g.font = "11px system-ui"; g.fillStyle = "#000"; g.strokeStyle = "#000";
  const km = sec.side_m >= 2000, unit = km ? 1000 : 1;
  const perPx = sec.side_m / full;
  // u along the bottom, v along the left; v counts down the page in sections.
  const u0 = sec.origin_m[0] + (0 - left) * perPx, u1 = sec.origin_m[0] + (w - left) * perPx;
  let step = niceStep((u1 - u0) / unit, 6) * unit;
  for (let u = Math.ceil(u0 / step) * step; u <= u1; u += step) {
    const x = left + (u - sec.origin_m[0]) / perPx;
    g.fillRect(x, h - 14, 1, 5); g.fillText((u / unit).toPrecision(4).replace(/\.?0+$/, ""), x + 2, h - 2);
  }
  const vAt = py => sec.down ? sec.origin_m[1] + (py - top) * perPx : sec.origin_m[1] + sec.side_m - (py - top) * perPx;
  const va = vAt(0), vb = vAt(h), v0 = Math.min(va, vb), v1 = Math.max(va, vb);
  step = niceStep((v1 - v0) / unit, 6) * unit;
  for (let v = Math.ceil(v0 / step) * step; v <= v1; v += step) {
    const y = sec.down ? top + (v - sec.origin_m[1]) / perPx : top + (sec.origin_m[1] + sec.side_m - v) / perPx;
    g.fillRect(0, y, 5, 1); g.fillText((v / unit).toPrecision(4).replace(/\.?0+$/, ""), 7, y + 4);
  }
  g.fillText(`${sec.u} (${km ? "km" : "m"}) →`, w - 70, h - 18);
  g.fillText(`${sec.v} (${km ? "km" : "m"})${sec.down ? ", down ↓" : " ↑"}`, 7, 12);
}
function viridis(t) {
  t = Math.min(Math.max(t, 0), 1) * 9; const i = Math.min(8, Math.floor(t)), f = t - i;
  return VIRIDIS[i].map((a, k) => Math.round(a + (VIRIDIS[i + 1][k] - a) * f));
}
function drawBar() {
  const g = $("bar").getContext("2d");
  g.clearRect(0, 0, 300, 46);
  for (let x = 0; x < 300; x++) { g.fillStyle = `rgb(${viridis(x / 299)})`; g.fillRect(x, 0, 1, 20); }
  g.fillStyle = "#000"; g.font = "12px system-ui";
  const u = units[view.color] ? " " + units[view.color] : "";
  g.fillText(`${+sec.min.toPrecision(5)}${u}`, 0, 36);
  const t = `${+sec.max.toPrecision(5)}${u}`; g.fillText(t, 300 - g.measureText(t).width, 36);
  $("note").textContent = `${sec.caption}, on the ${view.axis} = ${+sec.at_m.toPrecision(8)} m plane; colour range over the section (${sec.samples} pixels)` +
    (view.dang ? "; dangling nodes on the plane marked on elements 6 pixels wide or more (red: edge, white: face)" : "") +
    // Without the aggregate table a pixel of many elements shows one of them:
    // small features (the basin's 40 m inclusions) vanish at coarse zooms.
    (stat.aggregates === null && stat.kind === "mesh" ? ". Each pixel shows the element at its centre: " +
      "'weaver aggregate DB' adds the summaries (the least vs of the elements in a pixel)" : "");
}
function worldAt(px, py) {
  const full = 256 * 2 ** view.zoom, perPx = sec.side_m / full;
  const left = map.clientWidth / 2 - view.cu * full, top = map.clientHeight / 2 - view.cv * full;
  const u = sec.origin_m[0] + (px - left) * perPx;
  const v = sec.down ? sec.origin_m[1] + (py - top) * perPx : sec.origin_m[1] + sec.side_m - (py - top) * perPx;
  const p = [0, 0, 0]; p[axisIndex(view.axis)] = sec.at_m; p[axisIndex(sec.u)] = u; p[axisIndex(sec.v)] = v;
  return p;
}
function fmt(p) { return p.map(v => (+v.toFixed(2)).toString()).join(", "); }
async function select(id) {
  view.sel = String(id); writeHash(false);
  try {
    const e = await json(`/api/element/${id}?units=m`);
    const nb = await json(`/api/neighbors/${id}?units=m`);
    selected = {x: e.x, y: e.y, z: e.z, edge: e.edge};
    draw();
    let html = `<h3 id="selected">element ${e.element}</h3><table id="element">`;
    for (const [k, v] of Object.entries(e)) if (k !== "element") html += `<tr><td>${k}</td><td>${Array.isArray(v) ? v.join(" ") : v}</td></tr>`;
    html += `</table><p>face neighbours:</p><table>`;
    for (const n of nb) html += `<tr><td>${n.across}</td><td><span class="id" data-id="${n.element}">${n.element}</span></td><td>level ${n.level}</td></tr>`;
    $("sel").innerHTML = html + "</table>";
  } catch (err) { $("sel").textContent = err.message; }
}
$("sel").addEventListener("click", ev => { const id = ev.target.dataset && ev.target.dataset.id; if (id) select(id); });
let drag = null, moved = false, boxing = null;
const boxDiv = document.createElement("div");
boxDiv.style.cssText = "position:absolute;border:2px dashed #d00;pointer-events:none;display:none";
map.appendChild(boxDiv);
// Two fingers pinch: the zoom steps by one each time their distance doubles
// or halves, about the point between them.
const touches = new Map();
let pinch = null;
function pinchState() {
  const [a, b] = [...touches.values()];
  return {d: Math.hypot(a.x - b.x, a.y - b.y), x: (a.x + b.x) / 2, y: (a.y + b.y) / 2};
}
map.addEventListener("pointerdown", ev => {
  map.setPointerCapture(ev.pointerId);
  const r = map.getBoundingClientRect();
  touches.set(ev.pointerId, {x: ev.clientX - r.left, y: ev.clientY - r.top});
  if (touches.size === 2) { pinch = {...pinchState(), zoom: view.zoom}; drag = null; return; }
  if (ev.shiftKey) { boxing = {x: ev.clientX - r.left, y: ev.clientY - r.top}; return; }
  drag = {x: ev.clientX, y: ev.clientY, cu: view.cu, cv: view.cv}; moved = false;
});
// The pointer's place in metres and, on a georeferenced mesh, its longitude
// and latitude: asked of the server at most every 100 ms.
let geoWanted = null, geoBusy = false;
function showWhere(p) {
  $("where").textContent = `(${fmt(p)}) m`;
  if (!stat.geo) return;
  geoWanted = p;
  if (geoBusy) return;
  geoBusy = true;
  setTimeout(async () => {
    const q = geoWanted;
    try {
      const g = await json(`/api/geo?x=${q[0]}&y=${q[1]}`);
      if (q === geoWanted) $("where").textContent = `(${fmt(q)}) m, ${g.lon.toFixed(5)}° ${g.lat.toFixed(5)}°, depth ${+q[2].toPrecision(6)} m`;
    } catch (e) { /* the metres stay */ }
    geoBusy = false;
  }, 100);
}
// Shift and drag: the elements the box cuts on this plane, downloaded as vtu.
async function exportBox(a, b) {
  const p = worldAt(a.x, a.y), q = worldAt(b.x, b.y);
  const box = [0, 1, 2].map(i => [Math.min(p[i], q[i]), Math.max(p[i], q[i])]);
  const url = `/api/export.vtu?box=${box.map(v => v[0]).join(",")},${box.map(v => v[1]).join(",")}`;
  $("sel").textContent = "exporting the region ...";
  try {
    const r = await fetch(url);
    if (!r.ok) throw new Error((await r.json()).error);
    const a = document.createElement("a");
    a.href = URL.createObjectURL(await r.blob()); a.download = "region.vtu"; a.click();
    $("sel").textContent = `region.vtu: (${fmt(box.map(v => v[0]))}) to (${fmt(box.map(v => v[1]))}) m`;
  } catch (err) { $("sel").textContent = err.message; }
}
map.addEventListener("pointermove", ev => {
  const r = map.getBoundingClientRect();
  if (touches.has(ev.pointerId)) touches.set(ev.pointerId, {x: ev.clientX - r.left, y: ev.clientY - r.top});
  if (pinch && touches.size === 2) {
    const now = pinchState(), z = pinch.zoom + Math.round(Math.log2(now.d / pinch.d));
    if (z !== view.zoom) zoomAt(z - view.zoom, now.x, now.y);
    return;
  }
  if (sec) showWhere(worldAt(ev.clientX - r.left, ev.clientY - r.top));
  if (boxing) {
    const x = ev.clientX - r.left, y = ev.clientY - r.top;
    Object.assign(boxDiv.style, {display: "block", left: Math.min(x, boxing.x) + "px", top: Math.min(y, boxing.y) + "px",
      width: Math.abs(x - boxing.x) + "px", height: Math.abs(y - boxing.y) + "px"});
    return;
  }
  if (!drag) return;
  const full = 256 * 2 ** view.zoom;
  if (Math.abs(ev.clientX - drag.x) + Math.abs(ev.clientY - drag.y) > 3) moved = true;
  view.cu = drag.cu - (ev.clientX - drag.x) / full; view.cv = drag.cv - (ev.clientY - drag.y) / full;
  draw();
});
map.addEventListener("pointercancel", ev => { touches.delete(ev.pointerId); pinch = null; drag = null; });
map.addEventListener("pointerup", async ev => {
  touches.delete(ev.pointerId);
  if (pinch) { if (touches.size < 2) { pinch = null; writeHash(false); } return; }
  if (boxing) {
    const r = map.getBoundingClientRect(), b = {x: ev.clientX - r.left, y: ev.clientY - r.top};
    const a = boxing; boxing = null; boxDiv.style.display = "none";
    if (Math.abs(b.x - a.x) + Math.abs(b.y - a.y) > 4) exportBox(a, b);
    return;
  }
  drag = null;
  if (moved) return writeHash(false);
  const r = map.getBoundingClientRect(), p = worldAt(ev.clientX - r.left, ev.clientY - r.top);
  try {
    const h = await json(`/api/locate?x=${p[0]}&y=${p[1]}&z=${p[2]}&units=m`);
    if (h.status === "inside") select(h.element); else $("sel").textContent = `(${fmt(p)}) m is outside the mesh`;
  } catch (err) { $("sel").textContent = err.message; }
});
function zoomAt(dz, px, py) {
  const z = Math.min(24, Math.max(0, view.zoom + dz));
  if (z === view.zoom) return;
  const full = 256 * 2 ** view.zoom, w = map.clientWidth, h = map.clientHeight;
  const fu = view.cu + (px - w / 2) / full, fv = view.cv + (py - h / 2) / full;
  const s = 2 ** (view.zoom - z);
  view.cu = fu - (fu - view.cu) * s; view.cv = fv - (fv - view.cv) * s; view.zoom = z;
  writeHash(false); draw();
}
map.addEventListener("wheel", ev => { ev.preventDefault(); const r = map.getBoundingClientRect(); zoomAt(ev.deltaY < 0 ? 1 : -1, ev.clientX - r.left, ev.clientY - r.top); }, {passive: false});
document.addEventListener("keydown", ev => {
  if (ev.target.tagName === "INPUT" || ev.target.tagName === "SELECT") return;
  const step = 64 / (256 * 2 ** view.zoom), w = map.clientWidth / 2, h = map.clientHeight / 2;
  if (ev.key === "+" || ev.key === "=") zoomAt(1, w, h);
  else if (ev.key === "-") zoomAt(-1, w, h);
  else if (ev.key === "ArrowLeft") view.cu -= step; else if (ev.key === "ArrowRight") view.cu += step;
  else if (ev.key === "ArrowUp") view.cv -= step; else if (ev.key === "ArrowDown") view.cv += step;
  else return;
  writeHash(false); draw();
});
$("axis").onchange = () => { view.axis = $("axis").value; view.at = NaN; loadSection(true, true); };
$("at").onchange = () => { view.at = Number($("at").value); loadSection(true); };
$("at").oninput = () => { $("atn").value = $("at").value; };
$("atn").onchange = () => { view.at = Number($("atn").value); loadSection(true); };
$("color").onchange = () => { view.color = $("color").value; loadSection(true); };
$("summary").onchange = () => { view.summary = $("summary").value; loadSection(true); };
$("dang").onchange = () => { view.dang = $("dang").checked ? "1" : ""; writeHash(true); drawBar(); draw(); };
const HINT = $("sel").textContent;
window.addEventListener("popstate", () => { readHash(); loadSection(false).then(() => { if (view.sel !== "") select(view.sel); else { $("sel").textContent = HINT; selected = null; draw(); } }); });
window.addEventListener("resize", draw);
(async () => {
  try { stat = await json("/api/stat"); } catch (e) { $("info").textContent = e.message; return; }
  const counts = stat.kind === "model" ? `${stat.elements} cells of a velocity model` : `${stat.elements} elements, ${stat.nodes} nodes`;
  $("info").innerHTML = `<b>${stat.database.replace(/[&<>]/g, "")}</b><br>${counts}`;
  for (const f of stat.fields) $("color").add(new Option(f, f));
  $("sumlabel").hidden = stat.aggregates === null;  // summaries need the aggregate table
  $("danglabel").hidden = stat.nodes === 0;  // a mesh's nodes
  readHash();
  if (!stat.fields.includes(view.color)) view.color = stat.fields.includes("vs") ? "vs" : "level";
  const fresh = !location.hash;  // no view asked: open on the domain's extent
  if (fresh) view.color = stat.fields.includes("vs") ? "vs" : "level";
  await loadSection(false, fresh);
  if (view.sel !== "") select(view.sel);  // a shared link's selected element
})();
)PAGE";

}  // namespace weaver::serve
