/*
 * The stickslip explorer: plain JavaScript drawing plain SVG.
 *
 * No plotting library: what the page draws (polylines, a grid of cells,
 * axes with a few ticks) is a few hundred lines of SVG, so there is nothing
 * to vendor, pin or license, and the page works with no network.  It asks
 * the daemon (its own origin, or ?api=URL for another daemon that allows
 * this origin with --cors-origin) for curves sampled to half a pixel of its
 * own plots (samples.tolerance with per-axis scales in data units per
 * pixel) and for only the columns it draws (samples.fields).
 */
"use strict";

const API = new URLSearchParams(location.search).get("api") || "";
const SVGNS = "http://www.w3.org/2000/svg";
const DASH = { overshoot: "", stick: "7 4", slip: "1.5 3" };
const COLORS = ["#1f5fa8", "#c2410c", "#15803d", "#7e22ce", "#b91c1c",
                "#0e7490", "#a16207", "#be185d"];
const PAD = { left: 48, right: 12, top: 12, bottom: 30 };

const state = { orbits: [], selected: 0, params: null, units: null };

/* ---- talking to the daemon ---------------------------------------------- */

/* A problem from the daemon, in words: its title, detail and field. */
class Problem extends Error {
  constructor(status, body) {
    const where = body && (body.pointer || body.field);
    super((body && body.detail) || (body && body.title) || "HTTP " + status);
    this.status = status;
    this.where = where || "";
    this.title = (body && body.title) || "";
  }
}

async function post(path, body, ndjson) {
  let res;
  try {
    res = await fetch(API + path, {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify(body),
    });
  } catch (e) {
    throw new Problem(0, { detail: "the daemon could not be reached (" + e.message + ")" });
  }
  const text = await res.text();
  if (!res.ok) {
    let problem = null;
    try { problem = JSON.parse(text); } catch (e) { /* not JSON */ }
    throw new Problem(res.status, problem || { detail: text.slice(0, 300) });
  }
  if (ndjson)
    return text.split("\n").filter((l) => l.trim()).map((l) => JSON.parse(l));
  return JSON.parse(text);
}

function showError(e) {
  const box = document.getElementById("error");
  box.textContent = "";
  const strong = document.createElement("strong");
  strong.textContent = e.title ? e.title + ": " : "Error: ";
  box.append(strong, e.message);
  if (e.where) {
    const w = document.createElement("span");
    w.className = "where";
    w.textContent = " (" + e.where + ")";
    box.append(w);
  }
  box.hidden = false;
}

function clearError() {
  const box = document.getElementById("error");
  box.hidden = true;
  box.textContent = "";
}

function status(text) {
  document.getElementById("status").textContent = text;
}

/* ---- the parameters ----------------------------------------------------- */

function readParams() {
  const units = document.getElementById("units").value;
  const group = document.getElementById(units);
  const out = {};
  for (const input of group.querySelectorAll("input")) {
    const v = Number(input.value);
    /* sent as typed when not a number: the daemon says what is wrong */
    out[input.name] = input.value.trim() === "" || isNaN(v) ? input.value : v;
  }
  return units === "physical" ? { physical: out } : { params: out };
}

/* ---- SVG plots ------------------------------------------------------------ */

function el(name, attrs, parent) {
  const e = document.createElementNS(SVGNS, name);
  for (const k in attrs)
    e.setAttribute(k, attrs[k]);
  if (parent)
    parent.appendChild(e);
  return e;
}

function niceTicks(lo, hi, n) {
  const span = hi - lo || 1;
  const step0 = span / n, mag = Math.pow(10, Math.floor(Math.log10(step0)));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= step0);
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + 1e-12 * span; t += step)
    ticks.push(Math.abs(t) < 1e-12 * span ? 0 : t);
  return ticks;
}

