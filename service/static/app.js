/* thrustshape page: Design, Compare, Model check and Batch tabs over the service's HTTP API.
   Every API error (application/problem+json, with `field` and `reason`) is shown next to the input that
   `field` names; anything else goes to the form's error box. No handler lets an exception escape. */
"use strict";

const $ = (sel, root) => (root || document).querySelector(sel);
const $$ = (sel, root) => Array.from((root || document).querySelectorAll(sel));

const state = { info: null, design: null, designMission: null, modelLog: null, fit: null, batch: null,
                batchMissions: [] };

/* ------------------------------------------------------------------ API */

class ApiError extends Error {
  constructor(status, field, reason, detail, errors) {
    super(detail || reason || `HTTP ${status}`);
    this.status = status; this.field = field; this.reason = reason || detail; this.errors = errors || [];
  }
}

function authHeaders() {
  const key = $("#api-key").value.trim();
  return key ? { Authorization: `Bearer ${key}` } : {};
}

async function api(method, path, body, { form = false, accept = "json" } = {}) {
  const headers = { ...authHeaders() };
  let payload;
  if (body !== undefined && form) payload = body;
  else if (body !== undefined) { headers["Content-Type"] = "application/json"; payload = JSON.stringify(body); }
  let resp;
  try {
    resp = await fetch(path, { method, headers, body: payload });
  } catch (e) {
    throw new ApiError(0, null, `cannot reach the server (${e.message})`);
  }
  if (!resp.ok) {
    let p = {};
    try { p = await resp.json(); } catch (e) { p = { detail: await resp.text().catch(() => "") }; }
    let field = p.field || null;
    if (resp.status === 401) field = "Authorization";
    const reason = p.reason || p.detail || resp.statusText || `HTTP ${resp.status}`;
    const extra = resp.status === 503 ? " (server busy, try again shortly)" : "";
    throw new ApiError(resp.status, field, reason + extra, p.detail, p.errors);
  }
  if (accept === "text") return resp.text();
  if (accept === "blob") return resp.blob();
  return resp.json();
}

/* ------------------------------------------------------------------ errors next to fields */

function clearErrors(scope) {
  $$(".field-error", scope).forEach((e) => e.remove());
  $$(".invalid", scope).forEach((e) => e.classList.remove("invalid"));
  $$(".form-error", scope).forEach((e) => { e.textContent = ""; });
}

function fieldElement(scope, field) {
  if (!field) return null;
  if (field === "Authorization") return $("#api-key");
  const parts = String(field).split(".");
  for (let n = parts.length; n > 0; n--) {
    const f = parts.slice(0, n).join(".");
    const hits = $$(`[data-field="${CSS.escape(f)}"]`, scope).filter((e) => !e.hidden && e.offsetParent !== null);
    if (hits.length) return hits[hits.length - 1];
  }
  return null;
}

function showFieldError(scope, field, reason) {
  // a field with no input of its own (a log column such as "voltage") goes next to the scope's fallback input
  const target = fieldElement(scope, field) || (field ? $("[data-field-fallback]", scope) : null);
  if (!target) {
    const box = $(".form-error", scope) || $("#toast");
    box.textContent = (box.textContent ? box.textContent + " · " : "") + (field ? `${field}: ` : "") + reason;
    if (box.id === "toast") { box.hidden = false; setTimeout(() => { box.hidden = true; }, 8000); }
    return;
  }
  target.classList.add("invalid");
  const msg = document.createElement("div");
  msg.className = "field-error";
  msg.setAttribute("data-error-for", field);
  msg.textContent = (target.getAttribute("data-field") === field ? "" : `${field}: `) + reason;
  (target.closest("label") || target).insertAdjacentElement("afterend", msg);
}

function showError(scope, err) {
  if (err instanceof ApiError) {
    const list = err.errors && err.errors.length ? err.errors : [{ field: err.field, reason: err.reason }];
    for (const e of list.slice(0, 6)) showFieldError(scope, e.field, e.reason);
  } else {
    showFieldError(scope, null, `unexpected error: ${err && err.message ? err.message : err}`);
    console.error(err);
  }
}

async function guarded(scope, busy, fn) {
  clearErrors(scope);
  const buttons = $$("button.primary:not(:disabled)", scope);  // the actions: no second run while one is under way
  buttons.forEach((b) => { b.disabled = true; });
  if (busy) busy.hidden = false;
  try {
    await fn();
  } catch (err) {
    showError(scope, err);
  } finally {
    if (busy) busy.hidden = true;
    buttons.forEach((b) => { b.disabled = false; });
  }
}

class FieldError extends ApiError {
  constructor(field, reason) { super(0, field, reason); }
}

/* ------------------------------------------------------------------ helpers */

const fmt = (v, digits = 4) => {
  if (v === null || v === undefined) return "—";
  if (v === "inf" || v === Infinity) return "∞";
  if (v === "-inf" || v === -Infinity) return "−∞";
  if (typeof v === "boolean") return v ? "yes" : "no";
  if (typeof v !== "number") return String(v);
  if (v === 0) return "0";
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-3) return v.toExponential(digits - 1);
  return String(Number(v.toPrecision(digits)));
};

