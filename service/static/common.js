/* thrustshape page, shared by every tab: DOM shortcuts, API calls, problem+json errors shown next to the
   field they name, table/number helpers, downloads, the API key and tab switching.
   Every API error (application/problem+json, with `field` and `reason`) is shown next to the input that
   `field` names; anything else goes to the form's error box. No handler lets an exception escape. */

export const $ = (sel, root) => (root || document).querySelector(sel);
export const $$ = (sel, root) => Array.from((root || document).querySelectorAll(sel));

/** the value of a parameter <select> that shows the JSON / parameter-file inputs instead of a preset */
export const CUSTOM = "__custom__";

/* ------------------------------------------------------------------ API */

export class ApiError extends Error {
  constructor(status, field, reason, detail, errors) {
    super(detail || reason || `HTTP ${status}`);
    this.status = status; this.field = field; this.reason = reason || detail; this.errors = errors || [];
  }
}

/** an input the page itself rejects before asking the server; shown like the server's errors */
export class FieldError extends ApiError {
  constructor(field, reason) { super(0, field, reason); }
}

function authHeaders() {
  const key = $("#api-key").value.trim();
  return key ? { Authorization: `Bearer ${key}` } : {};
}

export async function api(method, path, body, { form = false, accept = "json" } = {}) {
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

/** a bundled example file (``/static/<name>``); a missing one is an error on `field` */
export async function fetchStatic(name, field, missing) {
  const resp = await fetch(`/static/${name}`);
  if (!resp.ok) throw new ApiError(resp.status, field, missing);
  return resp;
}

/* ------------------------------------------------------------------ errors next to fields */

export function clearErrors(scope) {
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

/** the page-wide message box (click to close) */
export function showToast(text) {
  const t = $("#toast");
  t.textContent = text;
  t.hidden = false;
}

export function showFieldError(scope, field, reason) {
  // a field with no input of its own (a log column such as "voltage") goes next to the scope's fallback input
  const target = fieldElement(scope, field) || (field ? $("[data-field-fallback]", scope) : null);
  if (!target) {
    const box = $(".form-error", scope) || $("#toast");
    const text = (box.textContent ? box.textContent + " · " : "") + (field ? `${field}: ` : "") + reason;
    if (box.id === "toast") { showToast(text); setTimeout(() => { box.hidden = true; }, 8000); } else box.textContent = text;
    return;
  }
  target.classList.add("invalid");
  const msg = document.createElement("div");
  msg.className = "field-error";
  msg.setAttribute("data-error-for", field);
  msg.textContent = (target.getAttribute("data-field") === field ? "" : `${field}: `) + reason;
  (target.closest("label") || target).insertAdjacentElement("afterend", msg);
}

export function showError(scope, err) {
  if (err instanceof ApiError) {
    const list = err.errors && err.errors.length ? err.errors : [{ field: err.field, reason: err.reason }];
    for (const e of list.slice(0, 6)) showFieldError(scope, e.field, e.reason);
  } else {
    showFieldError(scope, null, `unexpected error: ${err && err.message ? err.message : err}`);
    console.error(err);
  }
}

/** run one action of a tab: old messages cleared, its buttons disabled meanwhile, any error shown in `scope` */
export async function guarded(scope, busy, fn) {
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

/** an event handler whose errors (sync or async) are shown in the tab of the element that fired */
export function on(sel, ev, fn) {
  $(sel).addEventListener(ev, (e) => {
    Promise.resolve().then(() => fn(e)).catch((err) => {
      const scope = e.target.closest(".tab") || document.body;
      showError(scope, err);
    });
  });
}

/* ------------------------------------------------------------------ numbers, tables, form inputs */

export const fmt = (v, digits = 4) => {
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

export function td(text, cls) {
  const c = document.createElement("td");
  c.textContent = text;
  if (cls) c.className = cls;
  return c;
}

export function row(cells) {
  const r = document.createElement("tr");
  cells.forEach((c) => r.appendChild(c instanceof Node ? c : td(c)));
  return r;
}

/** the element `sel`, emptied (a table body or a plot container about to be refilled) */
export function emptied(sel) {
  const e = $(sel);
  e.innerHTML = "";
  return e;
}

/** "omega [rad/s]": a channel named with its unit */
export const withUnit = (name, units) => `${name} [${units[name] || ""}]`;

/** a new plot container in `parent` (one chart of a group; `group` goes to data-group) */
export function plotBox(parent, group) {
  const div = document.createElement("div");
  div.className = "plotbox";
  if (group !== undefined) div.dataset.group = group;
  parent.appendChild(div);
  return div;
}

/** ±limit lines for Plot.line (none without a limit) */
export function limitLines(limit, unit) {
  return limit ? [{ y: limit, label: `+${fmt(limit)} ${unit} limit` }, { y: -limit, label: `−${fmt(limit)} ${unit} limit` }] : [];
}

export function fillSelect(sel, values, labels) {
  sel.innerHTML = "";
  values.forEach((v, k) => {
    const o = document.createElement("option");
    o.value = v; o.textContent = labels ? labels[k] : v;
    sel.appendChild(o);
  });
}

/** the preset names, then the CUSTOM choice under `customLabel` */
export function fillPresets(sel, presets, customLabel) {
  fillSelect(sel, [...presets, CUSTOM], [...presets, customLabel]);
}

/** show `inputs` (JSON text, file button) only while the parameter select is on CUSTOM */
export function syncCustom(select, ...inputs) {
  const custom = select.value === CUSTOM;
  inputs.forEach((e) => { e.hidden = !custom; });
}

export function readNumber(input, { optional = false, integer = false } = {}) {
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

export function parseJsonField(text, field) {
  try {
    return JSON.parse(text);
  } catch (e) {
    throw new FieldError(field, `not valid JSON: ${e.message}`);
  }
}

/** a preset name, or the JSON object typed in `textEl` when the select is on CUSTOM */
export function readParams(selectEl, textEl, field) {
  if (selectEl.value !== CUSTOM) return selectEl.value;
  const text = textEl.value.trim();
  if (!text) throw new FieldError(field, "paste a parameter mapping (JSON) or pick a preset");
  const p = parseJsonField(text, field);
  if (p === null || typeof p !== "object" || Array.isArray(p)) throw new FieldError(field, "must be a JSON object");
  return p;
}

/** the missions of a JSON file: one mission, a list of them, or {"missions": [...]} */
export function missionsFromJson(name, text) {
  let data;
  try { data = JSON.parse(text); } catch (e) { throw new FieldError("missions", `${name}: not valid JSON (${e.message})`); }
  const list = Array.isArray(data) ? data : data && Array.isArray(data.missions) ? data.missions : [data];
  return list.map((m, k) => {
    if (!m || typeof m !== "object" || Array.isArray(m)) throw new FieldError("missions", `${name}: item ${k + 1} is not a mission object`);
    return { source: list.length > 1 ? `${name} [${k + 1}]` : name, mission: m };
  });
}

/* ------------------------------------------------------------------ downloads */

export function download(name, text, type) {
  // one way to save a file on this page: plot.js's (its plots' PNG/SVG/CSV buttons use it too)
  Plot.save(name, text instanceof Blob ? text : new Blob([text], { type: type || "application/octet-stream" }));
}

export function downloadJson(name, value, indent, trailer = "") {
  download(name, JSON.stringify(value, null, indent) + trailer, "application/json");
}

export const safeName = (s) => String(s || "mission").replace(/[^A-Za-z0-9._-]+/g, "_");

/* ------------------------------------------------------------------ tabs, api key */

export function selectTab(name) {
  if (!$(`#tab-${name}`)) name = "design";
  $$("#tabs button").forEach((b) => b.setAttribute("aria-selected", String(b.dataset.tab === name)));
  $$(".tab").forEach((s) => { s.hidden = s.id !== `tab-${name}`; });
  if (location.hash !== `#${name}`) history.replaceState(null, "", `#${name}`);
}

export function initTabs() {
  $$("#tabs button").forEach((b) => b.addEventListener("click", () => selectTab(b.dataset.tab)));
  $$("[data-goto]").forEach((a) => a.addEventListener("click", (e) => { e.preventDefault(); selectTab(a.dataset.goto); }));
  window.addEventListener("hashchange", () => selectTab(location.hash.slice(1)));
  selectTab(location.hash.slice(1) || "design");
}

/** the key kept in localStorage; `changed` runs after the user edits it */
export function initApiKey(changed) {
  const key = $("#api-key");
  key.value = localStorage.getItem("thrustshape.apiKey") || "";
  key.addEventListener("change", () => { localStorage.setItem("thrustshape.apiKey", key.value.trim()); clearErrors($("header")); changed(); });
}
