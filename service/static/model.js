/* thrustshape page, Model check tab: a measured log and a parameter file through /v1/model-check (check:
   where the model fails; diagnose: which effect is missing; fit: refit with the ticked effects), and the
   calibrated parameters handed to the Design tab or downloaded. */

import {
  $, $$, FieldError, api, downloadJson, emptied, fetchStatic, fillPresets, fmt, guarded, on, parseJsonField,
  plotBox, readNumber, readParams, row, selectTab, syncCustom, td, withUnit,
} from "./common.js";
import { useParams } from "./design.js";

const state = { modelLog: null, fit: null };
const CHANNEL_UNITS = { omega: "rad/s", current: "A", thrust: "N" };

/* ------------------------------------------------------------------ the request */

export function modelForm(extra) {
  if (!state.modelLog) throw new FieldError("log", "choose a log file or use the bundled example");
  const fd = new FormData();
  fd.append("log", state.modelLog.blob, state.modelLog.name);
  const p = readParams($("#m-preset"), $("#m-params"), "params");
  if (typeof p === "string") fd.append("params", p);
  else fd.append("params", JSON.stringify(p));
  const cols = $("#m-columns").value.trim();
  if (cols) { parseJsonField(cols, "columns"); fd.append("columns", cols); }
  for (const [k, v] of Object.entries(readFields())) fd.append(k, v);
  for (const [k, v] of Object.entries(extra || {})) fd.append(k, v);
  return fd;
}

/** the ESC-rig / flight-log read options that differ from the server's defaults (form fields of the API) */
function readFields() {
  const out = {};
  const steady = $("#m-steady").value;
  if (steady) out.steady_state = steady;
  const pp = readNumber($("#m-pole-pairs"), { optional: true, integer: true });
  if (pp !== undefined) out.pole_pairs = String(pp);
  const neutral = readNumber($("#m-neutral"), { optional: true });
  if (neutral !== undefined) out.neutral_us = String(neutral);
  const range = $("#m-throttle-range").value.trim();
  if (range) out.throttle_range_us = range;
  if ($("#m-electrical").value !== "auto") out.electrical = $("#m-electrical").value;
  const motor = readNumber($("#m-motor"), { optional: true, integer: true });
  if (motor !== undefined) out.motor = String(motor);
  const negate = $("#m-negate").value.trim();
  if (negate) out.negate = negate;
  return out;
}

/** which equations the log could check, and why not the others; what the reader did */
function showEquations(sel, res) {
  const box = emptied(sel);
  const list = document.createElement("ul");
  for (const e of res.equations || []) {
    const li = document.createElement("li");
    li.dataset.equation = e.equation; li.dataset.checked = String(e.checked);
    li.className = e.checked ? "good" : "muted";
    li.textContent = `${e.checked ? "checked" : "not checked"}: ${e.label} — ${e.uses || e.reason}`;
    list.appendChild(li);
  }
  box.appendChild(list);
  const ratio = (res.fitted_maps || {}).thrust_ratio_reverse_to_forward;
  const maps = res.maps || {};
  const p = document.createElement("p");
  const parts = Object.entries(maps).map(([k, m]) => `${k} reverse/forward ${fmt(m.ratio_reverse_to_forward, 3)}`);
  if (ratio != null) parts.push(`fitted thrust reverse/forward ${fmt(ratio, 3)}`);
  p.textContent = parts.join("; ");
  box.appendChild(p);
  if ((res.notes || []).length) {
    const d = document.createElement("details");
    const s = document.createElement("summary");
    s.textContent = "how the log was read";
    d.appendChild(s);
    for (const n of res.notes) { const q = document.createElement("div"); q.className = "muted"; q.textContent = n; d.appendChild(q); }
    box.appendChild(d);
  }
}

function setLog(blob, name, note) {
  state.modelLog = { blob, name };
  $("#m-log-info").textContent = `${name} (${Math.round(blob.size / 1024)} kB)${note ? " — " + note : ""}`;
}

const syncParamInputs = () => syncCustom($("#m-preset"), $("#m-params"), $("#m-params-file-label"));

/** the parameter presets the server offers; a note when it does not report the model-check routes */
export function setModelChoices(presets, features) {
  fillPresets($("#m-preset"), presets, "parameter file / JSON…");
  if (features && features.model_check === false) {
    $("#m-route-note").textContent = "This server does not report the model-check routes; requests may fail.";
  }
}

/* ------------------------------------------------------------------ results */

const scale = (v, k) => (v === null || v === undefined ? null : v * k);

