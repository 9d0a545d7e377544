/* report.html (dnasim.report): the page's script, inlined.
 * Reads the JSON data block, draws the schematic's values, the variable browser,
 * the main panels and the steps. Builds the DOM with textContent only: no string
 * from the plant ever becomes markup. */
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("dnasim-data").textContent);
  var HAVE_PLOTLY = typeof window.Plotly !== "undefined";
  if (!HAVE_PLOTLY) document.getElementById("noplotly").hidden = false;

  // ------------------------------------------------------------------ data
  function bytes(s) {
    var bin = atob(s), u = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) u[i] = bin.charCodeAt(i);
    return u.buffer;
  }
  function f64(s) { return new Float64Array(bytes(s)); }
  function f32(s) { return new Float32Array(bytes(s)); }
  var T = f64(D.time), N = T.length;
  var VARS = D.vars, BY = {};
  VARS.forEach(function (v, i) { v.index = i; BY[v.name] = v; });
  var cache = {};
  function values(name) {
    if (cache[name]) return cache[name];
    var v = BY[name], out = new Float64Array(N), d = v.data;
    if (d.c !== undefined) { out.fill(d.c === null ? NaN : d.c); }
    else { var a = f32(d.d); for (var i = 0; i < N; i++) out[i] = d.b + a[i]; }
    cache[name] = out;
    return out;
  }

  // ------------------------------------------------------------------ units
  var mode = D.units === "engineering" ? "engineering" : "si";
  function conv(unit, mag) {
    // {label, scale, offset}: display = SI * scale + offset
    if (mode === "engineering" && D.engineering[unit]) {
      var e = D.engineering[unit], s = D.engineering_small[unit];
      if (s && mag !== undefined && mag < s[0]) return { label: s[1], scale: s[2], offset: 0 };
      return { label: e[0], scale: e[1], offset: e[2] };
    }
    return { label: unit === "1" ? "-" : unit, scale: 1, offset: 0 };
  }
  function fmt(x) {
    // 5 significant digits; whole numbers from 1e5 on; exponents beyond 1e10 and below 1e-3
    if (x === null || x === undefined || !isFinite(x)) return "–";
    var a = Math.abs(x);
    if (a === 0) return "0";
    if (a >= 1e10 || a < 1e-3) return x.toExponential(3).replace(/\.?0+e/, "e").replace("e+", "e");
    if (a >= 1e5) return x.toFixed(0);
    return x.toPrecision(5).replace(/(\.\d*?)0+$/, "$1").replace(/\.$/, "");
  }
  function show(v, x) { // a value of variable v in the current units, with its unit
    var c = conv(v.unit, Math.max(Math.abs(v.min || 0), Math.abs(v.max || 0)));
    if (x === null || x === undefined) return "–";
    if (Math.abs(x) <= (D.zero[v.unit] || 0)) x = 0; // round-off of a zero: "0 t/h", not "6.9e-26 t/h"
    return fmt(x * c.scale + c.offset) + (c.label === "-" ? "" : " " + c.label);
  }
  function timeAxis() {
    var span = N ? T[N - 1] : 0;
    if (span >= 3 * 3600) return { scale: 3600, label: "time [h]" };
    if (span >= 180) return { scale: 60, label: "time [min]" };
    return { scale: 1, label: "time [s]" };
  }
  function isConst(v) { return v.data.c !== undefined; }

  // ------------------------------------------------------------------ helpers
  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }
  var COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
    "#17becf", "#7f7f7f", "#bcbd22"];
  function markerShapes() {
    var ta = timeAxis(), shapes = [];
    D.restarts.forEach(function (t) {
      shapes.push({ type: "line", xref: "x", yref: "paper", x0: t / ta.scale, x1: t / ta.scale,
        y0: 0, y1: 1, line: { color: "#999", width: 1, dash: "dot" } });
    });
    D.events.forEach(function (t) {
      shapes.push({ type: "line", xref: "x", yref: "paper", x0: t / ta.scale, x1: t / ta.scale,
        y0: 0, y1: 1, line: { color: "#d62728", width: 1, dash: "dash" } });
    });
    return shapes;
  }
  var CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["lasso2d", "select2d"] };
  // the main panels: zoom by dragging, double-click to reset; no tool bar over the legend
  var PANEL_CONFIG = { displaylogo: false, responsive: true, displayModeBar: false };
  function tx() { var ta = timeAxis(), x = new Array(N); for (var i = 0; i < N; i++) x[i] = T[i] / ta.scale; return x; }
  function ys(name, c, sign) {
    var v = values(name), y = new Array(N), s = sign || 1;
    for (var i = 0; i < N; i++) y[i] = isFinite(v[i]) ? s * v[i] * c.scale + c.offset : null;
    return y;
  }
  function mag(names) {
    var m = 0;
    names.forEach(function (n) { var v = BY[n]; m = Math.max(m, Math.abs(v.min || 0), Math.abs(v.max || 0)); });
    return m;
  }
  function axisRange(traces, minRel) {
    // do not blow round-off up: at least minRel of the magnitude (as the PNG plots)
    var lo = Infinity, hi = -Infinity;
    traces.forEach(function (t) { t.y.forEach(function (y) { if (y !== null) { lo = Math.min(lo, y); hi = Math.max(hi, y); } }); });
    if (!isFinite(lo)) return null;
    var span = Math.max(minRel * Math.max(Math.abs(lo), Math.abs(hi)), 1e-12);
    if (hi - lo >= span) return null;
    var mid = (lo + hi) / 2;
    return [mid - span / 2, mid + span / 2];
  }

  // ------------------------------------------------------------------ main panels
  function drawPanels() {
    var box = document.getElementById("panels");
    if (!HAVE_PLOTLY) return;
    box.textContent = "";
    var x = tx(), ta = timeAxis();
    D.panels.forEach(function (p, k) {
      var div = el("div", "panel");
      div.id = "panel-" + k;
      box.appendChild(div);
      var m = mag(p.curves.map(function (c) { return c.name; }));
      var c = conv(p.unit, m);
      var traces = p.curves.map(function (cv, i) {
        return { x: x, y: ys(cv.name, c, cv.sign), name: cv.label, mode: "lines", type: "scatter",
          line: { width: 1.6, dash: cv.dashed ? "dash" : "solid", color: COLORS[i % COLORS.length] } };
      });
      var unitLabel = p.quantity === "control error" && (c.label === "-" || c.label === "1") ? "unit of the measured signal" : c.label;
      var layout = {
        margin: { l: 64, r: 12, t: 24, b: 38 }, height: 298,
        title: p.title ? { text: p.title, font: { size: 12 }, x: 0.01, xanchor: "left", y: 0.99, yanchor: "top" } : undefined,
        xaxis: { title: { text: ta.label }, showgrid: true, zeroline: false },
        yaxis: { title: { text: p.quantity + " [" + unitLabel + "]" }, zeroline: false, exponentformat: "power", automargin: true },
        legend: { orientation: "h", y: 1.0, yanchor: "bottom", x: p.title ? 0.12 : 0, xanchor: "left", font: { size: 11 } },
        showlegend: true, hovermode: "x unified", shapes: markerShapes()
      };
      if (p.limits) {
        var lo = p.limits[0] * c.scale + c.offset, hi = p.limits[1] * c.scale + c.offset, pad = 0.04 * (hi - lo || 1);
        traces.forEach(function (t) { t.y.forEach(function (y) { if (y !== null) { lo = Math.min(lo, y); hi = Math.max(hi, y); } }); });
        layout.yaxis.range = [lo - pad, hi + pad];
      } else {
        var r = axisRange(traces, 1e-3);
        if (r) layout.yaxis.range = r;
      }
      Plotly.newPlot(div, traces, layout, PANEL_CONFIG);
    });
    var note = document.getElementById("constants");
    if (D.constants.length) {
      note.textContent = "Constant over the run (not drawn): " + D.constants.map(function (k) {
        var v = BY[k.name];
        return k.name + " = " + (v ? show(v, k.value) : fmt(k.value) + " " + k.unit);
      }).join(", ") + ".";
    } else note.textContent = "";
  }

  // ------------------------------------------------------------------ steps
  function drawSteps() {
    var div = document.getElementById("steps");
    if (!HAVE_PLOTLY || !D.steps) return;
    var t = f64(D.steps.t), h = f64(D.steps.h), o = f32(D.steps.order), ta = timeAxis();
    if (!t.length) { div.textContent = "no steps recorded"; div.className = "empty"; return; }
    var x = Array.from(t, function (v) { return v / ta.scale; });
    var shapes = markerShapes().map(function (s) { s.yref = "paper"; return s; });
    Plotly.newPlot(div, [
      { x: x, y: Array.from(h), mode: "lines+markers", marker: { size: 3 }, line: { width: 1 }, name: "step size [s]" },
      { x: x, y: Array.from(o, function (v) { return isFinite(v) ? v : null; }), mode: "lines", line: { shape: "hv", width: 1.2 }, name: "order", xaxis: "x", yaxis: "y2" }
    ], {
      height: 418, margin: { l: 64, r: 12, t: 12, b: 38 }, showlegend: false, hovermode: "x unified",
      grid: { rows: 2, columns: 1, subplots: [["xy"], ["xy2"]] },
      xaxis: { title: { text: ta.label } },
      yaxis: { type: "log", title: { text: "step size [s]" }, domain: [0.4, 1], exponentformat: "power" },
      yaxis2: { title: { text: "order" }, dtick: 1, domain: [0, 0.32] },
      shapes: shapes
    }, CONFIG);
  }

  // ------------------------------------------------------------------ browser
  var plots = [], active = 0, nextId = 1, colorOf = {}, colorNext = 0;
  var rows = {}; // name -> row element
  var grouping = "component";
  var search = document.getElementById("search"), tree = document.getElementById("tree");

  function ownerLabel(owner) {
    if (D.components[owner]) return D.components[owner].type;
    if (D.nodes.indexOf(owner) >= 0) return "node";
    return "";
  }
  function groupKey(v) {
    if (grouping === "quantity") return v.quantity + " [" + conv(v.unit, 1e9).label + "]";
    return v.owner || v.name;
  }
  function buildTree() {
    tree.textContent = "";
    rows = {};
    var groups = {}, order = [];
    VARS.forEach(function (v) {
      var k = groupKey(v);
      if (!groups[k]) { groups[k] = []; order.push(k); }
      groups[k].push(v);
    });
    if (grouping === "quantity") order.sort();
    else {
      var comps = Object.keys(D.components);
      var rank = function (k) {
        var i = comps.indexOf(k);
        if (i >= 0) return i;
        var j = D.nodes.indexOf(k);
        return j >= 0 ? comps.length + j : comps.length + D.nodes.length;
      };
      order.sort(function (a, b) { return rank(a) - rank(b); });
    }
    order.forEach(function (k) {
      var g = el("div", "group"), head = el("div", "ghead"), body = el("div", "gbody");
      g.dataset.group = k;
      head.appendChild(el("span", "caret", "▾"));
      head.appendChild(el("span", "gname", k));
      if (grouping === "component") head.appendChild(el("span", "gtype", ownerLabel(k)));
      head.appendChild(el("span", "gcount", String(groups[k].length)));
      head.addEventListener("click", function () { setOpen(g, g.classList.contains("closed")); });
      g.appendChild(head);
      groups[k].forEach(function (v) {
        var r = el("div", "var");
        r.dataset.name = v.name;
        r.appendChild(el("span", "swatch"));
        r.appendChild(el("span", "vname", grouping === "component" && v.owner ? v.name.slice(v.owner.length) : v.name));
        r.appendChild(el("span", "vunit", "[" + conv(v.unit, mag([v.name])).label + "]"));
        r.appendChild(el("span", "vval" + (isConst(v) ? " const" : ""), show(v, v.final).split(" ")[0] + (isConst(v) ? " const" : "")));
        r.title = v.name + " [" + v.unit + "], " + v.quantity + "\nfinal " + show(v, v.final) +
          "\nmin " + show(v, v.min) + "\nmax " + show(v, v.max);
        r.addEventListener("click", function () { toggle(v.name); });
        body.appendChild(r);
        rows[v.name] = r;
      });
      g.appendChild(body);
      if (groups[k].length > 40 && order.length > 1) g.classList.add("closed");
      tree.appendChild(g);
    });
    paintRows();
    filter();
  }
  function setOpen(g, open) {
    g.classList.toggle("closed", !open);
    g.querySelector(".caret").textContent = open ? "▾" : "▸";
  }
  function matcher(q) {
    var terms = q.trim().toLowerCase().split(/\s+/).filter(Boolean);
    var res = terms.map(function (t) {
      if (/[*?]/.test(t)) {
        var re = "^" + t.replace(/[.+^${}()|[\]\\]/g, "\\$&").replace(/\*/g, ".*").replace(/\?/g, ".") + "$";
        return new RegExp(re);
      }
      return null;
    });
    return function (v) {
      var type = D.components[v.owner] ? D.components[v.owner].type : (D.nodes.indexOf(v.owner) >= 0 ? "node" : "");
      var hay = (v.name + " " + v.unit + " " + conv(v.unit, 1e9).label + " " + v.quantity + " " + type).toLowerCase();
      for (var i = 0; i < terms.length; i++) {
        if (res[i] ? !res[i].test(v.name.toLowerCase()) : hay.indexOf(terms[i]) < 0) return false;
      }
      return true;
    };
  }
  function visibleMatches() {
    var m = matcher(search.value);
    return VARS.filter(m);
  }
  function filter() {
    var q = search.value.trim(), m = matcher(q), n = 0;
    tree.querySelectorAll(".group").forEach(function (g) {
      var any = false;
      g.querySelectorAll(".var").forEach(function (r) {
        var ok = m(BY[r.dataset.name]);
        r.style.display = ok ? "" : "none";
        if (ok) { any = true; n++; }
      });
      g.style.display = any ? "" : "none";
      if (q && any) setOpen(g, true);
    });
    document.getElementById("count").textContent = (q ? n + " of " : "") + VARS.length + " variables" +
      (D.rows.shown < D.rows.of ? "; " + D.rows.shown + " of " + D.rows.of + " rows drawn (results.csv holds all)" : "");
  }
  function colorFor(name) {
    if (!colorOf[name]) { colorOf[name] = COLORS[colorNext % COLORS.length]; colorNext++; }
    return colorOf[name];
  }
  function paintRows() {
    var on = {};
    plots.forEach(function (p) { p.vars.forEach(function (n) { on[n] = true; }); });
    Object.keys(rows).forEach(function (n) {
      var r = rows[n];
      r.classList.toggle("on", !!on[n]);
      r.querySelector(".swatch").style.background = on[n] ? colorFor(n) : "";
    });
    document.querySelectorAll("#card tr.cvar").forEach(function (tr) { tr.classList.toggle("sel", !!on[tr.dataset.name]); });
  }
  function unitsOf(p) {
    var u = [];
    p.vars.forEach(function (n) { if (u.indexOf(BY[n].unit) < 0) u.push(BY[n].unit); });
    return u;
  }
  function newPlot() {
    var p = { id: nextId++, vars: [] };
    plots.push(p);
    active = plots.length - 1;
    renderPlots();
    return p;
  }
  function add(name) {
    var u = BY[name].unit, p = plots[active];
    var fits = function (q) { var us = unitsOf(q); return us.indexOf(u) >= 0 || us.length < 2; };
    if (!p || !fits(p)) {
      var other = plots.filter(function (q) { return unitsOf(q).indexOf(u) >= 0; })[0];
      p = other || newPlot();
      active = plots.indexOf(p);
    }
    if (p.vars.indexOf(name) < 0) p.vars.push(name);
  }
  function remove(name) {
    plots.forEach(function (p) { var i = p.vars.indexOf(name); if (i >= 0) p.vars.splice(i, 1); });
  }
  function plotted(name) { return plots.some(function (p) { return p.vars.indexOf(name) >= 0; }); }
  function toggle(name) {
    if (plotted(name)) remove(name); else add(name);
    renderPlots();
  }
  function plotMany(names) {
    names.forEach(function (n) { if (!plotted(n)) add(n); });
    renderPlots();
  }
  function renderPlots() {
    var stack = document.getElementById("plotstack");
    if (!plots.length) { plots.push({ id: nextId++, vars: [] }); active = 0; }
    if (active >= plots.length) active = plots.length - 1;
    // drop empty plots other than the active one
    plots = plots.filter(function (p, i) { return p.vars.length || i === active; });
    active = Math.max(0, Math.min(active, plots.length - 1));
    var keep = {};
    plots.forEach(function (p, i) {
      keep[p.id] = true;
      var box = document.getElementById("plot-" + p.id);
      if (!box) {
        box = el("div", "plot");
        box.id = "plot-" + p.id;
        var head = el("div", "phead");
        head.appendChild(el("span", "ptitle"));
        head.appendChild(el("span", "punits"));
        var close = el("button", "pclose", "×");
        close.title = "remove this plot";
        close.addEventListener("click", function (ev) {
          ev.stopPropagation();
          plots = plots.filter(function (q) { return q !== p; });
          box.remove();
          renderPlots();
        });
        head.appendChild(close);
        box.appendChild(head);
        var div = el("div", "pdiv");
        box.appendChild(div);
        box.addEventListener("mousedown", function () { active = plots.indexOf(p); markActive(); });
        stack.appendChild(box);
      }
      stack.appendChild(box); // keep the order
      box.querySelector(".ptitle").textContent = "Plot " + (i + 1) + (i === active ? " (active)" : "");
      var us = unitsOf(p);
      box.querySelector(".punits").textContent = us.map(function (u) {
        return conv(u, mag(p.vars.filter(function (n) { return BY[n].unit === u; }))).label;
      }).join(" | ");
      drawPlot(p, box.querySelector(".pdiv"));
    });
    stack.querySelectorAll(".plot").forEach(function (b) {
      if (!keep[b.id.slice(5)]) b.remove();
    });
    markActive();
    paintRows();
  }
  function markActive() {
    plots.forEach(function (p, i) {
      var b = document.getElementById("plot-" + p.id);
      if (b) {
        b.classList.toggle("active", i === active);
        b.querySelector(".ptitle").textContent = "Plot " + (i + 1) + (i === active ? " (active)" : "");
      }
    });
  }
  function drawPlot(p, div) {
    if (!p.vars.length) {
      if (HAVE_PLOTLY && div.classList.contains("js-plotly-plot")) Plotly.purge(div);
      div.textContent = "";
      div.appendChild(el("div", "empty", "Click variables on the left (or components in the schematic) to plot them here."));
      return;
    }
    if (!HAVE_PLOTLY) { div.textContent = "plotly.min.js is missing"; return; }
    var empty = div.querySelector(".empty");
    if (empty) empty.remove();
    var us = unitsOf(p), x = tx(), ta = timeAxis();
    var convs = us.map(function (u) { return conv(u, mag(p.vars.filter(function (n) { return BY[n].unit === u; }))); });
    var traces = p.vars.map(function (n) {
      var k = us.indexOf(BY[n].unit);
      return { x: x, y: ys(n, convs[k]), name: n + (k ? " (right)" : ""), mode: "lines", type: "scatter",
        yaxis: k ? "y2" : "y", line: { width: 1.6, color: colorFor(n), dash: k ? "dot" : "solid" } };
    });
    var q = function (u) {
      var qs = [];
      p.vars.forEach(function (n) { if (BY[n].unit === u && qs.indexOf(BY[n].quantity) < 0) qs.push(BY[n].quantity); });
      return qs.join(", ");
    };
    var layout = {
      margin: { l: 70, r: us.length > 1 ? 70 : 16, t: 8, b: 40 }, height: 338,
      xaxis: { title: { text: ta.label } },
      yaxis: { title: { text: q(us[0]) + " [" + convs[0].label + "]" }, zeroline: false, automargin: true, exponentformat: "power" },
      legend: { orientation: "h", y: 1.02, yanchor: "bottom", x: 0, font: { size: 11 } },
      hovermode: "x unified", shapes: markerShapes(), showlegend: true
    };
    var r0 = axisRange(traces.filter(function (t) { return t.yaxis === "y"; }), 1e-3);
    if (r0) layout.yaxis.range = r0;
    if (us.length > 1) {
      layout.yaxis2 = { title: { text: q(us[1]) + " [" + convs[1].label + "]" }, overlaying: "y", side: "right", zeroline: false, showgrid: false, automargin: true, exponentformat: "power" };
      var r1 = axisRange(traces.filter(function (t) { return t.yaxis === "y2"; }), 1e-3);
      if (r1) layout.yaxis2.range = r1;
    }
    Plotly.react(div, traces, layout, CONFIG);
  }
  document.getElementById("newplot").addEventListener("click", function () { newPlot(); });
  document.getElementById("clearplots").addEventListener("click", function () {
    plots.forEach(function (p) { var b = document.getElementById("plot-" + p.id); if (b) b.remove(); });
    plots = []; renderPlots();
  });
  search.addEventListener("input", filter);
  search.addEventListener("keydown", function (ev) {
    if (ev.key === "Enter") {
      ev.preventDefault();
      var first = visibleMatches().filter(function (v) { return !plotted(v.name); })[0];
      if (first) { add(first.name); renderPlots(); }
    } else if (ev.key === "Escape") { search.value = ""; filter(); }
  });
  document.querySelectorAll(".seg button").forEach(function (b) {
    b.addEventListener("click", function () {
      grouping = b.dataset.group;
      document.querySelectorAll(".seg button").forEach(function (o) { o.classList.toggle("on", o === b); });
      buildTree();
    });
  });

  // ------------------------------------------------------------------ schematic
  var svg = document.querySelector("svg.schematic"), tip = el("div");
  tip.id = "tip"; tip.hidden = true; document.body.appendChild(tip);
  function ownVars(owner) { return VARS.filter(function (v) { return v.owner === owner; }); }
  function mainVars(owner) {
    // the owner's variables in the main panels and the values under its symbol, else its scalars
    var names = [];
    D.panels.forEach(function (p) { p.curves.forEach(function (c) { if (BY[c.name] && BY[c.name].owner === owner) names.push(c.name); }); });
    if (svg) svg.querySelectorAll('[data-comp] .value').forEach(function (t) {
      if (t.closest("[data-comp]").dataset.comp === owner && t.dataset.col && names.indexOf(t.dataset.col) < 0) names.push(t.dataset.col);
    });
    if (!names.length) names = ownVars(owner).filter(function (v) { return v.name.indexOf("[") < 0 && !isConst(v); }).map(function (v) { return v.name; }).slice(0, 4);
    return names;
  }
  function varTable(list, clickable) {
    var t = el("table"), head = el("tr");
    ["variable", "final", "min", "max"].forEach(function (h) { head.appendChild(el("th", "", h)); });
    t.appendChild(head);
    list.forEach(function (v) {
      var tr = el("tr", clickable ? "cvar" : "");
      tr.dataset.name = v.name;
      tr.appendChild(el("td", "", v.name.slice(v.owner.length + 1) || v.name));
      tr.appendChild(el("td", "num", show(v, v.final)));
      tr.appendChild(el("td", "num", isConst(v) ? "const" : fmt(v.min * conv(v.unit, mag([v.name])).scale + conv(v.unit, mag([v.name])).offset)));
      tr.appendChild(el("td", "num", isConst(v) ? "" : fmt(v.max * conv(v.unit, mag([v.name])).scale + conv(v.unit, mag([v.name])).offset)));
      if (clickable) { tr.title = "plot " + v.name; tr.addEventListener("click", function () { toggle(v.name); }); }
      t.appendChild(tr);
    });
    return t;
  }
  function heading(owner) {
    if (D.components[owner]) return owner + " (" + D.components[owner].type + ")";
    return "node " + owner;
  }
  function showTip(owner, ev) {
    var list = ownVars(owner).filter(function (v) { return v.name.indexOf("[") < 0; });
    tip.textContent = "";
    tip.appendChild(el("h4", "", heading(owner)));
    var short = list.slice(0, 14);
    if (short.length) tip.appendChild(varTable(short, false));
    else tip.appendChild(el("div", "muted", "no variables of its own"));
    if (list.length > short.length) tip.appendChild(el("div", "muted", "… " + (list.length - short.length) + " more: click"));
    tip.hidden = false;
    moveTip(ev);
  }
  function moveTip(ev) {
    var w = tip.offsetWidth, h = tip.offsetHeight, x = ev.clientX + 16, y = ev.clientY + 14;
    if (x + w > window.innerWidth - 8) x = ev.clientX - w - 16;
    if (y + h > window.innerHeight - 8) y = Math.max(8, window.innerHeight - h - 8);
    tip.style.left = x + "px"; tip.style.top = y + "px";
  }
  function select(owner, scroll) {
    if (svg) svg.querySelectorAll(".selected").forEach(function (e) { e.classList.remove("selected"); });
    var sel = svg && (svg.querySelector('g.comp[data-comp="' + CSS.escape(owner) + '"]') || svg.querySelector('g.node[data-node="' + CSS.escape(owner) + '"]'));
    if (sel) sel.classList.add("selected");
    var card = document.getElementById("card");
    card.textContent = "";
    card.appendChild(el("h3", "", owner));
    card.appendChild(el("div", "type", D.components[owner] ? D.components[owner].type : "node"));
    var list = ownVars(owner);
    var bar = el("div");
    var b1 = el("button", "", "plot main variables");
    b1.addEventListener("click", function () { plotMany(mainVars(owner)); document.getElementById("browser").scrollIntoView(); });
    var b2 = el("button", "", "show in browser");
    b2.addEventListener("click", function () { document.getElementById("browser").scrollIntoView(); });
    bar.appendChild(b1); bar.appendChild(document.createTextNode(" ")); bar.appendChild(b2);
    card.appendChild(bar);
    if (list.length) card.appendChild(varTable(list, true));
    else card.appendChild(el("p", "muted", "It has no variables of its own (its values are its nodes')."));
    card.appendChild(el("p", "muted", "Click a row to plot it."));
    // the browser shows this component's variables
    search.value = owner + ".*";
    if (grouping !== "component") { grouping = "component"; document.querySelectorAll(".seg button").forEach(function (o) { o.classList.toggle("on", o.dataset.group === "component"); }); buildTree(); }
    filter();
    paintRows();
    if (scroll) document.getElementById("browser").scrollIntoView();
  }
  function fillValues() {
    if (!svg) return;
    svg.querySelectorAll("text.value").forEach(function (t) {
      var v = BY[t.dataset.col];
      t.textContent = v ? show(v, v.final) : "";
    });
  }
  if (svg) {
    svg.querySelectorAll("g.comp, g.node").forEach(function (g) {
      var owner = g.dataset.comp || g.dataset.node;
      var title = g.querySelector("title");
      if (title) title.remove(); // the card replaces the native tooltip
      g.addEventListener("mouseenter", function (ev) { showTip(owner, ev); });
      g.addEventListener("mousemove", moveTip);
      g.addEventListener("mouseleave", function () { tip.hidden = true; });
      g.addEventListener("click", function () { tip.hidden = true; select(owner, false); });
      g.addEventListener("keydown", function (ev) { if (ev.key === "Enter") select(owner, true); });
    });
    document.getElementById("shownodes").addEventListener("change", function (ev) { svg.classList.toggle("nonames", !ev.target.checked); });
    document.getElementById("showvalues").addEventListener("change", function (ev) { svg.classList.toggle("novalues", !ev.target.checked); });
    // a drawing wider than its box keeps its natural size (scroll) when it would shrink below 60 %
    // a small drawing is shown up to 1.35 times its size; a wide one shrinks to 3/4 at
    // most and scrolls beyond (its text stays readable)
    var w = parseFloat(svg.getAttribute("width"));
    var fit = function () {
      var box = svg.parentNode.clientWidth - 2, narrow = box < 0.75 * w;
      svg.classList.toggle("natural", narrow);
      svg.style.width = narrow ? 0.75 * w + "px" : Math.min(box, 1.35 * w) + "px";
    };
    fit(); window.addEventListener("resize", fit);
  }

  // ------------------------------------------------------------------ units switch
  function setMode(m) {
    mode = m;
    document.querySelectorAll(".unitswitch button").forEach(function (b) { b.classList.toggle("on", b.dataset.units === m); });
    fillValues();
    buildTree();
    drawPanels();
    renderPlots();
  }
  document.querySelectorAll(".unitswitch button").forEach(function (b) {
    b.addEventListener("click", function () { setMode(b.dataset.units); });
  });

  // ------------------------------------------------------------------ start
  // a view to open with: report.html#search=drum%20level&plot=drum.level,drum.p
  var hash = {};
  location.hash.replace(/^#/, "").split("&").forEach(function (kv) {
    var i = kv.indexOf("=");
    if (i > 0) hash[decodeURIComponent(kv.slice(0, i))] = decodeURIComponent(kv.slice(i + 1));
  });
  document.querySelectorAll(".unitswitch button").forEach(function (b) { b.classList.toggle("on", b.dataset.units === mode); });
  fillValues();
  buildTree();
  drawPanels();
  drawSteps();
  if (hash.search) { search.value = hash.search; filter(); }
  if (hash.plot) plotMany(hash.plot.split(",").filter(function (n) { return BY[n]; }));
  else renderPlots();
  window.dnasimReport = { select: select, toggle: toggle, plots: function () { return plots; } };
})();