function download(name, text, type) {
  const blob = text instanceof Blob ? text : new Blob([text], { type: type || "application/octet-stream" });
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

function td(text, cls) {
  const c = document.createElement("td");
  c.textContent = text;
  if (cls) c.className = cls;
  return c;
}

function row(cells) {
  const r = document.createElement("tr");
  cells.forEach((c) => r.appendChild(c instanceof Node ? c : td(c)));
  return r;
}

function readNumber(input, { optional = false, integer = false } = {}) {
  const raw = input.value.trim();
  const field = input.getAttribute("data-field");
  if (raw === "") {
    if (optional) return undefined;
    throw new FieldError(field, "required");
  }
  const v = Number(raw);
  if (!Number.isFinite(v)) throw new FieldError(field, `not a number: ${raw}`);
  if (integer && !Number.isInteger(v)) throw new FieldError(field, "must be a whole number");
  return v;
}

function parseJsonField(text, field) {
  try {
    return JSON.parse(text);
  } catch (e) {
    throw new FieldError(field, `not valid JSON: ${e.message}`);
  }
}

const safeName = (s) => String(s || "mission").replace(/[^A-Za-z0-9._-]+/g, "_");

/* ------------------------------------------------------------------ tabs, info, api key */

function selectTab(name) {
  if (!$(`#tab-${name}`)) name = "design";
  $$("#tabs button").forEach((b) => b.setAttribute("aria-selected", String(b.dataset.tab === name)));
  $$(".tab").forEach((s) => { s.hidden = s.id !== `tab-${name}`; });
  if (location.hash !== `#${name}`) history.replaceState(null, "", `#${name}`);
}

function fillSelect(sel, values, labels) {
  sel.innerHTML = "";
  values.forEach((v, k) => {
    const o = document.createElement("option");
    o.value = v; o.textContent = labels ? labels[k] : v;
    sel.appendChild(o);
  });
}

async function loadInfo() {
  const presets = ["paper-rig"], regs = ["bounded", "continuous-current", "continuous-voltage", "c1-voltage"];
  let info = null;
  try {
    info = await api("GET", "/v1/info");
  } catch (err) {
    if (err.status === 401) showFieldError(document.body, "Authorization", err.reason);
    $("#server-info").textContent = `server info unavailable: ${err.reason}`;
  }
  state.info = info;
  const ps = info ? info.presets : presets;
  const custom = "__custom__";
  fillSelect($("#d-preset"), [...ps, custom], [...ps, "custom (JSON)…"]);
  fillSelect($("#m-preset"), [...ps, custom], [...ps, "parameter file / JSON…"]);
  const cur = $("#d-regularity").value;
  fillSelect($("#d-regularity"), info ? info.regularities : regs);
  if (cur) $("#d-regularity").value = cur;
  if (info) {
    const f = info.features || {};
    $("#server-info").textContent = `server ${info.version} · ${info.workers} worker(s) · batches on ${info.batch_backend}` +
      ` · presets ${info.presets.join(", ")}`;
    if (f.model_check === false) {
      $("#m-route-note").textContent = "This server does not report the model-check routes; requests may fail.";
    }
  }
}

/* ------------------------------------------------------------------ Design: segments editor */

const SEG_FIELDS = {
  hold: [["duration", 0.5], ["thrust", 0.4]],
  ramp: [["duration", 0.5], ["to", 0.0]],
  reversal: [["duration", 0.4], ["to", -0.4], ["shape", "cosine"]],
  sine: [["duration", 1.0], ["amplitude", 0.3], ["period", 1.0], ["offset", 0.0], ["phase", 0.0]],
};
const SEG_UNITS = { duration: "s", thrust: "N", to: "N", amplitude: "N", period: "s", offset: "N", phase: "rad" };

function renumberSegments() {
  $$("#d-segments tr").forEach((tr, i) => {
    tr.firstChild.textContent = String(i + 1);
    $$("[data-key]", tr).forEach((inp) => inp.setAttribute("data-field", `segments.${i}.${inp.dataset.key}`));
  });
  drawPreview();
}

function segParams(cell, kind, values) {
  cell.innerHTML = "";
  const box = document.createElement("div");
  box.className = "segparams";
  for (const [key, def] of SEG_FIELDS[kind]) {
    const lab = document.createElement("label");
    lab.textContent = SEG_UNITS[key] ? `${key} [${SEG_UNITS[key]}]` : key;
    let inp;
    if (key === "shape") {
      inp = document.createElement("select");
      fillSelect(inp, ["cosine", "ramp", "step"]);
    } else {
      inp = document.createElement("input");
      inp.type = "number"; inp.step = "any";
    }
    inp.dataset.key = key;
    inp.value = values && values[key] !== undefined ? values[key] : def;
    inp.addEventListener("input", drawPreview);
    lab.appendChild(inp);
    box.appendChild(lab);
  }
  cell.appendChild(box);
}

function addSegment(seg) {
  const kind = (seg && seg.kind) || "hold";
  const tr = document.createElement("tr");
  tr.appendChild(td(""));
  const kc = document.createElement("td");
  const ks = document.createElement("select");
  fillSelect(ks, Object.keys(SEG_FIELDS));
  ks.value = SEG_FIELDS[kind] ? kind : "hold";
  ks.dataset.key = "kind";
  kc.appendChild(ks);
  tr.appendChild(kc);
  const pc = document.createElement("td");
  tr.appendChild(pc);
  segParams(pc, ks.value, seg);
  ks.addEventListener("change", () => { segParams(pc, ks.value); renumberSegments(); });
  const rc = document.createElement("td");
  const rm = document.createElement("button");
  rm.type = "button"; rm.textContent = "✕"; rm.title = "remove this segment"; rm.className = "rm-seg";
  rm.addEventListener("click", () => { tr.remove(); renumberSegments(); });
  rc.appendChild(rm);
  tr.appendChild(rc);
  $("#d-segments").appendChild(tr);
  renumberSegments();
}

function readSegments(strict) {
  return $$("#d-segments tr").map((tr) => {
    const seg = { kind: $("[data-key=kind]", tr).value };
    for (const inp of $$(".segparams [data-key]", tr)) {
      if (inp.tagName === "SELECT") seg[inp.dataset.key] = inp.value;
      else if (strict) seg[inp.dataset.key] = readNumber(inp);
      else seg[inp.dataset.key] = Number(inp.value);
    }
    return seg;
  });
}

/* the same sampling as ocp.mission.sample_segments (1 kHz, segments share their boundary sample) */
function sampleSegments(segments, rate = 1000) {
  const t = [], f = [];
  let level = 0, t0 = 0;
  for (const seg of segments) {
    const d = seg.duration;
    if (!(d > 0)) continue;
    const n = Math.max(2, Math.ceil(d * rate)) + 1;
    let last = level;
    for (let k = 0; k < n; k++) {
      const s = (d * k) / (n - 1), x = s / d;
      let v;
      if (seg.kind === "hold") v = seg.thrust;
      else if (seg.kind === "ramp" || (seg.kind === "reversal" && seg.shape === "ramp")) v = level + (seg.to - level) * x;
      else if (seg.kind === "reversal" && seg.shape === "step") v = x < 0.5 ? level : seg.to;
      else if (seg.kind === "reversal") v = level + (seg.to - level) * 0.5 * (1 - Math.cos(Math.PI * x));
      else v = seg.offset + seg.amplitude * Math.sin((2 * Math.PI * s) / seg.period + seg.phase);
      if (k === 0 && t.length) continue;
      t.push(t0 + s); f.push(v);
      last = v;
    }
    t0 += d; level = last;
  }
  return { t, f };
}

function desiredProfile() {
  if (profileMode() === "csv") return state.csvProfile ? { t: state.csvProfile.t, f: state.csvProfile.thrust } : { t: [], f: [] };
  return sampleSegments(readSegments(false));
}

function drawPreview() {
  try {
    const { t, f } = desiredProfile();
    if (t.length < 2) { $("#d-preview").innerHTML = ""; return; }
    Plot.line($("#d-preview"), { title: "desired thrust", xlabel: "t [s]", ylabel: "N", height: 150,
      series: [{ x: t, y: f, color: "#57606a" }] });
  } catch (e) { $("#d-preview").innerHTML = ""; }
}

function profileMode() { return $("input[name=d-profile]:checked").value; }

function setProfileMode(mode) {
  $(`input[name=d-profile][value=${mode}]`).checked = true;
  $("#d-segments-box").hidden = mode !== "segments";
  $("#d-csv-box").hidden = mode !== "csv";
  drawPreview();
}

function parseProfileCsv(text) {
  const lines = text.split(/\r?\n/).map((l) => l.trim()).filter((l) => l && !l.startsWith("#"));
  if (!lines.length) throw new FieldError("profile", "the file is empty");
  const split = (l) => l.split(/[,;\t]/).map((c) => c.trim());
  let it = 0, ic = 1, start = 0;
  const head = split(lines[0]);
  if (head.some((c) => c !== "" && !Number.isFinite(Number(c)))) {
    const low = head.map((c) => c.toLowerCase().replace(/\s*\[.*\]$/, ""));
    it = low.findIndex((c) => c === "t" || c === "time");
    ic = low.findIndex((c) => c === "thrust" || c === "f" || c === "force");
    if (it < 0 || ic < 0) throw new FieldError("profile", `need columns t and thrust; the header has ${head.join(", ")}`);
    start = 1;
  }
  const t = [], thrust = [];
  for (let k = start; k < lines.length; k++) {
    const c = split(lines[k]);
    const a = Number(c[it]), b = Number(c[ic]);
    if (!Number.isFinite(a) || !Number.isFinite(b)) throw new FieldError("profile", `line ${k + 1}: not two numbers: ${lines[k]}`);
    if (t.length && a <= t[t.length - 1]) throw new FieldError("profile", `line ${k + 1}: t must be strictly increasing`);
    t.push(a); thrust.push(b);
  }
  if (t.length < 2) throw new FieldError("profile", "need at least two samples");
  return { t, thrust };
}

/* ------------------------------------------------------------------ Design: mission <-> form */

function readParams(selectEl, textEl, field) {
  if (selectEl.value !== "__custom__") return selectEl.value;
  const text = textEl.value.trim();
  if (!text) throw new FieldError(field, "paste a parameter mapping (JSON) or pick a preset");
  const p = parseJsonField(text, field);
  if (p === null || typeof p !== "object" || Array.isArray(p)) throw new FieldError(field, "must be a JSON object");
  return p;
}

function buildMission() {
  const m = { name: $("#d-name").value.trim() || "mission" };
  m.params = readParams($("#d-preset"), $("#d-params"), "params");
  m.limits = { voltage: readNumber($("#d-voltage")), current: readNumber($("#d-current")) };
  const vr = readNumber($("#d-vrate"), { optional: true }), sp = readNumber($("#d-speed"), { optional: true });
  if (vr !== undefined) m.limits.voltage_rate = vr;
  if (sp !== undefined) m.limits.speed = sp;
  m.regularity = $("#d-regularity").value;
  m.objective = $("#d-objective").value;
  m.retiming = { min_stretch: readNumber($("#d-minstretch")), max_stretch: readNumber($("#d-maxstretch")) };
  m.collocation = { intervals: readNumber($("#d-intervals"), { integer: true }) };
  m.time_limit_s = readNumber($("#d-timelimit"));
  if (profileMode() === "csv") {
    if (!state.csvProfile) throw new FieldError("profile", "choose a t,thrust CSV file");
    m.profile = { t: state.csvProfile.t, thrust: state.csvProfile.thrust };
  } else {
    const segs = readSegments(true);
    if (!segs.length) throw new FieldError("segments", "add at least one segment");
    m.segments = segs;
  }
  return m;
}

function fillMission(m) {
  clearErrors($("#tab-design"));
  $("#d-name").value = m.name || "mission";
  const p = m.params === undefined ? "paper-rig" : m.params;
  if (typeof p === "string" && $$("#d-preset option").some((o) => o.value === p)) {
    $("#d-preset").value = p; $("#d-params").hidden = true;
  } else {
    $("#d-preset").value = "__custom__"; $("#d-params").hidden = false;
    $("#d-params").value = typeof p === "string" ? p : JSON.stringify(p, null, 1);
  }
  const lim = m.limits || {};
  $("#d-voltage").value = lim.voltage ?? 12;
  $("#d-current").value = lim.current ?? 2;
  $("#d-vrate").value = lim.voltage_rate ?? "";
  $("#d-speed").value = lim.speed ?? "";
  if (m.regularity) $("#d-regularity").value = m.regularity;
  $("#d-objective").value = m.objective || "track";
  $("#d-minstretch").value = (m.retiming || {}).min_stretch ?? 1;
  $("#d-maxstretch").value = (m.retiming || {}).max_stretch ?? 1.5;
  $("#d-intervals").value = (m.collocation || {}).intervals ?? 120;
  $("#d-timelimit").value = m.time_limit_s ?? 10;
  $("#d-segments").innerHTML = "";
  if (m.profile) {
    state.csvProfile = { t: m.profile.t, thrust: m.profile.thrust };
    $("#d-csv-info").textContent = `${m.profile.t.length} samples from the mission file`;
    setProfileMode("csv");
  } else {
    (m.segments || []).forEach(addSegment);
    setProfileMode("segments");
  }
}

async function loadExampleMission() {
  const resp = await fetch("/static/example-mission.json");
  if (!resp.ok) throw new ApiError(resp.status, null, "the bundled example is missing");
  fillMission(await resp.json());
}

/* ------------------------------------------------------------------ Design: results */

function limitLines(limit, unit) {
  return limit ? [{ y: limit, label: `+${fmt(limit)} ${unit} limit` }, { y: -limit, label: `−${fmt(limit)} ${unit} limit` }] : [];
}

function showDesign(res, mission) {
  state.design = res; state.designMission = mission;
  $("#d-results").hidden = false;
  const src = $("#d-source");
  src.textContent = res.source === "optimized" ? "optimiser" : "analytic fallback";
  src.className = `badge ${res.source}`;
  src.setAttribute("data-source", res.source);
  $("#d-status").textContent = `status ${res.status}` + (res.solve_time_s != null ? ` · solve ${fmt(res.solve_time_s * 1000, 3)} ms` : "") +
    (res.iterations != null ? ` · ${res.iterations} iterations` : "");
  $("#d-reason").textContent = res.reason ? `why: ${res.reason}` : "";
  const v = res.verification || {};
  const lim = mission.limits;
  const rows = [
    ["thrust RMS error (plan vs simulated) [N]", v.thrust_rms_error],
    ["tracking RMS error (vs desired) [N]", v.tracking_rms_error],
    ["max |current| [A]", v.max_abs_current, `limit ${fmt(lim.current)} A, margin ${fmt(v.current_margin)} A`],
    ["max |voltage| [V]", v.max_abs_voltage, `limit ${fmt(lim.voltage)} V, margin ${fmt(v.voltage_margin)} V`],
    ["max |speed| [rad/s]", v.max_abs_speed],
    ["within limits along the path", v.path_ok],
  ];
  const vb = $("#d-verification tbody");
  vb.innerHTML = "";
  for (const [k, val, note] of rows) {
    if (val === undefined) continue;
    const r = row([k, td(fmt(val), typeof val === "boolean" ? (val ? "good" : "bad") : "num"), note || ""]);
    r.dataset.key = k;
    vb.appendChild(r);
  }
  const cb = $("#d-crossings tbody");
  cb.innerHTML = "";
  const cross = res.crossings || [];
  if (!cross.length) cb.appendChild(row([td("no thrust reversal", "muted"), "", "", ""]));
  for (const c of cross) cb.appendChild(row([td(fmt(c.t), "num"), td(`g = ${fmt(c.exponent, 3)}`, "num exponent"),
                                              td(fmt(c.current), "num"), td(fmt(c.voltage), "num")]));
  const t = res.t;
  const markers = (key) => cross.map((c) => ({ x: c.t, y: key ? c[key] : 0, label: `g = ${fmt(c.exponent, 3)}` }));
  Plot.line($("#d-plot-thrust"), { title: "thrust", xlabel: "t [s]", ylabel: "N", markers: markers(null),
    series: [{ x: t, y: res.thrust_desired, label: "desired", color: "#8c959f", dash: "5 4" },
             { x: t, y: res.thrust, label: "optimised (simulated)", color: "#1f6feb" }] });
  Plot.line($("#d-plot-speed"), { title: "speed", xlabel: "t [s]", ylabel: "rad/s", markers: markers(null),
    series: [{ x: t, y: res.omega, label: "ω", color: "#1a7f37" }],
    hlines: lim.speed ? limitLines(lim.speed, "rad/s") : [] });
  Plot.line($("#d-plot-current"), { title: "current", xlabel: "t [s]", ylabel: "A", markers: markers("current"),
    series: [{ x: t, y: res.current, label: "i", color: "#bf8700" }], hlines: limitLines(lim.current, "A") });
  Plot.line($("#d-plot-voltage"), { title: "voltage", xlabel: "t [s]", ylabel: "V", markers: markers("voltage"),
    series: [{ x: t, y: res.voltage, label: "V", color: "#8250df" }],
    hlines: limitLines(lim.voltage, "V") });
}

function designCsv(res) {
  const cols = ["t", "thrust", "thrust_desired", "omega", "theta", "current", "voltage"].filter((c) => Array.isArray(res[c]));
  const lines = [cols.join(",")];
  for (let i = 0; i < res.t.length; i++) lines.push(cols.map((c) => (res[c][i] === null ? "" : res[c][i])).join(","));
  return lines.join("\n") + "\n";
}

async function runDesign() {
  const scope = $("#tab-design");
  await guarded(scope, $("#d-busy"), async () => {
    const mission = buildMission();
    const res = await api("POST", "/v1/references/optimize", mission);
    showDesign(res, mission);
  });
}

/* ------------------------------------------------------------------ Compare */

const COMPARE_COLS = [
  ["label", "shape"], ["duration_s", "duration [s]"], ["peak_current_a", "peak current [A]"],
  ["peak_voltage_v", "peak voltage [V]"], ["energy_j", "energy [J]"], ["thrust_rms_error_n", "thrust RMS error [N]"],
  ["crossing_exponents", "crossing exponents"], ["within_limits", "within limits"],
  ["loop_thrust_rms_n", "closed-loop thrust RMS [N]"], ["loop_peak_voltage_v", "closed-loop peak V [V]"],
  ["loop_peak_current_a", "closed-loop peak i [A]"],
];
const UNBOUNDED_IF_NULL = new Set(["peak_current_a", "peak_voltage_v", "energy_j"]);

function exponentsText(xs) {
  if (!Array.isArray(xs) || !xs.length) return "none";
  const uniq = [...new Set(xs.map((x) => fmt(x, 3)))];
  return `${uniq.join(", ")} (${xs.length} crossing${xs.length > 1 ? "s" : ""})`;
}

function showCompareTable(table) {
  const head = $("#c-table thead"), body = $("#c-table tbody");
  head.innerHTML = ""; body.innerHTML = "";
  head.appendChild(row(COMPARE_COLS.map(([, h]) => { const th = document.createElement("th"); th.textContent = h; return th; })));
  for (const r of table) {
    body.appendChild(row(COMPARE_COLS.map(([k]) => {
      const v = r[k];
      if (k === "label") return td(v);
      if (k === "crossing_exponents") return td(exponentsText(v));
      if (k === "within_limits") return td(fmt(v), v ? "good" : "bad");
      if ((v === null || v === "inf") && UNBOUNDED_IF_NULL.has(k)) return td("∞ unbounded", "num bad");
      return td(fmt(v), "num");
    })));
  }
}

function compareCurves(cmp, opt) {
  /* the curves of every candidate when the server sends them (``candidates``: label, t, thrust, omega, current,
     voltage); otherwise the optimised reference alone (the table still has every shape) */
  const cands = (cmp.candidates || []).filter((c) => c && Array.isArray(c.t));
  if (cands.length) return cands.map((c) => ({ label: c.label, r: c }));
  return [{ label: opt.source === "optimized" ? "optimised" : "fallback", r: opt }];
}

function drawCompare(series, mission) {
  const lim = mission.limits;
  const colors = ["#1f6feb", "#cf222e", "#bf8700", "#1a7f37", "#8250df"];
  const mk = (key) => series.map((s, k) => ({ x: s.r.t, y: s.r[key], label: s.label, color: colors[k % colors.length] }));
  Plot.line($("#c-plot-thrust"), { title: "thrust", xlabel: "t [s]", ylabel: "N", series: mk("thrust") });
  Plot.line($("#c-plot-speed"), { title: "speed", xlabel: "t [s]", ylabel: "rad/s", series: mk("omega") });
  Plot.line($("#c-plot-current"), { title: "current (clipped at ±3× limit)", xlabel: "t [s]", ylabel: "A",
    series: mk("current"), hlines: limitLines(lim.current, "A"), yrange: [-3 * lim.current, 3 * lim.current] });
  Plot.line($("#c-plot-voltage"), { title: "voltage (clipped at ±3× limit)", xlabel: "t [s]", ylabel: "V",
    series: mk("voltage"), hlines: limitLines(lim.voltage, "V"), yrange: [-3 * lim.voltage, 3 * lim.voltage] });
}

function drawCompareBars(table, mission) {
  /* the table's figures side by side; an unbounded peak (null) gets no bar and an "∞" label */
  const box = $("#c-bars");
  box.innerHTML = "";
  const labels = table.map((r) => String(r.label).replace(" (mission q)", "*"));
  const charts = [
    ["peak_current_a", `ideal peak current [A] (limit ${fmt(mission.limits.current)} A)`],
    ["peak_voltage_v", `ideal peak voltage [V] (limit ${fmt(mission.limits.voltage)} V)`],
    ["loop_thrust_rms_n", "closed-loop thrust RMS error [N]"],
    ["loop_peak_current_a", "closed-loop peak current [A]"],
  ];
  for (const [key, title] of charts) {
    const div = document.createElement("div");
    div.className = "plotbox";
    box.appendChild(div);
    const glabels = table.map((r, k) => (r[key] === null || r[key] === "inf" ? `${labels[k]} (∞)` : labels[k]));
    Plot.bars(div, { title, groups: glabels, series: [{ label: "", values: table.map((r) => (r[key] === "inf" ? null : r[key])) }],
                     height: 190 });
  }
}

async function runCompare() {
  await guarded($("#tab-compare"), $("#c-busy"), async () => {
    let mission;
    try {
      mission = buildMission();
    } catch (err) {
      selectTab("design");
      showError($("#tab-design"), err);
      throw new ApiError(0, null, "the mission on the Design tab is not valid; see the message there");
    }
    const cmp = await api("POST", "/v1/compare", mission);
    const sameAsDesign = state.design && JSON.stringify(state.designMission) === JSON.stringify(mission);
    const opt = (cmp.candidates || []).length ? null
      : sameAsDesign ? state.design : await api("POST", "/v1/references/optimize", mission);
    showCompareTable(cmp.table || []);
    $("#c-note").textContent = `mission ${cmp.mission}: optimised answer from the ${cmp.optimized_source === "optimized" ? "optimiser" : "analytic fallback"}` +
      (cmp.optimized_reason ? ` (${cmp.optimized_reason})` : "") + ". Unbounded peaks are the ideal feedforward at a linear crossing.";
    const curves = compareCurves(cmp, opt);
    if (curves.length === 1) $("#c-note").textContent += " This server's answer carries no curves of the analytic shapes: only the optimised reference is drawn.";
    drawCompare(curves, mission);
    drawCompareBars(cmp.table || [], mission);
  });
}

/* ------------------------------------------------------------------ Model check */

function modelForm(extra) {
  if (!state.modelLog) throw new FieldError("log", "choose a log file or use the bundled example");
  const fd = new FormData();
  fd.append("log", state.modelLog.blob, state.modelLog.name);
  const p = readParams($("#m-preset"), $("#m-params"), "params");
  if (typeof p === "string") fd.append("params", p);
  else fd.append("params", JSON.stringify(p));
  const cols = $("#m-columns").value.trim();
  if (cols) { parseJsonField(cols, "columns"); fd.append("columns", cols); }
  for (const [k, v] of Object.entries(extra || {})) fd.append(k, v);
  return fd;
}

function setLog(blob, name, note) {
  state.modelLog = { blob, name };
  $("#m-log-info").textContent = `${name} (${Math.round(blob.size / 1024)} kB)${note ? " — " + note : ""}`;
}

const CHANNEL_UNITS = { omega: "rad/s", current: "A", thrust: "N" };

function showCheck(res, reportHtml) {
  $("#m-check-results").hidden = false;
  const fr = res.free_run || {}, os_ = res.one_step || {}, noise = res.noise || {};
  const units = fr.units || CHANNEL_UNITS;
  const eb = $("#m-errors tbody");
  eb.innerHTML = "";
  for (const ch of Object.keys(fr.rms || {})) {
    const rms = fr.rms[ch], n = noise[ch];
    const ratio = rms != null && n ? rms / n : null;
    const r = row([`${ch} [${units[ch] || ""}]`, td(fmt(rms), "num"), td(fmt((fr.max || {})[ch]), "num"), td(fmt(n), "num"),
                   td(ratio == null ? "—" : `${fmt(ratio, 3)}×`, ratio != null && ratio > 2 ? "num bad" : "num good")]);
    r.dataset.channel = ch;
    eb.appendChild(r);
  }
  const ob = $("#m-onestep tbody");
  ob.innerHTML = "";
  const ou = os_.units || {};
  for (const eq of Object.keys(os_.rms || {})) {
    ob.appendChild(row([`${eq} [${ou[eq] || ""}]`, td(fmt(os_.rms[eq]), "num"), td(fmt((os_.mean || {})[eq]), "num")]));
  }
  // breakdowns: mean torque residual and free-run speed error per bin, for every grouping
  const box = $("#m-breakdown");
  box.innerHTML = "";
  for (const [group, bins] of Object.entries(res.breakdown || {})) {
    const labels = Object.keys(bins);
    const div = document.createElement("div");
    div.className = "plotbox";
    div.dataset.group = group;
    box.appendChild(div);
    Plot.bars(div, { title: `by ${group}`, groups: labels, ylabel: "residual",
      series: [{ label: "mean torque residual [mN m]", values: labels.map((l) => scale(bins[l]["one_step_mean.mechanical"], 1e3)) },
               { label: "free-run speed RMS [rad/s]", values: labels.map((l) => bins[l]["free_run_rms.omega"]) }] });
  }
  // measured vs simulated: the figures of the server's HTML report
  const figs = $("#m-figures");
  figs.innerHTML = "";
  $("#m-report-link").innerHTML = "";
  if (reportHtml) {
    const doc = new DOMParser().parseFromString(reportHtml, "text/html");
    for (const alt of ["free_run", "one_step"]) {
      const img = doc.querySelector(`img[alt="${alt}"]`);
      if (!img) continue;
      const fig = document.createElement("figure");
      const cap = document.createElement("figcaption");
      cap.textContent = alt === "free_run" ? "measured vs simulated (free run under the measured voltage)" : "one-step equation residuals";
      const im = document.createElement("img");
      im.src = img.getAttribute("src"); im.alt = alt;
      fig.appendChild(cap); fig.appendChild(im);
      figs.appendChild(fig);
    }
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([reportHtml], { type: "text/html" }));
    a.download = "model-check.html"; a.textContent = "Download the full HTML report";
    $("#m-report-link").appendChild(a);
  }
}