function showReportFigures(reportHtml) {
  // measured vs simulated: the figures of the server's HTML report
  const figs = emptied("#m-figures");
  $("#m-report-link").innerHTML = "";
  if (!reportHtml) return;
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

// the lag the equations moved the command by, where it differs from the estimate (a fast armature's current shows
// whole samples: ocp.identify.align.switched)
function moved(al) {
  const a = al.applied_samples;
  return a === null || a === undefined || Math.abs(a - al.samples) < 0.005 ? "" :
    ` The equations moved the command ${fmt(a, 3)} samples.`;
}

function showCheck(res, reportHtml) {
  $("#m-check-results").hidden = false;
  showEquations("#m-check-equations", res);
  const al = res.alignment;
  $("#m-check-alignment").textContent = al ? `Compared after removing the logging convention: the command acts ` +
    `${fmt(al.samples, 3)} samples (${fmt(1e3 * al.seconds, 3)} ms) after its row` +
    (al.identified ? "." : " (not identifiable from this log: none assumed).") + moved(al) : "";
  const fr = res.free_run || {}, os_ = res.one_step || {}, noise = res.noise || {};
  if (fr.current_sensor_lag) {
    $("#m-check-alignment").textContent += ` The simulated current is read through the current sensor's lag ` +
      `that fits the log, ${fmt(fr.current_sensor_lag, 2)} samples (a logger's filter, not the model's failure).`;
  }
  const units = fr.units || CHANNEL_UNITS;
  const eb = emptied("#m-errors tbody");
  for (const ch of Object.keys(fr.rms || {})) {
    const rms = fr.rms[ch], n = noise[ch];
    const ratio = rms != null && n ? rms / n : null;
    const r = row([withUnit(ch, units), td(fmt(rms), "num"), td(fmt((fr.max || {})[ch]), "num"), td(fmt(n), "num"),
                   td(ratio == null ? "—" : `${fmt(ratio, 3)}×`, ratio != null && ratio > 2 ? "num bad" : "num good")]);
    r.dataset.channel = ch;
    eb.appendChild(r);
  }
  const ob = emptied("#m-onestep tbody");
  const ou = os_.units || {};
  for (const eq of Object.keys(os_.rms || {})) {
    ob.appendChild(row([withUnit(eq, ou), td(fmt(os_.rms[eq]), "num"), td(fmt((os_.mean || {})[eq]), "num")]));
  }
  // breakdowns: mean torque residual and free-run speed error per bin, for every grouping
  const box = emptied("#m-breakdown");
  for (const [group, bins] of Object.entries(res.breakdown || {})) {
    const labels = Object.keys(bins);
    Plot.bars(plotBox(box, group), { title: `by ${group}`, groups: labels, ylabel: "residual",
      series: [{ label: "mean torque residual [mN m]", values: labels.map((l) => scale(bins[l]["one_step_mean.mechanical"], 1e3)) },
               { label: "free-run speed RMS [rad/s]", values: labels.map((l) => bins[l]["free_run_rms.omega"]) }] });
  }
  showReportFigures(reportHtml);
}

/** Ascending counts as runs: [3, 4, 5, 9] -> "3-5, 9" (a run of three or more joined). */
function runs(counts) {
  const out = [];
  for (const n of counts) {
    const last = out[out.length - 1];
    if (last && n === last[last.length - 1] + 1) last.push(n); else out.push([n]);
  }
  return out.map((r) => (r.length > 2 ? `${r[0]}-${r[r.length - 1]}` : r.join(", "))).join(", ");
}

export function showDiagnose(res) {
  $("#m-diag-results").hidden = false;
  showEquations("#m-diag-equations", res);
  const verdict = res.verdict || [];
  const vd = emptied("#m-verdict");
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
  showDiagnosisDetails(res, vd);
  const tb = emptied("#m-ranking tbody");
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

/* Ambiguity, blind spots, alignment, calibration and the angle spectrum's peak, in a block after the verdict. */
function showDiagnosisDetails(res, after) {
  let box = document.getElementById("m-diag-details");
  if (!box) {
    box = document.createElement("div");
    box.id = "m-diag-details";
    box.className = "muted";
    after.insertAdjacentElement("afterend", box);
  }
  box.replaceChildren();
  const line = (text, id) => {
    const p = document.createElement("div");
    if (id) p.id = id;
    p.textContent = text;
    box.appendChild(p);
  };
  for (const a of res.ambiguous || []) line(`Ambiguous: ${a.adopted} or ${a.alternative} — ${a.reason}`, "m-ambiguous");
  const ev = Object.entries(res.evidence || {});  // how each name won (ocp/identify/strength.py)
  if (ev.length) {
    const held = (h) => {  // per equation the name enters: held-out RMS without and with it [noise units]
      const pairs = Object.entries(h || {}).map(([eq, [a, b]]) => `${eq} ${fmt(a, 3)} → ${fmt(b, 3)}`);
      return pairs.length ? `; held out: ${pairs.join(", ")} noise units` : "";
    };
    line("Evidence: " + ev.map(([k, e]) => `${k} ${e.strong ? "strong" : "weak"} (${e.test.replaceAll("_", " ")}` +
         (e.z == null ? "" : `, z = ${fmt(e.z, 3)}`) + held(e.heldout) + ")").join("; ") + ".", "m-evidence");
  }
  for (const b of res.blind_spots || []) {  // what this log cannot show, whatever the verdict
    line((b.hidden.length ? `This log cannot show ${b.hidden.join(", ")}: ` : "Note: ") + `${b.text}.` +
         (b.design ? " Design the experiment to show them." : ""), "m-blind");
  }
  const al = res.alignment;
  if (al) {
    line(`Alignment: the command acts ${fmt(al.samples, 3)} samples (${fmt(1e3 * al.seconds, 3)} ms) after its row` +
         (al.called_input_delay ? " — called input_delay." : " — removed as a logging convention.") + moved(al) +
         ` Rule: ${al.rule}`, "m-alignment");
  }
  const cal = res.calibration || {};
  const keys = Object.keys(cal);
  if (keys.length) {
    const tol = 100 * (res.tolerance ?? 0.1);
    // a constant the log cannot resolve has no estimate (relative null): "—", never its free column's value
    const est = (c) => typeof c.relative === "number";
    // (its free column quoted within a factor two of nominal: beyond, it is an artefact's value)
    const reads = (c) => (typeof c.apparent === "number" && c.apparent >= -0.5 && c.apparent <= 1
      ? `; its free column reads ${fmt(100 * c.apparent, 2)} %` : "");
    const kept = (c) => (typeof c.applied === "number" && (!est(c) || Math.abs(c.applied - c.relative) > 1e-12)
      ? ` (not resolved by this log: plant keeps ${c.applied === 0 ? "nominal" : fmt(100 * c.applied, 2) + " %"}` +
        `${reads(c)})` : "");
    const parts = keys.map((k) => `${k} ${est(cal[k]) ? fmt(100 * cal[k].relative, 2) + " %" : "—"}` +
      `${cal[k].named ? " (named)" : ""}${kept(cal[k])}`);
    const given = keys.some((k) => cal[k].as_given)
      ? ". None applied: the nominal constants as given predict the held-out rows better than any refinement" : "";
    line(`Calibration (within ±${fmt(tol, 2)} % a constant is refined, not named): ${parts.join(", ")}${given}`,
         "m-calibration");
  }
  const ap = res.angle_periodic;
  if (ap) line(`Angle-periodic torque: best fit at ${ap.periods} periods/rev, ${fmt(ap.amplitude, 3)} N m` +
               ((res.verdict || []).includes("cogging") ? "" : `, not named (${ap.unnamed})`) +
               ((ap.rivals || []).length ? `; the count is not decided by this log: ${ap.rivals.length} other ` +
                `count(s) explain the held-out torque as well (${runs(ap.rivals)})` : "") +
               (ap.note ? ` (${ap.note})` : ""), "m-angle");
}

function showFit(res) {
  state.fit = res;
  $("#m-fit-results").hidden = false;
  const note = $("#m-fit-note");  // a fit that predicts worse than the starting plant is not adopted
  note.hidden = res.adopted !== false;
  note.textContent = res.adopted === false ? res.note : "";
  const before = res.rms_before || {}, after = res.rms_after || {};
  const units = res.units || CHANNEL_UNITS;
  const tb = emptied("#m-beforeafter tbody");
  const chans = Object.keys(before);
  for (const ch of chans) {
    const b = before[ch], a = after[ch];
    const ratio = b && a != null ? a / b : null;
    const r = row([withUnit(ch, units), td(fmt(b), "num before"), td(fmt(a), "num after"),
                   td(ratio == null ? "—" : `${fmt(ratio, 3)}`, ratio != null && ratio < 1 ? "num good" : "num bad")]);
    r.dataset.channel = ch; r.dataset.before = b; r.dataset.after = a;
    tb.appendChild(r);
  }
  const fb = emptied("#m-fitted tbody");
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

/* ------------------------------------------------------------------ actions */

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

/* ------------------------------------------------------------------ wiring */

export function initModel() {
  on("#m-log", "change", (e) => { const f = e.target.files[0]; if (f) setLog(f, f.name); });
  on("#m-example", "click", () => guarded($("#tab-model"), null, async () => {
    const resp = await fetchStatic("example-log.csv", "log", "the bundled example log is missing");
    setLog(await resp.blob(), "example-log.csv", "bundled synthetic rig log, paper-rig plant with one hidden effect");
    $("#m-preset").value = "paper-rig";
    syncParamInputs();
  }));
  on("#m-preset", "change", syncParamInputs);
  on("#m-params-file", "change", async (e) => { const f = e.target.files[0]; if (f) $("#m-params").value = await f.text(); });
  on("#m-check", "click", runCheck);
  on("#m-diagnose", "click", runDiagnose);
  on("#m-fit", "click", runFit);
  on("#m-dl-params", "click", () => downloadJson("calibrated-params.json", calibratedParams(), 2, "\n"));
  on("#m-use-params", "click", () => {
    const p = calibratedParams();
    if (!p) return;
    const { notes, ...clean } = p;  // provenance notes are not plant parameters
    useParams(clean);
    selectTab("design");
  });
}
