// The explorer in a real browser (Debian's chromium, headless, driven by
// puppeteer-core) against a live stickslipd:
//   node explorer.test.mjs BASE_URL OUT_DIR
// It checks that the page loads with no console error and no failed
// request, finds the paper's orbit (period 10.2714...), draws both phase
// portraits with its three phases (slip dotted, overshoot solid, stick
// dashed) from samples placed to half a pixel, draws the stick constraints
// and the multipliers inside the unit circle, simulates from a clicked
// state, continues the family (with its grazing point), and shows the
// daemon's own words for a bad parameter; a screenshot of the page on the
// paper's orbit goes to OUT_DIR/explorer.png.
import puppeteer from "puppeteer-core";

const [base, out] = process.argv.slice(2);
const document_has = (texts, word) => texts.some((s) => s.includes(word));
const failures = [];
let checks = 0;
function check(ok, what) {
  checks++;
  if (!ok) {
    failures.push(what);
    console.log("FAIL: " + what);
  } else {
    console.log("ok: " + what);
  }
}

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 1300 });
  const consoleErrors = [], failed = [], problems = [];
  page.on("console", (m) => {
    if (m.type() === "error")
      consoleErrors.push(m.text());
  });
  page.on("pageerror", (e) => consoleErrors.push(e.message));
  page.on("requestfailed", (r) => failed.push(r.url()));
  page.on("response", (r) => {
    if (r.status() >= 400)
      problems.push(r.status() + " " + r.url());
  });

  const t0 = Date.now();
  await page.goto(base + "/", { waitUntil: "networkidle0" });
  await page.waitForFunction(
    () => document.querySelectorAll("#orbits tbody tr").length > 0,
    { timeout: 30000 });
  const loadMs = Date.now() - t0;

  // the paper's orbit, found with no guess
  const rows = await page.$$eval("#orbits tbody tr", (trs) =>
    trs.map((tr) => tr.textContent));
  check(rows.some((r) => r.includes("overshoot") && r.includes("10.2714")),
        "the paper's overshoot orbit (period 10.2714) is listed: " + rows.length + " orbit(s)");

  check(await page.$eval("#error", (e) => e.hidden && getComputedStyle(e).display === "none"),
        "no error shown after a successful search");

  // the portraits: the selected orbit drawn in its three phases, styled
  const seg = await page.evaluate(() => {
    const out = {};
    for (const id of ["portrait2", "portrait1"]) {
      const lines = [...document.querySelectorAll("#" + id + " polyline.curve.selected")];
      out[id] = {
        modes: lines.map((l) => l.dataset.mode),
        dash: lines.map((l) => l.getAttribute("stroke-dasharray")),
        points: lines.map((l) => l.getAttribute("points").trim().split(/\s+/).length),
      };
    }
    return out;
  });
  const out_points = {};
  for (const id of ["portrait2", "portrait1"]) {
    const s = seg[id];
    check(s.modes.join(",") === "slip,overshoot,stick",
          id + ": three segments in the orbit's order, got " + s.modes.join(","));
    out_points[id] = s.points;
    check(s.dash[0] !== "" && s.dash[1] === "" && s.dash[2] !== "" && s.dash[0] !== s.dash[2],
          id + ": slip dotted, overshoot solid, stick dashed (" + JSON.stringify(s.dash) + ")");
    check(s.points.every((n) => n >= 2), id + ": each segment has points: " + s.points);
  }
  // the stick is the straight x2' = V in (x2, x2')
  const stickY = await page.$eval("#portrait2 polyline.curve.selected[data-mode=stick]",
    (l) => [...new Set(l.getAttribute("points").trim().split(/\s+/).map((p) => p.split(",")[1]))]);
  check(stickY.length === 1, "portrait2: the stick is a horizontal line: " + stickY);

  // the constraints of Fig. 4 and the multipliers
  const fig4 = await page.$$eval("#constraints polyline.constraint", (ls) => ls.map((l) => l.dataset.name));
  check(fig4.join(",") === "F1,F2", "the stick constraints F1 and F2 are drawn");
  const mods = await page.$$eval("#multipliers circle.multiplier", (cs) => cs.map((c) => Number(c.dataset.modulus)));
  check(mods.length === 2 && mods.every((m) => Math.abs(m - 0.195452) < 1e-4),
        "two multipliers of modulus 0.19545 inside the unit circle: " + mods);

  // the samples asked for are placed to the plots' pixels
  const status = await page.$eval("#status", (e) => e.textContent);
  check(/points drawn/.test(status), "status: " + status);

  await page.screenshot({ path: out + "/explorer.png", fullPage: false });

  // a click in the (x2, x2') portrait simulates from there
  const box = await (await page.$("#portrait2")).boundingBox();
  await page.mouse.click(box.x + box.width * 0.6, box.y + box.height * 0.5);
  await page.waitForFunction(
    () => /6 of 6 pieces/.test(document.getElementById("status").textContent) ||
          !document.getElementById("error").hidden, { timeout: 60000 });
  const sims = await page.$$eval("#portrait2 polyline.simulated", (ls) => ls.length);
  check(sims >= 6, "a click simulates three periods from the clicked state, drawn piece by " +
        "piece: " + sims + " segments");

  // the family of the selected orbit, down in ur to its grazing
  await page.click("#continue-form button");
  await page.waitForFunction(
    () => document.querySelectorAll("#family line.branch").length > 0 ||
          !document.getElementById("error").hidden, { timeout: 120000 });
  const specials = await page.$$eval("#family circle.special", (cs) => cs.map((c) => c.dataset.type));
  check(specials.includes("grazing"), "the continuation diagram shows its grazing: " + specials);

  // the existence map and the basins of the paper's set (small enough for
  // a daemon built with the sanitizers); a problem instead is reported
  const drawnOrError = (sel) => page.waitForFunction(
    (s) => document.querySelectorAll(s).length > 0 || !document.getElementById("error").hidden,
    { timeout: 120000 }, sel);
  await page.$eval("#map-form input[name=n]", (e) => { e.value = "12"; });
  await page.click("#map-form button");
  await drawnOrError("#map rect.cell");
  const shown = async () => page.$eval("#error", (e) => (e.hidden ? "" : e.textContent));
  const cells = await page.$$eval("#map rect.cell", (rs) => ({
    all: rs.length, stable: rs.filter((r) => r.classList.contains("stable")).length }));
  check(cells.all === 144 && cells.stable > 0,
        "the existence map: " + cells.all + " of 144 cells, " + cells.stable +
        " with a stable orbit " + (await shown()));
  await page.$eval("#basins-form input[name=n]", (e) => { e.value = "32"; });
  await page.click("#basins-form button");
  await drawnOrError("#basins rect.basin");
  const legend = await page.$$eval("#basins-legend li", (ls) => ls.map((l) => l.textContent));
  check(document_has(legend, "overshoot"),
        "the basins name the overshoot orbit: " + legend.join("; ") + " " + (await shown()));

  await page.screenshot({ path: out + "/explorer-families.png", fullPage: true });

  check(consoleErrors.length === 0, "no console error: " + consoleErrors.join("; "));
  check(failed.length === 0, "no failed request: " + failed.join("; "));
  check(problems.length === 0, "no 4xx/5xx answer before the bad input: " + problems.join("; "));

  // a bad parameter: the daemon's words, in an alert
  await page.$eval("input[name=chi]", (e) => { e.value = "2"; });
  await page.click("#find");
  await page.waitForSelector("#error:not([hidden])", { timeout: 10000 });
  const alert = await page.$eval("[role=alert]", (e) => e.textContent);
  check(/chi/.test(alert) && alert.length > 20, "a bad chi shows the daemon's problem: " + alert);

  console.log("explorer: loaded with the paper's orbit in " + loadMs + " ms; points per " +
              "phase of the paper's orbit: " + JSON.stringify(out_points));
} finally {
  await browser.close();
}
console.log(checks + " checks, " + failures.length + " failures");
process.exit(failures.length ? 1 : 0);