/* A plot: the svg, its data ranges, and the maps to pixels. */
function frame(svg, xr, yr, xlabel, ylabel, exact) {
  svg.textContent = "";
  const w = Number(svg.getAttribute("width")), h = Number(svg.getAttribute("height"));
  const pw = w - PAD.left - PAD.right, ph = h - PAD.top - PAD.bottom;
  const pad = (r) => {
    const d = (r[1] - r[0]) || Math.abs(r[0]) || 1;
    return [r[0] - 0.05 * d, r[1] + 0.05 * d];
  };
  if (!exact) {
    xr = pad(xr);
    yr = pad(yr);
  }
  const p = {
    svg, xr, yr, pw, ph,
    x: (v) => PAD.left + (v - xr[0]) / (xr[1] - xr[0]) * pw,
    y: (v) => PAD.top + (yr[1] - v) / (yr[1] - yr[0]) * ph,
    /* data units per pixel, for samples.scale */
    sx: (xr[1] - xr[0]) / pw,
    sy: (yr[1] - yr[0]) / ph,
  };
  const axes = el("g", { class: "axes" }, svg);
  el("rect", { x: PAD.left, y: PAD.top, width: pw, height: ph, class: "box" }, axes);
  for (const t of niceTicks(xr[0], xr[1], 6)) {
    el("line", { x1: p.x(t), x2: p.x(t), y1: PAD.top + ph, y2: PAD.top + ph + 4 }, axes);
    el("text", { x: p.x(t), y: PAD.top + ph + 16, "text-anchor": "middle" }, axes)
      .textContent = +t.toPrecision(4);
  }
  for (const t of niceTicks(yr[0], yr[1], 5)) {
    el("line", { x1: PAD.left - 4, x2: PAD.left, y1: p.y(t), y2: p.y(t) }, axes);
    el("text", { x: PAD.left - 6, y: p.y(t) + 4, "text-anchor": "end" }, axes)
      .textContent = +t.toPrecision(4);
  }
  el("text", { x: PAD.left + pw / 2, y: h - 2, "text-anchor": "middle", class: "label" }, axes)
    .textContent = xlabel;
  el("text", { x: 12, y: PAD.top + ph / 2, "text-anchor": "middle", class: "label",
               transform: "rotate(-90 12 " + (PAD.top + ph / 2) + ")" }, axes)
    .textContent = ylabel;
  p.layer = el("g", { class: "data" }, svg);
  return p;
}

/* Polylines of (xs, ys), split where mode changes, styled as the paper's
 * figures; returns the number of segments drawn. */
function drawModes(p, xs, ys, modes, color, cls) {
  let start = 0, segments = 0;
  for (let i = 1; i <= xs.length; i++) {
    if (i < xs.length && modes[i] === modes[start])
      continue;
    const pts = [];
    for (let k = start; k < i; k++)
      pts.push(p.x(xs[k]).toFixed(2) + "," + p.y(ys[k]).toFixed(2));
    if (pts.length > 1) {
      el("polyline", {
        points: pts.join(" "), fill: "none", stroke: color,
        "stroke-width": modes[start] === "overshoot" ? 2 : 1.6,
        "stroke-dasharray": DASH[modes[start]] || "",
        class: cls || "curve", "data-mode": modes[start],
      }, p.layer);
      segments++;
    }
    start = i;
  }
  return segments;
}

function range(arrays) {
  let lo = Infinity, hi = -Infinity;
  for (const a of arrays)
    for (const v of a) {
      if (v < lo) lo = v;
      if (v > hi) hi = v;
    }
  return [lo, hi];
}

/* ---- orbits --------------------------------------------------------------- */

const PORTRAIT_FIELDS = ["t", "x1", "x2", "v1", "v2", "mode", "F1", "F2"];

/* The plots' ranges from a first, coarse pass; then the orbits again,
 * sampled to half a pixel of those plots. */
async function findOrbits() {
  clearError();
  const base = readParams();
  const form = document.getElementById("params");
  const body = Object.assign({}, base, {
    kind: form.kind.value,
    max_period: Number(form.max_period.value),
    samples: { tolerance: 0.05, fields: ["x1", "x2", "v1", "v2"] },
  });
  status("searching...");
  const t0 = performance.now();
  try {
    const first = await post("/orbit", body);
    state.params = base;
    state.units = first.units;
    if (!first.orbits.length) {
      state.orbits = [];
      listOrbits();
      clearPlots();
      status("no orbit: " + (first.reason || "none found"));
      return;
    }
    const s = first.orbits.map((o) => o.samples);
    const r2 = frame(document.getElementById("portrait2"),
                     range(s.map((q) => q.x2)), range(s.map((q) => q.v2)), "x2", "x2'");
    const r1 = frame(document.getElementById("portrait1"),
                     range(s.map((q) => q.x1)), range(s.map((q) => q.v1)), "x1", "x1'");
    state.frames = { r1, r2 };
    /* half a pixel in both portraits */
    body.samples = {
      tolerance: 0.5,
      scale: { x1: r1.sx, v1: r1.sy, x2: r2.sx, v2: r2.sy },
      fields: PORTRAIT_FIELDS,
    };
    const answer = await post("/orbit", body);
    state.orbits = answer.orbits;
    state.selected = 0;
    listOrbits();
    drawOrbits();
    const n = answer.orbits.reduce((k, o) => k + (o.samples ? o.samples.t.length : 0), 0);
    status(answer.orbits.length + " orbit(s), " + n + " points drawn, in " +
           Math.round(performance.now() - t0) + " ms");
  } catch (e) {
    status("");
    showError(e);
  }
}