function scale(v, k) { return v === null || v === undefined ? null : v * k; }

function showDiagnose(res) {
  $("#m-diag-results").hidden = false;
  const verdict = res.verdict || [];
  const vd = $("#m-verdict");
  vd.innerHTML = "";
  if (!verdict.length) vd.textContent = "Nothing missing: no candidate effect reduces the held-out error significantly.";
  else {
    vd.append("Missing: ");
    const s = document.createElement("strong");
    s.textContent = verdict.join(", ");
    vd.appendChild(s);
    const p = document.createElement("div");
    p.className = "muted";
    p.textContent = res.message || (res.explanations || []).join("; ") || res.explanation || "";
    vd.appendChild(p);
  }
  vd.dataset.verdict = verdict.join(",");
  const tb = $("#m-ranking tbody");
  tb.innerHTML = "";
  for (const e of res.ranking || []) {
    const cb = document.createElement("input");
    cb.type = "checkbox"; cb.value = e.effect; cb.checked = verdict.includes(e.effect);
    cb.setAttribute("aria-label", `add ${e.effect}`);
    const c0 = document.createElement("td"); c0.appendChild(cb);
    const units = e.units || {};
    const params = Object.entries(e.parameters || {}).map(([k, v]) => `${k} = ${fmt(v)}${units[k] ? " " + units[k] : ""}`).join(", ");
    const imp = e.improvement == null ? "—" : `${fmt(100 * e.improvement, 3)} %`;
    const r = row([c0, td(e.effect), td(imp, "num"), td(e.significant ? "yes" : "no", e.significant ? "good" : ""),
                   td(params), td(e.explanation || "")]);
    r.dataset.effect = e.effect;
    tb.appendChild(r);
  }
}

