// The explorer in a real browser (Debian's chromium, headless, driven by
// puppeteer-core) against a live stickslipd:
//   node explorer.test.mjs BASE_URL OUT_DIR
// It loads a URL holding a view and finds the orbits /orbit gives for it;
// checks the portraits (the paper's orbit in its three phases, sampled to
// half a pixel), the legend tying each curve to its row, hiding a row's
// curves, keyboard selection and a simulation from a typed state, axis
// labels with units, the back button, panels marked stale when the
// parameters change; draws the overshoot map with its colour key and the
// current point, loads a cell's orbits by a click; exports every figure
// (the SVG parses, the PNG is one, the CSV and JSON hold the answer's
// numbers); picks a map cell with the keyboard; runs maps as jobs
// (progress; one of 100x100 cancelled, one of 30x30 finished) and 256x256 basins whose rows are
// drawn as they arrive; continues the family in Fr in physical units; shows errors
// next to their panel and explains a CORS failure; with requests
// intercepted, checks races (two searches, Back, a double click), lost job
// statuses, retries after a 503, Cancel of an answer given at once and
// exports while a map runs; runs axe-core (no serious or critical
// violation), checks that nothing overflows at 420 px and that axes over
// one ulp are drawn.  Screenshots go to OUT_DIR.
import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";
import puppeteer from "puppeteer-core";

