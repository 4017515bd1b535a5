/* Inline SVG line charts over time, drawn in the browser from API data (no library). */
"use strict";
const Chart = (() => {
  const NS = "http://www.w3.org/2000/svg";
  const COLORS = ["#0b4f9c", "#a1161b", "#0b6b2b", "#6a3d9a"];

  function s(tag, attrs, text) {
    const n = document.createElementNS(NS, tag);
    for (const [k, v] of Object.entries(attrs || {})) n.setAttribute(k, v);
    if (text !== undefined) n.textContent = text;
    return n;
  }
  function niceStep(span, ticks) {
    const raw = span / Math.max(1, ticks), mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const f = raw / mag;
    return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * mag;
  }

  /**
   * Returns a <figure> with an SVG line chart.
   * series: [{name, points: [{t: Date|ISO, y: number|null, hollow?: bool, label?: string}], color?}]
   * opts: {title, yLabel, target: {y, label}, yMin, width, height, big}
   */
  function timeChart(series, opts = {}) {
    const W = opts.width || 640, H = opts.height || 260, big = !!opts.big;
    const m = { l: big ? 56 : 48, r: 16, t: 14, b: big ? 40 : 34 };
    const pts = series.flatMap((se) => se.points.filter((p) => p.y !== null && p.y !== undefined));
    const fig = document.createElement("figure");
    fig.className = "chart";
    if (opts.title) { const c = document.createElement("figcaption"); c.textContent = opts.title; fig.append(c); }
    const svg = s("svg", { viewBox: `0 0 ${W} ${H}`, class: "chart", role: "img", "aria-label": opts.title || "chart" });
    fig.append(svg);
    if (!pts.length) {
      svg.append(s("text", { x: W / 2, y: H / 2, "text-anchor": "middle" }, "No sessions yet"));
      return fig;
    }
    const times = pts.map((p) => +new Date(p.t));
    let t0 = Math.min(...times), t1 = Math.max(...times);
    if (t1 - t0 < 86400000) { t0 -= 43200000; t1 += 43200000; }
    const padT = (t1 - t0) * 0.04;  // keep the first and last points off the axes
    t0 -= padT; t1 += padT;
    const ys = pts.map((p) => p.y).concat(opts.target ? [opts.target.y] : []);
    let y0 = opts.yMin !== undefined ? opts.yMin : Math.min(...ys), y1 = Math.max(...ys);
    if (y1 === y0) { y1 += 1; y0 = Math.max(0, y0 - 1); }
    const step = niceStep(y1 - y0, 4);
    y0 = Math.floor(y0 / step) * step; y1 = Math.ceil(y1 / step) * step;
    if (Math.max(...ys) > y1 - step * 0.25) y1 += step;  // headroom above the highest point
    const X = (t) => m.l + ((+new Date(t) - t0) / (t1 - t0)) * (W - m.l - m.r);
    const Y = (y) => H - m.b - ((y - y0) / (y1 - y0)) * (H - m.t - m.b);

    const grid = s("g", { class: "grid" });
    for (let y = y0; y <= y1 + 1e-9; y += step) {
      grid.append(s("line", { x1: m.l, x2: W - m.r, y1: Y(y), y2: Y(y), stroke: "#ddd" }));
      grid.append(s("text", { x: m.l - 6, y: Y(y) + 4, "text-anchor": "end" }, +y.toFixed(1)));
    }
    const nx = Math.min(5, Math.max(2, Math.round((t1 - t0) / 86400000 / 7) + 1));
    for (let i = 0; i < nx; i++) {
      const t = t0 + padT + (i / (nx - 1)) * (t1 - t0 - 2 * padT);
      grid.append(s("text", { x: X(t), y: H - m.b + (big ? 24 : 20), "text-anchor": i === 0 ? "start" : i === nx - 1 ? "end" : "middle" },
        new Date(t).toLocaleDateString("en-GB", { day: "numeric", month: "short" })));
    }
    grid.append(s("line", { x1: m.l, x2: m.l, y1: m.t, y2: H - m.b, stroke: "#333" }));
    grid.append(s("line", { x1: m.l, x2: W - m.r, y1: H - m.b, y2: H - m.b, stroke: "#333" }));
    if (opts.yLabel) grid.append(s("text", { x: 12, y: m.t + (H - m.t - m.b) / 2, transform: `rotate(-90 12 ${m.t + (H - m.t - m.b) / 2})`, "text-anchor": "middle" }, opts.yLabel));
    svg.append(grid);

    if (opts.target) {
      svg.append(s("line", { class: "target", x1: m.l, x2: W - m.r, y1: Y(opts.target.y), y2: Y(opts.target.y),
        stroke: "#0b6b2b", "stroke-width": 3, "stroke-dasharray": "8 6" }));
    }
    series.forEach((se, i) => {
      const color = se.color || COLORS[i % COLORS.length];
      const ps = se.points.filter((p) => p.y !== null && p.y !== undefined).sort((a, b) => new Date(a.t) - new Date(b.t));
      if (ps.length > 1) svg.append(s("polyline", { fill: "none", stroke: color, "stroke-width": big ? 4 : 2.5,
        points: ps.map((p) => `${X(p.t).toFixed(1)},${Y(p.y).toFixed(1)}`).join(" ") }));
      for (const p of ps) {
        const c = s("circle", { class: "point", cx: X(p.t).toFixed(1), cy: Y(p.y).toFixed(1), r: big ? 7 : 5,
          fill: p.hollow ? "#fff" : color, stroke: color, "stroke-width": 2.5 });
        c.append(s("title", {}, p.label || `${se.name}: ${p.y} on ${new Date(p.t).toLocaleDateString("en-GB")}`));
        svg.append(c);
      }
    });
    const legend = document.createElement("div");
    legend.className = "legend";
    series.forEach((se, i) => {
      const it = document.createElement("span");
      const sw = document.createElement("i"); sw.style.borderColor = se.color || COLORS[i % COLORS.length];
      it.append(sw, se.name); legend.append(it);
    });
    if (opts.target) {
      const it = document.createElement("span");
      const sw = document.createElement("i"); sw.style.borderColor = "#0b6b2b"; sw.style.borderTopStyle = "dashed";
      it.append(sw, opts.target.label || "target"); legend.append(it);
    }
    if (opts.hollowNote) { const it = document.createElement("span"); it.textContent = "○ " + opts.hollowNote; legend.append(it); }
    fig.append(legend);
    return fig;
  }

  return { timeChart };
})();
