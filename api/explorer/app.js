/*
 * The stickslip explorer: the page's state, its calls to the daemon, and
 * its figures (drawn by Plot, plot.js, embedded ahead of this file).
 *
 * It asks the daemon (its own origin, or ?api=URL for another daemon that
 * allows this origin with --cors-origin) for curves sampled to half a
 * pixel of its own plots (samples.tolerance with per-axis scales in data
 * units per pixel) and for only the columns it draws (samples.fields).
 * Maps and basins run as jobs (Prefer: respond-async) with progress and
 * cancel; a daemon that answers them at once is read the same way.  The
 * view lives in the URL (the contract's field names), so that it can be
 * shared and the browser's back button returns to the previous one.
 */
"use strict";

const API = new URLSearchParams(location.search).get("api") || "";
const DASH = { overshoot: "", stick: "7 4", slip: "1.5 3" };
/* orbit colours, told apart in print (Tableau's ten, less the grey and olive) */
const COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                "#8c564b", "#e377c2", "#17becf"];
const PARAMS = {
  dimensionless: ["chi", "eta", "us", "ur", "V"],
  physical: ["m1", "m2", "k1", "k2", "Fs", "Fr", "v0"],
};
/* the unit of each parameter in physical units (M, L: the request's mass
 * and length units; s: its time unit) */
const PUNIT = { m1: "M", m2: "M", k1: "M/s²", k2: "M/s²", Fs: "M L/s²", Fr: "M L/s²", v0: "L/s" };

const $ = (sel, root) => (root || document).querySelector(sel);
const state = { orbits: [], selected: 0, hidden: new Set(), params: null, units: null,
                frames: null, open: new Set(), figures: {}, work: {} };

/* ---- talking to the daemon ---------------------------------------------- */

/* A problem from the daemon, in words: its title, detail and field. */
class Problem extends Error {
  constructor(status, body) {
    super((body && body.detail) || (body && body.title) || "HTTP " + status);
    this.status = status;
    this.where = (body && (body.pointer || body.field)) || "";
    this.title = (body && body.title) || "";
    this.type = (body && body.type) || "";
  }
}

/* fetch, with a failure to connect explained: from another origin it is
 * most often a daemon started without --cors-origin for this page. */
async function call(path, opts) {
  const url = /^https?:/.test(path) ? path : API + path;
  try {
    return await fetch(url, opts);
  } catch (e) {
    if (e.name === "AbortError")
      throw e;
    const target = API || location.origin;
    const other = API && new URL(API, location.href).origin !== location.origin;
    throw new Problem(0, {
      title: "Cannot reach the daemon",
      detail: other
        ? "the browser could not read " + target + " (" + e.message + "): it is down, or it " +
          "does not allow this page's origin. Start it with --cors-origin " + location.origin +
          " (or STICKSLIP_CORS_ORIGIN=" + location.origin + ")."
        : target + " could not be reached (" + e.message + "): is the daemon running?",
    });
  }
}

async function failure(res) {
  const text = await res.text();
  let problem = null;
  try { problem = JSON.parse(text); } catch (e) { /* not JSON */ }
  return new Problem(res.status, problem || { detail: text.slice(0, 300) });
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
class Cancelled extends Error {}
const STORE_UNAVAILABLE = /\/problems\/store-unavailable$/;

/* call(), sent again after a 503 with Retry-After (every compute slot
 * busy) once that has passed: at most 10 s, three tries in all.  A job
 * store that cannot take the job is not waited for (job() asks without). */
async function send(path, opts) {
  for (let tries = 1; ; tries++) {
    const res = await call(path, opts);
    const wait = Number(res.headers.get("Retry-After"));
    if (res.status !== 503 || tries === 3 || !res.headers.has("Retry-After") || !(wait >= 0) ||
        STORE_UNAVAILABLE.test((await failure(res.clone())).type))
      return res;
    await sleep(Math.min(wait, 10) * 1000);
  }
}

async function post(path, body, signal) {
  const res = await send(path, {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body), signal,
  });
  if (!res.ok)
    throw await failure(res);
  return res.json();
}

/* Deletes job loc: null when done (or the job already gone), else why not. */
async function dismiss(loc) {
  try {
    const r = await call(loc, { method: "DELETE" });
    return r.ok || r.status === 404 ? null : await failure(r);
  } catch (e) {
    return e;
  }
}

/* Each NDJSON line of the answer res, parsed, to onLine as soon as it has
 * come whole: the body read as it streams. */
async function eachLine(res, onLine) {
  const reader = res.body.getReader(), dec = new TextDecoder();
  let buf = "";
  for (;;) {
    const { value, done } = await reader.read();
    buf += done ? dec.decode() : dec.decode(value, { stream: true });
    let nl;
    while ((nl = buf.indexOf("\n")) >= 0) {
      const line = buf.slice(0, nl);
      buf = buf.slice(nl + 1);
      if (line.trim())
        onLine(JSON.parse(line));
    }
    if (done)
      break;
  }
  if (buf.trim())
    onLine(JSON.parse(buf));
}

/* A long computation as a job: POST with Prefer: respond-async, the status
 * polled for its progress (progress(status) each time), the job deleted
 * when ctl.cancelled is set.  Without onLine its results are read when it
 * succeeds, and returned as text.  With onLine its answer is NDJSON (asked
 * for with Accept: /basins answers JSON by default) and its results are
 * read as they stream while the job runs, each line to onLine as it
 * arrives (the daemon sends the lines of the chunks already stored, then
 * each chunk's as it is stored).  A daemon that answers at once (200) is
 * taken as it answers. */
async function job(path, body, ctl, progress, onLine) {
  const headers = { "Content-Type": "application/json", Prefer: "respond-async" };
  if (onLine)
    headers.Accept = "application/x-ndjson";
  /* Cancel aborts a request answered at once (the daemon stops when the
   * connection closes); a request that may create a job gets a second to
   * answer first, so that the job it made is known, and deleted */
  const request = new AbortController();
  ctl.abort.signal.addEventListener("abort", () => {
    setTimeout(() => request.abort(), headers.Prefer ? 1000 : 0);
  }, { once: true });
  const opts = { method: "POST", headers, body: JSON.stringify(body), signal: request.signal };
  let res, loc, st;
  try {
    res = await send(path, opts);
    if (res.status === 503) {
      const p = await failure(res);
      if (!STORE_UNAVAILABLE.test(p.type))
        throw p;
      /* no job store to take it: asked again without, answered at once */
      delete headers.Prefer;
      res = await send(path, opts);
    }
    if (res.status === 200)
      return await (onLine ? eachLine(res, onLine) : res.text());
    if (res.status !== 201)
      throw await failure(res);
    loc = res.headers.get("Location");
    ctl.location = loc;
    if (ctl.cancelled)
      throw (await dismiss(loc)) || new Cancelled();
    st = await res.json();
  } catch (e) {
    throw e.name === "AbortError" ? new Cancelled() : e;
  }
  if (onLine)
    return streamJob(loc, st, ctl, progress, onLine);
  for (;;) {
    progress(st);
    if (ctl.cancelled)
      throw (await dismiss(loc)) || new Cancelled();
    if (st.status === "successful" || st.status === "failed" || st.status === "dismissed")
      break;
    await sleep(250);
    const r = await call(loc);
    if (!r.ok)
      throw await failure(r);
    st = await r.json();
  }
  if (st.status === "dismissed")
    throw new Cancelled();
  const r = await call(loc + "/results");
  if (!r.ok)
    throw await failure(r);
  return r.text();
}

