// Browser test of a flight report (run by ctest): opens REPORT.html in headless Chromium and checks
// that the page loads without console errors, the 3D canvas has drawn something, moving the time
// slider moves the vehicle to where the log says it was, and the plots are present. Saves a
// screenshot to SCREENSHOT.png. Given a benchmark's page too, checks its tables and histograms.
//   node test/report_browser.test.mjs REPORT.html SCREENSHOT.png [BENCH.html]
import { launchBrowser, openReport } from "./browser.mjs";
import { check, finish } from "./check.mjs";

const [reportPath, screenshotPath, benchPath] = process.argv.slice(2);
if (!reportPath || !screenshotPath) {
  console.error("usage: node test/report_browser.test.mjs REPORT.html SCREENSHOT.png");
  process.exit(2);
}

const browser = await launchBrowser();
try {
  const started = Date.now();
  const { page, errors } = await openReport(browser, reportPath);
  console.log(`info page ready in ${Date.now() - started} ms`);

  // The 3D view: a WebGL canvas whose pixels are not all one colour.
  const distinct = await page.evaluate(() => {
    const canvas = document.querySelector("#replay-viewport canvas");
    if (!canvas) return -1;
    const copy = document.createElement("canvas");
    copy.width = canvas.width;
    copy.height = canvas.height;
    const ctx = copy.getContext("2d");
    ctx.drawImage(canvas, 0, 0);
    const pixels = ctx.getImageData(0, 0, copy.width, copy.height).data;
    const colours = new Set();
    for (let i = 0; i < pixels.length; i += 4 * 97) colours.add((pixels[i] << 16) | (pixels[i + 1] << 8) | pixels[i + 2]);
    return colours.size;
  });
  check(distinct > 8, `the 3D canvas is drawn (${distinct} distinct colours sampled)`);

  // The slider, as a user drives it: the keyboard's End key goes to the end of the flight, then a
  // value typed in moves to the instant farthest from the start. The vehicle must be drawn where
  // the log says it was then.
  const slider = page.locator("#time-slider");
  await slider.focus();
  await page.keyboard.press("End");
  const label = await page.locator("#time-label").textContent();
  const end = await page.evaluate(() => window.rotorguardReport.time());
  const duration = await page.evaluate(() => window.rotorguardReport.duration());
  check(Math.abs(end - duration) < 1e-9, `End moves the replay to the end (t = ${end})`);
  check(/t = \d/.test(label || ""), `the time label follows the slider ("${label}")`);
  await page.keyboard.press("Home");
  const before = await page.evaluate(() => window.rotorguardReport.vehiclePosition());
  const target = await page.evaluate(() => {
    const s = JSON.parse(document.getElementById("rotorguard-data").textContent).series;
    let best = 0;
    let far = -1;
    for (let i = 0; i < s.t.length; i += 1) {
      // Instants on the slider's 0.01 s grid, so the slider lands on them exactly.
      if (Math.abs(s.t[i] * 100 - Math.round(s.t[i] * 100)) > 1e-6) continue;
      const d = Math.hypot(s.p_x[i] - s.p_x[0], s.p_y[i] - s.p_y[0], s.p_z[i] - s.p_z[0]);
      if (d > far) [far, best] = [d, i];
    }
    return { t: s.t[best], p: [s.p_x[best], s.p_y[best], s.p_z[best]] };
  });
  await slider.fill(String(target.t));
  const after = await page.evaluate(() => window.rotorguardReport.vehiclePosition());
  const moved = Math.hypot(after[0] - before[0], after[1] - before[1], after[2] - before[2]);
  const offLog = Math.hypot(after[0] - target.p[0], after[1] - target.p[1], after[2] - target.p[2]);
  check(moved > 0.05, `the slider moves the vehicle from its start (${moved.toFixed(3)} m)`);
  check(offLog < 1e-3, `the vehicle is drawn at the log's position for t = ${target.t} s (off by ${offLog.toExponential(2)} m)`);

  // Plots: uPlot charts with drawn canvases.
  const plots = await page.evaluate(() =>
    Array.from(document.querySelectorAll(".uplot canvas")).filter((c) => c.width > 100 && c.height > 50).length);
  check(plots >= 8, `the plots are present (${plots} charts)`);
  const titles = await page.evaluate(() => Array.from(document.querySelectorAll(".plot h3")).map((h) => h.textContent));
  for (const want of ["commanded vs actual thrust", "Rotor speeds", "Position x", "Yaw rate", "Tracking error"]) {
    check(titles.some((t) => t.includes(want)), `a plot titled "...${want}..."`);
  }
  await page.screenshot({ path: screenshotPath, fullPage: false });
  console.log(`info screenshot ${screenshotPath}`);
  check(errors.length === 0, `no console errors${errors.length ? ": " + errors.join(" | ") : ""}`);
  if (benchPath) {
    const { page: bench, errors: benchErrors } = await openReport(browser, benchPath);
    const tables = await bench.locator("table.data").count();
    const histograms = await bench.evaluate(() => Array.from(document.querySelectorAll(".uplot canvas")).filter((c) => c.width > 100).length);
    check(tables >= 2, `the benchmark page has its tables (${tables})`);
    check(histograms >= 1, `the benchmark page has its distributions (${histograms} histograms)`);
    check(benchErrors.length === 0, `no console errors on the benchmark page${benchErrors.length ? ": " + benchErrors.join(" | ") : ""}`);
  }
} finally {
  await browser.close();
}
finish();
