/* thrustshape page: interactive line plots on the vendored uPlot (uPlot-1.6.32.iife.min.js, MIT, see
   uPlot-LICENSE.txt): drag to zoom on t (plots of one `group` zoom together), double-click to zoom out,
   the legend reads out every series at the cursor, uPlot draws at most a few points per pixel column
   (min/max decimation), so a millisecond reversal inside a seconds-long reference stays visible when zoomed.
   Every plot has downloads: PNG (what is drawn), SVG (plot-svg.js over the current zoom) and CSV (the samples
   in view). Bar charts stay SVG (plot-svg.js) with the same downloads.

   Public API (other tabs use only this):
     Plot.line(container, opts) -> the plot element   opts: {title, xlabel, ylabel, height, group,
       series: [{x, y, label, color, dash}], hlines: [{y, label, color}], markers: [{x, y, label}],
       yrange: [lo, hi] (fixed; else from the data in view and the hlines)}
     Plot.bars(container, opts) -> the plot element   opts: {title, ylabel, height, groups, series: [{label, values}]}
   Values null/NaN break a line; "inf"/"-inf" and values outside a fixed yrange are drawn clipped at the edge.
   The plot element carries data-points, data-xmin/data-xmax (current zoom); each series a hidden
   .series[data-label][data-n][data-clipped], each limit line a hidden .limit, each marker a .marker-label. */
"use strict";