function clearPlots() {
  for (const id of ["portrait1", "portrait2", "constraints", "multipliers"])
    document.getElementById(id).textContent = "";
}

function listOrbits() {
  const tbody = document.querySelector("#orbits tbody");
  tbody.textContent = "";
  state.orbits.forEach((o, i) => {
    const tr = document.createElement("tr");
    tr.dataset.index = i;
    if (i === state.selected)
      tr.className = "selected";
    const phases = o.phases.map((p) => p.mode + " " + p.duration.toFixed(4)).join(", ");
    const st = o.stability;
    const cells = [i, o.kind + (o.n_turns > 1 ? " (" + o.n_turns + " turns)" : ""),
                   phases, o.period.toFixed(6),
                   st.spectral_radius.toFixed(4) + (st.stable ? " stable" : " unstable"),
                   o.margins.min.value === null ? "-" : o.margins.min.value.toPrecision(3)];
    for (const c of cells) {
      const td = document.createElement("td");
      td.textContent = c;
      tr.appendChild(td);
    }
    tr.addEventListener("click", () => {
      state.selected = i;
      listOrbits();
      drawOrbits();
    });
    tbody.appendChild(tr);
  });
}

function drawOrbits() {
  const { r1, r2 } = state.frames;
  r1.layer.textContent = "";
  r2.layer.textContent = "";
  state.orbits.forEach((o, i) => {
    if (!o.samples)
      return;
    const s = o.samples, color = COLORS[i % COLORS.length];
    const cls = i === state.selected ? "curve selected" : "curve";
    drawModes(r2, s.x2, s.v2, s.mode, color, cls);
    drawModes(r1, s.x1, s.v1, s.mode, color, cls);
  });
  drawConstraints();
  drawMultipliers();
}

/* F1 and F2 over the stick phases of the selected orbit (Fig. 4). */
function drawConstraints() {
  const svg = document.getElementById("constraints");
  const o = state.orbits[state.selected];
  if (!o || !o.samples) {
    svg.textContent = "";
    return;
  }
  const s = o.samples, ts = [], f1 = [], f2 = [];
  for (let i = 0; i < s.t.length; i++)
    if (s.mode[i] === "stick") {
      ts.push(s.t[i]);
      f1.push(s.F1[i]);
      f2.push(s.F2[i]);
    }
  if (!ts.length) {
    frame(svg, [0, 1], [-1, 1], "t (no stick)", "F");
    return;
  }
  const p = frame(svg, range([ts]), range([f1, f2, [0]]), "t", "F1, F2");
  el("line", { x1: PAD.left, x2: PAD.left + p.pw, y1: p.y(0), y2: p.y(0), class: "zero" }, p.layer);
  const draw = (ys, dash, name) => {
    const pts = ts.map((t, i) => p.x(t).toFixed(2) + "," + p.y(ys[i]).toFixed(2));
    el("polyline", { points: pts.join(" "), fill: "none", stroke: "#1f5fa8",
                     "stroke-width": 1.6, "stroke-dasharray": dash, class: "constraint",
                     "data-name": name }, p.layer);
  };
  draw(f1, "", "F1");
  draw(f2, "6 4", "F2");
}

/* The multipliers of the selected orbit against the unit circle. */
function drawMultipliers() {
  const svg = document.getElementById("multipliers");
  const o = state.orbits[state.selected];
  svg.textContent = "";
  if (!o)
    return;
  const ev = o.stability.eigenvalues;
  const m = Math.max(1.2, ...ev.map((e) => Math.hypot(e[0], e[1]) * 1.1));
  const p = frame(svg, [-m, m], [-m, m], "Re", "Im");
  el("circle", { cx: p.x(0), cy: p.y(0), r: p.x(1) - p.x(0), class: "unit" }, p.layer);
  for (const e of ev)
    el("circle", { cx: p.x(e[0]), cy: p.y(e[1]), r: 4, class: "multiplier",
                   "data-modulus": Math.hypot(e[0], e[1]).toFixed(6) }, p.layer);
}

