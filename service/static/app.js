/* thrustshape page, start-up: the page-wide error box, tab switching, the API key, the server's info (presets,
   regularities, features) and each tab's wiring; the Design tab starts on the bundled example mission.
   The tabs live in design.js, compare.js, model.js and batch.js; what they share in common.js. */

import { $, initApiKey, initTabs, showError, showFieldError, showToast, api } from "./common.js";
import { initDesign, loadExampleIfEmpty, setDesignChoices } from "./design.js";
import { initCompare } from "./compare.js";
import { initModel, setModelChoices } from "./model.js";
import { initExperiment } from "./experiment.js";
import { initBatch } from "./batch.js";

const FALLBACK_PRESETS = ["paper-rig"];
const FALLBACK_REGULARITIES = ["bounded", "continuous-current", "continuous-voltage", "c1-voltage"];

async function loadInfo() {
  let info = null;
  try {
    info = await api("GET", "/v1/info");
  } catch (err) {
    if (err.status === 401) showFieldError(document.body, "Authorization", err.reason);
    $("#server-info").textContent = `server info unavailable: ${err.reason}`;
  }
  const presets = info ? info.presets : FALLBACK_PRESETS;
  setDesignChoices(presets, info ? info.regularities : FALLBACK_REGULARITIES);
  setModelChoices(presets, info && (info.features || {}));
  if (info) {
    $("#server-info").textContent = `server ${info.version} · ${info.workers} worker(s) · batches on ${info.batch_backend}` +
      ` · presets ${info.presets.join(", ")}`;
  }
}

function init() {
  window.addEventListener("error", (e) => showToast(`page error: ${e.message}`));
  window.addEventListener("unhandledrejection", (e) => showToast(`page error: ${e.reason}`));
  $("#toast").addEventListener("click", () => { $("#toast").hidden = true; });
  initTabs();
  initApiKey(loadInfo);
  initDesign();
  initCompare();
  initModel();
  initExperiment();
  initBatch();
  loadInfo().then(loadExampleIfEmpty).catch((err) => showError($("#tab-design"), err));
}

document.addEventListener("DOMContentLoaded", init);
