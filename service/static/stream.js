/* thrustshape page, Stream tab: the paper's interaction example (GET /v1/stream/example) played sample by
   sample through the live shaper (WS /v1/stream), paced in real time (or 2x, 4x); desired vs shaped thrust,
   current and voltage against their limits, redrawn as the samples come back. The page does no physics:
   the reference comes from the server's core, the shaping from the stream. Self-starting module. */

import { $, ApiError, api, clearErrors, fmt, readNumber, showError, showFieldError, td, row, emptied } from "./common.js";

const FRAME_MS = 25;      // one frame of samples every 25 ms of wall-clock time
const REDRAW_MS = 250;    // plots redrawn at most this often while streaming
const scope = () => $("#tab-stream");

let session = null;       // the running stream: { ws, timer, out, ... }

function wsUrl() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  return `${proto}//${location.host}/v1/stream`;
}

function readForm() {
  return {
    law: $("#s-law").value, regularity: $("#s-regularity").value,
    delay: readNumber($("#s-delay")), amplitude: readNumber($("#s-amplitude")),
    current: readNumber($("#s-current")), voltage: readNumber($("#s-voltage")),
    duration: readNumber($("#s-duration")), speed: Number($("#s-speed").value),
  };
}

function status(text) { $("#s-status").textContent = text; }

function summary(s) {
  const o = s.out, n = o.t.length;
  let se = 0, peak = 0, imax = 0, vmax = 0, sat = 0, rev = 0;
  for (let k = 0; k < n; k++) {
    const e = o.thrust[k] - o.desired[k];
    se += e * e; peak = Math.max(peak, Math.abs(o.desired[k]));
    imax = Math.max(imax, Math.abs(o.current[k])); vmax = Math.max(vmax, Math.abs(o.voltage[k]));
    if (o.saturated[k]) sat++;
    if (k > 0 && o.thrust[k] * o.thrust[k - 1] < 0) rev++;
  }
  const body = emptied("#s-summary tbody");
  const rows = [
    ["samples", "samples", `${n} of ${s.total}`],
    ["tracking", "tracking RMS error vs desired(t − delay) [% of amplitude]",
     n ? fmt(100 * Math.sqrt(se / n) / (peak || 1), 3) : "–"],
    ["current", "max |current| [A]", fmt(imax, 4)],
    ["voltage", "max |voltage| [V]", fmt(vmax, 4)],
    ["limits", "within limits", imax <= s.form.current && vmax <= s.form.voltage ? "yes" : "NO"],
    ["reversals", "reversals of the shaped thrust", String(rev)],
    ["governed", "samples where the governor acted", String(sat)],
  ];
  for (const [key, label, value] of rows) {
    const r = row([td(label), td(value, "num")]);
    r.dataset.key = key;
    body.appendChild(r);
  }
}

function draw(s) {
  const o = s.out, lim = s.form;
  Plot.line($("#s-plot-thrust"), { title: "thrust: desired (delayed by the look-ahead) and shaped", xlabel: "t [s]",
    ylabel: "N", series: [{ x: o.t, y: o.desired, label: "desired(t − delay)", dash: "4 3" },
                          { x: o.t, y: o.thrust, label: "shaped" }] });
  Plot.line($("#s-plot-current"), { title: "current feed-forward", xlabel: "t [s]", ylabel: "A",
    series: [{ x: o.t, y: o.current, label: "current" }],
    hlines: [{ y: lim.current, label: `+${fmt(lim.current)} A limit` }, { y: -lim.current, label: `−${fmt(lim.current)} A limit` }] });
  Plot.line($("#s-plot-voltage"), { title: "voltage feed-forward", xlabel: "t [s]", ylabel: "V",
    series: [{ x: o.t, y: o.voltage, label: "voltage" }],
    hlines: [{ y: lim.voltage, label: `+${fmt(lim.voltage)} V limit` }, { y: -lim.voltage, label: `−${fmt(lim.voltage)} V limit` }] });
  summary(s);
}

function finish(text) {
  const s = session;
  if (!s) return;
  clearInterval(s.timer);
  session = null;
  if (s.ws.readyState <= 1) s.ws.close();
  draw(s);
  status(text);
  $("#s-play").disabled = false;
  $("#s-stop").disabled = true;
}

function pump(s) {
  // samples due by now at the chosen playback speed, in frames the server accepts (<= max_batch)
  const due = Math.min(s.total, Math.floor(((performance.now() - s.started) / 1000) * s.rate * s.form.speed) + 1);
  while (s.sent < due) {
    const end = Math.min(due, s.sent + s.maxBatch);
    s.ws.send(JSON.stringify({ t: s.ex.t.slice(s.sent, end), thrust: s.ex.thrust.slice(s.sent, end) }));
    s.sent = end;
  }
}

function onMessage(s, ev) {
  const msg = JSON.parse(ev.data);
  if (msg.type === "ready") {
    s.maxBatch = msg.max_batch;
    s.started = performance.now();
    s.timer = setInterval(() => pump(s), FRAME_MS);
    status("streaming…");
  } else if (msg.type === "samples") {
    for (const k of Object.keys(s.out)) s.out[k].push(...msg[k]);
    if (s.out.t.length >= s.total) { finish(`done: ${s.total} samples`); return; }
    if (performance.now() - s.drawn > REDRAW_MS) { s.drawn = performance.now(); draw(s); }
  } else if (msg.type === "error") {
    s.failed = true;
    showFieldError(scope(), msg.field, msg.reason);
    finish(`stopped: ${msg.field}: ${msg.reason}`);
  }
}

async function play() {
  clearErrors(scope());
  if (session) finish("stopped");
  const form = readForm();
  const q = new URLSearchParams({ law: form.law, duration: form.duration, amplitude: form.amplitude });
  const ex = await api("GET", `/v1/stream/example?${q}`);
  const s = { form, ex, rate: ex.rate, total: ex.t.length, sent: 0, drawn: 0, maxBatch: 100, failed: false,
              out: { t: [], desired: [], thrust: [], current: [], voltage: [], saturated: [] } };
  s.ws = new WebSocket(wsUrl());
  session = s;
  $("#s-results").hidden = false;
  $("#s-play").disabled = true;
  $("#s-stop").disabled = false;
  status("connecting…");
  s.ws.onopen = () => s.ws.send(JSON.stringify({
    params: "paper-rig", current: form.current, voltage: form.voltage, regularity: form.regularity,
    delay: form.delay, dt: 1 / ex.rate, api_key: $("#api-key").value.trim() || null }));
  s.ws.onmessage = (ev) => onMessage(s, ev);
  s.ws.onerror = () => { if (session === s) finish("the connection failed"); };
  s.ws.onclose = () => { if (session === s && !s.failed) finish(`closed after ${s.out.t.length} samples`); };
}

function init() {
  $("#stream-form").addEventListener("submit", (e) => {
    e.preventDefault();
    play().catch((err) => {
      $("#s-play").disabled = false;
      showError(scope(), err instanceof ApiError ? err : new ApiError(0, null, String(err)));
    });
  });
  $("#s-stop").addEventListener("click", () => finish("stopped"));
}

init();
