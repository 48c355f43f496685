// Browser test of a replay's report (run by ctest in a build with ROS): `rotorguard replay` of a
// bag writes a run folder without the truth; its page must say so, draw the vehicle at the
// stack's estimate, plot no quantity only the simulator knows, and still show the FDD and the
// odometry's own health.
//   node test/report_replay.test.mjs REPLAY_REPORT.html
import { launchBrowser, openReport } from "./browser.mjs";
import { check, finish } from "./check.mjs";

const [reportPath] = process.argv.slice(2);
if (!reportPath) {
  console.error("usage: node test/report_replay.test.mjs REPLAY_REPORT.html");
  process.exit(2);
}

const browser = await launchBrowser();
try {
  const { page, errors } = await openReport(browser, reportPath);
  const seen = await page.evaluate(() => {
    const data = JSON.parse(document.getElementById("rotorguard-data").textContent);
    return {
      columns: Object.keys(data.series),
      last: { t: data.series.t.at(-1), p: ["x", "y", "z"].map((a) => data.series[`est_p_${a}`].at(-1)) },
      badge: document.querySelector(".sub .badge")?.textContent,
      sub: document.querySelector(".sub")?.textContent,
      cards: Array.from(document.querySelectorAll(".card .k")).map((k) => k.textContent),
      plots: Array.from(document.querySelectorAll(".plot h3")).map((h) => h.textContent),
      legends: Array.from(document.querySelectorAll(".plot")).map((p) => p.textContent),
      replay: data.summary.replay,
    };
  });
  check(!seen.columns.includes("p_x") && !seen.columns.some((c) => c.startsWith("thrust_")),
    "the replay's log has no truth columns (p_*, thrust_*)");
  check(seen.columns.includes("est_p_x") && seen.columns.includes("mi_0") && seen.columns.includes("lio_matched"),
    "it has the estimate, the FDD indices and the odometry's health");
  check(seen.badge === "replay", `the header says replay ("${seen.badge}")`);
  check((seen.sub || "").includes("agrees with the recording"), `and the comparison's outcome ("${seen.sub}")`);
  for (const truthCard of ["tracking RMSE", "max error", "estimate RMSE", "min altitude"]) {
    check(!seen.cards.includes(truthCard), `no "${truthCard}" card (it needs the truth)`);
  }
  check(seen.cards.includes("replay vs recording") && seen.cards.includes("FDD"), "the replay's and the FDD's cards");
  check(!seen.plots.some((t) => t.includes("vs truth") || t.includes("actual")), "no plot against the truth or of actual thrust");
  for (const want of ["Motor index", "Propeller index", "matched points per frame", "Rotor 0: commanded thrust", "Position x"]) {
    check(seen.plots.some((t) => t.includes(want)), `a plot titled "...${want}..."`);
  }

  // The vehicle is drawn at the stack's estimate: at the end of the flight, its last row.
  await page.evaluate((t) => window.rotorguardReport.setTime(t), seen.last.t);
  const drawn = await page.evaluate(() => window.rotorguardReport.vehiclePosition());
  const gap = Math.hypot(...drawn.map((v, k) => v - seen.last.p[k]));
  check(gap < 1e-3, `the vehicle is drawn at the estimate (${gap.toExponential(2)} m from the last row's est_p)`);
  check(errors.length === 0, `no console errors${errors.length ? ": " + errors.join(" | ") : ""}`);
} finally {
  await browser.close();
}
finish();