function showFit(res) {
  state.fit = res;
  $("#m-fit-results").hidden = false;
  const before = res.rms_before || {}, after = res.rms_after || {};
  const units = res.units || CHANNEL_UNITS;
  const tb = $("#m-beforeafter tbody");
  tb.innerHTML = "";
  const chans = Object.keys(before);
  for (const ch of chans) {
    const b = before[ch], a = after[ch];
    const ratio = b && a != null ? a / b : null;
    const r = row([`${ch} [${units[ch] || ""}]`, td(fmt(b), "num before"), td(fmt(a), "num after"),
                   td(ratio == null ? "—" : `${fmt(ratio, 3)}`, ratio != null && ratio < 1 ? "num good" : "num bad")]);
    r.dataset.channel = ch; r.dataset.before = b; r.dataset.after = a;
    tb.appendChild(r);
  }
  const fb = $("#m-fitted tbody");
  fb.innerHTML = "";
  for (const [k, v] of Object.entries(res.parameters || {})) {
    fb.appendChild(row([k, td(fmt(v && typeof v === "object" ? v.value : v), "num"),
                        td(fmt(v && typeof v === "object" ? v.stderr : null), "num")]));
  }
  Plot.bars($("#m-plot-beforeafter"), { title: "free-run RMS error, relative to before", groups: chans, ylabel: "after / before",
    series: [{ label: "before", values: chans.map(() => 1), color: "#8c959f" },
             { label: "after", values: chans.map((c) => (before[c] ? after[c] / before[c] : null)), color: "#1a7f37" }] });
}