/* The results of job loc read as they stream, its status polled beside
 * them for the progress bar and the cancel button; a cancel aborts the
 * stream and deletes the job. */
async function streamJob(loc, st, ctl, progress, onLine) {
  const abort = new AbortController();
  let reading = true, undeleted = null;
  /* never rejects: a status lost (the network, a busy daemon) is no reason
   * to drop the results still streaming; the next poll asks again */
  const poll = (async () => {
    while (reading) {
      progress(st);
      if (ctl.cancelled) {
        abort.abort();
        undeleted = await dismiss(loc);
        return;
      }
      await sleep(250);
      try {
        const r = await call(loc);
        if (r.ok)
          st = await r.json();
      } catch (e) { /* asked again next time */ }
    }
  })();
  try {
    const res = await call(loc + "/results", { signal: abort.signal });
    if (!res.ok)
      throw await failure(res);
    await eachLine(res, onLine);
  } catch (e) {
    if (!ctl.cancelled)
      throw e;
  } finally {
    reading = false;
    await poll;
  }
  if (ctl.cancelled)
    throw undeleted || new Cancelled();
  const r = await call(loc).catch(() => null);
  const fin = r && r.ok ? await r.json() : st;
  progress(fin);
  if (fin.status === "dismissed")
    throw new Cancelled();
  if (fin.status === "failed")
    throw await failure(await call(loc + "/results"));
}

/* ---- panels: their errors, status, staleness ----------------------------- */

function panelOf(id) {
  return id === "orbits" ? { error: $("#error"), status: $("#status") }
    : { error: $("#" + id + "-panel .error"), status: $("#" + id + "-panel .status") };
}

