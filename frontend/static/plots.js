/* Plots: charts for every page, on plotly.js's cartesian bundle (scatter, bar, heatmap: every trace the pages draw;
   1.5 MB to parse against the full bundle's 4.8 MB) from the pinned npm package plotly.js-cartesian-dist-min
   (kinect_agent/vendor/lock.json, served at /static/vendor/plotly/plotly.min.js).

   Load /static/vendor/plotly/plotly.min.js, /static/api.js, then this file. One call:

     const fig = Plots.figure({
       title: "Right knee flexion",          // caption above the chart (also the table's caption by default)
       traces: [{x: [...], y: [...], name: "raw", type: "scatter", mode: "lines"}, ...],   // Plotly traces
       layout: {xaxis: {title: {text: "time (s)"}}, shapes: [...], annotations: [...]},  // merged over the defaults
       table: {caption: "...", columns: ["time (s)", "raw (°)"], rows: [[0, 12.5], ...]}, // the same data as a table
       fontSize: 16,                         // axis, tick, legend and hover labels, px; at least 14 (therapist
                                             // pages); the patient's page passes 20
       height: 360,                          // px; the width follows the container (responsive)
       config: {...},                        // extra Plotly config (merged; never turns the privacy defaults off)
     });
     container.append(fig);                  // a <figure>: caption, chart, "Show as table" toggle, hidden <table>

   The chart is drawn when the figure is in the document (immediately if it already is, else on the next frame).
   Zoom and hover are on; nothing leaves the origin: no Chart Studio link ("edit in chart studio" is off),
   no Plotly logo, no MathJax or web fonts fetched. The toggle button carries aria-expanded and aria-controls;
   the table is a real <table> with <caption>, <th scope="col"> and a row per data point, so screen readers read
   the numbers. Plots.table(spec) builds the table alone. Plots.draw(figure) redraws (e.g. after a resize).
   fig.plot is the Plotly graph div (its .data holds the traces, for tests). */