function calibratedParams() {
  const r = state.fit || {};
  return r.calibrated_params || r.calibrated || null;
}

async function checkReport() {
  try {
    return await api("POST", "/v1/model-check/check?report=html", modelForm(), { form: true, accept: "text" });
  } catch (e) {
    return null;  // the figures are a bonus: the numbers above are the check
  }
}

async function runCheck() {
  await guarded($("#tab-model"), $("#m-busy"), async () => {
    const res = await api("POST", "/v1/model-check/check", modelForm(), { form: true });
    showCheck(res, null);
    showCheck(res, await checkReport());
  });
}

async function runDiagnose() {
  await guarded($("#tab-model"), $("#m-busy"), async () => {
    const diag = await api("POST", "/v1/model-check/diagnose", modelForm(), { form: true });
    showDiagnose(diag);
    try {  // where it fails, too (requests one after the other: solves share the server's few workers)
      const res = await api("POST", "/v1/model-check/check", modelForm(), { form: true });
      showCheck(res, await checkReport());
    } catch (e) { /* the diagnosis stands on its own */ }
  });
}

async function runFit() {
  await guarded($("#tab-model"), $("#m-fit-busy"), async () => {
    const effects = $$("#m-ranking input[type=checkbox]:checked").map((c) => c.value);
    if (!effects.length) throw new FieldError("effects", "tick at least one effect to add");
    showFit(await api("POST", "/v1/model-check/fit", modelForm({ effects: effects.join(",") }), { form: true }));
  });
}