const Plot = (() => {
  const { num, fmt, PALETTE } = PlotSvg;
  const groups = new Map(); // group name -> Set of uPlot instances zooming together
  /* the legend's read-out: 5 significant digits (the axes' ticks keep fmt's shorter form) */
  const readout = (u, v) => (v === null || v === undefined ? "–" : String(Number(v.toPrecision(5))));

  function hidden(parent, cls, attrs, text) {
    const e = document.createElement("span");
    e.className = cls;
    e.hidden = true;
    for (const [k, v] of Object.entries(attrs || {})) e.dataset[k] = String(v);
    if (text) e.textContent = text;
    parent.appendChild(e);
    return e;
  }

  /* one x grid for all series: shared when every series has the same x, else the union (uPlot.join) */
  function align(series) {
    const same = series.every((s) => s.xs.length === series[0].xs.length && s.xs.every((v, i) => v === series[0].xs[i]));
    if (same) return [series[0].xs, ...series.map((s) => s.ys)];
    return uPlot.join(series.map((s) => [s.xs, s.ys]));
  }

  /* numbers for uPlot: NaN -> null (a gap), +-inf and values outside a fixed range -> the range edge (counted) */
  function prepare(opts) {
    const series = (opts.series || []).map((s, k) => ({ ...s, color: s.color || PALETTE[k % PALETTE.length],
      xs: Array.from(s.x, num), raw: Array.from(s.y, num) }));
    let ylo = Infinity, yhi = -Infinity;
    for (const s of series) for (const y of s.raw) if (Number.isFinite(y)) { ylo = Math.min(ylo, y); yhi = Math.max(yhi, y); }
    for (const h of opts.hlines || []) { ylo = Math.min(ylo, h.y); yhi = Math.max(yhi, h.y); }
    if (!Number.isFinite(ylo)) { ylo = -1; yhi = 1; }
    const [lo, hi] = opts.yrange || [ylo - 0.06 * (yhi - ylo || 1), yhi + 0.06 * (yhi - ylo || 1)];
    for (const s of series) {
      s.clipped = 0; s.n = 0;
      s.ys = s.raw.map((y) => {
        if (Number.isNaN(y)) return null;
        s.n++;
        if (y > hi || y < lo) { s.clipped++; return y > hi ? hi : lo; }
        return y;
      });
    }
    return { series, lo, hi };
  }

  function drawOverlays(u, opts) {
    const ctx = u.ctx, { left, top, width, height } = u.bbox, dpr = devicePixelRatio || 1;
    ctx.save();
    ctx.beginPath(); ctx.rect(left, top, width, height); ctx.clip();
    ctx.font = `${10 * dpr}px system-ui, sans-serif`;
    for (const h of opts.hlines || []) {
      const y = u.valToPos(h.y, "y", true);
      ctx.strokeStyle = h.color || "#d1242f"; ctx.fillStyle = h.color || "#d1242f";
      ctx.setLineDash([6 * dpr, 4 * dpr]); ctx.lineWidth = 1.3 * dpr;
      ctx.beginPath(); ctx.moveTo(left, y); ctx.lineTo(left + width, y); ctx.stroke();
      if (h.label) { ctx.textAlign = "right"; ctx.fillText(h.label, left + width - 4 * dpr, y + (h.y >= 0 ? -4 : 12) * dpr); }
    }
    ctx.strokeStyle = "#8250df"; ctx.fillStyle = "#8250df"; ctx.setLineDash([2 * dpr, 3 * dpr]); ctx.lineWidth = dpr;
    ctx.font = `600 ${11 * dpr}px system-ui, sans-serif`; ctx.textAlign = "left";
    for (const m of opts.markers || []) {
      const x = u.valToPos(m.x, "x", true);
      if (x < left || x > left + width) continue;
      ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + height); ctx.stroke();
      const sy = u.scales.y;
      const yv = Number.isFinite(m.y) ? Math.min(Math.max(m.y, sy.min), sy.max) : (sy.min + sy.max) / 2;
      ctx.beginPath(); ctx.arc(x, u.valToPos(yv, "y", true), 4 * dpr, 0, 2 * Math.PI); ctx.fill();
      if (m.label) ctx.fillText(m.label, x + 6 * dpr, top + 14 * dpr);
    }
    ctx.restore();
  }

  function yRange(opts) {
    if (opts.yrange) return { auto: false, range: opts.yrange };
    const limits = (opts.hlines || []).map((h) => h.y);
    return { range: (u, lo, hi) => {
      if (lo === null || hi === null) { lo = -1; hi = 1; }
      lo = Math.min(lo, ...limits); hi = Math.max(hi, ...limits);
      const pad = 0.06 * (hi - lo || Math.abs(hi) || 1);
      return [lo - pad, hi + pad];
    } };
  }

  function zoomTogether(u, group) {
    if (!group) return;
    if (!groups.has(group)) groups.set(group, new Set());
    groups.get(group).add(u);
  }

  function onScale(u, key, root, group) {
    if (key !== "x") return;
    const { min, max } = u.scales.x;
    root.dataset.xmin = String(min); root.dataset.xmax = String(max);
    if (!group || u._syncing) return;
    for (const other of groups.get(group) || []) {
      if (other === u || !document.contains(other.root)) { if (!document.contains(other.root)) groups.get(group).delete(other); continue; }
      const s = other.scales.x;
      if (s.min === min && s.max === max) continue;
      other._syncing = true;
      other.setScale("x", { min, max });
      other._syncing = false;
    }
  }

  function line(container, opts) {
    container.innerHTML = "";
    const root = document.createElement("div");
    root.className = "plot";
    root.setAttribute("role", "img");
    root.setAttribute("aria-label", opts.title || "plot");
    container.appendChild(root);
    const { series } = prepare(opts);
    const data = series.length ? align(series) : [[0, 1]];
    const uopts = {
      title: opts.title || "", width: Math.max(container.clientWidth - 8, 320), height: opts.height || 230,
      scales: { x: { time: false }, y: yRange(opts) },
      series: [{ label: opts.xlabel || "x", value: readout },
               ...series.map((s) => ({ label: s.label || "", stroke: s.color, width: 1.6, spanGaps: false,
                 dash: s.dash ? String(s.dash).split(/[ ,]+/).map(Number) : undefined,
                 value: readout }))],
      axes: [{ label: opts.xlabel || "" }, { label: opts.ylabel || "", size: 60 }],
      cursor: { drag: { x: true, y: false, setScale: true } },
      legend: { live: true },
      hooks: { draw: [(u) => drawOverlays(u, opts)], setScale: [(u, key) => onScale(u, key, root, opts.group)] },
    };
    const u = new uPlot(uopts, data, root);
    root._uplot = u;
    root._opts = opts;
    zoomTogether(u, opts.group);
    let total = 0;
    for (const s of series) {
      total += s.n;
      hidden(root, "series", { label: s.label || "", n: s.n, clipped: s.clipped });
    }
    for (const h of opts.hlines || []) hidden(root, "limit", { y: h.y }, h.label || "");
    for (const m of opts.markers || []) hidden(root, "marker-label", { x: m.x }, m.label || "");
    root.dataset.points = String(total);
    root.dataset.xmin = String(u.scales.x.min); root.dataset.xmax = String(u.scales.x.max);
    toolbar(root, { png: () => linePng(u), svg: () => lineSvg(root), csv: () => lineCsv(u, opts),
                    reset: () => u.setScale("x", { min: data[0][0], max: data[0][data[0].length - 1] }) });
    if (window.ResizeObserver) {
      new ResizeObserver(() => {
        const w = Math.max(container.clientWidth - 8, 320);
        if (Math.abs(w - u.width) > 2) u.setSize({ width: w, height: u.height });
      }).observe(container);
    }
    return root;
  }

  /* ------------------------------------------------------------------ downloads */

  function save(name, blob) {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.appendChild(a);
    a.click();
    setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
  }

  const fileName = (root, ext) => `${(root.getAttribute("aria-label") || "plot").replace(/[^A-Za-z0-9._-]+/g, "_")}.${ext}`;

  function toolbar(root, actions) {
    const bar = document.createElement("div");
    bar.className = "plot-tools";
    for (const [fmtName, label] of [["png", "PNG"], ["svg", "SVG"], ["csv", "CSV"], ["reset", "reset zoom"]]) {
      if (!actions[fmtName]) continue;
      const b = document.createElement("button");
      b.type = "button"; b.className = "plot-dl"; b.dataset.format = fmtName; b.textContent = label;
      b.title = fmtName === "reset" ? "show all (or double-click the plot)" : `download this plot as ${label}`;
      b.addEventListener("click", async () => {
        const out = await actions[fmtName]();
        if (out) save(fileName(root, fmtName), out);
      });
      bar.appendChild(b);
    }
    root.insertBefore(bar, root.firstChild);
  }

  function linePng(u) {
    const src = u.ctx.canvas, dpr = devicePixelRatio || 1, head = Math.round(24 * dpr);
    const c = document.createElement("canvas");
    c.width = src.width; c.height = src.height + head;
    const ctx = c.getContext("2d");
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, c.width, c.height);
    ctx.fillStyle = "#1f2328"; ctx.font = `600 ${13 * dpr}px system-ui, sans-serif`;
    ctx.fillText(u.root.querySelector(".u-title")?.textContent || "", 8 * dpr, 17 * dpr);
    ctx.drawImage(src, 0, head);
    return new Promise((resolve) => c.toBlob(resolve, "image/png"));
  }

  function lineSvg(root) {
    const u = root._uplot, opts = root._opts, tmp = document.createElement("div");
    const { min, max } = u.scales.x;
    const yr = opts.yrange || [u.scales.y.min, u.scales.y.max];
    const svg = PlotSvg.line(tmp, { ...opts, xrange: [min, max], yrange: yr, series: (opts.series || []).map((s) => {
      const xs = Array.from(s.x, num), ys = Array.from(s.y, num);
      const keep = xs.map((x, i) => i).filter((i) => xs[i] >= min && xs[i] <= max);
      return { ...s, x: keep.map((i) => xs[i]), y: keep.map((i) => ys[i]) };
    }), markers: (opts.markers || []).filter((m) => m.x >= min && m.x <= max) });
    return new Blob([PlotSvg.serialize(svg)], { type: "image/svg+xml" });
  }

  function lineCsv(u, opts) {
    const [xs, ...cols] = u.data, { min, max } = u.scales.x;
    const head = [opts.xlabel || "x", ...(opts.series || []).map((s, k) => s.label || `series ${k + 1}`)];
    const lines = [head.map((h) => `"${String(h).replace(/"/g, '""')}"`).join(",")];
    for (let i = 0; i < xs.length; i++) {
      if (xs[i] < min || xs[i] > max) continue;
      lines.push([xs[i], ...cols.map((c) => (c[i] === null || c[i] === undefined ? "" : c[i]))].join(","));
    }
    return new Blob([lines.join("\n") + "\n"], { type: "text/csv" });
  }

  function barsCsv(opts) {
    const series = opts.series || [];
    const lines = [["group", ...series.map((s, k) => s.label || `value ${k + 1}`)].join(",")];
    (opts.groups || []).forEach((g, gi) => lines.push([`"${String(g).replace(/"/g, '""')}"`,
      ...series.map((s) => { const v = num(s.values[gi]); return Number.isNaN(v) ? "" : v; })].join(",")));
    return new Blob([lines.join("\n") + "\n"], { type: "text/csv" });
  }

  function svgPng(svg) {
    const text = PlotSvg.serialize(svg);
    const [, , w, h] = svg.getAttribute("viewBox").split(" ").map(Number);
    const img = new Image(), scale = 2;
    return new Promise((resolve, reject) => {
      img.onload = () => {
        const c = document.createElement("canvas");
        c.width = w * scale; c.height = h * scale;
        const ctx = c.getContext("2d");
        ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, c.width, c.height);
        ctx.drawImage(img, 0, 0, c.width, c.height);
        c.toBlob(resolve, "image/png");
      };
      img.onerror = reject;
      img.src = "data:image/svg+xml;charset=utf-8," + encodeURIComponent(text);
    });
  }

  function bars(container, opts) {
    const svg = PlotSvg.bars(container, opts);
    const root = document.createElement("div");
    root.className = "plot plot-bars";
    root.setAttribute("aria-label", opts.title || "bars");
    root.dataset.points = svg.getAttribute("data-points");
    container.appendChild(root);
    root.appendChild(svg);
    toolbar(root, { png: () => svgPng(svg), svg: () => new Blob([PlotSvg.serialize(svg)], { type: "image/svg+xml" }),
                    csv: () => barsCsv(opts) });
    return root;
  }

  return { line, bars, num, fmt, save, PALETTE };
})();