/* ---- simulating from a clicked state ----------------------------------- */

async function simulateFrom(evt, which) {
  const o = state.orbits[state.selected];
  if (!o || !state.frames)
    return;
  const p = which === 2 ? state.frames.r2 : state.frames.r1;
  const box = p.svg.getBoundingClientRect();
  const px = evt.clientX - box.left, py = evt.clientY - box.top;
  const a = p.xr[0] + (px - PAD.left) / p.pw * (p.xr[1] - p.xr[0]);
  const b = p.yr[1] - (py - PAD.top) / p.ph * (p.yr[1] - p.yr[0]);
  /* the clicked pair, the other two from the selected orbit's start */
  const x = o.x0.slice();
  if (which === 2) { x[1] = a; x[3] = b; } else { x[0] = a; x[2] = b; }
  const { r1, r2 } = state.frames;
  clearError();
  for (const f of [r1, r2])
    for (const old of f.layer.querySelectorAll(".simulated"))
      old.remove();
  /* three periods in six pieces, each drawn as it arrives and the next
   * started from its final state */
  const pieces = 6, span = 3 * o.period / pieces;
  let from = x, points = 0;
  try {
    for (let k = 0; k < pieces; k++) {
      const ans = await post("/simulate", Object.assign({}, state.params, {
        initial: from, t_end: span, events: false,
        samples: { tolerance: 0.5, scale: { x1: r1.sx, v1: r1.sy, x2: r2.sx, v2: r2.sy },
                   fields: ["x1", "x2", "v1", "v2", "mode"] },
      }));
      const s = ans.samples;
      drawModes(r2, s.x2, s.v2, s.mode, "#555", "simulated");
      drawModes(r1, s.x1, s.v1, s.mode, "#555", "simulated");
      points += s.x1.length;
      from = ans.final.x;
      status("simulating from (" + x.map((v) => v.toPrecision(4)).join(", ") + "): " +
             points + " points, " + (k + 1) + " of " + pieces + " pieces");
    }
  } catch (e) {
    showError(e);
  }
}

/* ---- families and regions ---------------------------------------------- */

async function continueFamily(evt) {
  evt.preventDefault();
  const o = state.orbits[state.selected];
  if (!o)
    return showError(new Problem(0, { detail: "find an orbit first" }));
  const f = evt.target;
  clearError();
  status("continuing...");
  try {
    const ans = await post("/continue", Object.assign({}, state.params, {
      guess: { durations: o.phases.map((q) => q.duration), modes: o.phases.map((q) => q.mode) },
      parameter: f.parameter.value,
      range: [Number(f.from.value), Number(f.to.value)],
    }));
    const pts = ans.branches.flatMap((b) => b.points);
    const p = frame(document.getElementById("family"), range([pts.map((q) => q.value)]),
                    range([pts.map((q) => q.period)]), ans.parameter, "period");
    ans.branches.forEach((b, k) => {
      for (let i = 1; i < b.points.length; i++) {
        const a = b.points[i - 1], c = b.points[i];
        el("line", { x1: p.x(a.value), y1: p.y(a.period), x2: p.x(c.value), y2: p.y(c.period),
                     stroke: COLORS[k % COLORS.length], "stroke-width": 1.8,
                     "stroke-dasharray": a.stable && c.stable ? "" : "5 4",
                     class: "branch" }, p.layer);
      }
      for (const s of b.special) {
        el("circle", { cx: p.x(s.value), cy: p.y(s.orbit.period), r: 4,
                       class: "special", "data-type": s.type }, p.layer);
        el("text", { x: p.x(s.value) + 6, y: p.y(s.orbit.period) - 6, class: "special-label" },
           p.layer).textContent = s.type.replace("_", " ") + " " + s.value.toPrecision(6);
      }
    });
    status("family: " + pts.length + " points, " +
           ans.branches.reduce((k, b) => k + b.special.length, 0) +
           " special points (stable solid, unstable dashed)");
  } catch (e) {
    status("");
    showError(e);
  }
}