/* ------------------------------------------------------------------ Batch */

async function unzip(buf) {
  /* entries of a zip file (stored or deflated), from its central directory */
  const v = new DataView(buf), out = [];
  let eocd = -1;
  for (let i = buf.byteLength - 22; i >= Math.max(0, buf.byteLength - 65557); i--) {
    if (v.getUint32(i, true) === 0x06054b50) { eocd = i; break; }
  }
  if (eocd < 0) throw new Error("not a zip file");
  const count = v.getUint16(eocd + 10, true);
  let p = v.getUint32(eocd + 16, true);
  const dec = new TextDecoder();
  for (let k = 0; k < count; k++) {
    if (v.getUint32(p, true) !== 0x02014b50) throw new Error("damaged zip directory");
    const method = v.getUint16(p + 10, true), csize = v.getUint32(p + 20, true);
    const nlen = v.getUint16(p + 28, true), xlen = v.getUint16(p + 30, true), clen = v.getUint16(p + 32, true);
    const local = v.getUint32(p + 42, true);
    const name = dec.decode(new Uint8Array(buf, p + 46, nlen));
    p += 46 + nlen + xlen + clen;
    if (name.endsWith("/")) continue;
    const start = local + 30 + v.getUint16(local + 26, true) + v.getUint16(local + 28, true);
    const data = new Uint8Array(buf, start, csize);
    let bytes;
    if (method === 0) bytes = data;
    else if (method === 8) bytes = new Uint8Array(await new Response(new Blob([data]).stream().pipeThrough(new DecompressionStream("deflate-raw"))).arrayBuffer());
    else throw new Error(`${name}: unsupported compression method ${method}`);
    out.push({ name, text: dec.decode(bytes) });
  }
  return out;
}

