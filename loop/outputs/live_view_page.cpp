// The live view's page (loop/outputs/live_view.hpp), embedded in the binary: HTML and JavaScript
// drawing on <canvas>, no external resources. The B-scope has its own geometry (900 x 700 pixels,
// margins 70/20/40/50, azimuth across, range up; once the geometry of the old detections.png) and
// sits at the page's top-left corner, so a pixel of a screenshot is a pixel of the
// plot. Detections are filled 7 x 7 squares of pure magenta (#ff00ff), a colour nothing else on the
// page uses; truth is a green ring.

#include <string_view>

#include "loop/outputs/live_view.hpp"

namespace radar_emu::loop {

namespace {

constexpr std::string_view kPage = R"HTML(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>radar-emu live view</title>
<style>
  html, body { margin: 0; padding: 0; background: #10141c; color: #d2d7e1;
               font: 13px/1.35 monospace; overflow: hidden; }
  #bscope { position: absolute; left: 0; top: 0; }
  #panel { position: absolute; left: 910px; top: 8px; width: 400px; }
  h1 { font-size: 15px; margin: 0 0 6px 0; }
  table { border-collapse: collapse; margin-bottom: 8px; }
  td { padding: 1px 10px 1px 0; }
  .k { color: #8c96aa; }
  #state.ok { color: #6fdc8c; } #state.bad { color: #e6a04a; }
  #outcome { max-height: 330px; overflow-y: auto; }
  #outcome td { padding: 0 6px 0 0; text-align: right; }
  #outcome td:first-child { text-align: left; }
</style>
</head>
<body>
<canvas id="bscope" width="900" height="700"></canvas>
<div id="panel">
  <h1>radar-emu live view</h1>
  <div>connection: <span id="state" class="bad">connecting</span></div>
  <div id="scenario" class="k"></div>
  <h1 style="margin-top:10px">ownship</h1>
  <table id="ownship"></table>
  <h1>stage times vs budget</h1>
  <canvas id="timing" width="400" height="230"></canvas>
  <table id="counters"></table>
  <div class="k">magenta squares: detections of the current frame;
    green rings: ground truth (objects in the beam)</div>
  <h1 style="margin-top:10px">outcome per target so far</h1>
  <div id="false_alarms" class="k"></div>
  <div id="outcome"><table id="targets"></table></div>
</div>
<script>
"use strict";
// The B-scope's geometry (the header comment above).
const L = { W: 900, H: 700, left: 70, right: 20, top: 40, bottom: 50 };
const BG = "#10141c", GRID = "rgb(55,62,78)", INK = "rgb(210,215,225)";
const DET = "#ff00ff", TRUTH = "rgb(60,220,80)";
const bscope = document.getElementById("bscope").getContext("2d");
const timing = document.getElementById("timing").getContext("2d");

function xOf(az, lay) {
  const f = (az - lay.azimuth_min_deg) / (lay.azimuth_max_deg - lay.azimuth_min_deg);
  return L.left + Math.round(f * (L.W - L.left - L.right - 1));
}
function yOf(r, lay) {
  return L.H - L.bottom - Math.round(r / lay.range_max_m * (L.H - L.top - L.bottom - 1));
}
function fmt(v, d) { return v === null || v === undefined ? "-" : Number(v).toFixed(d); }
function rows(table, list) {
  table.innerHTML = list.map(([k, v]) => `<tr><td class="k">${k}</td><td>${v}</td></tr>`).join("");
}

function drawBScope(m) {
  const c = bscope, lay = m.layout;
  c.fillStyle = BG;
  c.fillRect(0, 0, L.W, L.H);
  c.fillStyle = GRID;
  c.font = "14px monospace";
  for (let r = 0; r <= lay.range_max_m + 1e-9; r += 500) {
    const y = yOf(r, lay);
    c.fillStyle = GRID;
    c.fillRect(L.left, y, L.W - L.right - L.left, 1);
    if (r % 1000 === 0) { c.fillStyle = INK; c.fillText((r / 1000) + " km", 8, y + 5); }
  }
  for (let a = Math.ceil(lay.azimuth_min_deg / 2) * 2; a <= lay.azimuth_max_deg + 1e-9; a += 2) {
    const x = xOf(a, lay);
    c.fillStyle = GRID;
    c.fillRect(x, L.top, 1, L.H - L.bottom - L.top);
    c.fillStyle = INK;
    c.fillText((a > 0 ? "+" : "") + a, x - 12, L.H - L.bottom + 20);
  }
  c.fillStyle = INK;
  c.fillText("azimuth [deg], right of boresight", L.W / 2 - 140, L.H - 10);
  c.fillText(`frame ${m.frame}   t = ${fmt(m.time_s, 2)} s   ${m.detections.length} detections, ` +
             `${m.truth.length} objects in the beam` + (m.ended ? "   (run ended)" : ""),
             L.left, 24);
  // Truth first, detections on top.
  c.strokeStyle = TRUTH;
  c.lineWidth = 2;
  c.font = "11px monospace";
  const labels = [];  // a label that would overlap one already drawn is left out
  for (const t of m.truth) {
    const x = xOf(t.azimuth_deg, lay), y = yOf(t.range_m, lay);
    c.beginPath();
    c.arc(x, y, 9, 0, 2 * Math.PI);
    c.stroke();
    if (!t.object) continue;
    const box = { x0: x + 12, y0: y - 18, x1: x + 12 + 7 * t.object.length, y1: y - 6 };
    if (labels.some((b) => box.x0 < b.x1 && b.x0 < box.x1 && box.y0 < b.y1 && b.y0 < box.y1))
      continue;
    labels.push(box);
    c.fillStyle = "rgb(140,150,170)";
    c.fillText(t.object, x + 12, y - 8);
  }
  c.fillStyle = DET;
  for (const d of m.detections) {
    const x = xOf(d.azimuth_deg, lay), y = yOf(d.range_m, lay);
    c.fillRect(x - 3, y - 3, 7, 7);
  }
}

const STAGES = ["input", "scene_update", "trace", "sensor", "output", "frame"];
function drawTiming(m) {
  const c = timing, W = 400, H = 230, left = 100, right = 10, barH = 22, gap = 10;
  c.fillStyle = BG;
  c.fillRect(0, 0, W, H);
  const frame = m.stages_ms.frame || 0;
  const scale = Math.max(m.budget_ms * 1.25, frame * 1.05);
  const px = (ms) => left + (W - left - right) * Math.min(ms, scale) / scale;
  c.font = "12px monospace";
  STAGES.forEach((s, i) => {
    const y = 10 + i * (barH + gap), v = m.stages_ms[s];
    c.fillStyle = INK;
    c.fillText(s, 4, y + 15);
    c.fillStyle = s === "frame" ? (v > m.budget_ms ? "rgb(230,140,60)" : "rgb(90,190,120)")
                                : "rgb(90,150,230)";
    if (v !== null && v !== undefined) c.fillRect(left, y, Math.max(1, px(v) - left), barH);
    c.fillStyle = INK;
    const xv = v !== null && v !== undefined ? px(v) : left;
    c.fillText(fmt(v, 3) + " ms", Math.min(xv + 6, W - 80), y + 15);
  });
  const xb = Math.round(px(m.budget_ms));
  c.fillStyle = "rgb(230,60,60)";
  c.fillRect(xb, 4, 2, H - 8);
  c.fillText(`budget ${fmt(m.budget_ms, 1)} ms`, Math.min(xb + 4, W - 130), H - 4);
}

function show(m) {
  drawBScope(m);
  drawTiming(m);
  document.getElementById("scenario").textContent = "scenario: " + m.scenario;
  const o = m.ownship;
  rows(document.getElementById("ownship"), o.valid ? [
    ["east / north / up", `${fmt(o.east_m, 1)} / ${fmt(o.north_m, 1)} / ${fmt(o.up_m, 1)} m`],
    ["ground speed", `${fmt(o.ground_speed_mps, 1)} m/s`],
    ["track", `${fmt(o.track_deg, 1)} deg`],
    ["climb", `${fmt(o.climb_mps, 1)} m/s`],
  ] : [["state", "no valid ownship state (stale)"]]);
  rows(document.getElementById("counters"), [
    ["frames run", m.view.published],
    ["view updates dropped", m.view.dropped],
    ["late / degraded", `${m.status.late} / ${m.status.degraded} (level ${m.status.governor_level})`],
  ]);
  // The outcome per target (docs/outcome.md): Pd, and the mean error of range and azimuth.
  const oc = m.outcome;
  if (oc) {
    document.getElementById("false_alarms").textContent =
      `false alarms ${fmt(oc.false_alarms_per_frame, 2)} per frame (${oc.false_alarms} in ` +
      `${oc.frames_scored} frames)`;
    document.getElementById("targets").innerHTML =
      "<tr class='k'><td>object</td><td>beam</td><td>det</td><td>Pd</td><td>dR m</td>" +
      "<td>dAz deg</td></tr>" +
      oc.targets.map((t) => `<tr><td>${t.object}</td><td>${t.frames_in_beam}</td>` +
        `<td>${t.frames_detected}</td><td>${fmt(t.pd, 2)}</td>` +
        `<td>${t.frames_detected ? fmt(t.range_error_m[0], 2) : "-"}</td>` +
        `<td>${t.frames_detected ? fmt(t.azimuth_error_deg[0], 3) : "-"}</td></tr>`).join("");
  }
}

let ended = false;
function connect() {
  const state = document.getElementById("state");
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  ws.onopen = () => { state.textContent = "live"; state.className = "ok"; };
  ws.onmessage = (e) => {
    const m = JSON.parse(e.data);
    ended = m.ended;
    if (ended) { state.textContent = "run ended (last frame shown)"; state.className = "ok"; }
    show(m);
  };
  ws.onclose = () => {
    if (!ended) { state.textContent = "disconnected, retrying"; state.className = "bad"; }
    setTimeout(connect, 1000);
  };
}
connect();
</script>
</body>
</html>
)HTML";

}  // namespace

std::string_view live_view_page() noexcept {
  return kPage;
}

}  // namespace radar_emu::loop
