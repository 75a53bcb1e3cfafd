/* thrustshape page, Model check tab: "Design the experiment" — the log and parameters of the model check sent
   as a job (POST /v1/model-check/jobs, op=design), its progress polled, then the proposal: why an experiment is
   needed, every candidate's separation z, the chosen one per rival pair, and its mission to download or open
   in the Design tab. */

import { $, api, downloadJson, emptied, fmt, guarded, on, readNumber, row, selectTab, td } from "./common.js";
import { fillMission } from "./design.js";
import { modelForm, showDiagnose } from "./model.js";

const state = { design: null };

function designFields() {
  const out = {};
  for (const [id, key] of [["#m-d-voltage", "voltage"], ["#m-d-current", "current"], ["#m-d-duration", "duration_s"]]) {
    const v = readNumber($(id), { optional: true });
    if (v !== undefined) out[key] = String(v);
  }
  return out;
}

/** submit a model-check job and poll it to the end, showing its progress; its result (or its problem) */
export async function runJob(fields, bar) {
  const job = await api("POST", "/v1/model-check/jobs", modelForm(fields), { form: true });
  bar.hidden = false;
  bar.value = 0;
  for (;;) {
    const s = await api("GET", `/v1/model-check/jobs/${job.id}`);
    bar.value = s.status === "done" ? 1 : s.progress;
    bar.dataset.status = s.status;
    if (s.status === "done" || s.status === "failed") break;
    await new Promise((r) => setTimeout(r, 400));
  }
  return await api("GET", `/v1/model-check/jobs/${job.id}/result`);
}

const worst = (z) => (z && Object.keys(z).length ? Math.min(...Object.values(z)) : null);

function showDesign(d) {
  state.design = d;
  $("#m-design-results").hidden = false;
  const msg = emptied("#m-design-message");
  msg.textContent = d.message;
  msg.dataset.needed = String(d.needed);
  const reasons = emptied("#m-design-reasons");
  for (const r of d.reasons || []) {
    const li = document.createElement("li");
    li.textContent = r;
    reasons.appendChild(li);
  }
  const tb = emptied("#m-design-candidates tbody");
  const chosen = d.chosen ? d.chosen.name : null;
  for (const c of d.candidates || []) {
    const z = worst(c.separation) ?? worst(c.raw_separation);
    const r = row([td(c.name + (c.name === chosen ? " (proposed)" : "")), td(c.description),
                   td(c.separation ? fmt(z, 3) : `${fmt(z, 3)} before refit`, "num"),
                   td(c.runnable ? "yes" : c.note, c.runnable ? "good" : "bad")]);
    r.dataset.candidate = c.name;
    if (c.name === chosen) r.classList.add("chosen");
    tb.appendChild(r);
  }
  const pairs = emptied("#m-design-pairs tbody");
  if (d.chosen) {
    for (const [pair, z] of Object.entries(d.chosen.separation || {})) {
      const r = row([td(pair), td(fmt(z, 3), "num"), td(fmt((d.current_log_separation || {})[pair], 3), "num"),
                     td(fmt((d.chosen.rms_ratio || {})[pair], 3), "num")]);
      r.dataset.pair = pair;
      pairs.appendChild(r);
    }
  }
  $("#m-dl-mission").disabled = $("#m-use-mission").disabled = !d.mission;
}

async function runDesign() {
  await guarded($("#tab-model"), $("#m-design-busy"), async () => {
    const d = await runJob({ op: "design", ...designFields() }, $("#m-design-progress"));
    if (d.diagnosis) showDiagnose(d.diagnosis);  // the diagnosis it settles: verdict, ambiguity, calibration
    showDesign(d);
  });
}

export function initExperiment() {
  on("#m-design", "click", runDesign);
  on("#m-dl-mission", "click", () => {
    if (state.design && state.design.mission) downloadJson("experiment-mission.json", state.design.mission, 2, "\n");
  });
  on("#m-use-mission", "click", () => {
    if (!state.design || !state.design.mission) return;
    fillMission(state.design.mission);
    selectTab("design");
  });
}
