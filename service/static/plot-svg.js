/* thrustshape page: the SVG renderer. Draws the bar charts on the page, and the vector (SVG) downloads
   of the interactive line plots (plot.js, on uPlot) over their current zoom. Values that are null/NaN
   break the line; "inf"/"-inf" or values outside a fixed y range are drawn clipped at the edge and counted
   in data-clipped. `serialize(svg)` gives a standalone SVG file (styles inlined). */
"use strict";

const PlotSvg = (() => {
  const NS = "http://www.w3.org/2000/svg";
  const PALETTE = ["#1f6feb", "#d1242f", "#1a7f37", "#8250df", "#bf8700", "#0a7e8c", "#cf222e", "#57606a"];
  const W = 640, M = { l: 58, r: 14, t: 26, b: 36 };

  function el(name, attrs, parent) {
    const e = document.createElementNS(NS, name);
    for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, String(v));
    if (parent) parent.appendChild(e);
    return e;
  }

  function num(v) {
    if (v === "inf") return Infinity;
    if (v === "-inf") return -Infinity;
    if (v === null || v === undefined || v === "") return NaN;
    return Number(v);
  }

  function niceStep(span, n) {
    const raw = span / Math.max(n, 1);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const f = raw / mag;
    return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
  }

  function ticks(lo, hi, n) {
    if (!(hi > lo)) return [lo];
    const step = niceStep(hi - lo, n);
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return out;
  }

  function fmt(v) {
    const a = Math.abs(v);
    if (a === 0) return "0";
    if (a >= 1e4 || a < 1e-3) return v.toExponential(1);
    return String(Number(v.toPrecision(4)));
  }

  function frame(container, title, height) {
    container.innerHTML = "";
    const svg = el("svg", { viewBox: `0 0 ${W} ${height}`, class: "plot", role: "img", "aria-label": title });
    el("text", { x: M.l, y: 16, class: "plot-title" }, svg).textContent = title;
    container.appendChild(svg);
    return svg;
  }

  function axes(svg, xr, yr, height, xlabel, ylabel, xticks) {
    const H = height, pw = W - M.l - M.r, ph = H - M.t - M.b;
    const sx = (x) => M.l + ((x - xr[0]) / (xr[1] - xr[0] || 1)) * pw;
    const sy = (y) => M.t + ph - ((y - yr[0]) / (yr[1] - yr[0] || 1)) * ph;
    const g = el("g", { class: "axes" }, svg);
    for (const v of ticks(yr[0], yr[1], 4)) {
      el("line", { x1: M.l, x2: M.l + pw, y1: sy(v), y2: sy(v), class: "grid" }, g);
      el("text", { x: M.l - 6, y: sy(v) + 4, class: "tick", "text-anchor": "end" }, g).textContent = fmt(v);
    }
    if (xticks !== false) {
      for (const v of ticks(xr[0], xr[1], 6)) {
        el("line", { x1: sx(v), x2: sx(v), y1: M.t, y2: M.t + ph, class: "grid" }, g);
        el("text", { x: sx(v), y: M.t + ph + 15, class: "tick", "text-anchor": "middle" }, g).textContent = fmt(v);
      }
    }
    el("rect", { x: M.l, y: M.t, width: pw, height: ph, class: "frame" }, g);
    if (xlabel) el("text", { x: M.l + pw / 2, y: H - 4, class: "label", "text-anchor": "middle" }, g).textContent = xlabel;
    if (ylabel) {
      el("text", { x: 12, y: M.t + ph / 2, class: "label", "text-anchor": "middle",
                   transform: `rotate(-90 12 ${M.t + ph / 2})` }, g).textContent = ylabel;
    }
    return { sx, sy, pw, ph };
  }

  function legend(svg, items) {
    let x = W - M.r;
    for (let k = items.length - 1; k >= 0; k--) {
      const it = items[k];
      const w = 22 + 6.2 * it.label.length;
      x -= w;
      el("line", { x1: x, x2: x + 16, y1: 12, y2: 12, stroke: it.color, "stroke-width": 2.5,
                   "stroke-dasharray": it.dash || "" }, svg);
      el("text", { x: x + 19, y: 16, class: "legend" }, svg).textContent = it.label;
    }
  }

  /* opts: {title, xlabel, ylabel, height, series: [{x, y, label, color, dash}], hlines: [{y, label, color}],
            markers: [{x, y, label}], yrange: [lo, hi] (fixed; else from data and hlines)} */
  function line(container, opts) {
    const height = opts.height || 230;
    const svg = frame(container, opts.title || "", height);
    const series = (opts.series || []).map((s, k) => ({ ...s, color: s.color || PALETTE[k % PALETTE.length],
      xs: Array.from(s.x, num), ys: Array.from(s.y, num) }));
    let xlo = Infinity, xhi = -Infinity, ylo = Infinity, yhi = -Infinity;
    for (const s of series) {
      for (let i = 0; i < s.xs.length; i++) {
        const x = s.xs[i], y = s.ys[i];
        if (Number.isFinite(x)) { xlo = Math.min(xlo, x); xhi = Math.max(xhi, x); }
        if (Number.isFinite(y)) { ylo = Math.min(ylo, y); yhi = Math.max(yhi, y); }
      }
    }
    for (const h of opts.hlines || []) { ylo = Math.min(ylo, h.y); yhi = Math.max(yhi, h.y); }
    if (opts.xrange) [xlo, xhi] = opts.xrange;
    if (opts.yrange) [ylo, yhi] = opts.yrange;
    if (!Number.isFinite(xlo)) { xlo = 0; xhi = 1; }
    if (!Number.isFinite(ylo)) { ylo = -1; yhi = 1; }
    if (yhi - ylo < 1e-12) { ylo -= 1; yhi += 1; }
    if (!opts.yrange) { const pad = 0.06 * (yhi - ylo); ylo -= pad; yhi += pad; }
    const ax = axes(svg, [xlo, xhi], [ylo, yhi], height, opts.xlabel, opts.ylabel);
    const clipId = "c" + Math.random().toString(36).slice(2);
    const clip = el("clipPath", { id: clipId }, el("defs", {}, svg));
    el("rect", { x: M.l, y: M.t - 1, width: ax.pw, height: ax.ph + 2 }, clip);
    const body = el("g", { "clip-path": `url(#${clipId})` }, svg);
    for (const h of opts.hlines || []) {
      el("line", { x1: M.l, x2: M.l + ax.pw, y1: ax.sy(h.y), y2: ax.sy(h.y), class: "limit",
                   stroke: h.color || "#d1242f" }, body);
      if (h.label) {
        el("text", { x: M.l + ax.pw - 4, y: ax.sy(h.y) + (h.y >= 0 ? -4 : 12), class: "limit-label",
                     "text-anchor": "end" }, body).textContent = h.label;
      }
    }
    let total = 0;
    for (const s of series) {
      let d = "", pen = false, n = 0, clipped = 0;
      for (let i = 0; i < s.xs.length; i++) {
        let x = s.xs[i], y = s.ys[i];
        if (Number.isNaN(x) || Number.isNaN(y)) { pen = false; continue; }
        if (y > yhi || y < ylo) { clipped++; y = y > yhi ? yhi : ylo; }
        d += (pen ? "L" : "M") + ax.sx(x).toFixed(1) + " " + ax.sy(y).toFixed(1);
        pen = true; n++;
      }
      total += n;
      el("path", { d: d || "M0 0", class: "series", stroke: s.color, "stroke-dasharray": s.dash || "",
                   "data-label": s.label || "", "data-n": n, "data-clipped": clipped }, body);
    }
    for (const m of opts.markers || []) {
      const x = ax.sx(m.x);
      el("line", { x1: x, x2: x, y1: M.t, y2: M.t + ax.ph, class: "marker-line" }, body);
      const yv = Number.isFinite(m.y) ? Math.min(Math.max(m.y, ylo), yhi) : (ylo + yhi) / 2;
      el("circle", { cx: x, cy: ax.sy(yv), r: 4, class: "marker" }, body);
      if (m.label) {
        const t = el("text", { x: x + 6, y: M.t + 14, class: "marker-label" }, svg);
        t.textContent = m.label;
      }
    }
    svg.setAttribute("data-points", total);
    legend(svg, series.filter((s) => s.label).map((s) => ({ label: s.label, color: s.color, dash: s.dash })));
    return svg;
  }

  /* opts: {title, ylabel, height, groups: [labels], series: [{label, values, color}]} */
  function bars(container, opts) {
    const height = opts.height || 220;
    const svg = frame(container, opts.title || "", height);
    const groups = opts.groups || [];
    const series = (opts.series || []).map((s, k) => ({ ...s, color: s.color || PALETTE[k % PALETTE.length],
      vs: Array.from(s.values, num) }));
    let lo = 0, hi = 0;
    for (const s of series) for (const v of s.vs) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (hi - lo < 1e-300) hi = lo + 1;
    const pad = 0.08 * (hi - lo);
    const yr = [lo < 0 ? lo - pad : 0, hi > 0 ? hi + pad : 0];
    const ax = axes(svg, [0, Math.max(groups.length, 1)], yr, height, "", opts.ylabel, false);
    const gw = ax.pw / Math.max(groups.length, 1);
    const bw = (gw * 0.76) / Math.max(series.length, 1);
    let total = 0;
    groups.forEach((label, gi) => {
      series.forEach((s, si) => {
        const v = s.vs[gi];
        if (!Number.isFinite(v)) return;
        const y0 = ax.sy(0), y1 = ax.sy(v);
        el("rect", { x: M.l + gi * gw + gw * 0.12 + si * bw, y: Math.min(y0, y1), width: Math.max(bw - 1, 1),
                     height: Math.max(Math.abs(y1 - y0), 0.5), fill: s.color, class: "bar",
                     "data-value": v }, svg).appendChild(el("title")).textContent = `${s.label || ""} ${label}: ${fmt(v)}`;
        total++;
      });
      const size = groups.length > 8 ? 9 : 11;
      el("text", { x: M.l + gi * gw + gw / 2, y: M.t + ax.ph + 15, class: "tick", "text-anchor": "middle",
                   style: `font-size:${size}px` }, svg).textContent = label;
    });
    el("line", { x1: M.l, x2: M.l + ax.pw, y1: ax.sy(0), y2: ax.sy(0), class: "zero" }, svg);
    svg.setAttribute("data-points", total);
    legend(svg, series.filter((s) => s.label).map((s) => ({ label: s.label, color: s.color })));
    return svg;
  }

  const STYLE = `.plot{font-family:system-ui,sans-serif;background:#fff}.plot-title{font-size:13px;font-weight:600}
.tick{font-size:11px;fill:#59636e}.label{font-size:12px}.legend{font-size:11px}.grid{stroke:#eaeef2}
.frame{fill:none;stroke:#afb8c1}.zero{stroke:#57606a}.series{fill:none;stroke-width:1.6;stroke-linejoin:round}
.limit{stroke-dasharray:6 4;stroke-width:1.3}.limit-label{font-size:10px;fill:#cf222e}
.marker-line{stroke:#8250df;stroke-dasharray:2 3}.marker{fill:#8250df}.marker-label{font-size:11px;fill:#8250df;font-weight:600}`;

  /** a standalone SVG document of `svg` (namespaces, size and the page's plot styles inlined) */
  function serialize(svg) {
    const copy = svg.cloneNode(true);
    copy.setAttribute("xmlns", NS);
    const [, , w, h] = (copy.getAttribute("viewBox") || "0 0 640 230").split(" ").map(Number);
    copy.setAttribute("width", w); copy.setAttribute("height", h);
    const style = document.createElementNS(NS, "style");
    style.textContent = STYLE;
    copy.insertBefore(style, copy.firstChild);
    copy.insertBefore(el("rect", { x: 0, y: 0, width: w, height: h, fill: "#fff" }), style.nextSibling);
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(copy);
  }

  return { line, bars, num, fmt, serialize, PALETTE };
})();
