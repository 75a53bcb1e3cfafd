/* thrustshape page, Compare tab: the Design tab's mission through POST /v1/compare (the optimised reference
   beside the A sin^(2q+1) family): the table, bar charts of its figures and the candidates' curves. */

import {
  $, ApiError, api, download, emptied, fmt, guarded, limitLines, on, plotBox, row, safeName, selectTab, showError, td,
} from "./common.js";
import { buildMission, lastDesign } from "./design.js";

const COMPARE_COLS = [
  ["label", "shape"], ["duration_s", "duration [s]"], ["peak_current_a", "peak current [A]"],
  ["peak_voltage_v", "peak voltage [V]"], ["energy_j", "energy [J]"], ["thrust_rms_error_n", "thrust RMS error [N]"],
  ["crossing_exponents", "crossing exponents"], ["within_limits", "within limits"],
  ["loop_thrust_rms_n", "closed-loop thrust RMS [N]"], ["loop_peak_voltage_v", "closed-loop peak V [V]"],
  ["loop_peak_current_a", "closed-loop peak i [A]"],
];
const UNBOUNDED_IF_NULL = new Set(["peak_current_a", "peak_voltage_v", "energy_j"]);
const unbounded = (v) => v === null || v === "inf";

function exponentsText(xs) {
  if (!Array.isArray(xs) || !xs.length) return "none";
  const uniq = [...new Set(xs.map((x) => fmt(x, 3)))];
  return `${uniq.join(", ")} (${xs.length} crossing${xs.length > 1 ? "s" : ""})`;
}

let lastTable = { mission: "", rows: [] };

/** the Compare table as CSV: one row per shape, the raw numbers (unbounded peaks as inf, exponents ;-separated) */
export function compareCsv(rows) {
  const cell = (k, v) => {
    if (v === null || v === undefined) return UNBOUNDED_IF_NULL.has(k) ? "inf" : "";
    if (Array.isArray(v)) return v.join(";");
    const text = String(v);
    return /[",\n]/.test(text) ? `"${text.replace(/"/g, '""')}"` : text;
  };
  const lines = [COMPARE_COLS.map(([k]) => k).join(",")];
  for (const r of rows) lines.push(COMPARE_COLS.map(([k]) => cell(k, r[k])).join(","));
  return lines.join("\n") + "\n";
}

function showCompareTable(table) {
  const head = emptied("#c-table thead"), body = emptied("#c-table tbody");
  head.appendChild(row(COMPARE_COLS.map(([, h]) => { const th = document.createElement("th"); th.textContent = h; return th; })));
  for (const r of table) {
    body.appendChild(row(COMPARE_COLS.map(([k]) => {
      const v = r[k];
      if (k === "label") return td(v);
      if (k === "crossing_exponents") return td(exponentsText(v));
      if (k === "within_limits") return td(fmt(v), v ? "good" : "bad");
      if (unbounded(v) && UNBOUNDED_IF_NULL.has(k)) return td("∞ unbounded", "num bad");
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
  Plot.line($("#c-plot-thrust"), { title: "thrust", group: "compare", xlabel: "t [s]", ylabel: "N", series: mk("thrust") });
  Plot.line($("#c-plot-speed"), { title: "speed", group: "compare", xlabel: "t [s]", ylabel: "rad/s", series: mk("omega") });
  Plot.line($("#c-plot-current"), { title: "current (clipped at ±3× limit)", group: "compare", xlabel: "t [s]", ylabel: "A",
    series: mk("current"), hlines: limitLines(lim.current, "A"), yrange: [-3 * lim.current, 3 * lim.current] });
  Plot.line($("#c-plot-voltage"), { title: "voltage (clipped at ±3× limit)", group: "compare", xlabel: "t [s]", ylabel: "V",
    series: mk("voltage"), hlines: limitLines(lim.voltage, "V"), yrange: [-3 * lim.voltage, 3 * lim.voltage] });
}

function drawCompareBars(table, mission) {
  /* the table's figures side by side; an unbounded peak (null) gets no bar and an "∞" label */
  const box = emptied("#c-bars");
  const labels = table.map((r) => String(r.label).replace(" (mission q)", "*"));
  const charts = [
    ["peak_current_a", `ideal peak current [A] (limit ${fmt(mission.limits.current)} A)`],
    ["peak_voltage_v", `ideal peak voltage [V] (limit ${fmt(mission.limits.voltage)} V)`],
    ["loop_thrust_rms_n", "closed-loop thrust RMS error [N]"],
    ["loop_peak_current_a", "closed-loop peak current [A]"],
  ];
  for (const [key, title] of charts) {
    const glabels = table.map((r, k) => (unbounded(r[key]) ? `${labels[k]} (∞)` : labels[k]));
    Plot.bars(plotBox(box), { title, groups: glabels, series: [{ label: "", values: table.map((r) => (r[key] === "inf" ? null : r[key])) }],
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
    const design = lastDesign();
    const sameAsDesign = design.result && JSON.stringify(design.mission) === JSON.stringify(mission);
    const opt = (cmp.candidates || []).length ? null
      : sameAsDesign ? design.result : await api("POST", "/v1/references/optimize", mission);
    showCompareTable(cmp.table || []);
    lastTable = { mission: cmp.mission, rows: cmp.table || [] };
    $("#c-dl-csv").disabled = !lastTable.rows.length;
    $("#c-note").textContent = `mission ${cmp.mission}: optimised answer from the ${cmp.optimized_source === "optimized" ? "optimiser" : "analytic fallback"}` +
      (cmp.optimized_reason ? ` (${cmp.optimized_reason})` : "") + ". Unbounded peaks are the ideal feedforward at a linear crossing.";
    const curves = compareCurves(cmp, opt);
    if (curves.length === 1) $("#c-note").textContent += " This server's answer carries no curves of the analytic shapes: only the optimised reference is drawn.";
    drawCompare(curves, mission);
    drawCompareBars(cmp.table || [], mission);
  });
}

export function initCompare() {
  on("#c-run", "click", runCompare);
  on("#c-dl-csv", "click", () => download(`${safeName(lastTable.mission)}-compare.csv`, compareCsv(lastTable.rows), "text/csv"));
}