async function existenceMap(evt) {
  evt.preventDefault();
  const n = Number(evt.target.n.value);
  const p0 = state.params && state.params.params;
  if (!p0)
    return showError(new Problem(0, { detail: "the map takes dimensionless parameters: find orbits with them first" }));
  clearError();
  status("mapping...");
  try {
    const lines = await post("/map", {
      params: p0, kind: "all", max_period: 1,
      axes: [{ parameter: "chi", from: 0.96, to: 0.04, n },
             { parameter: "ur", from: 1.5 * p0.us, to: 15 * p0.us, n }],
    }, true);
    const svg = document.getElementById("map");
    /* cells centred on the grid's values */
    const hx = 13.5 / (2 * (n - 1 || 1)), hy = 0.92 / (2 * (n - 1 || 1));
    const p = frame(svg, [1.5 - hx, 15 + hx], [0.04 - hy, 0.96 + hy], "ur / us", "chi", true);
    const cw = p.pw / n, chh = p.ph / n;
    let with_orbit = 0;
    for (const l of lines) {
      if (!l.index)
        continue;
      const stable = l.orbits.some((q) => q.stable);
      with_orbit += l.orbits.length > 0;
      el("rect", { x: PAD.left + l.index[1] * cw, y: PAD.top + l.index[0] * chh,
                   width: cw + 0.5, height: chh + 0.5,
                   class: l.orbits.length ? (stable ? "cell stable" : "cell unstable") : "cell none" },
         p.layer);
    }
    const done = lines[lines.length - 1];
    status("map: " + with_orbit + " of " + n * n + " cells with a period-1 orbit (dark: a stable one), " +
           done.seconds.toFixed(2) + " s");
  } catch (e) {
    status("");
    showError(e);
  }
}

async function basins(evt) {
  evt.preventDefault();
  const n = Number(evt.target.n.value);
  if (!state.params)
    return showError(new Problem(0, { detail: "find orbits first" }));
  clearError();
  status("computing basins...");
  try {
    const ans = await post("/basins", Object.assign({}, state.params, {
      axes: [{ variable: "x1", from: -2, to: 4, n }, { variable: "x2", from: 0, to: 8, n }],
      state: { v1: 0, v2: state.params.params ? state.params.params.V : state.params.physical.v0 },
    }));
    const L = ans.labels, bytes = atob(L.data);
    const hx = 6 / (2 * (L.rows - 1 || 1)), hy = 8 / (2 * (L.cols - 1 || 1));
    const p = frame(document.getElementById("basins"), [-2 - hx, 4 + hx], [-hy, 8 + hy],
                    "x1", "x2", true);
    const cw = p.pw / L.rows, chh = p.ph / L.cols;
    for (let i = 0; i < L.rows; i++)
      for (let j = 0; j < L.cols; j++) {
        const b = bytes.charCodeAt(i * L.cols + j);
        const fill = b === L.unresolved ? "#ddd" : b === L.perpetual_slip ? "#999" : COLORS[b % COLORS.length];
        /* row i runs along x1, column j along x2 */
        el("rect", { x: PAD.left + i * cw, y: PAD.top + (L.cols - 1 - j) * chh,
                     width: cw + 0.5, height: chh + 0.5, fill, class: "basin" }, p.layer);
      }
    const legend = document.getElementById("basins-legend");
    legend.textContent = "";
    for (const a of ans.attractors) {
      const li = document.createElement("li");
      li.style.setProperty("--swatch", COLORS[a.label % COLORS.length]);
      li.textContent = a.kind + ", period " + a.period.toFixed(4) + ", " +
        (100 * a.fraction).toFixed(1) + " % of the slice";
      legend.appendChild(li);
    }
    status("basins: " + ans.attractors.length + " attractor(s)");
  } catch (e) {
    status("");
    showError(e);
  }
}

/* ---- wiring ------------------------------------------------------------- */

document.getElementById("units").addEventListener("change", (e) => {
  document.getElementById("dimensionless").hidden = e.target.value !== "dimensionless";
  document.getElementById("physical").hidden = e.target.value !== "physical";
});
document.getElementById("params").addEventListener("submit", (e) => {
  e.preventDefault();
  findOrbits();
});
document.getElementById("portrait2").addEventListener("click", (e) => simulateFrom(e, 2));
document.getElementById("portrait1").addEventListener("click", (e) => simulateFrom(e, 1));
document.getElementById("continue-form").addEventListener("submit", continueFamily);
document.getElementById("map-form").addEventListener("submit", existenceMap);
document.getElementById("basins-form").addEventListener("submit", basins);
findOrbits();
