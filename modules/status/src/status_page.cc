#include "bricklayer/status/status_page.h"

namespace bricklayer::status {

namespace {
// Every string from the bus is put in with textContent, never innerHTML: a module's status line is
// data, not markup.
constexpr const char* kPage = R"HTML(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>Bricklayer status</title>
<link rel="icon" href="data:,">
<style>
  body { font-family: system-ui, sans-serif; margin: 0; padding: 12px; background: #f4f4f4; color: #222; }
  h1 { font-size: 1.3em; margin: 0 0 8px 0; }
  #overall { padding: 10px 14px; border-radius: 8px; font-size: 1.1em; font-weight: bold; margin-bottom: 10px; }
  .ok { background: #d7f5d7; } .warning { background: #fff0c2; } .failed { background: #ffd2d2; }
  .badge { display: inline-block; padding: 1px 8px; border-radius: 10px; font-size: 0.85em; }
  #problems li { margin: 4px 0; }
  .card { background: white; border-radius: 8px; padding: 10px 12px; margin-bottom: 10px; box-shadow: 0 1px 2px #0002; }
  .card h2 { font-size: 1.1em; margin: 0 0 6px 0; }
  table { border-collapse: collapse; width: 100%; font-size: 0.92em; }
  td, th { text-align: left; padding: 3px 6px; border-bottom: 1px solid #eee; }
  .muted { color: #777; font-size: 0.85em; }
  #round { font-size: 1.05em; }
  button { font-size: 0.95em; padding: 6px 10px; margin: 3px 4px 3px 0; border-radius: 6px; border: 1px solid #999; background: #fafafa; }
  td button { padding: 2px 6px; font-size: 0.85em; }
  input { font-size: 0.95em; padding: 4px 6px; margin: 3px 0; }
  .figures { color: #555; font-size: 0.85em; }
  .scroll { overflow-x: auto; }
  /* Two images side by side on a laptop, one above the other on a phone; never wider than the card. */
  .images { display: flex; flex-wrap: wrap; gap: 10px; }
  .images figure { margin: 0; flex: 1 1 240px; max-width: 480px; }
  .images img { width: 100%; height: auto; display: block; background: #ddd; min-height: 40px; }
  select { font-size: 0.95em; padding: 4px 6px; }
</style>
</head>
<body>
<h1>Bricklayer</h1>
<div id="overall" class="warning">Waiting for the first answer&hellip;</div>
<ul id="problems"></ul>
<div class="card" id="round-card"><h2>Round</h2><div id="round">No round heard of yet.</div>
  <div>Best today: <b id="best">0</b> | display condition: <b id="condition">not heard yet</b></div></div>
<div class="card" id="images-card"><h2>What the camera sees, what the projector shows</h2>
  <div class="images">
    <figure><img id="camera-img" alt="the latest camera frame"><figcaption id="camera-age" class="muted">No camera frame seen yet.</figcaption></figure>
    <figure><img id="projector-img" alt="the latest projector image"><figcaption id="projector-age" class="muted">No projector image seen yet.</figcaption></figure>
  </div></div>
<div id="hosts"></div>
<div class="card" id="actions-card"><h2>Actions</h2>
  <div id="actions-off" class="muted"></div>
  <form id="token-form"><input type="text" name="username" value="operator" autocomplete="username" hidden>
    <label>Operator token <input id="token" type="password" autocomplete="current-password" size="20"></label></form>
  <div>
    <button data-action="start_round">Start a round</button>
    <button data-action="reset_round">Reset the round</button>
    <button data-action="check_calibration">Check the calibration</button>
    <button data-action="calibrate" data-confirm="Calibrate now? The board must be empty: once it has been empty for 5 s the projector shows calibration patterns instead of the game for about 5 s.">Calibrate now</button>
  </div>
  <div><button data-action="calibrate" data-step="scale-from-blocks" data-confirm="Correct the board scale now? Three or more blocks must stand apart on the bottom row, spread along it (the game may go on); for the whole board, also stand a tower of blocks, one on another up to row 9 or higher, on two of them. The camera measures them for a few seconds.">Correct the scale with blocks</button></div>
  <div id="calibration" class="muted">Calibration: nothing heard from bricklayer-calibrate --serve yet.</div>
  <div><label>Display condition for the next round
    <select id="condition-choice"><option value="proposed">proposed (only the blocks that start the fall red)</option>
      <option value="blue">blue (always blue)</option><option value="red">red (all red while it falls)</option></select></label>
    <button data-action="set_condition">Set</button></div>
  <div><input id="note" placeholder="what happened (optional)" size="24"> <button data-action="mark_moment">Mark this moment</button></div>
  <div id="action-result" class="muted"></div>
</div>
<div class="muted" id="updated"></div>
<script>
"use strict";
function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = String(text);
  if (cls) e.className = cls;
  return e;
}
function duration(s) {
  s = Math.max(0, Math.floor(s));
  if (s < 120) return s + " s";
  if (s < 7200) return Math.floor(s / 60) + " min";
  return Math.floor(s / 3600) + " h " + (Math.floor(s / 60) % 60) + " min";
}
const words = { ok: "Everything is working.", warning: "Something needs a look.", failed: "The exhibit is not working." };
function draw(state) {
  const overall = document.getElementById("overall");
  overall.className = state.level;
  overall.textContent = words[state.level] || state.level;
  const problems = document.getElementById("problems");
  problems.replaceChildren(...state.problems.map((p) => el("li", p)));
  const round = document.getElementById("round");
  if (state.round) {
    const r = state.round;
    round.textContent = "Round " + r.state + (r.state === "running" ? ", " + duration(r.remaining_s) + " left" : "") +
      " | score " + r.score + " | MAX " + r.max_score + " | " + r.num_blocks + " blocks";
  }
  document.getElementById("best").textContent = state.best_today;
  if (state.round) document.getElementById("condition").textContent = state.round.condition;
  show_calibration(state.calibration);
  show_image("camera", state.camera, "camera frame");
  show_image("projector", state.projector, "projector image");
  const hosts = document.getElementById("hosts");
  hosts.replaceChildren(...state.hosts.map((h) => {
    const card = el("div", undefined, "card");
    card.id = "host-" + h.host;
    const title = el("h2", h.host + " ");
    title.appendChild(el("span", h.silent ? "silent" : h.level, "badge " + h.level));
    card.appendChild(title);
    card.appendChild(el("div", "profile " + h.profile + " | running for " + duration(h.uptime_s) + " | " +
      h.modules_up + " of " + h.num_modules + " modules up | " + h.status, "muted"));
    const table = el("table");
    const head = table.createTHead().insertRow();
    for (const c of ["module", "state", "restarts", "up for", "status", "figures"]) head.appendChild(el("th", c));
    const body = table.createTBody();
    for (const m of h.modules) {
      const row = body.insertRow();
      row.className = m.level;
      row.dataset.module = m.name;
      const name = el("td", m.name);
      const restart = el("button", "restart");
      restart.onclick = () => act({ action: "restart", host: h.host, module: m.name });
      name.appendChild(el("br"));
      name.appendChild(restart);
      row.appendChild(name);
      row.appendChild(el("td", m.state));
      row.appendChild(el("td", m.restarts));
      row.appendChild(el("td", m.state === "up" ? duration(m.uptime_s) : ""));
      row.appendChild(el("td", m.words || m.status));
      row.appendChild(el("td", figures(m.figures), "figures"));
    }
    // A phone's width: the table scrolls sideways inside its card rather than spilling out of it.
    const scroll = el("div", undefined, "scroll");
    scroll.appendChild(table);
    card.appendChild(scroll);
    return card;
  }));
  document.getElementById("actions-off").textContent = state.actions ? "" :
    "Actions are off on this machine (no token file): the page only shows the state.";
  document.getElementById("updated").textContent = "Updated " + new Date().toLocaleTimeString();
}
// The serving calibrate node's heartbeat: its status (a calibration's progress, a rejection and why) and
// figures in words.
function show_calibration(c) {
  const line = document.getElementById("calibration");
  if (!c) return;
  const f = c.figures || {};
  const number = (v) => Number(v.toPrecision(2));
  const parts = [];
  if (f.calibration_age_s !== undefined) parts.push("calibrated " + duration(f.calibration_age_s) + " ago");
  if (f.reprojection_error_mean_px !== undefined) parts.push("error " + number(f.reprojection_error_mean_px) + " px");
  if (f.drift_px !== undefined) parts.push("drift " + number(f.drift_px) + " px at the last check");
  if (f.calibrations_done) parts.push(f.calibrations_done + " done on request");
  if (f.calibrations_failed) parts.push(f.calibrations_failed + " not done");
  line.textContent = "Calibration: " + c.status + (c.age_s > 5 ? " (heard " + duration(c.age_s) + " ago)" : "") +
    (parts.length ? " | " + parts.join(", ") : "");
  line.className = c.status === "ok" ? "muted" : "muted warning";
}
// An image is asked for only once the JSON says one was seen (asking before would be a 404, an error
// in the browser's console) and again every 3 s; a new URL each time, so no cache keeps an old one.
const imageAsked = {};
function show_image(name, info, what) {
  const age = document.getElementById(name + "-age");
  if (!info || !info.seen) {
    age.textContent = "No " + what + " seen yet.";
    return;
  }
  age.textContent = what[0].toUpperCase() + what.slice(1) + " from " + duration(info.age_s) + " ago (" +
    info.width + " \u00d7 " + info.height + ", " + info.source + ")";
  const now = Date.now();
  if (imageAsked[name] && now - imageAsked[name] < 3000) return;
  imageAsked[name] = now;
  document.getElementById(name + "-img").src = name + ".jpg?t=" + now;
}
// A module's own figures from its heartbeat, at most six, each to three significant digits.
function figures(f) {
  if (!f) return "";
  return Object.entries(f).slice(0, 6).map(([k, v]) => k + " " + Number(v.toPrecision(3))).join(" \u00b7 ");
}
// The token stays in this tab only (sessionStorage): a shared phone forgets it when the tab closes.
const tokenInput = document.getElementById("token");
tokenInput.value = sessionStorage.getItem("bricklayer-token") || "";
tokenInput.onchange = () => sessionStorage.setItem("bricklayer-token", tokenInput.value);
document.getElementById("token-form").onsubmit = (e) => e.preventDefault();  // Enter does not reload the page
async function act(request) {
  const result = document.getElementById("action-result");
  try {
    const res = await fetch("action", { method: "POST", cache: "no-store",
      headers: { "Content-Type": "application/json", "X-Bricklayer-Token": tokenInput.value },
      body: JSON.stringify(request) });
    const answer = await res.json();
    result.textContent = (answer.ok ? "Done: " : "Not done: ") + answer.words;
  } catch (e) {
    result.textContent = "Not done: this page cannot reach bricklayer-status.";
  }
}
for (const b of document.querySelectorAll("#actions-card button")) {
  // A calibration takes the projector from the game: the operator says the board is empty first.
  b.onclick = () => (b.dataset.confirm && !confirm(b.dataset.confirm)) || act(b.dataset.action === "mark_moment"
    ? { action: "mark_moment", note: document.getElementById("note").value }
    : b.dataset.step
    ? { action: b.dataset.action, step: b.dataset.step }
    : b.dataset.action === "set_condition"
    ? { action: "set_condition", condition: document.getElementById("condition-choice").value }
    : { action: b.dataset.action });
}
let failures = 0;
async function poll() {
  try {
    const res = await fetch("state.json", { cache: "no-store" });
    if (!res.ok) throw new Error("HTTP " + res.status);
    draw(await res.json());
    failures = 0;
  } catch (e) {
    // The page stays up when the status program restarts: it says so and keeps asking.
    if (++failures >= 3) {
      const overall = document.getElementById("overall");
      overall.className = "failed";
      overall.textContent = "This page cannot reach bricklayer-status (it is restarting, or this machine is off).";
    }
  }
  setTimeout(poll, 1000);
}
poll();
</script>
</body>
</html>
)HTML";
}  // namespace

const std::string& status_page_html() {
  static const std::string page(kPage);
  return page;
}

}  // namespace bricklayer::status