function showError(panel, e) {
  const box = panelOf(panel).error;
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

function clearError(panel) {
  const box = panelOf(panel).error;
  box.hidden = true;
  box.textContent = "";
}

function status(panel, text) {
  panelOf(panel).status.textContent = text;
}

/* Figures computed under parameters or units no longer in the form: each
 * is marked stale (faded, said in its panel) until computed again. */
function markStale() {
  for (const svg of document.querySelectorAll("svg.plot"))
    if (svg.childNodes.length)
      svg.classList.add("stale");
  for (const id of ["family", "map", "basins"])
    if ($("#" + id).childNodes.length)
      status(id, "stale: computed under other parameters or units; run again");
  if (state.orbits.length)
    status("orbits", "stale: the parameters changed; Find orbits again");
}

/* ---- the parameters and their units -------------------------------------- */

function units() {
  return $("#units").value;
}

function readParams() {
  const out = {};
  for (const input of $("#" + units()).querySelectorAll("input")) {
    const v = Number(input.value);
    /* sent as typed when not a number: the daemon says what is wrong */
    out[input.name] = input.value.trim() === "" || isNaN(v) ? input.value : v;
  }
  return units() === "physical" ? { physical: out } : { params: out };
}

function paramValues() {
  return state.params && (state.params.params || state.params.physical);
}

/* An axis label: the quantity and its unit in the answer's units. */
function label(q, kind) {
  const phys = state.units === "physical";
  if (kind === "param")
    return q + (phys && PUNIT[q] ? " (" + PUNIT[q] + ")" : " (dimensionless)");
  const u = { x: "L", v: "L/s", t: "s" }[kind];
  return q + (phys ? " (" + u + ")" : " (dimensionless)");
}

function fillSelect(select, names, keep) {
  const was = select.value;
  select.textContent = "";
  for (const n of names) {
    const o = document.createElement("option");
    o.textContent = n;
    select.appendChild(o);
  }
  if (keep && names.includes(was))
    select.value = was;
}

/* The parameter choices and default ranges of the family and the map for
 * the form's units. */
function setUnits(u, defaults) {
  $("#units").value = u;
  $("#dimensionless").hidden = u !== "dimensionless";
  $("#physical").hidden = u !== "physical";
  const c = $("#continue-form"), m = $("#map-form");
  fillSelect(c.parameter, PARAMS[u], !defaults);
  fillSelect(m.xp, PARAMS[u], !defaults);
  fillSelect(m.yp, PARAMS[u], !defaults);
  if (!defaults)
    return;
  const v = {};
  for (const input of $("#" + u).querySelectorAll("input"))
    v[input.name] = Number(input.value);
  const r = (x) => +x.toPrecision(3);
  if (u === "dimensionless") {
    c.parameter.value = "ur";
    m.xp.value = "ur";
    m.xfrom.value = r(1.5 * v.us);
    m.xto.value = r(15 * v.us);
    m.yp.value = "chi";
    m.yfrom.value = 0.04;
    m.yto.value = 0.96;
  } else {
    c.parameter.value = "Fr";
    m.xp.value = "Fr";
    m.xfrom.value = r(1.5 * v.Fs);
    m.xto.value = r(15 * v.Fs);
    m.yp.value = "k2";
    m.yfrom.value = r(0.05 * v.k1);
    m.yto.value = r(2 * v.k1);
  }
  familyRange();
}

/* The family's default range about the current value of its parameter. */
function familyRange() {
  const c = $("#continue-form"), input = $("#" + units() + " input[name=" + c.parameter.value + "]");
  const v = Number(input && input.value);
  if (!(v > 0))
    return;
  c.from.value = +(v / 2).toPrecision(3);
  c.to.value = +(v * 2.4).toPrecision(3);
}

/* ---- the view in the URL ----------------------------------------------- */

/* Forms whose fields the URL keeps, and their prefixes there. */
const FORMS = [["continue-form", "c."], ["map-form", "m."], ["basins-form", "b."]];

function viewURL() {
  const q = new URLSearchParams();
  if (API)
    q.set("api", API);
  q.set("units", units());
  for (const input of $("#" + units()).querySelectorAll("input"))
    q.set(input.name, input.value);
  const f = $("#params");
  q.set("kind", f.kind.value);
  q.set("max_period", f.max_period.value);
  q.set("selected", state.selected);
  if (state.hidden.size)
    q.set("hidden", [...state.hidden].join(","));
  if (state.open.size)
    q.set("open", [...state.open].join(","));
  for (const [id, pre] of FORMS)
    for (const e of $("#" + id).elements)
      if (e.name)
        q.set(pre + e.name, e.value);
  return "?" + q.toString();
}

/* The URL's selected and hidden as the search found settled them (it
 * resets them), unless a newer search took its place. */
function settle(found) {
  return found.then((mine) => mine && remember(true));
}

function remember(replace) {
  const url = viewURL();
  shownView = viewKey(url);
  if (url === location.search)
    return;
  if (replace)
    history.replaceState(null, "", url);
  else
    history.pushState(null, "", url);
}

/* Sets the forms from the URL; returns what it asks to show. */
function readURL() {
  const q = new URLSearchParams(location.search);
  const u = q.get("units") === "physical" ? "physical" : "dimensionless";
  for (const input of $("#" + u).querySelectorAll("input"))
    if (q.has(input.name))
      input.value = q.get(input.name);
  setUnits(u, true);
  const f = $("#params");
  if (q.has("kind"))
    f.kind.value = q.get("kind");
  if (q.has("max_period"))
    f.max_period.value = q.get("max_period");
  for (const [id, pre] of FORMS)
    for (const e of $("#" + id).elements)
      if (e.name && q.has(pre + e.name))
        e.value = q.get(pre + e.name);
  return {
    selected: Number(q.get("selected")) || 0,
    hidden: new Set((q.get("hidden") || "").split(",").filter((s) => s !== "").map(Number)),
    open: (q.get("open") || "").split(",").filter((s) => ["family", "map", "basins"].includes(s)),
  };
}

/* ---- orbits --------------------------------------------------------------- */

const PORTRAIT_FIELDS = ["t", "x1", "x2", "v1", "v2", "mode", "F1", "F2"];
const color = (i) => COLORS[i % COLORS.length];

/* The search in flight: a newer one (Find, a map cell, Back) aborts it and
 * drops whatever it still gets. */
let search = null;

/* The plots' ranges from a first, coarse pass; then the orbits again,
 * sampled to half a pixel of those plots.  True unless a newer search
 * took its place. */
async function findOrbits(view) {
  if (search)
    search.abort();
  const mine = search = new AbortController();
  const current = () => search === mine;
  clearError("orbits");
  const base = readParams();
  const form = $("#params");
  const body = Object.assign({}, base, {
    kind: form.kind.value,
    max_period: Number(form.max_period.value),
    samples: { tolerance: 0.05, fields: ["x1", "x2", "v1", "v2"] },
  });
  status("orbits", "searching...");
  $("#find").disabled = true;
  const t0 = performance.now();
  try {
    const first = await post("/orbit", body, mine.signal);
    if (!current())
      return false;
    state.params = base;
    state.units = first.units;
    state.orbits = [];
    state.selected = 0;
    state.hidden = new Set();
    if (!first.orbits.length) {
      listOrbits();
      clearPlots();
      status("orbits", "no orbit: " + (first.reason || "none found"));
      return true;
    }
    const s = first.orbits.map((o) => o.samples);
    framePortraits([Plot.extent(s.map((q) => q.x1)), Plot.extent(s.map((q) => q.v1))],
                   [Plot.extent(s.map((q) => q.x2)), Plot.extent(s.map((q) => q.v2))], false);
    const { r1, r2 } = state.frames;
    /* half a pixel in both portraits */
    body.samples = {
      tolerance: 0.5,
      scale: { x1: r1.sx, v1: r1.sy, x2: r2.sx, v2: r2.sy },
      fields: PORTRAIT_FIELDS,
    };
    const answer = await post("/orbit", body, mine.signal);
    if (!current())
      return false;
    state.orbits = answer.orbits;
    if (view) {
      state.selected = view.selected < answer.orbits.length ? view.selected : 0;
      state.hidden = new Set([...view.hidden].filter((i) => i < answer.orbits.length));
    }
    listOrbits();
    drawOrbits();
    const n = answer.orbits.reduce((k, o) => k + (o.samples ? o.samples.t.length : 0), 0);
    status("orbits", answer.orbits.length + " orbit(s), " + n + " points drawn, in " +
           Math.round(performance.now() - t0) + " ms");
  } catch (e) {
    if (!current())
      return false;
    status("orbits", "");
    state.orbits = [];
    listOrbits();
    clearPlots();
    showError("orbits", e);
  } finally {
    if (current()) {
      search = null;
      $("#find").disabled = false;
    }
  }
  return true;
}

function clearPlots() {
  for (const id of ["portrait1", "portrait2", "constraints", "multipliers"])
    $("#" + id).textContent = "";
  state.frames = null;
}

function framePortraits(w1, w2, exact) {
  const mk = (id, r, n) => Plot.frame($("#" + id), {
    x: r[0], y: r[1], exact, side: 150, xlabel: label("x" + n, "x"), ylabel: label("x" + n + "'", "v"),
    xname: "x" + n, yname: "x" + n + "'",
  });
  state.frames = { r1: mk("portrait1", w1, 1), r2: mk("portrait2", w2, 2) };
  if (!exact)
    state.home = { r1: [state.frames.r1.xr, state.frames.r1.yr],
                   r2: [state.frames.r2.xr, state.frames.r2.yr] };
}

function selectOrbit(i) {
  state.selected = i;
  listOrbits();
  drawOrbits();
  remember();
}

function toggleOrbit(i) {
  if (state.hidden.has(i))
    state.hidden.delete(i);
  else
    state.hidden.add(i);
  listOrbits();
  drawOrbits();
  remember();
}

function listOrbits() {
  const tbody = $("#orbits tbody");
  tbody.textContent = "";
  state.orbits.forEach((o, i) => {
    const tr = document.createElement("tr");
    tr.dataset.index = i;
    tr.tabIndex = 0;
    tr.setAttribute("aria-selected", i === state.selected);
    if (i === state.selected)
      tr.className = "selected";
    const show = document.createElement("td");
    const box = document.createElement("input");
    box.type = "checkbox";
    box.checked = !state.hidden.has(i);
    box.setAttribute("aria-label", "show orbit " + i);
    box.addEventListener("click", (e) => e.stopPropagation());
    box.addEventListener("change", () => toggleOrbit(i));
    const sw = document.createElement("span");
    sw.className = "swatch";
    sw.style.setProperty("--swatch", color(i));
    show.append(box, sw);
    tr.appendChild(show);
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
    tr.addEventListener("click", () => selectOrbit(i));
    tr.addEventListener("keydown", (e) => {
      if (e.target !== tr)
        return;
      if (e.key === "Enter" || e.key === " ") {
        e.preventDefault();
        selectOrbit(i);
        $("#orbits tbody tr[data-index='" + i + "']").focus();
      } else if (e.key === "ArrowDown" || e.key === "ArrowUp") {
        e.preventDefault();
        const next = tr[e.key === "ArrowDown" ? "nextElementSibling" : "previousElementSibling"];
        if (next)
          next.focus();
      }
    });
    tbody.appendChild(tr);
  });
  const o = state.orbits[state.selected], f = $("#simulate-form");
  if (o)
    ["x1", "x2", "v1", "v2"].forEach((k, j) => { f[k].value = +o.x0[j].toPrecision(6); });
}

/* The orbits' table as a figure's data: one row a sample. */
function orbitTable(cols) {
  const rows = [];
  state.orbits.forEach((o, i) => {
    if (state.hidden.has(i) || !o.samples)
      return;
    for (let k = 0; k < o.samples.t.length; k++)
      rows.push([i, ...cols.map((c) => o.samples[c][k])]);
  });
  return { columns: ["orbit", ...cols], rows };
}

function drawOrbits() {
  if (!state.frames)
    return;
  /* the layers redrawn: a simulation drawing into them stops */
  simulation++;
  const { r1, r2 } = state.frames;
  const style = (m) => ({ dash: DASH[m] || "", width: m === "overshoot" ? 2 : 1.6 });
  for (const [p, n] of [[r1, 1], [r2, 2]]) {
    p.layer.textContent = "";
    p.top.textContent = "";
    state.orbits.forEach((o, i) => {
      if (!o.samples || state.hidden.has(i))
        return;
      const sel = i === state.selected;
      Plot.lines(p, o.samples["x" + n], o.samples["v" + n], o.samples.mode, color(i),
                 { class: sel ? "curve selected" : "curve", "data-orbit": i,
                   "stroke-opacity": sel ? 1 : 0.55 }, style);
    });
    const entries = state.orbits.map((o, i) => ({
      label: "#" + i + " " + o.kind + " " + o.period.toFixed(3), color: color(i),
      off: state.hidden.has(i) }));
    for (const m of ["slip", "overshoot", "stick"])
      entries.push({ label: m, color: "#555", dash: DASH[m] });
    Plot.legend(p, entries, (k) => k < state.orbits.length && toggleOrbit(k));
    Plot.readout(p);
    Plot.zoom(p, (xr, yr) => {
      const keep = state.frames;
      const q = Plot.frame(p.svg, { x: xr, y: yr, exact: true, side: 150, xlabel: label("x" + n, "x"),
                                    ylabel: label("x" + n + "'", "v"), xname: "x" + n,
                                    yname: "x" + n + "'" });
      state.frames = n === 1 ? { r1: q, r2: keep.r2 } : { r1: keep.r1, r2: q };
      drawOrbits();
    }, state.home["r" + n]);
    state.figures["portrait" + n] = () => orbitTable(["t", "x" + n, "v" + n, "mode"]);
  }
  drawConstraints();
  drawMultipliers();
}

/* F1 and F2 over the stick phases of the selected orbit (Fig. 4). */
function drawConstraints() {
  const svg = $("#constraints");
  const o = state.orbits[state.selected];
  if (!o || !o.samples) {
    svg.textContent = "";
    return;
  }
  /* runs: where each stick starts in ts, so that the slips between are not joined */
  const s = o.samples, ts = [], f1 = [], f2 = [], runs = [];
  for (let i = 0; i < s.t.length; i++)
    if (s.mode[i] === "stick") {
      if (i === 0 || s.mode[i - 1] !== "stick")
        runs.push(ts.length);
      ts.push(s.t[i]);
      f1.push(s.F1[i]);
      f2.push(s.F2[i]);
    }
  state.figures.constraints = () => ({ columns: ["t", "F1", "F2"],
                                       rows: ts.map((t, i) => [t, f1[i], f2[i]]) });
  if (!ts.length) {
    Plot.frame(svg, { x: [0, 1], y: [-1, 1], xlabel: label("t", "t") + ": no stick",
                      ylabel: "F1, F2" });
    return;
  }
  const p = Plot.frame(svg, { x: Plot.extent([ts]), y: Plot.extent([f1, f2, [0]]),
                              xlabel: label("t", "t"), ylabel: "F1, F2 (dimensionless)",
                              xname: "t", yname: "F" });
  Plot.el("line", { x1: p.pad.left, x2: p.pad.left + p.pw, y1: p.y(0), y2: p.y(0),
                    stroke: "#5b6570", "stroke-width": 0.8 }, p.layer);
  const draw = (ys, dash, name) => runs.forEach((from, k) => {
    const pts = ts.slice(from, runs[k + 1]).map((t, i) => p.x(t).toFixed(2) + "," +
                                                          p.y(ys[from + i]).toFixed(2));
    Plot.el("polyline", { points: pts.join(" "), fill: "none", stroke: color(state.selected),
                          "stroke-width": 1.6, "stroke-dasharray": dash, class: "constraint",
                          "data-name": name }, p.layer);
  });
  draw(f1, "", "F1");
  draw(f2, "6 4", "F2");
  Plot.legend(p, [{ label: "F1 > 0", color: color(state.selected) },
                  { label: "F2 <= 0", color: color(state.selected), dash: "6 4" }], null, "left");
  Plot.readout(p);
}

/* The multipliers of the selected orbit against the unit circle. */
function drawMultipliers() {
  const svg = $("#multipliers");
  const o = state.orbits[state.selected];
  svg.textContent = "";
  if (!o)
    return;
  const ev = o.stability.eigenvalues;
  state.figures.multipliers = () => ({
    columns: ["re", "im", "modulus"], rows: ev.map((e) => [e[0], e[1], Math.hypot(e[0], e[1])]) });
  const m = Math.max(1.2, ...ev.map((e) => Math.hypot(e[0], e[1]) * 1.1));
  const p = Plot.frame(svg, { x: [-m, m], y: [-m, m], exact: true, xlabel: "Re (dimensionless)",
                              ylabel: "Im (dimensionless)", xname: "Re", yname: "Im" });
  Plot.el("circle", { cx: p.x(0), cy: p.y(0), r: p.x(1) - p.x(0), fill: "none", stroke: "#5b6570",
                      "stroke-dasharray": "3 3" }, p.layer);
  for (const e of ev)
    Plot.el("circle", { cx: p.x(e[0]), cy: p.y(e[1]), r: 4, fill: "#c2410c", class: "multiplier",
                        "data-modulus": Math.hypot(e[0], e[1]).toFixed(6) }, p.layer)
      .appendChild(Plot.el("title", {})).textContent =
        "multiplier " + Plot.fmt(e[0]) + (e[1] < 0 ? " - " : " + ") + Plot.fmt(Math.abs(e[1])) +
        "i, modulus " + Plot.fmt(Math.hypot(e[0], e[1]));
  Plot.legend(p, [{ label: "multiplier", color: "#c2410c", mark: "dot" },
                  { label: "|z| = 1", color: "#5b6570", dash: "3 3" }], null, "left");
  Plot.readout(p);
}

/* ---- simulating from a state ------------------------------------------- */

/* The simulation running: a newer one, or a redraw, ends it. */
let simulation = 0;

/* Three periods of the selected orbit from x in six pieces, each drawn as
 * it arrives and the next started from its final state. */
async function simulateFrom(x) {
  const o = state.orbits[state.selected];
  if (!o || !state.frames)
    return showError("orbits", new Problem(0, { detail: "find an orbit first: a simulation runs " +
                                                        "for three of its periods" }));
  const mine = ++simulation;
  const { r1, r2 } = state.frames;
  clearError("orbits");
  for (const f of [r1, r2])
    for (const old of f.layer.querySelectorAll(".simulated"))
      old.remove();
  const pieces = 6, span = 3 * o.period / pieces;
  const style = (m) => ({ dash: DASH[m] || "", width: 1.4 });
  let from = x, points = 0;
  try {
    for (let k = 0; k < pieces; k++) {
      const ans = await post("/simulate", Object.assign({}, state.params, {
        initial: from, t_end: span, events: false,
        samples: { tolerance: 0.5, scale: { x1: r1.sx, v1: r1.sy, x2: r2.sx, v2: r2.sy },
                   fields: ["x1", "x2", "v1", "v2", "mode"] },
      }));
      if (mine !== simulation)
        return;
      const s = ans.samples;
      Plot.lines(r2, s.x2, s.v2, s.mode, "#555", { class: "simulated" }, style);
      Plot.lines(r1, s.x1, s.v1, s.mode, "#555", { class: "simulated" }, style);
      points += s.x1.length;
      from = ans.final.x;
      status("orbits", "simulating from (" + x.map((v) => v.toPrecision(4)).join(", ") + "): " +
             points + " points, " + (k + 1) + " of " + pieces + " pieces");
    }
  } catch (e) {
    if (mine === simulation)
      showError("orbits", e);
  }
}

function clickSimulate(evt, n) {
  const o = state.orbits[state.selected];
  /* the second click of a double click (which returns to the whole) */
  if (!o || !state.frames || evt.detail > 1)
    return;
  const p = n === 2 ? state.frames.r2 : state.frames.r1;
  if (!p.inside(evt))
    return;
  const [a, b] = p.invert(evt);
  /* the clicked pair, the other two from the selected orbit's start */
  const x = o.x0.slice();
  x[n - 1] = a;
  x[n + 1] = b;
  simulateFrom(x);
}

/* ---- families ------------------------------------------------------------ */

async function continueFamily() {
  const o = state.orbits[state.selected];
  const f = $("#continue-form");
  clearError("family");
  if (!o)
    return showError("family", new Problem(0, { detail: "find an orbit first" }));
  status("family", "continuing...");
  state.figures.family = null;
  f.querySelector("button").disabled = true;
  /* a newer family (Continue again, Back) aborts this one */
  stopWork("family");
  const ctl = state.work.family = { cancelled: false, abort: new AbortController() };
  const current = () => state.work.family === ctl;
  try {
    const ans = await post("/continue", Object.assign({}, state.params, {
      guess: { durations: o.phases.map((q) => q.duration), modes: o.phases.map((q) => q.mode) },
      parameter: f.parameter.value,
      range: [Number(f.from.value), Number(f.to.value)],
      fields: ["period", "stable"],
    }), ctl.abort.signal);
    if (!current())
      return;
    const pts = ans.branches.flatMap((b) => b.points);
    const rows = [];
    ans.branches.forEach((b, k) => b.points.forEach((q) => rows.push([k, q.value, q.period, q.stable])));
    state.figures.family = () => ({ columns: ["branch", ans.parameter, "period", "stable"], rows });
    const p = Plot.frame($("#family"), {
      x: Plot.extent([pts.map((q) => q.value)]), y: Plot.extent([pts.map((q) => q.period)]),
      side: 110, xlabel: label(ans.parameter, "param"), ylabel: label("period", "t"),
      xname: ans.parameter, yname: "period" });
    ans.branches.forEach((b, k) => {
      for (let i = 1; i < b.points.length; i++) {
        const a = b.points[i - 1], c = b.points[i];
        Plot.el("line", { x1: p.x(a.value), y1: p.y(a.period), x2: p.x(c.value), y2: p.y(c.period),
                          stroke: color(k), "stroke-width": 1.8,
                          "stroke-dasharray": a.stable && c.stable ? "" : "5 4",
                          class: "branch" }, p.layer);
      }
      for (const s of b.special) {
        const x = p.x(s.value), right = x > p.pad.left + p.pw * 0.6;
        Plot.el("circle", { cx: x, cy: p.y(s.orbit.period), r: 4, fill: "#fff", stroke: "#b91c1c",
                            "stroke-width": 2, class: "special", "data-type": s.type }, p.layer);
        Plot.el("text", { x: right ? x - 6 : x + 6, y: p.y(s.orbit.period) - 6, fill: "#b91c1c",
                          "font-size": 11, "text-anchor": right ? "end" : "start",
                          class: "special-label" }, p.top)
          .textContent = s.type.replace("_", " ") + " " + s.value.toPrecision(6);
      }
    });
    Plot.legend(p, [
      ...ans.branches.map((b, k) => ({ label: "branch " + k, color: color(k) })),
      { label: "stable", color: "#555" }, { label: "unstable", color: "#555", dash: "5 4" },
      { label: "special point", color: "#fff", stroke: "#b91c1c", mark: "dot" }]);
    Plot.readout(p);
    status("family", "family: " + pts.length + " points, " +
           ans.branches.reduce((k, b) => k + b.special.length, 0) + " special points");
  } catch (e) {
    if (!current())
      return;
    status("family", "");
    showError("family", e);
  } finally {
    if (current() || !state.work.family) {
      state.work.family = null;
      f.querySelector("button").disabled = false;
    }
  }
}

/* ---- long work: maps and basins as jobs --------------------------------- */

/* Runs work(ctl) for a panel whose form has a submit, a cancel button and
 * a progress bar: the submit disabled while it runs, cancel asks the job
 * to end, the bar follows the job's status. */
async function longWork(id, what, work) {
  const form = $("#" + id + "-form"), go = form.querySelector("button[type=submit]");
  const cancel = form.querySelector(".cancel"), bar = form.querySelector("progress");
  stopWork(id);
  const ctl = state.work[id] = { cancelled: false, abort: new AbortController() };
  /* a run stopped for a newer one leaves the panel to it */
  const current = () => state.work[id] === ctl;
  state.figures[id] = null;
  clearError(id);
  go.disabled = true;
  cancel.hidden = false;
  cancel.disabled = false;
  bar.hidden = false;
  bar.value = 0;
  cancel.onclick = () => {
    stopWork(id, true);
    cancel.disabled = true;
    status(id, what + ": cancelling...");
  };
  ctl.progress = (st) => {
    if (!current())
      return;
    bar.value = st.progress;
    const items = st.items ? ", " + st.items.done + " of " + st.items.total + " done" : "";
    status(id, what + " job: " + st.status + ", " + st.progress + " %" + items);
  };
  try {
    await work(ctl);
  } catch (e) {
    if (!current())
      return;
    if (e instanceof Cancelled)
      status(id, what + ": cancelled");
    else {
      status(id, "");
      showError(id, e);
    }
  } finally {
    /* the panel back to idle unless a newer run has it */
    if (current() || !state.work[id]) {
      state.work[id] = null;
      go.disabled = false;
      cancel.hidden = true;
      bar.hidden = true;
    }
  }
}

/* Cancels panel id's running job (its fetch aborted, its job deleted);
 * kept as the panel's current run only when asked (Cancel), so that a
 * newer run or view takes the panel over. */
function stopWork(id, keep) {
  const ctl = state.work[id];
  if (!ctl)
    return;
  ctl.cancelled = true;
  ctl.abort.abort();
  if (!keep)
    state.work[id] = null;
}

/* The map's categories: a cell's orbits of the asked kind. */
const MAP_KEY = [
  { label: "none", color: "#eef0f2" }, { label: "unstable", color: "#f4a259" },
  { label: "stable", color: "#1f5fa8" }, { label: "two or more", color: "#0b2545" }];

function mapClass(l) {
  if (!l.orbits.length)
    return 0;
  return l.orbits.length > 1 ? 3 : l.orbits[0].stable ? 2 : 1;
}

/* A map axis: its cells centred on the grid's values; a single cell (the
 * daemon puts it at from) as wide as the range, about from. */
function cellAxis(r, n) {
  if (n === 1) {
    const h = Math.abs(r[1] - r[0]) / 2 || Math.abs(r[0]) / 2 || 0.5;
    return [r[0] - h, r[0] + h];
  }
  const h = Math.abs(r[1] - r[0]) / (2 * (n - 1 || 1));
  return [Math.min(r[0], r[1]) - h, Math.max(r[0], r[1]) + h];
}

async function existenceMap() {
  const f = $("#map-form");
  if (!state.params)
    return showError("map", new Problem(0, { detail: "find orbits first" }));
  const xp = f.xp.value, yp = f.yp.value;
  const xn = Number(f.xn.value), yn = Number(f.yn.value);
  const xr = [Number(f.xfrom.value), Number(f.xto.value)];
  const yr = [Number(f.yfrom.value), Number(f.yto.value)];
  const request = Object.assign({}, state.params, {
    kind: f.kind.value, max_period: Number(f.max_period.value),
    axes: [{ parameter: xp, from: xr[0], to: xr[1], n: xn },
           { parameter: yp, from: yr[0], to: yr[1], n: yn }],
  });
  await longWork("map", "map", async (ctl) => {
    status("map", "map: submitted");
    const svg = $("#map");
    const p = Plot.frame(svg, {
      x: cellAxis(xr, xn), y: cellAxis(yr, yn), exact: true, side: 100, xlabel: label(xp, "param"), ylabel: label(yp, "param"), xname: xp, yname: yp });
    svg.setAttribute("aria-label", "existence map: each cell a button (arrow keys move between " +
                     "cells, Enter loads the cell's orbits)");
    const cw = p.pw / xn, ch = p.ph / yn;
    const byCell = new Map();
    const rows = [], lines = [];
    /* arrow keys move along the axes as they are drawn */
    state.mapStep = { x: xr[1] >= xr[0] ? 1 : -1, y: yr[1] >= yr[0] ? 1 : -1 };
    state.mapLines = lines;
    /* each cell drawn as its line arrives */
    const cell = (l) => {
      lines.push(l);
      if (!l.index)
        return;
      const k = mapClass(l);
      byCell.set(l.index[0] + "," + l.index[1], l);
      const x = p.x(l.at[xp]) - cw / 2, y = p.y(l.at[yp]) - ch / 2;
      const orbits = l.orbits.map((q) => q.kind + " T=" + Plot.fmt(q.period) +
                                   (q.stable ? " stable" : " unstable"));
      const words = xp + " = " + Plot.fmt(l.at[xp]) + ", " + yp + " = " + Plot.fmt(l.at[yp]) + ": " +
        (orbits.join("; ") || "no orbit");
      /* a roving tabindex: one cell in the page's tab order, the arrow
       * keys move it */
      const r = Plot.el("rect", { x: x.toFixed(2), y: y.toFixed(2), width: (cw + 0.4).toFixed(2),
                                  height: (ch + 0.4).toFixed(2), fill: MAP_KEY[k].color,
                                  class: "cell " + ["none", "unstable", "stable", "several"][k],
                                  "data-i": l.index[0], "data-j": l.index[1], role: "button",
                                  tabindex: svg.querySelector("rect.cell") ? -1 : 0,
                                  "aria-label": words }, p.layer);
      Plot.el("title", {}, r).textContent = words;
      rows.push([l.at[xp], l.at[yp], l.orbits.length, l.orbits.filter((q) => q.stable).length,
                 l.orbits.map((q) => q.kind + ":" + q.period).join(" ")]);
    };
    await job("/map", request, ctl, ctl.progress, cell);
    if (ctl.cancelled)
      throw new Cancelled();
    state.figures.map = () => ({ columns: [xp, yp, "orbits", "stable", "kind:period"], rows });
    /* the current parameter point */
    const cur = paramValues();
    if (cur && cur[xp] !== undefined && cur[yp] !== undefined) {
      Plot.el("circle", { cx: p.x(cur[xp]), cy: p.y(cur[yp]), r: 6, fill: "none", stroke: "#b91c1c",
                          "stroke-width": 2.5, class: "current" }, p.top);
    }
    Plot.legend(p, [...MAP_KEY.map((e) => ({ label: e.label, color: e.color, mark: "box" })),
                    { label: "current point", color: "#fff", stroke: "#b91c1c", mark: "dot" }]);
    Plot.readout(p, (x, y) => {
      const i = Math.round((x - xr[0]) / ((xr[1] - xr[0]) / (xn - 1 || 1)));
      const j = Math.round((y - yr[0]) / ((yr[1] - yr[0]) / (yn - 1 || 1)));
      const l = byCell.get(i + "," + j);
      return l ? (l.orbits.length ? l.orbits.map((q) => q.kind + " T=" + Plot.fmt(q.period))
                  .join(", ") : "no orbit") : "";
    });
    const done = lines[lines.length - 1];
    status("map", "map: " + done.with_orbits + " of " + done.cells + " cells with orbits (kind " +
           f.kind.value + ", period at most " + f.max_period.value + "), " +
           done.seconds.toFixed(2) + " s");
  });
}

/* The arrow keys move the map's roving focus to the next cell along the
 * axes; Enter or Space loads the focused cell's orbits (as a click). */
function mapKey(evt) {
  const r = evt.target.closest && evt.target.closest("rect.cell");
  if (!r || !state.mapStep)
    return;
  if (evt.key === "Enter" || evt.key === " ") {
    evt.preventDefault();
    mapCell(evt);
    return;
  }
  const moves = { ArrowRight: [1, 0], ArrowLeft: [-1, 0], ArrowUp: [0, 1], ArrowDown: [0, -1] };
  const m = moves[evt.key];
  if (!m)
    return;
  evt.preventDefault();
  const i = Number(r.dataset.i) + m[0] * state.mapStep.x, j = Number(r.dataset.j) + m[1] * state.mapStep.y;
  const next = $("#map").querySelector("rect.cell[data-i='" + i + "'][data-j='" + j + "']");
  if (next) {
    r.setAttribute("tabindex", "-1");
    next.setAttribute("tabindex", "0");
    next.focus();
  }
}

/* A map cell clicked: its parameters in the form, and its orbits found. */
function mapCell(evt) {
  const r = evt.target.closest("rect.cell");
  if (!r || !state.mapLines)
    return;
  const l = state.mapLines.find((q) => q.index && q.index[0] === Number(r.dataset.i) &&
                                q.index[1] === Number(r.dataset.j));
  for (const k in l.at) {
    const input = $("#" + units() + " input[name=" + k + "]");
    if (input)
      input.value = +l.at[k].toPrecision(8);
  }
  markStale();
  remember();
  settle(findOrbits());
}

async function basins() {
  const f = $("#basins-form");
  if (!state.params)
    return showError("basins", new Problem(0, { detail: "find orbits first" }));
  /* no more cells a side than the figure has pixels: the rest is not seen */
  const most = Math.min(...Plot.inner($("#basins"), 150));
  if (Number(f.n.value) > most)
    f.n.value = most;
  const n = Number(f.n.value);
  const xr = [Number(f.x1from.value), Number(f.x1to.value)];
  const yr = [Number(f.x2from.value), Number(f.x2to.value)];
  const v = paramValues();
  const v2 = f.v2.value.trim() === "" ? (state.params.params ? v.V : v.v0) : Number(f.v2.value);
  const request = Object.assign({}, state.params, {
    axes: [{ variable: "x1", from: xr[0], to: xr[1], n }, { variable: "x2", from: yr[0], to: yr[1], n }],
    state: { v1: Number(f.v1.value), v2 },
  });
  await longWork("basins", "basins", async (ctl) => {
    status("basins", "basins: submitted");
    const hx = (xr[1] - xr[0]) / (2 * (n - 1 || 1)), hy = (yr[1] - yr[0]) / (2 * (n - 1 || 1));
    const svg = $("#basins");
    const p = Plot.frame(svg, { x: [xr[0] - hx, xr[1] + hx], y: [yr[0] - hy, yr[1] + hy],
                                exact: true, side: 150, xlabel: label("x1", "x"),
                                ylabel: label("x2", "x"), xname: "x1", yname: "x2" });
    /* the NDJSON form: the head (the slice and the search's attractors),
     * each group of rows drawn as it arrives, then the last line (every
     * attractor, its counts, and the cells it relabels) */
    let L = null, labels = null, attractors = [], image = null, g = null, img = null, c = null;
    let painted = 0;
    const fill = (b) => (b === L.unresolved ? "#dddddd" : b === L.perpetual_slip ? "#999999"
                         : color(b));
    /* one pixel a cell: row i runs along x1, column j along x2 (up) */
    const paint = (from, to) => {
      for (let i = from; i < to; i++)
        for (let j = 0; j < L.cols; j++) {
          const hex = fill(labels[i * L.cols + j]), o = 4 * ((L.cols - 1 - j) * L.rows + i);
          img.data[o] = parseInt(hex.slice(1, 3), 16);
          img.data[o + 1] = parseInt(hex.slice(3, 5), 16);
          img.data[o + 2] = parseInt(hex.slice(5, 7), 16);
          img.data[o + 3] = 255;
        }
      g.putImageData(img, 0, 0);
      image.setAttribute("href", c.toDataURL());
    };
    const line = (l) => {
      if (l.attractors && !l.done) {
        L = l.labels;
        attractors = l.attractors;
        labels = new Uint8Array(L.rows * L.cols).fill(L.unresolved);
        c = document.createElement("canvas");
        c.width = L.rows;
        c.height = L.cols;
        g = c.getContext("2d");
        img = g.createImageData(L.rows, L.cols);
        image = Plot.el("image", { x: p.pad.left, y: p.pad.top, width: p.pw, height: p.ph,
                                   preserveAspectRatio: "none", "image-rendering": "pixelated",
                                   class: "basin" }, p.layer);
        svg.dataset.rows = L.rows;
      } else if (l.row !== undefined) {
        const bytes = atob(l.labels), at = l.row * L.cols;
        for (let k = 0; k < bytes.length; k++)
          labels[at + k] = bytes.charCodeAt(k);
        paint(l.row, l.row + l.rows);
        painted += l.rows;
        svg.dataset.painted = painted;
      } else if (l.done) {
        attractors = l.attractors;
        for (const [cell, count, b] of l.relabelled)
          labels.fill(b, cell, cell + count);
        paint(0, L.rows);
        state.basinsAnswer = l;
      }
    };
    await job("/basins", request, ctl, ctl.progress, line);
    if (ctl.cancelled)
      throw new Cancelled();
    const counts = new Map();
    for (const b of labels)
      counts.set(b, (counts.get(b) || 0) + 1);
    const name = (b) => {
      const a = attractors.find((q) => q.label === b);
      return a ? a.kind + " T=" + Plot.fmt(a.period) : b === L.unresolved ? "unresolved"
        : b === L.perpetual_slip ? "perpetual slip" : "label " + b;
    };
    const entries = attractors.map((a) => ({
      label: a.kind + " " + (100 * a.fraction).toFixed(1) + " %",
      color: color(a.label), mark: "box" }));
    if (counts.has(L.unresolved))
      entries.push({ label: "unresolved", color: "#dddddd", mark: "box" });
    if (counts.has(L.perpetual_slip))
      entries.push({ label: "perpetual slip", color: "#999999", mark: "box" });
    Plot.legend(p, entries);
    Plot.readout(p, (x, y) => {
      const i = Math.round((x - xr[0]) / ((xr[1] - xr[0]) / (L.rows - 1 || 1)));
      const j = Math.round((y - yr[0]) / ((yr[1] - yr[0]) / (L.cols - 1 || 1)));
      return i >= 0 && j >= 0 && i < L.rows && j < L.cols ? name(labels[i * L.cols + j]) : "";
    });
    state.figures.basins = () => {
      const rows = [];
      for (let i = 0; i < L.rows; i++)
        for (let j = 0; j < L.cols; j++)
          rows.push([xr[0] + i * 2 * hx, yr[0] + j * 2 * hy, name(labels[i * L.cols + j])]);
      return { columns: ["x1", "x2", "attractor"], rows };
    };
    const legend = attractors.map((a) => a.kind + " " + (100 * a.fraction).toFixed(1) + " %");
    status("basins", "basins: " + attractors.length + " attractor(s): " + legend.join(", "));
  });
}

/* ---- export ---------------------------------------------------------------- */

/* Each figure's buttons: SVG and PNG of the figure, CSV and JSON of its data. */
function exportButtons() {
  for (const fig of document.querySelectorAll("figure[data-name]")) {
    const svg = fig.querySelector("svg"), name = "stickslip-" + fig.dataset.name;
    /* the figure's place kept while it is empty */
    svg.setAttribute("viewBox", "0 0 " + svg.dataset.width + " " + svg.dataset.height);
    svg.style.width = svg.dataset.width + "px";
    const bar = document.createElement("div");
    bar.className = "export";
    const add = (fmt, make) => {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = fmt;
      b.className = "export-" + fmt.toLowerCase();
      b.setAttribute("aria-label", fmt + " of " + svg.getAttribute("aria-label"));
      b.addEventListener("click", async () => {
        if (!svg.childNodes.length)
          return;
        try {
          const blob = await make();
          if (blob)
            Plot.download(name + "." + fmt.toLowerCase(), blob);
        } catch (e) {
          showError(["family", "map", "basins"].includes(svg.id) ? svg.id : "orbits", e);
        }
      });
      bar.appendChild(b);
    };
    add("SVG", () => new Blob([Plot.svgText(svg)], { type: "image/svg+xml" }));
    add("PNG", () => Plot.pngBlob(svg));
    /* a figure's data: none while it is computed (null), so none exported */
    const data = () => state.figures[svg.id] && state.figures[svg.id]();
    add("CSV", () => data() && new Blob([Plot.csv(data())], { type: "text/csv" }));
    add("JSON", () => {
      const t = data();
      if (!t)
        return null;
      const doc = { figure: fig.dataset.name, units: state.units, input: state.params,
                    columns: t.columns, rows: t.rows };
      return new Blob([JSON.stringify(doc, null, 1)], { type: "application/json" });
    });
    fig.appendChild(bar);
  }
}

/* ---- wiring ------------------------------------------------------------- */

/* The view a URL's search asks for, less its selection and hidden curves:
 * what needs computing.  shownView: the one on the page. */
function viewKey(search) {
  const q = new URLSearchParams(search);
  q.delete("selected");
  q.delete("hidden");
  return q.toString();
}
let shownView = null;

/* The view of the URL: the forms set, the orbits found, and the panels it
 * names run again (cancelling those running). */
async function showURL() {
  const was = shownView;
  shownView = viewKey(location.search);
  const view = readURL();
  if (shownView === was && state.orbits.length) {
    /* only the selection or the hidden curves differ: nothing to compute */
    state.selected = view.selected < state.orbits.length ? view.selected : 0;
    state.hidden = new Set([...view.hidden].filter((i) => i < state.orbits.length));
    listOrbits();
    drawOrbits();
    return;
  }
  state.open = new Set(view.open);
  for (const id of ["family", "map", "basins"]) {
    stopWork(id);
    $("#" + id).textContent = "";
    status(id, "");
    clearError(id);
  }
  /* a newer view (Back again, Find) ends this one's work */
  const mine = shownView;
  if (!(await findOrbits(view)))
    return;
  const runs = { family: continueFamily, map: existenceMap, basins };
  for (const id of view.open) {
    if (shownView !== mine)
      return;
    await runs[id]();
  }
}

$("#units").addEventListener("change", (e) => {
  setUnits(e.target.value, true);
  markStale();
});
$("#params").addEventListener("input", (e) => {
  if (e.target.id !== "units")
    markStale();
});
$("#params").addEventListener("submit", (e) => {
  e.preventDefault();
  state.open.clear();
  remember();
  settle(findOrbits());
});
$("#continue-form").parameter.addEventListener("change", familyRange);
$("#simulate-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const f = e.target;
  simulateFrom(["x1", "x2", "v1", "v2"].map((k) => Number(f[k].value)));
});
$("#portrait2").addEventListener("click", (e) => clickSimulate(e, 2));
$("#portrait1").addEventListener("click", (e) => clickSimulate(e, 1));
$("#map").addEventListener("click", mapCell);
$("#map").addEventListener("keydown", mapKey);
for (const [id, run] of [["continue-form", continueFamily], ["map-form", existenceMap],
                         ["basins-form", basins]])
  $("#" + id).addEventListener("submit", (e) => {
    e.preventDefault();
    state.open.add(id === "continue-form" ? "family" : id.replace("-form", ""));
    remember();
    run();
  });
window.addEventListener("popstate", showURL);
/* the daemon the answers come from, when not this page's */
if (API)
  $("#daemon").textContent = "the daemon at " + API;
exportButtons();
showURL().then(() => remember(true));