const [base, out] = process.argv.slice(2);
const require = createRequire(import.meta.url);
const failures = [];
let checks = 0;
function check(ok, what) {
  checks++;
  if (!ok)
    failures.push(what);
  console.log((ok ? "ok: " : "FAIL: ") + what);
}
const PAPER = { chi: 0.2, eta: 4, us: 0.0724, ur: 0.6178, V: 1 };
async function api(p, body) {
  const r = await fetch(base + p, { method: "POST", headers: { "Content-Type": "application/json" },
                                    body: JSON.stringify(body) });
  return r.text();
}

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
});
const t00 = Date.now();
let downloads = null;
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 1300 });
  const consoleErrors = [], failed = [], problems = [];
  page.on("console", (m) => m.type() === "error" && consoleErrors.push(m.text()));
  page.on("pageerror", (e) => consoleErrors.push(e.message));
  page.on("requestfailed", (r) => failed.push(r.url()));
  page.on("response", (r) => r.status() >= 400 && problems.push(r.status() + " " + r.url()));
  downloads = fs.mkdtempSync(path.join(out, "downloads-"));
  const cdp = await browser.target().createCDPSession();
  await cdp.send("Browser.setDownloadBehavior", { behavior: "allow", downloadPath: downloads,
                                                  eventsEnabled: true });
  const ended = [];
  cdp.on("Browser.downloadProgress", (e) => e.state !== "inProgress" && ended.push(e.state));
  const text = (sel) => page.$eval(sel, (e) => e.textContent);
  const shown = (sel) => page.$eval(sel, (e) => (e.hidden ? "" : e.textContent));
  const rowsOf = () => page.$$eval("#orbits tbody tr", (trs) =>
    trs.map((tr) => [...tr.cells].map((c) => c.textContent)));

  // 1. a view in the URL: the orbits /orbit gives for it
  const t0 = Date.now();
  const q = new URLSearchParams(Object.assign({ units: "dimensionless", kind: "all", max_period: 4,
                                                selected: 0 }, PAPER));
  await page.goto(base + "/?" + q, { waitUntil: "networkidle0" });
  await page.waitForFunction(() => document.querySelectorAll("#orbits tbody tr").length > 0,
                             { timeout: 30000 });
  const loadMs = Date.now() - t0;
  const direct = JSON.parse(await api("/orbit", { params: PAPER, kind: "all", max_period: 4 }));
  let rows = await rowsOf();
  check(rows.length === direct.orbits.length &&
        direct.orbits.every((o, i) => rows[i][4] === o.period.toFixed(6)),
        "the URL's view lists the orbits of /orbit: " + rows.map((r) => r[4]).join(", "));
  check(rows.some((r) => r[2] === "overshoot" && r[4].startsWith("10.2714")),
        "the paper's overshoot orbit (period 10.2714) is listed");
  check(await page.$eval("#error", (e) => e.hidden), "no error shown after a successful search");

  // the portraits: the selected orbit drawn in its three phases, styled
  const seg = await page.evaluate(() => {
    const o = {};
    for (const id of ["portrait2", "portrait1"]) {
      const ls = [...document.querySelectorAll("#" + id + " polyline.curve.selected")];
      o[id] = { modes: ls.map((l) => l.dataset.mode), dash: ls.map((l) => l.getAttribute("stroke-dasharray")),
                points: ls.map((l) => l.getAttribute("points").trim().split(/\s+/).length) };
    }
    return o;
  });
  for (const id of ["portrait2", "portrait1"]) {
    const s = seg[id];
    check(s.modes.join(",") === "slip,overshoot,stick", id + ": slip, overshoot, stick: " + s.modes);
    check(s.dash[0] !== "" && s.dash[1] === "" && s.dash[2] !== "" && s.dash[0] !== s.dash[2],
          id + ": slip dotted, overshoot solid, stick dashed (" + JSON.stringify(s.dash) + ")");
  }
  const stickY = await page.$eval("#portrait2 polyline.curve.selected[data-mode=stick]",
    (l) => [...new Set(l.getAttribute("points").trim().split(/\s+/).map((p) => p.split(",")[1]))]);
  check(stickY.length === 1, "portrait2: the stick is a horizontal line: " + stickY);
  const fig4 = await page.$$eval("#constraints polyline.constraint", (ls) => ls.map((l) => l.dataset.name));
  check(fig4.join(",") === "F1,F2", "the stick constraints F1 and F2 are drawn");
  const mods = await page.$$eval("#multipliers circle.multiplier", (cs) => cs.map((c) => Number(c.dataset.modulus)));
  check(mods.length === 2 && mods.every((m) => Math.abs(m - 0.195452) < 1e-4),
        "two multipliers of modulus 0.19545 inside the unit circle: " + mods);

  // axis labels with units; a legend whose colours are the rows' swatches
  const labels = await page.$$eval("svg.plot .xlabel, svg.plot .ylabel", (ts) => ts.map((t) => t.textContent));
  check(labels.length >= 8 && labels.every((l) => /\(.+\)/.test(l)),
        "every axis says its unit: " + labels.join("; "));
  const tie = await page.evaluate(() => {
    const sw = [...document.querySelectorAll("#orbits .swatch")].map((s) => s.style.getPropertyValue("--swatch"));
    const leg = [...document.querySelectorAll("#portrait2 .legend .entry line")].map((l) => l.getAttribute("stroke"));
    const curves = sw.map((_, i) => {
      const l = document.querySelector("#portrait2 polyline[data-orbit='" + i + "']");
      return l && l.getAttribute("stroke");
    });
    return { sw, leg, curves };
  });
  check(tie.sw.length === rows.length && tie.sw.every((c, i) => c === tie.leg[i] && c === tie.curves[i]),
        "each row's swatch is its legend entry's and its curve's colour: " + tie.sw.join(" "));

  // hide a row's curves, then the back button shows them again
  await page.click("#orbits tbody tr[data-index='1'] input[type=checkbox]");
  const hiddenNow = await page.$$eval("#portrait2 polyline[data-orbit='1']", (l) => l.length);
  check(hiddenNow === 0 && (await page.evaluate(() => location.search)).includes("hidden=1"),
        "a row's box hides its curves, and the URL says so");
  await page.goBack();
  await page.waitForFunction(() => document.querySelectorAll("#portrait2 polyline[data-orbit='1']").length > 0,
                             { timeout: 20000 }).catch(() => {});
  check(!(await page.evaluate(() => location.search)).includes("hidden") &&
        (await page.$$eval("#portrait2 polyline[data-orbit='1']", (l) => l.length)) > 0,
        "the back button returns to the view with every curve shown");

  // keyboard: a focused row selected with Enter, a simulation from a typed state
  await page.focus("#orbits tbody tr[data-index='0']");
  await page.keyboard.press("ArrowDown");
  await page.keyboard.press("ArrowDown");
  await page.keyboard.press("Enter");
  const sel = await page.$eval("#orbits tbody tr.selected", (tr) => tr.dataset.index);
  check(sel === "2" && (await page.evaluate(() => location.search)).includes("selected=2"),
        "rows focusable: two ArrowDown and Enter select orbit 2 (URL selected=" + sel + ")");
  await page.focus("#orbits tbody tr[data-index='0']");
  await page.keyboard.press("Enter");
  await page.focus("#simulate-form input[name=x1]");
  await page.keyboard.press("Enter");
  await page.waitForFunction(() => /6 of 6 pieces/.test(document.getElementById("status").textContent) ||
                                   !document.getElementById("error").hidden, { timeout: 60000 });
  const sims = await page.$$eval("#portrait2 polyline.simulated", (ls) => ls.length);
  check(sims >= 6, "Enter in the typed state simulates three periods, piece by piece: " + sims);
  const box = await (await page.$("#portrait2")).boundingBox();
  await page.mouse.click(box.x + box.width * 0.4, box.y + box.height * 0.5);
  await page.waitForFunction(() => /6 of 6 pieces/.test(document.getElementById("status").textContent) ||
                                   !document.getElementById("error").hidden, { timeout: 60000 });
  check(/simulating from/.test(await text("#status")), "a click in a portrait simulates from there");
  // the wheel zooms a portrait about the pointer, a double click returns
  const ticks = () => page.$$eval("#portrait2 .axes text", (ts) => ts.map((t) => t.textContent).join(" "));
  const whole = await ticks();
  await page.mouse.move(box.x + box.width * 0.4, box.y + box.height * 0.5);
  await page.mouse.wheel({ deltaY: -300 });
  await page.waitForFunction((w) => [...document.querySelectorAll("#portrait2 .axes text")]
    .map((t) => t.textContent).join(" ") !== w, { timeout: 5000 }, whole).catch(() => {});
  const zoomed = await ticks();
  await page.mouse.click(box.x + box.width * 0.4, box.y + box.height * 0.5, { clickCount: 2 });
  await page.waitForFunction(() => /6 of 6 pieces/.test(document.getElementById("status").textContent),
                             { timeout: 60000 });
  check(zoomed !== whole && (await ticks()) === whole,
        "the wheel zooms the portrait (ticks " + zoomed.slice(0, 30) + "), a double click returns");
  await page.screenshot({ path: out + "/explorer.png" });

  // the family, its grazing labelled inside the figure
  await page.click("#continue-form button");
  await page.waitForFunction(() => document.querySelectorAll("#family line.branch").length > 0 ||
                                   !document.querySelector("#family-panel .error").hidden, { timeout: 60000 });
  const graz = await page.evaluate(() => {
    const t = [...document.querySelectorAll("#family .special-label")].find((e) => /grazing/.test(e.textContent));
    if (!t)
      return null;
    const b = t.getBBox(), w = Number(document.getElementById("family").dataset.width);
    return { text: t.textContent, inside: b.x >= 0 && b.x + b.width <= w };
  });
  check(graz && graz.inside, "the family's grazing is labelled within the figure: " + JSON.stringify(graz));

  // 2. the overshoot map, its key and the current point; a cell loads its orbits
  await page.evaluate(() => {
    const f = document.getElementById("map-form");
    f.kind.value = "overshoot";
    f.xn.value = "12";
    f.yn.value = "12";
  });
  await page.click("#map-form button[type=submit]");
  // its cells are drawn as they arrive, its key once the job ends
  await page.waitForFunction(() => document.querySelectorAll("#map .legend").length > 0 ||
                                   !document.querySelector("#map-panel .error").hidden, { timeout: 60000 });
  const map = await page.evaluate(() => ({
    cells: document.querySelectorAll("#map rect.cell").length,
    stable: document.querySelectorAll("#map rect.cell.stable").length,
    key: [...document.querySelectorAll("#map .legend text")].map((t) => t.textContent),
    current: document.querySelectorAll("#map circle.current").length,
    title: document.querySelector("#map rect.cell.stable title")?.textContent || "",
  }));
  check(map.cells === 144 && map.stable > 0, "the overshoot map: 144 cells, " + map.stable + " stable " +
        (await shown("#map-panel .error")));
  check(["none", "unstable", "stable"].every((k) => map.key.includes(k)) && map.current === 1,
        "the map has its colour key and marks the current point: " + map.key.join(", "));
  check(/overshoot T=/.test(map.title), "a cell's title names its orbits: " + map.title);
  const directMap = (await api("/map", {
    params: PAPER, kind: "overshoot", max_period: 1,
    axes: [{ parameter: "ur", from: 0.109, to: 1.09, n: 12 }, { parameter: "chi", from: 0.04, to: 0.96, n: 12 }],
  })).trim().split("\n").map((l) => JSON.parse(l));

  // 3. every figure's exports
  const files = async (n) => {
    for (let k = 0; k < 100 && ended.length < n; k++)
      await new Promise((r) => setTimeout(r, 50));
    return fs.readdirSync(downloads);
  };
  const figures = await page.$$eval("figure[data-name]", (fs) => fs.map((f) => f.dataset.name).filter((n) => n !== "basins"));
  let count = 0, got = [];
  for (const name of figures)
    for (const fmt of ["svg", "png", "csv", "json"]) {
      await page.click("figure[data-name='" + name + "'] .export-" + fmt);
      got = await files(++count);
      // Chrome drops, at times, a download started right after another
      await new Promise((r) => setTimeout(r, 250));
    }
  check(got.length === count && ended.every((e) => e === "completed"),
        "each figure exports SVG, PNG, CSV and JSON: " + got.length + " of " + count + " (" + ended + ")");
  const read = (n) => (fs.existsSync(path.join(downloads, n)) ? fs.readFileSync(path.join(downloads, n)) : Buffer.from(""));
  const parses = await page.evaluate((texts) => texts.map((t) => {
    const d = new DOMParser().parseFromString(t, "image/svg+xml");
    return !d.querySelector("parsererror") && d.documentElement.nodeName === "svg" &&
      d.querySelectorAll(".legend").length > 0;
  }), figures.map((n) => read("stickslip-" + n + ".svg").toString()));
  check(parses.every(Boolean), "each SVG parses and carries its legend: " + parses);
  check(figures.every((n) => read("stickslip-" + n + ".png").subarray(1, 4).toString() === "PNG"),
        "each PNG is a PNG");
  const mapCsv = read("stickslip-map.csv").toString().trim().split("\n").slice(1).map((l) => l.split(","));
  const mapLines = directMap.filter((l) => l.index);
  check(mapCsv.length === 144 && mapLines.every((l, i) => Number(mapCsv[i][0]) === l.at.ur &&
          Number(mapCsv[i][1]) === l.at.chi && Number(mapCsv[i][2]) === l.orbits.length),
        "the map's CSV holds /map's cells and orbit counts");
  const p2 = JSON.parse(read("stickslip-portrait-x2.json").toString());
  const o0 = direct.orbits[0];
  check(p2.columns.join() === "orbit,t,x2,v2,mode" && p2.rows.some((r) => r[0] === 0 && r[1] === 0 &&
          Math.abs(r[2] - o0.x0[1]) < 1e-12 && Math.abs(r[3] - o0.x0[3]) < 1e-12),
        "the portrait's JSON holds the orbit's samples from its start x0");
  const famCsv = read("stickslip-family.csv").toString();
  check(/^branch,ur,period,stable\n0,/.test(famCsv), "the family's CSV: " + famCsv.slice(0, 40));

  // a map cell loads that point's orbits
  const before = await page.$eval("input[name=ur]", (e) => e.value);
  await page.$eval("#map rect.cell.stable", (r) => r.dispatchEvent(new MouseEvent("click", { bubbles: true })));
  await page.waitForFunction((b) => document.querySelector("input[name=ur]").value !== b &&
                             /orbit\(s\)/.test(document.getElementById("status").textContent), { timeout: 30000 }, before).catch(() => {});
  rows = await rowsOf();
  check(rows.some((r) => r[2] === "overshoot"), "a stable cell's click loads its overshoot orbit: ur = " +
        (await page.$eval("input[name=ur]", (e) => e.value)));
  check(await page.$eval("#map", (s) => s.classList.contains("stale")), "the map is marked stale after it");

  // a map cell picked with the keyboard: the roving cell moved with the
  // arrow keys to the last stable cell, Enter loads its orbits
  const keys = await page.evaluate(() => {
    const cells = [...document.querySelectorAll("#map rect.cell")];
    const start = cells.filter((r) => r.getAttribute("tabindex") === "0");
    const goal = [...document.querySelectorAll("#map rect.cell.stable")].pop();
    return { roving: start.length, labelled: cells.every((r) => /: /.test(r.getAttribute("aria-label") || "")),
             i0: Number(start[0]?.dataset.i), j0: Number(start[0]?.dataset.j),
             i: Number(goal.dataset.i), j: Number(goal.dataset.j) };
  });
  await page.$eval("#map rect.cell[tabindex='0']", (r) => r.focus());
  for (let k = keys.i0; k < keys.i; k++)
    await page.keyboard.press("ArrowRight");
  for (let k = keys.j0; k < keys.j; k++)
    await page.keyboard.press("ArrowUp");
  const focused = await page.evaluate(() => {
    const a = document.activeElement;
    return { i: Number(a?.dataset?.i), j: Number(a?.dataset?.j), stable: !!a?.classList?.contains("stable"),
             roving: document.querySelectorAll("#map rect.cell[tabindex='0']").length };
  });
  const goalUr = directMap.find((l) => l.index && l.index[0] === keys.i && l.index[1] === keys.j).at.ur;
  const urBefore = await page.$eval("input[name=ur]", (e) => e.value);
  await page.keyboard.press("Enter");
  await page.waitForFunction((b) => document.querySelector("input[name=ur]").value !== b &&
                             /orbit\(s\)/.test(document.getElementById("status").textContent), { timeout: 30000 }, urBefore).catch(() => {});
  const urNow = Number(await page.$eval("input[name=ur]", (e) => e.value));
  rows = await rowsOf();
  check(keys.roving === 1 && keys.labelled && focused.i === keys.i && focused.j === keys.j && focused.stable &&
        focused.roving === 1 && Math.abs(urNow - goalUr) < 1e-6 && rows.some((r) => r[2] === "overshoot"),
        "a map cell picked with the keyboard (one cell in the tab order, arrow keys to cell " + keys.i + "," + keys.j +
        ", Enter): ur = " + urNow + " (the cell's " + goalUr + "), its overshoot orbit loaded; focus " +
        JSON.stringify(focused));

  check(consoleErrors.length === 0, "no console error: " + consoleErrors.join("; "));
  check(failed.length === 0, "no failed request: " + failed.join("; "));
  check(problems.length === 0, "no 4xx/5xx answer before the bad inputs: " + problems.join("; "));

  // 5a. races, lost answers, retries: each a few seconds.  Requests are
  // intercepted: held, failed, answered 503 or sent without Prefer once
  // (each rule taken by the first request it matches)
  const rules = [], posted = [];
  await page.setRequestInterception(true);
  page.on("request", (r) => {
    const u = new URL(r.url());
    if (r.method() === "POST")
      posted.push(u.pathname);
    const k = rules.findIndex((x) => x.method === r.method() && x.path.test(u.pathname));
    const rule = k >= 0 ? rules.splice(k, 1)[0] : null;
    const go = () => r.continue().catch(() => {});
    if (!rule)
      go();
    else if (rule.hold)
      setTimeout(go, rule.hold);
    else if (rule.fail)
      r.abort().catch(() => {});
    else if (rule.respond)
      r.respond(rule.respond).catch(() => {});
    else if (rule.noPrefer) {
      const h = Object.assign({}, r.headers());
      delete h.prefer;
      r.continue({ headers: h }).catch(() => {});
    }
  });
  const settled = () => page.waitForFunction(() => /orbit\(s\)/.test(document.getElementById("status").textContent) &&
                                             !document.getElementById("find").disabled, { timeout: 30000 });
  const pause = (ms) => new Promise((r) => setTimeout(r, ms));
  const periods = async () => (await rowsOf()).map((r) => r[4]).join(", ");
  const paperPeriods = direct.orbits.map((o) => o.period.toFixed(6)).join(", ");
  await page.goto(base + "/?" + q + "&open=map&m.xn=3&m.yn=3&m.max_period=1&m.kind=overshoot", { waitUntil: "networkidle0" });
  await page.waitForFunction(() => document.querySelectorAll("#map .legend").length > 0, { timeout: 30000 });
  // Back to a view that differs only in its selection: nothing computed again
  await page.click("#orbits tbody tr[data-index='1']");
  posted.length = 0;
  await page.goBack();
  await page.waitForFunction(() => document.querySelector("#orbits tbody tr.selected")?.dataset.index === "0", { timeout: 5000 })
    .catch(() => {});
  await pause(300);
  check(posted.length === 0 && (await page.$$eval("#map rect.cell", (r) => r.length)) === 9,
        "Back to the same view but its selection computes nothing again (posted: " + posted.join(" ") + ")");
  // while a map runs, its CSV is not the previous map's; a map answered at
  // once (no Prefer, as a daemon without jobs answers) is cancelled at once
  const downloadsBefore = ended.length, errorsBefore = consoleErrors.length;
  rules.push({ method: "POST", path: /^\/map$/, noPrefer: true });
  await page.$eval("#map-form input[name=xn]", (e) => { e.value = "30"; });
  await page.$eval("#map-form input[name=yn]", (e) => { e.value = "30"; });
  await page.$eval("#map-form input[name=max_period]", (e) => { e.value = "4"; });
  await page.click("#map-form button[type=submit]");
  await page.click("figure[data-name='map'] .export-csv");
  await pause(800);
  check(ended.length === downloadsBefore && consoleErrors.length === errorsBefore,
        "a map's CSV while it runs: no download of the previous map, no error (" +
        consoleErrors.slice(errorsBefore).join("; ") + ")");
  const tc = Date.now();
  await page.click("#map-form .cancel").catch(() => {});
  await page.waitForFunction(() => /cancelled/.test(document.querySelector("#map-panel .status").textContent),
                             { timeout: 3000 }).catch(() => {});
  check(/cancelled/.test(await text("#map-panel .status")) &&
        !(await page.$eval("#map-form button[type=submit]", (b) => b.disabled)),
        "Cancel ends a map the daemon answers at once, in " + (Date.now() - tc) + " ms: " + await text("#map-panel .status"));
  // a single column of cells: the cell at its from, filling the frame
  await page.$eval("#map-form input[name=xn]", (e) => { e.value = "1"; });
  await page.$eval("#map-form input[name=yn]", (e) => { e.value = "2"; });
  await page.$eval("#map-form input[name=max_period]", (e) => { e.value = "1"; });
  await page.click("#map-form button[type=submit]");
  await page.waitForFunction(() => document.querySelectorAll("#map .legend").length > 0, { timeout: 30000 });
  const one = await page.$eval("#map rect.cell", (r) => Number(r.getAttribute("x")));
  check(Math.abs(one - 54) < 1, "a map one cell wide: the cell fills the frame from its left edge (x = " + one + ")");
  // a job's status lost once (the network): its results are still drawn
  await page.$eval("#basins-form input[name=n]", (e) => { e.value = "16"; });
  rules.push({ method: "GET", path: /^\/jobs\/[0-9a-f]+$/, fail: true });
  await page.click("#basins-form button[type=submit]");
  await page.waitForFunction(() => document.querySelector("#basins-form progress").hidden, { timeout: 30000 });
  check(rules.length === 0 && Number(await page.$eval("#basins", (s) => s.dataset.painted)) === 16 &&
        (await page.$eval("#basins-panel .error", (e) => e.hidden)),
        "a job status lost on the way: the basins still drawn " + (await shown("#basins-panel .error")));
  // a job store that cannot take the job (503 store-unavailable): asked again without Prefer
  await page.$eval("#basins", (s) => { s.textContent = ""; s.dataset.painted = 0; });
  rules.push({ method: "POST", path: /^\/basins$/, respond: {
    status: 503, headers: { "Retry-After": "1" }, contentType: "application/problem+json",
    body: JSON.stringify({ type: base + "/problems/store-unavailable", title: "Service Unavailable", status: 503 }) } });
  await page.click("#basins-form button[type=submit]");
  await page.waitForFunction(() => document.querySelector("#basins-form progress").hidden, { timeout: 30000 });
  check(Number(await page.$eval("#basins", (s) => s.dataset.painted)) === 16,
        "basins refused by the job store are computed at once " + (await shown("#basins-panel .error")));
  // a busy daemon's 503 is tried again after its Retry-After
  rules.push({ method: "POST", path: /^\/orbit$/, respond: {
    status: 503, headers: { "Retry-After": "1" }, contentType: "application/problem+json",
    body: JSON.stringify({ title: "Service Unavailable", status: 503, detail: "every compute slot is busy" }) } });
  await page.click("#find");
  await settled().catch(() => {});
  check((await periods()) === paperPeriods && (await page.$eval("#error", (e) => e.hidden)),
        "a 503 with Retry-After is tried again: " + (await periods()) + (await shown("#error")));
  // two searches: the first held, the second's orbits stay
  await page.$eval("input[name=ur]", (e) => { e.value = "0.5"; });
  rules.push({ method: "POST", path: /^\/orbit$/, hold: 1200 });
  await page.click("#find");
  await page.$eval("input[name=ur]", (e) => { e.value = "0.6178"; });
  await page.$eval("#find", (b) => { b.disabled = false; b.click(); });
  await settled().catch(() => {});
  await pause(1800);
  check((await periods()) === paperPeriods && !(await page.$eval("#find", (b) => b.disabled)),
        "of two searches in flight the last one's orbits are shown: " + (await periods()));
  await page.setRequestInterception(false);
  // Find resets the selection and the hidden curves, and so does the URL
  await page.click("#orbits tbody tr[data-index='2']");
  await page.click("#orbits tbody tr[data-index='1'] input[type=checkbox]");
  await page.click("#find");
  await settled().catch(() => {});
  await pause(100);
  const search = await page.evaluate(() => location.search);
  check(!search.includes("hidden") && search.includes("selected=0"),
        "after Find the URL's selection is the page's: " + search.replace(/.*(selected=[^&]*).*/, "$1"));
  // the constraints of an orbit with several sticks: one line a stick
  const several = direct.orbits.findIndex((o) => o.phases.filter((p) => p.mode === "stick").length > 1);
  await page.click("#orbits tbody tr[data-index='" + several + "']");
  const sticks = direct.orbits[several].phases.filter((p) => p.mode === "stick").length;
  const f1 = await page.$$eval("#constraints polyline[data-name=F1]", (l) => l.length);
  check(f1 === sticks, "orbit " + several + "'s F1 drawn as " + f1 + " lines, one a stick (" + sticks + ")");
  // a trackpad's small wheel steps zoom a little
  const span = () => page.evaluate(() => state.frames.r2.xr[1] - state.frames.r2.xr[0]);
  const box2 = await (await page.$("#portrait2")).boundingBox();
  const s0 = await span();
  await page.mouse.move(box2.x + box2.width * 0.4, box2.y + box2.height * 0.5);
  await page.mouse.wheel({ deltaY: 4 });
  await pause(200);
  const s1 = await span();
  check(s1 !== s0 && Math.abs(s1 / s0 - 1) < 0.03, "a wheel step of 4 px zooms by " + ((s1 / s0 - 1) * 100).toFixed(1) + " %");
  // a double click returns to the whole and leaves no simulation running
  posted.length = 0;
  await page.mouse.click(box2.x + box2.width * 0.4, box2.y + box2.height * 0.5, { clickCount: 2 });
  await pause(1500);
  const sims2 = posted.filter((u) => u === "/simulate").length;
  check(sims2 <= 1, "a double click starts at most its first click's simulation (" + sims2 +
        " /simulate sent)");

  // errors next to their panel
  await page.goto(base + "/?" + q, { waitUntil: "networkidle0" });
  await page.waitForFunction(() => document.querySelectorAll("#orbits tbody tr").length > 0, { timeout: 30000 });
  await page.$eval("#map-form input[name=xn]", (e) => { e.value = "0"; });
  await page.click("#map-form button[type=submit]");
  await page.waitForSelector("#map-panel .error:not([hidden])", { timeout: 10000 }).catch(() => {});
  check(/n/.test(await text("#map-panel .error")) && (await page.$eval("#error", (e) => e.hidden)),
        "a bad map shows its problem in the map's panel: " + (await text("#map-panel .error")));
  await page.$eval("input[name=chi]", (e) => { e.value = "2"; e.dispatchEvent(new Event("input", { bubbles: true })); });
  check(await page.$eval("#portrait2", (s) => s.classList.contains("stale")), "a changed parameter marks the portraits stale");
  await page.click("#find");
  await page.waitForSelector("#error:not([hidden])", { timeout: 10000 }).catch(() => {});
  const alert = await text("#error");
  check(/chi/.test(alert) && (await page.$$eval("#orbits tbody tr", (t) => t.length)) === 0 &&
        (await page.$eval("#portrait2", (s) => s.childNodes.length)) === 0,
        "a bad chi: the daemon's problem, the old table and portraits cleared: " + alert);

  // a CORS failure explained: this page's origin is not the daemon's
  const other = base.replace("127.0.0.1", "localhost");
  await page.goto(base + "/?api=" + encodeURIComponent(other), { waitUntil: "networkidle0" });
  await page.waitForSelector("#error:not([hidden])", { timeout: 10000 }).catch(() => {});
  check(/--cors-origin/.test(await text("#error")), "a CORS failure says --cors-origin: " + await text("#error"));
  const daemon = await text("#daemon").catch(() => "");
  check(daemon.includes(other), "the header names the other daemon: " + daemon);

  // 4. physical units: continuation in Fr, its grazing at Fr = 6.1663
  await page.goto(base + "/?units=physical", { waitUntil: "networkidle0" });
  await page.waitForFunction(() => document.querySelectorAll("#orbits tbody tr").length > 0, { timeout: 30000 });
  const opts = await page.$$eval("#continue-form select option", (o) => o.map((x) => x.value));
  check(opts.includes("Fr") && !opts.includes("ur"), "in physical units the family offers " + opts);
  await page.select("#continue-form select", "Fr");
  await page.$eval("#continue-form input[name=from]", (e) => { e.value = "3"; });
  await page.$eval("#continue-form input[name=to]", (e) => { e.value = "15"; });
  await page.click("#continue-form button");
  await page.waitForFunction(() => document.querySelectorAll("#family line.branch").length > 0 ||
                                   !document.querySelector("#family-panel .error").hidden, { timeout: 60000 });
  const famP = await page.evaluate(() => ({
    special: [...document.querySelectorAll("#family .special-label")].map((t) => t.textContent),
    x: document.querySelector("#family .xlabel").textContent,
    y: document.querySelector("#portrait2 .ylabel").textContent }));
  check(famP.special.some((s) => /grazing 6\.166/.test(s)) && /Fr \(M L\/s²\)/.test(famP.x) && /L\/s/.test(famP.y),
        "the family in Fr grazes at 6.1663, axes in physical units: " + JSON.stringify(famP) +
        (await shown("#family-panel .error")));
  const dopts = await page.evaluate(() => {
    document.getElementById("units").value = "dimensionless";
    document.getElementById("units").dispatchEvent(new Event("change"));
    return [...document.querySelectorAll("#continue-form select option")].map((x) => x.value);
  });
  check(dopts.includes("V"), "the dimensionless family offers V: " + dopts);

  // 5. long work as jobs: a 100x100 map cancelled, a 30x30 one finished
  await page.goto(base + "/?" + q + "&open=family&m.xn=100&m.yn=100&m.kind=overshoot", { waitUntil: "networkidle0" });
  await page.waitForFunction(() => document.querySelectorAll("#family line.branch").length > 0, { timeout: 60000 });
  await page.click("#map-form button[type=submit]");
  await page.waitForFunction(() => /job: .* of 10000 done/.test(document.querySelector("#map-panel .status").textContent),
                             { timeout: 20000 }).catch(() => {});
  const during = await page.evaluate(() => ({
    go: document.querySelector("#map-form button[type=submit]").disabled,
    bar: !document.querySelector("#map-form progress").hidden,
    cancel: !document.querySelector("#map-form .cancel").hidden }));
  check(during.go && during.bar && during.cancel,
        "while the map runs: its button disabled, a progress bar and a cancel button " + JSON.stringify(during));
  const orbitMs = await page.evaluate(async () => {
    const t = performance.now();
    await fetch("/orbit", { method: "POST", headers: { "Content-Type": "application/json" },
                            body: JSON.stringify({ params: { chi: 0.2, eta: 4, us: 0.0724, ur: 0.6178, V: 1 } }) });
    return performance.now() - t;
  });
  check(orbitMs < 5000, "an /orbit during the map is not queued behind it: " + Math.round(orbitMs) + " ms");
  await page.click("#map-form .cancel").catch(() => {});
  await page.waitForFunction(() => /cancelled/.test(document.querySelector("#map-panel .status").textContent),
                             { timeout: 20000 }).catch(() => {});
  const jobs = await (await fetch(base + "/jobs")).json();
  const maps = (jobs.jobs || []).filter((j) => j.processID === "map").map((j) => j.status);
  check(/cancelled/.test(await text("#map-panel .status")) && maps.includes("dismissed") &&
        !(await page.$eval("#map-form button[type=submit]", (b) => b.disabled)),
        "cancelled: the job dismissed (" + maps + "), the button enabled again");
  // a map searches every cell: 30x30 is 900 full searches, about 2 minutes
  // under the sanitizers beside the job tests on a loaded 2-core machine
  await page.$eval("#map-form input[name=max_period]", (e) => { e.value = "1"; });
  await page.$eval("#map-form input[name=xn]", (e) => { e.value = "30"; });
  await page.$eval("#map-form input[name=yn]", (e) => { e.value = "30"; });
  await page.click("#map-form button[type=submit]");
  const seen = new Set();
  const tj = Date.now();
  while (Date.now() - tj < 240000) {
    const s = await page.evaluate(() => ({ v: document.querySelector("#map-form progress").value,
                                          n: document.querySelectorAll("#map .legend").length }));
    seen.add(s.v);
    if (s.n)
      break;
    await new Promise((r) => setTimeout(r, 200));
  }
  const cells = await page.$$eval("#map rect.cell", (r) => r.length);
  check(cells === 900 && [...seen].some((v) => v > 0 && v < 100),
        "a 30x30 map job finished with progress between (" + [...seen].join(" ") + "): " + cells + " cells " +
        (await shown("#map-panel .error")));
  // basins drawn as their rows arrive: a 256x256 slice is nine chunks of
  // 32 rows after the attractors; some rows are painted while the job runs
  await page.$eval("#basins-form input[name=n]", (e) => { e.value = "256"; });
  await page.click("#basins-form button[type=submit]");
  let midway = null;
  const tb = Date.now();
  while (Date.now() - tb < 120000) {
    const s = await page.evaluate(() => ({
      painted: Number(document.getElementById("basins").dataset.painted || 0),
      rows: Number(document.getElementById("basins").dataset.rows || 0),
      running: !document.querySelector("#basins-form progress").hidden,
      progress: document.querySelector("#basins-form progress").value,
      error: !document.querySelector("#basins-panel .error").hidden }));
    if (!midway && s.running && s.painted > 0 && s.painted < s.rows)
      midway = s;
    if (!s.running || s.error)
      break;
    await new Promise((r) => setTimeout(r, 40));
  }
  const painted = await page.$eval("#basins", (s) => Number(s.dataset.painted || 0));
  check(midway !== null && painted === 256,
        "basins: rows painted while the job runs (" + JSON.stringify(midway) + "), all 256 at its end (" +
        painted + ")" + (await shown("#basins-panel .error")));
  const legend = await page.$$eval("#basins .legend text", (ts) => ts.map((t) => t.textContent));
  check(legend.some((l) => /overshoot/.test(l)), "the basins name the overshoot orbit: " + legend.join("; ") +
        (await shown("#basins-panel .error")));
  await page.screenshot({ path: out + "/explorer-families.png", fullPage: true });

  // 6. axe-core, and 420 px
  const a11y = await browser.newPage();
  await a11y.setBypassCSP(true);
  await a11y.setViewport({ width: 420, height: 900 });
  await a11y.goto(base + "/?" + q + "&open=family", { waitUntil: "networkidle0" });
  await a11y.waitForFunction(() => document.querySelectorAll("#family line.branch").length > 0, { timeout: 60000 });
  await a11y.addScriptTag({ path: require.resolve("axe-core/axe.min.js") });
  const axe = await a11y.evaluate(async () => (await window.axe.run()).violations
    .filter((v) => v.impact === "serious" || v.impact === "critical")
    .map((v) => v.id + " (" + v.impact + "): " + v.nodes.length));
  check(axe.length === 0, "axe-core: no serious or critical violation: " + axe.join("; "));
  const wide = await a11y.evaluate(() => ({
    scroll: document.documentElement.scrollWidth,
    over: [...document.querySelectorAll("body *")].filter((e) => !e.closest(".scroll") &&
      e.getBoundingClientRect().right > window.innerWidth + 0.5).map((e) => e.tagName + "#" + e.id).slice(0, 5) }));
  check(wide.scroll <= 420 && wide.over.length === 0, "at 420 px nothing overflows: " + JSON.stringify(wide));
  await a11y.screenshot({ path: out + "/explorer-420.png", fullPage: true });

  // axes over a span of one ulp (their ticks once looped for ever), on a
  // page of its own that a hang does not take the others with
  const tiny = await browser.newPage();
  await tiny.goto(base + "/", { waitUntil: "domcontentloaded" });
  const nticks = await Promise.race([
    tiny.evaluate(() => {
      const p = Plot.frame(document.getElementById("constraints"),
                           { x: [0.6, 0.6000000000000001], y: [0, 1], exact: true, xlabel: "t", ylabel: "F" });
      return p.svg.querySelectorAll(".axes text").length;
    }),
    new Promise((r) => setTimeout(() => r(-1), 3000))]);
  check(nticks >= 0, "axes over a span of one ulp are drawn (" + nticks + " labels)");
  if (nticks >= 0)
    await tiny.close();

  // the user's guide, served beside the explorer under a policy of its own
  // (the explorer's once stopped mkdocs' inline scripts and styles)
  const guide = await browser.newPage();
  const refused = [];
  guide.on("console", (m) => {
    if (/Content Security Policy/i.test(m.text()))
      refused.push(m.text());
  });
  guide.on("pageerror", (e) => refused.push(e.message));
  const res = await guide.goto(base + "/docs/", { waitUntil: "networkidle0" });
  if (res.status() === 200)
    check(refused.length === 0, "the guide at /docs/ runs its scripts and styles: " +
          refused.slice(0, 2).join("; "));
  else
    console.log("explorer: no guide in this build (/docs/ answered " + res.status() + ")");
  await guide.close();

  console.log("explorer: loaded with the paper's orbit in " + loadMs + " ms; all in " +
              Math.round((Date.now() - t00) / 1000) + " s");
} finally {
  await browser.close();
  if (downloads)
    fs.rmSync(downloads, { recursive: true, force: true });
}
console.log(checks + " checks, " + failures.length + " failures");
process.exit(failures.length ? 1 : 0);