function missionsFromJson(name, text) {
  let data;
  try { data = JSON.parse(text); } catch (e) { throw new FieldError("missions", `${name}: not valid JSON (${e.message})`); }
  const list = Array.isArray(data) ? data : data && Array.isArray(data.missions) ? data.missions : [data];
  return list.map((m, k) => {
    if (!m || typeof m !== "object" || Array.isArray(m)) throw new FieldError("missions", `${name}: item ${k + 1} is not a mission object`);
    return { source: list.length > 1 ? `${name} [${k + 1}]` : name, mission: m };
  });
}

async function addBatchFiles(files) {
  const got = [];
  for (const f of files) {
    if (/\.zip$/i.test(f.name)) {
      let entries;
      try { entries = await unzip(await f.arrayBuffer()); } catch (e) { throw new FieldError("missions", `${f.name}: ${e.message}`); }
      for (const e of entries) if (/\.json$/i.test(e.name)) got.push(...missionsFromJson(`${f.name}/${e.name}`, e.text));
    } else {
      got.push(...missionsFromJson(f.name, await f.text()));
    }
  }
  state.batchMissions.push(...got);
  renderBatchList();
}

function renderBatchList() {
  const list = $("#b-list");
  list.textContent = state.batchMissions.length
    ? `${state.batchMissions.length} mission(s): ` + state.batchMissions.map((m) => `${m.mission.name || "mission"} (${m.source})`).join(", ")
    : "no missions chosen";
}

function batchErrorField(err) {
  /* "missions.3.limits.current" -> name the file the mission came from */
  const m = /^missions\.(\d+)\.?(.*)$/.exec(err.field || "");
  if (!m) return err;
  const item = state.batchMissions[Number(m[1])];
  const where = item ? `${item.source}` : `mission ${Number(m[1]) + 1}`;
  return new ApiError(err.status, "missions", `${where}: ${m[2] || "mission"}: ${err.reason}`);
}

async function pollBatch(id) {
  for (;;) {
    const s = await api("GET", `/v1/batches/${encodeURIComponent(id)}`);
    const c = s.counts;
    $("#b-progress").value = s.progress;
    $("#b-status").textContent = `${s.status} — ${c.done} done, ${c.failed} failed, ${c.running} running, ${c.queued} queued of ${c.total} (${Math.round(100 * s.progress)} %)`;
    $("#b-status").dataset.status = s.status;
    if (s.status === "done" || s.status === "failed") return s;
    await new Promise((r) => setTimeout(r, 400));
  }
}

async function runBatch() {
  await guarded($("#tab-batch"), null, async () => {
    if (!state.batchMissions.length) throw new FieldError("missions", "choose mission files (or a zip), or add the Design tab's mission");
    let acc;
    try {
      acc = await api("POST", "/v1/batches", { missions: state.batchMissions.map((m) => m.mission) });
    } catch (err) {
      throw err instanceof ApiError ? batchErrorField(err) : err;
    }
    state.batch = acc.id;
    $("#b-results").hidden = false;
    $("#b-id").textContent = `batch ${acc.id}`;
    $("#b-table tbody").innerHTML = "";
    $("#b-dl-json").disabled = true; $("#b-dl-csv").disabled = true;
    await pollBatch(acc.id);
    const res = await api("GET", `/v1/batches/${encodeURIComponent(acc.id)}/results`);
    state.batchResults = res;
    const tb = $("#b-table tbody");
    for (const it of res.results) {
      const r = it.result || {}, v = r.verification || {};
      const e = it.error ? `${it.error.type}${it.error.field ? " " + it.error.field : ""}: ${it.error.reason}` : "";
      tb.appendChild(row([String(it.index + 1), it.name, td(it.status, it.status === "done" ? "good" : "bad"), r.source || "",
                          td(fmt(v.thrust_rms_error), "num"), td(fmt(v.max_abs_current), "num"), td(fmt(v.max_abs_voltage), "num"), e]));
    }
    $("#b-dl-json").disabled = false; $("#b-dl-csv").disabled = false;
  });
}

