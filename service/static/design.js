/* thrustshape page, Design tab: the mission form (segments editor or t,thrust CSV), POST
   /v1/references/optimize, and its verification, crossings, plots and downloads.
   Other tabs use the mission as typed here (buildMission) and the last answer (lastDesign). */

import {
  $, $$, CUSTOM, FieldError, api, clearErrors, downloadJson, download, emptied, fetchStatic, fillPresets,
  fillSelect, fmt, guarded, limitLines, missionsFromJson, on, readNumber, readParams, row, safeName, syncCustom, td,
} from "./common.js";

const state = { design: null, designMission: null, csvProfile: null };

/** the last optimised answer and the mission it answers (both null before the first run) */
export const lastDesign = () => ({ result: state.design, mission: state.designMission });

/* ------------------------------------------------------------------ segments editor */

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

/* the same sampling as ocp.optimize.mission.sample_segments (1 kHz, segments share their boundary sample) */
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

/* ------------------------------------------------------------------ desired profile: segments or CSV */

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

/* ------------------------------------------------------------------ mission <-> form */

/** the mission the form describes; a FieldError names the first input that does not read */
export function buildMission() {
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

/** put parameters (a mapping, or its JSON text) in the custom box, e.g. a model check's calibrated file */
export function useParams(params) {
  $("#d-preset").value = CUSTOM;
  syncCustom($("#d-preset"), $("#d-params"));
  $("#d-params").value = typeof params === "string" ? params : JSON.stringify(params, null, 1);
}

export function fillMission(m) {
  clearErrors($("#tab-design"));
  $("#d-name").value = m.name || "mission";
  const p = m.params === undefined ? "paper-rig" : m.params;
  if (typeof p === "string" && $$("#d-preset option").some((o) => o.value === p)) {
    $("#d-preset").value = p;
    syncCustom($("#d-preset"), $("#d-params"));
  } else {
    useParams(p);
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

export async function loadExampleMission() {
  const resp = await fetchStatic("example-mission.json", null, "the bundled example is missing");
  fillMission(await resp.json());
}

/** the parameter presets and regularities the server offers (the choice made so far is kept) */
export function setDesignChoices(presets, regularities) {
  fillPresets($("#d-preset"), presets, "custom (JSON)…");
  const cur = $("#d-regularity").value;
  fillSelect($("#d-regularity"), regularities);
  if (cur) $("#d-regularity").value = cur;
}

/* ------------------------------------------------------------------ results */

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
  const vb = emptied("#d-verification tbody");
  for (const [k, val, note] of rows) {
    if (val === undefined) continue;
    const r = row([k, td(fmt(val), typeof val === "boolean" ? (val ? "good" : "bad") : "num"), note || ""]);
    r.dataset.key = k;
    vb.appendChild(r);
  }
  const cb = emptied("#d-crossings tbody");
  const cross = res.crossings || [];
  if (!cross.length) cb.appendChild(row([td("no thrust reversal", "muted"), "", "", ""]));
  for (const c of cross) cb.appendChild(row([td(fmt(c.t), "num"), td(`g = ${fmt(c.exponent, 3)}`, "num exponent"),
                                              td(fmt(c.current), "num"), td(fmt(c.voltage), "num")]));
  const t = res.t;
  const markers = (key) => cross.map((c) => ({ x: c.t, y: key ? c[key] : 0, label: `g = ${fmt(c.exponent, 3)}` }));
  Plot.line($("#d-plot-thrust"), { title: "thrust", group: "design", xlabel: "t [s]", ylabel: "N", markers: markers(null),
    series: [{ x: t, y: res.thrust_desired, label: "desired", color: "#8c959f", dash: "5 4" },
             { x: t, y: res.thrust, label: "optimised (simulated)", color: "#1f6feb" }] });
  Plot.line($("#d-plot-speed"), { title: "speed", group: "design", xlabel: "t [s]", ylabel: "rad/s", markers: markers(null),
    series: [{ x: t, y: res.omega, label: "ω", color: "#1a7f37" }],
    hlines: lim.speed ? limitLines(lim.speed, "rad/s") : [] });
  Plot.line($("#d-plot-current"), { title: "current", group: "design", xlabel: "t [s]", ylabel: "A", markers: markers("current"),
    series: [{ x: t, y: res.current, label: "i", color: "#bf8700" }], hlines: limitLines(lim.current, "A") });
  Plot.line($("#d-plot-voltage"), { title: "voltage", group: "design", xlabel: "t [s]", ylabel: "V", markers: markers("voltage"),
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
  await guarded($("#tab-design"), $("#d-busy"), async () => {
    const mission = buildMission();
    const res = await api("POST", "/v1/references/optimize", mission);
    showDesign(res, mission);
  });
}

/* ------------------------------------------------------------------ wiring */

export function initDesign() {
  const scope = $("#tab-design");
  on("#d-preset", "change", () => syncCustom($("#d-preset"), $("#d-params")));
  $$("input[name=d-profile]").forEach((r) => r.addEventListener("change", () => setProfileMode(r.value)));
  on("#d-add-seg", "click", () => addSegment({ kind: "hold" }));
  on("#d-example", "click", () => guarded(scope, null, loadExampleMission));
  on("#d-mission-file", "change", (e) => guarded(scope, null, async () => {
    const f = e.target.files[0];
    if (!f) return;
    fillMission(missionsFromJson(f.name, await f.text())[0].mission);
  }));
  on("#d-csv", "change", (e) => guarded(scope, null, async () => {
    state.csvProfile = null;
    $("#d-csv-info").textContent = "";
    const f = e.target.files[0];
    if (!f) return;
    const p = parseProfileCsv(await f.text());
    state.csvProfile = p;
    $("#d-csv-info").textContent = `${f.name}: ${p.t.length} samples, ${fmt(p.t[0])}–${fmt(p.t[p.t.length - 1])} s`;
    drawPreview();
  }));
  $("#design-form").addEventListener("submit", (e) => { e.preventDefault(); runDesign(); });
  on("#d-dl-csv", "click", () => download(`${safeName(state.design.name)}.csv`, designCsv(state.design), "text/csv"));
  on("#d-dl-json", "click", () => downloadJson(`${safeName(state.design.name)}.json`, state.design, 1));
  on("#d-dl-mission", "click", () => downloadJson(`${safeName(state.designMission.name)}-mission.json`, state.designMission, 2));
}

/** the example mission, unless the form has segments already (called once the presets are known) */
export async function loadExampleIfEmpty() {
  if (!$("#d-segments tr")) await loadExampleMission();
}