"use strict";
const Plots = (() => {
  const MIN_FONT = 14;
  let counter = 0;
  const COLORS = ["#0b4f9c", "#c0392b", "#1b7f3b", "#8a4b00", "#6a3d9a", "#00798c", "#b8336a", "#3d3d3d"];
  const CONFIG = {
    responsive: true, displaylogo: false, showLink: false, showEditInChartStudio: false, showSendToCloud: false,
    plotlyServerURL: "", linkText: "", typesetMath: false, scrollZoom: false,
    modeBarButtonsToRemove: ["sendDataToCloud", "editInChartStudio", "lasso2d", "select2d"],
  };

  /** Teaches plotly.js the page's language (month and day names, decimal sign) from the browser's Intl, so date
   *  axes read "8 nov." on a French page; returns the locale name for the charts' config. */
  function plotLocale() {
    if (!window.Plotly || I18n.locale === "en") return "en";
    const names = (options, dates) => dates.map((d) => new Intl.DateTimeFormat(I18n.tag, { timeZone: "UTC", ...options }).format(d));
    const months = [...Array(12).keys()].map((m) => new Date(Date.UTC(2026, m, 1)));
    const days = [...Array(7).keys()].map((d) => new Date(Date.UTC(2026, 10, 1 + d)));  // 1 Nov 2026 is a Sunday
    const decimal = new Intl.NumberFormat(I18n.tag).format(1.5).charAt(1);
    window.Plotly.register({ moduleType: "locale", name: I18n.locale, dictionary: {}, format: {
      months: names({ month: "long" }, months), shortMonths: names({ month: "short" }, months),
      days: names({ weekday: "long" }, days), shortDays: names({ weekday: "short" }, days),
      decimal, thousands: decimal === "," ? "." : ",",
    } });
    return I18n.locale;
  }
  const LOCALE = plotLocale();

  function merge(base, extra) {
    const out = { ...base };
    for (const [k, v] of Object.entries(extra || {})) {
      out[k] = v && typeof v === "object" && !Array.isArray(v) && base[k] && typeof base[k] === "object" ? merge(base[k], v) : v;
    }
    return out;
  }

  function baseLayout(size) {
    const font = { size, family: "system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif", color: "#111" };
    const axis = { tickfont: { size }, title: { font: { size } }, gridcolor: "#e2e2dc", zerolinecolor: "#9a9a94", automargin: true };
    return {
      font, autosize: true, colorway: COLORS, paper_bgcolor: "#fff", plot_bgcolor: "#fff",
      margin: { l: 16, r: 16, t: 16, b: 16 }, hoverlabel: { font: { size } },
      legend: { orientation: "h", x: 0, y: 1.02, yanchor: "bottom", font: { size } },
      xaxis: { ...axis }, yaxis: { ...axis }, dragmode: "zoom",
    };
  }

  /** Returns a <table> of spec {caption, columns: [names], rows: [[cells]]}; null cells read "—". */
  function table(spec) {
    const { el } = Coach;
    const fmt = (v) => (v === null || v === undefined || (typeof v === "number" && !isFinite(v)) ? "—" : String(v));
    return el("table", { class: "grid plot-table" },
      spec.caption ? el("caption", {}, spec.caption) : null,
      el("thead", {}, el("tr", {}, ...spec.columns.map((c) => el("th", { scope: "col" }, c)))),
      el("tbody", {}, ...spec.rows.map((r) => el("tr", {}, ...r.map((v) => el("td", {}, fmt(v)))))));
  }

  /** Draws (or redraws) the chart of a figure made by Plots.figure. */
  function draw(fig) {
    const spec = fig._plotSpec;
    return window.Plotly.react(fig.plot, spec.traces, spec.layout, spec.config);
  }

  /** Returns a <figure> with the chart, a "Show as table" toggle and the table (see the top of this file). */
  function figure({ title, traces, layout, table: tableSpec, fontSize = 16, height = 360, config } = {}) {
    const { el } = Coach;
    const size = Math.max(MIN_FONT, fontSize);
    const id = `plot-${++counter}`;
    const plot = el("div", { class: "plot", id: `${id}-chart` });
    const fig = el("figure", { class: "plot-figure", id }, title ? el("figcaption", { class: "plot-title" }, title) : null, plot);
    fig.plot = plot;
    fig._plotSpec = {
      traces: traces || [],
      layout: merge(merge(baseLayout(size), { height }), layout || {}),
      config: { ...(config || {}), ...CONFIG, locale: LOCALE },
    };
    if (tableSpec) {
      const wrap = el("div", { class: "table-wrap plot-table-wrap", id: `${id}-table`, hidden: true, tabindex: 0,
        role: "region", "aria-label": tableSpec.caption || title || I18n.t("chart data") },  // scrollable: keyboard reachable
        table({ caption: tableSpec.caption || title, columns: tableSpec.columns, rows: tableSpec.rows }));
      const button = el("button", { type: "button", class: "btn btn-quiet plot-toggle", "aria-expanded": "false", "aria-controls": `${id}-table` }, I18n.t("Show as table"));
      button.addEventListener("click", () => {
        const open = wrap.hidden;
        wrap.hidden = !open;
        button.setAttribute("aria-expanded", String(open));
        button.textContent = open ? I18n.t("Hide table") : I18n.t("Show as table");
      });
      fig.append(button, wrap);
    }
    const start = () => (fig.isConnected ? draw(fig) : requestAnimationFrame(start));
    if (window.Plotly) requestAnimationFrame(start);
    else plot.append(el("p", { class: "muted" }, I18n.t("The chart could not be drawn; use “Show as table”.")));
    return fig;
  }

  /** Returns an x-axis layout for dates (ISO strings): day-month ticks, at most one tick a day, so a few
      sessions close together never show the same date under several ticks. */
  function dateAxis(dates, extra = {}) {
    const DAY = 86400000, times = dates.map((d) => +new Date(d)).filter(isFinite);
    const axis = { type: "date", tickformat: "%-d %b", ...extra };
    if (!times.length) return axis;
    const lo = Math.min(...times), hi = Math.max(...times);
    if (hi - lo < 6 * DAY) {  // short span: one tick per day, with half a day of room on each side
      const first = new Date(lo); first.setHours(12, 0, 0, 0);  // a tick at noon: under the middle of its day
      Object.assign(axis, { dtick: DAY, tick0: first.toISOString(), range: [new Date(lo - DAY / 2).toISOString(), new Date(hi + DAY / 2).toISOString()] });
      delete axis.nticks;
    }
    return axis;
  }

  return { figure, table, draw, dateAxis, COLORS, MIN_FONT };
})();
