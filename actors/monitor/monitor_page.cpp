// The monitor's page: everything it needs is here (no scripts or styles from elsewhere, so it works offline).
// It listens to /events, draws the lighting network (a band per host, columns by depth from the renderers), the
// actors' figures, the image as tiles land, the phases, setup steps and the log.
// Elements carry data-* attributes (actor, state, tiles) so that tests read the page as a browser shows it.
#include "actors/monitor/monitor.hpp"

namespace lf {

const char* const kMonitorPage = R"PAGE(<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>lightfarm monitor</title>
<style>
body { font: 13px/1.4 system-ui, sans-serif; margin: 0; background: #14161a; color: #d8dce3; }
header { padding: 8px 14px; background: #1d2026; display: flex; gap: 24px; align-items: baseline; flex-wrap: wrap; }
header h1 { font-size: 15px; margin: 0; }
main { display: grid; grid-template-columns: minmax(420px, 1fr) minmax(320px, 1fr); gap: 12px; padding: 12px; }
section { background: #1d2026; border-radius: 6px; padding: 8px 10px; overflow: auto; }
h2 { font-size: 13px; margin: 0 0 6px; color: #9aa3b2; font-weight: 600; }
table { border-collapse: collapse; width: 100%; }
td, th { padding: 2px 6px; text-align: right; white-space: nowrap; }
td:first-child, th:first-child, td.l, th.l { text-align: left; }
tr[data-state=lost] td { color: #ff6b6b; }
.bar { height: 6px; background: #2c313a; border-radius: 3px; }
.bar > div { height: 6px; background: #5fb3ff; border-radius: 3px; }
#log { font-family: ui-monospace, monospace; font-size: 12px; max-height: 260px; }
#log .warning { color: #f2c94c; } #log .error, #log .loss { color: #ff6b6b; } #log .recovery { color: #6fcf97; }
canvas { image-rendering: pixelated; max-width: 100%; background: #000; }
svg text { fill: #d8dce3; font-size: 11px; }
.state-launching { fill: #4a4f5a; } .state-configuring, .state-setup { fill: #7a6a2a; }
.state-ready { fill: #33546e; } .state-rendering { fill: #2f6b45; } .state-done { fill: #3b3f47; }
.state-lost { fill: #8a2f2f; } .state-restarting { fill: #8a5a2f; } .state-pool { fill: #2b3340; }
</style>
</head>
<body>
<header><h1>lightfarm</h1><span id="script"></span><span>stage <b id="stage">-</b></span>
<span id="elapsed"></span><span id="tiles"></span><span id="connection">connecting</span></header>
<main>
<section><h2>Network</h2><svg id="graph" width="100%" height="200"></svg></section>
<section><h2>Image</h2><canvas id="preview" data-tiles="0" data-checksum="0" data-updates="0" width="1" height="1"></canvas></section>
<section style="grid-column: 1 / span 2"><h2>Actors</h2><table><thead><tr><th>actor</th><th class="l">kind</th><th class="l">host</th>
<th class="l">state</th><th>busy</th><th>requests/s</th><th>points/s</th><th>queue</th><th>in flight</th><th>MiB in</th><th>MiB out</th><th>pid</th>
</tr></thead><tbody id="actors"></tbody></table></section>
<section><h2>Phases</h2><table id="stages"></table><h2 style="margin-top:10px">Setup</h2><table id="progress"></table><div id="radiosity"></div></section>
<section><h2>Log</h2><div id="log"></div></section>
</main>
<script>
"use strict";
const query = location.search, params = new URLSearchParams(query);
// The whole image as a preview event (a page that has none yet).
const wholePreviewUrl = "/api/preview" + query + (query ? "&" : "?") + "format=json";
const $ = id => document.getElementById(id);
const esc = s => String(s).replace(/[&<>"]/g, c => ({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c]));
const num = (v, d = 0) => (typeof v === "number" && Number.isFinite(v) ? v.toFixed(d) : "-");

function drawGraph(actors) {
  const byName = new Map(actors.map(a => [a.name, a]));
  const depth = new Map();
  const visit = (a, d) => {
    if ((depth.get(a.name) ?? -1) >= d) return;
    depth.set(a.name, d);
    for (const i of [...a.inputs, ...(a.rays_from || [])]) if (byName.has(i)) visit(byName.get(i), d + 1);
  };
  for (const a of actors) if (a.kind === "renderer") visit(a, 0);
  for (const a of actors) if (!depth.has(a.name)) visit(a, 0);
  // One band per host, top to bottom; in a band, columns by depth from the renderers.
  const hosts = [...new Set(actors.map(a => a.host))];
  const w = 130, h = 34, gap = 14, labelW = 60, at = new Map();
  let top = 10, bands = "";
  for (const host of hosts) {
    const rows = [];
    for (const a of actors.filter(a => a.host === host)) {
      const d = depth.get(a.name);
      rows[d] = (rows[d] ?? 0) + 1;
      at.set(a.name, {x: labelW + 10 + d * (w + 30), y: top + 8 + (rows[d] - 1) * (h + gap)});
    }
    const height = 16 + Math.max(1, ...rows.filter(r => r)) * (h + gap) - gap;
    bands += `<g class="host" data-host="${esc(host)}"><rect x="2" y="${top}" width="99.5%" height="${height}" rx="6" ` +
      `fill="#23272e" /><text x="10" y="${top + 18}" opacity="0.8">${esc(host)}</text></g>`;
    top += height + 8;
  }
  let svg = bands;
  for (const a of actors)
    for (const i of a.inputs) {
      const p = at.get(a.name), q = at.get(i);
      if (p && q) svg += `<line x1="${p.x + w}" y1="${p.y + h / 2}" x2="${q.x}" y2="${q.y + h / 2}" stroke="#566" />`;
    }
  for (const a of actors)  // a partitioned scene's parts, answering rays (dotted, as lightfarm graph draws them)
    for (const g of a.rays_from || []) {
      const p = at.get(a.name), q = at.get(g);
      if (p && q) svg += `<line class="rays" x1="${p.x + w}" y1="${p.y + h / 2}" x2="${q.x}" y2="${q.y + h / 2}" ` +
        `stroke="#566" stroke-dasharray="2 3" />`;
    }
  for (const a of actors) {
    const p = at.get(a.name);
    svg += `<g class="node" data-actor="${esc(a.name)}" data-state="${esc(a.state)}">` +
      `<rect x="${p.x}" y="${p.y}" width="${w}" height="${h}" rx="5" class="state-${esc(a.state)}" />` +
      `<text x="${p.x + 6}" y="${p.y + 14}">${esc(a.name)}</text>` +
      `<text x="${p.x + 6}" y="${p.y + 28}" opacity="0.7">${esc(a.kind)} · ${esc(a.state)}</text></g>`;
  }
  const right = Math.max(400, ...[...at.values()].map(p => p.x + w + 10));
  $("graph").setAttribute("height", top);
  $("graph").setAttribute("width", right);
  $("graph").innerHTML = svg;
}

// Sets what changed only: a page a browser keeps open costs its machine CPU for every node it restyles and repaints.
function setText(el, text) { if (el.textContent !== text) el.textContent = text; }
const shown = new WeakMap();  // element -> the markup it was last given
function setHtml(el, html) { if (shown.get(el) !== html) { shown.set(el, html); el.innerHTML = html; } }

// The actors' table, a row per actor updated cell by cell; rebuilt only when the actors themselves change.
function renderActors(actors) {
  const body = $("actors");
  const names = actors.map(a => a.name).join("\n");
  if (shown.get(body) !== names) {
    shown.set(body, names);
    body.textContent = "";
    for (const a of actors) {
      const tr = body.insertRow();
      tr.dataset.actor = a.name;
      tr.dataset.state = a.state;
      for (let c = 0; c < 12; ++c) tr.insertCell().className = c >= 1 && c <= 3 ? "l" : "";
    }
  }
  actors.forEach((a, i) => {
    const tr = body.rows[i], live = a.live || {}, rate = a.rates || {};
    if (tr.dataset.state !== a.state) tr.dataset.state = a.state;
    const cells = [a.name, a.kind, a.host, a.state + (a.loss ? " — " + a.loss : ""),
      rate.busy_share === undefined ? "-" : num(100 * rate.busy_share) + "%", num(rate.requests_per_second, 1),
      num(rate.points_per_second), String(live.queue ?? "-"), String(live.in_flight ?? "-"),
      num((live.bytes_in ?? NaN) / 1048576, 1), num((live.bytes_out ?? NaN) / 1048576, 1), String(a.pid ?? "")];
    cells.forEach((text, c) => setText(tr.cells[c], text));
  });
}

function render(s) {
  const f = s.farm || {};
  setText($("script"), f.script || "");
  setText($("stage"), f.stage || "-");
  setText($("elapsed"), num(f.elapsed_seconds, 1) + " s");
  // A job of frames: which frame, how many are done, and what the rest should take.
  const j = s.job;
  const job = j ? `frame ${j.frame || "-"}${j.frames_in_flight > 1 ? " and the next" : ""} (${j.frames_done} of ${j.frames_total} done` +
    (j.eta_seconds === undefined ? ") · " : `, ~${num(j.eta_seconds)} s left) · `) : "";
  setText($("tiles"), job + `tiles ${f.tiles_done ?? 0} / ${f.tiles_total ?? 0}`);
  const actors = s.actors || [];
  const graphKey = actors.map(a => a.name + ":" + a.state + ":" + a.inputs.join(",") + ":" + (a.rays_from || []).join(",")).join(";");
  if (graphKey !== lastGraph) { lastGraph = graphKey; drawGraph(actors); }
  renderActors(actors);
  setHtml($("stages"), (s.stages || []).map(t => `<tr><td>${esc(t.name)}</td><td>${num(t.seconds, 3)} s</td></tr>`).join(""));
  setHtml($("progress"), (s.progress || []).map(p => `<tr><td>${esc(p.actor)}</td><td class="l">${esc(p.what)}</td>` +
    `<td style="width:40%"><div class="bar"><div style="width:${(100 * p.done / Math.max(1, p.total)).toFixed(1)}%"></div></div></td>` +
    `<td>${p.done} / ${p.total}</td></tr>`).join(""));
  const rad = s.radiosity;
  setHtml($("radiosity"), rad && rad.unshot_fraction.length ? (() => {
    const u = rad.unshot_fraction, w = 300, h = 60, top = Math.max(...u, 1e-9);
    const pts = u.map((v, i) => `${(w * i / Math.max(1, u.length - 1)).toFixed(1)},${(h - h * v / top).toFixed(1)}`).join(" ");
    return `radiosity: ${rad.iterations} iterations, unshot ${(100 * u[u.length - 1]).toFixed(2)} %<br>` +
      `<svg width="${w}" height="${h}"><polyline fill="none" stroke="#5fb3ff" points="${pts}" /></svg>`;
  })() : "");
  const lines = s.log || [];
  const logKey = lines.length + ":" + (lines.length ? lines[lines.length - 1].seconds : 0);
  if (logKey !== lastLog) {
    lastLog = logKey;
    $("log").innerHTML = lines.map(l => `<div class="${esc(l.kind)}">${num(l.seconds, 1)} s  ${esc(l.text)}</div>`).join("");
  }
}
let lastGraph = "", lastLog = "";

// The image: a whole one first, then the blocks that changed (each event says which version it builds on).
// data-checksum is the sum over the shown pixels' bytes (in /api/preview's order) of byte k times (k mod 251) + 1,
// so that a misplaced block shows; data-updates the count of partial updates applied, for
// tests that look at the page.
let previewVersion = 0, previewImage = null, previewSum = 0, previewUpdates = 0;
function preview(p) {
  if (p.version <= previewVersion) return;
  const c = $("preview");
  if (p.base === 0) {
    if (c.width !== p.width || c.height !== p.height) { c.width = p.width; c.height = p.height; }
    previewImage = new ImageData(p.width, p.height);
    for (let j = 3; j < previewImage.data.length; j += 4) previewImage.data[j] = 255;
    previewSum = 0;
  } else if (p.base !== previewVersion || !previewImage) {
    // Changes to an image this page does not hold (cannot happen on one stream): take the whole image instead.
    fetch(wholePreviewUrl).then(r => r.json()).then(q => { if (q.patches) preview(q); });
    return;
  }
  const ctx = c.getContext("2d"), data = previewImage.data, width = p.width;
  for (const q of p.patches) {
    const bytes = atob(q.rgb);
    if (bytes.length !== q.w * q.h * 3 || q.x < 0 || q.y < 0 || q.x + q.w > p.width || q.y + q.h > p.height) continue;
    for (let y = q.y, i = 0; y < q.y + q.h; ++y)
      for (let j = (y * width + q.x) * 4, end = j + q.w * 4; j < end; j += 4, i += 3) {
        const r = bytes.charCodeAt(i), g = bytes.charCodeAt(i + 1), b = bytes.charCodeAt(i + 2);
        const k = (j >> 2) * 3;  // the byte's place in /api/preview
        previewSum += (r - data[j]) * (k % 251 + 1) + (g - data[j + 1]) * ((k + 1) % 251 + 1) +
                      (b - data[j + 2]) * ((k + 2) % 251 + 1);
        data[j] = r; data[j + 1] = g; data[j + 2] = b;
      }
    ctx.putImageData(previewImage, 0, 0, q.x, q.y, q.w, q.h);
  }
  previewVersion = p.version;
  if (p.base !== 0) c.dataset.updates = ++previewUpdates;
  c.dataset.tiles = p.tiles;
  c.dataset.checksum = previewSum;
}

if (params.has("snapshot")) {
  // One look, no stream: for tools that read the page once (a headless browser's --dump-dom).
  fetch("/api/state" + query).then(r => r.json()).then(s => { $("connection").textContent = "snapshot"; render(s); });
  fetch(wholePreviewUrl).then(r => r.json()).then(p => { if (p.patches) preview(p); });
} else {
  const events = new EventSource("/events" + query);
  events.addEventListener("state", e => { setText($("connection"), "live"); render(JSON.parse(e.data)); });
  events.addEventListener("preview", e => preview(JSON.parse(e.data)));
  events.onerror = () => { $("connection").textContent = "disconnected (the farm has ended?)"; };
  // ?watch=MS: listen for MS milliseconds, then hang up (a headless browser's --dump-dom returns once the
  // network is quiet, so tests can look at the live page after watching it).
  const watch = Number(params.get("watch"));
  if (watch > 0) setTimeout(() => { events.close(); $("connection").textContent = "watched"; }, watch);
}
</script>
</body>
</html>
)PAGE";

}  // namespace lf