/* ------------------------------------------------------------------ wiring */

function on(sel, ev, fn) {
  $(sel).addEventListener(ev, (e) => {
    Promise.resolve().then(() => fn(e)).catch((err) => {
      const scope = e.target.closest(".tab") || document.body;
      showError(scope, err);
    });
  });
}

function init() {
  window.addEventListener("error", (e) => { const t = $("#toast"); t.textContent = `page error: ${e.message}`; t.hidden = false; });
  window.addEventListener("unhandledrejection", (e) => { const t = $("#toast"); t.textContent = `page error: ${e.reason}`; t.hidden = false; });
  $("#toast").addEventListener("click", () => { $("#toast").hidden = true; });
  $$("#tabs button").forEach((b) => b.addEventListener("click", () => selectTab(b.dataset.tab)));
  $$("[data-goto]").forEach((a) => a.addEventListener("click", (e) => { e.preventDefault(); selectTab(a.dataset.goto); }));
  window.addEventListener("hashchange", () => selectTab(location.hash.slice(1)));
  selectTab(location.hash.slice(1) || "design");

  const key = $("#api-key");
  key.value = localStorage.getItem("thrustshape.apiKey") || "";
  key.addEventListener("change", () => { localStorage.setItem("thrustshape.apiKey", key.value.trim()); clearErrors($("header")); loadInfo(); });

  // design
  on("#d-preset", "change", () => { $("#d-params").hidden = $("#d-preset").value !== "__custom__"; });
  $$("input[name=d-profile]").forEach((r) => r.addEventListener("change", () => setProfileMode(r.value)));
  on("#d-add-seg", "click", () => addSegment({ kind: "hold" }));
  on("#d-example", "click", () => guarded($("#tab-design"), null, loadExampleMission));
  on("#d-mission-file", "change", (e) => guarded($("#tab-design"), null, async () => {
    const f = e.target.files[0];
    if (!f) return;
    const m = missionsFromJson(f.name, await f.text())[0].mission;
    fillMission(m);
  }));
  on("#d-csv", "change", (e) => guarded($("#tab-design"), null, async () => {
    state.csvProfile = null;
    $("#d-csv-info").textContent = "";
    const f = e.target.files[0];
    if (!f) return;
    state.csvProfile = parseProfileCsv(await f.text());
    $("#d-csv-info").textContent = `${f.name}: ${state.csvProfile.t.length} samples, ${fmt(state.csvProfile.t[0])}–${fmt(state.csvProfile.t[state.csvProfile.t.length - 1])} s`;
    drawPreview();
  }));
  $("#design-form").addEventListener("submit", (e) => { e.preventDefault(); runDesign(); });
  on("#d-dl-csv", "click", () => download(`${safeName(state.design.name)}.csv`, designCsv(state.design), "text/csv"));
  on("#d-dl-json", "click", () => download(`${safeName(state.design.name)}.json`, JSON.stringify(state.design, null, 1), "application/json"));
  on("#d-dl-mission", "click", () => download(`${safeName(state.designMission.name)}-mission.json`, JSON.stringify(state.designMission, null, 2), "application/json"));

  // compare
  on("#c-run", "click", runCompare);

  // model check
  on("#m-log", "change", (e) => { const f = e.target.files[0]; if (f) setLog(f, f.name); });
  on("#m-example", "click", () => guarded($("#tab-model"), null, async () => {
    const resp = await fetch("/static/example-log.csv");
    if (!resp.ok) throw new ApiError(resp.status, "log", "the bundled example log is missing");
    setLog(await resp.blob(), "example-log.csv", "bundled synthetic rig log, paper-rig plant with one hidden effect");
    $("#m-preset").value = "paper-rig";
    $("#m-params").hidden = true; $("#m-params-file-label").hidden = true;
  }));
  on("#m-preset", "change", () => {
    const custom = $("#m-preset").value === "__custom__";
    $("#m-params").hidden = !custom; $("#m-params-file-label").hidden = !custom;
  });
  on("#m-params-file", "change", async (e) => { const f = e.target.files[0]; if (f) $("#m-params").value = await f.text(); });
  on("#m-check", "click", runCheck);
  on("#m-diagnose", "click", runDiagnose);
  on("#m-fit", "click", runFit);
  on("#m-dl-params", "click", () => download("calibrated-params.json", JSON.stringify(calibratedParams(), null, 2) + "\n", "application/json"));
  on("#m-use-params", "click", () => {
    const p = calibratedParams();
    if (!p) return;
    const { notes, ...clean } = p;  // provenance notes are not plant parameters
    $("#d-preset").value = "__custom__"; $("#d-params").hidden = false;
    $("#d-params").value = JSON.stringify(clean, null, 1);
    selectTab("design");
  });

  // batch
  on("#b-files", "change", (e) => guarded($("#tab-batch"), null, async () => {
    state.batchMissions = [];
    await addBatchFiles(Array.from(e.target.files));
  }));
  on("#b-add-design", "click", () => guarded($("#tab-batch"), null, async () => {
    state.batchMissions.push({ source: "Design tab", mission: buildMission() });
    renderBatchList();
  }));
  on("#b-clear", "click", () => { state.batchMissions = []; $("#b-files").value = ""; renderBatchList(); });
  $("#batch-form").addEventListener("submit", (e) => { e.preventDefault(); runBatch(); });
  on("#b-dl-json", "click", () => download(`batch-${state.batch}.json`, JSON.stringify(state.batchResults, null, 1), "application/json"));
  on("#b-dl-csv", "click", () => guarded($("#tab-batch"), null, async () => {
    download(`batch-${state.batch}.csv`, await api("GET", `/v1/batches/${encodeURIComponent(state.batch)}/results?format=csv`, undefined, { accept: "blob" }));
  }));
  renderBatchList();

  loadInfo().then(() => {
    if (!$("#d-segments tr")) return loadExampleMission();
    return undefined;
  }).catch((err) => showError($("#tab-design"), err));
}

document.addEventListener("DOMContentLoaded", init);
