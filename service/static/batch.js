/* thrustshape page, Batch tab: mission files (JSON, or a zip of them) and the Design tab's mission sent as
   one POST /v1/batches, polled until done, then the results table and downloads. */

import {
  $, ApiError, FieldError, api, downloadJson, download, fmt, guarded, missionsFromJson, on, row, td,
} from "./common.js";
import { buildMission } from "./design.js";

const state = { batch: null, batchResults: null, batchMissions: [] };

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

/** a .json entry of a zip that is a mission file: not macOS metadata (__MACOSX/, AppleDouble ._name), not hidden */
export function isMissionEntry(name) {
  const parts = name.split("/");
  const base = parts[parts.length - 1];
  return /\.json$/i.test(base) && !parts.includes("__MACOSX") && !base.startsWith("._") && !base.startsWith(".");
}

async function addBatchFiles(files) {
  const got = [];
  for (const f of files) {
    if (/\.zip$/i.test(f.name)) {
      let entries;
      try { entries = await unzip(await f.arrayBuffer()); } catch (e) { throw new FieldError("missions", `${f.name}: ${e.message}`); }
      for (const e of entries) if (isMissionEntry(e.name)) got.push(...missionsFromJson(`${f.name}/${e.name}`, e.text));
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

function setDownloadsEnabled(enabled) {
  $("#b-dl-json").disabled = !enabled; $("#b-dl-csv").disabled = !enabled;
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
    setDownloadsEnabled(false);
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
    setDownloadsEnabled(true);
  });
}

export function initBatch() {
  const scope = $("#tab-batch");
  on("#b-files", "change", (e) => guarded(scope, null, async () => {
    state.batchMissions = [];
    await addBatchFiles(Array.from(e.target.files));
  }));
  on("#b-add-design", "click", () => guarded(scope, null, async () => {
    state.batchMissions.push({ source: "Design tab", mission: buildMission() });
    renderBatchList();
  }));
  on("#b-clear", "click", () => { state.batchMissions = []; $("#b-files").value = ""; renderBatchList(); });
  $("#batch-form").addEventListener("submit", (e) => { e.preventDefault(); runBatch(); });
  on("#b-dl-json", "click", () => downloadJson(`batch-${state.batch}.json`, state.batchResults, 1));
  on("#b-dl-csv", "click", () => guarded(scope, null, async () => {
    download(`batch-${state.batch}.csv`, await api("GET", `/v1/batches/${encodeURIComponent(state.batch)}/results?format=csv`, undefined, { accept: "blob" }));
  }));
  renderBatchList();
}
