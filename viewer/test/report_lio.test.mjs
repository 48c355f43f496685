// Browser test of the report's localisation section (run by ctest): a flight on the stack's
// LiDAR-inertial odometry gets the section, with its estimate-against-truth and health plots drawn
// and the degeneracy threshold taken from its summary; a flight on another estimator (its log has
// no lio_* columns) has neither the section nor its header cards.
//   node test/report_lio.test.mjs LIO_REPORT.html OTHER_REPORT.html
import { launchBrowser, openReport } from "./browser.mjs";
import { check, finish } from "./check.mjs";

const [lioPath, otherPath] = process.argv.slice(2);
if (!lioPath || !otherPath) {
  console.error("usage: node test/report_lio.test.mjs LIO_REPORT.html OTHER_REPORT.html");
  process.exit(2);
}

const HEADING = "Localisation (LiDAR-inertial odometry)";

/** Opens a report and returns what the checks need: its headings, cards, the section's plots, the data. */
async function open(browser, path) {
  const { page, errors } = await openReport(browser, path);
  const seen = await page.evaluate((heading) => {
    const data = JSON.parse(document.getElementById("rotorguard-data").textContent);
    const cards = Array.from(document.querySelectorAll(".card .k")).map((k) => k.textContent);
    const h2 = Array.from(document.querySelectorAll("h2"));
    const section = h2.find((h) => h.textContent === heading);
    const plots = [];
    let note = null;
    // The section runs from its heading to the next one.
    for (let e = section ? section.nextElementSibling : null; e && e.tagName !== "H2"; e = e.nextElementSibling) {
      if (e.classList.contains("note")) note = e.textContent;
      for (const box of e.querySelectorAll(".plot")) {
        const canvas = box.querySelector(".uplot canvas");
        plots.push({ title: box.querySelector("h3").textContent, drawn: !!canvas && canvas.width > 100 && canvas.height > 50 });
      }
    }
    return {
      headings: h2.map((h) => h.textContent),
      cards,
      plots,
      note,
      columns: Object.keys(data.series).filter((c) => c.startsWith("lio_")),
      odometry: data.summary.odometry ?? null,
    };
  }, HEADING);
  await page.close();
  return { ...seen, errors };
}

const browser = await launchBrowser();
try {
  const lio = await open(browser, lioPath);
  check(lio.columns.length === 5, `the LIO flight's data has the lio_* columns (${lio.columns.join(", ")})`);
  check(lio.headings.includes(HEADING), `the LIO flight's page has the section "${HEADING}"`);
  for (const want of ["Estimate vs truth: x", "Estimate vs truth: y", "Estimate vs truth: z", "Estimate error: position",
    "Estimate error: attitude", "matched points", "residual RMS", "weakest direction"]) {
    const plot = lio.plots.find((p) => p.title.includes(want));
    check(plot !== undefined && plot.drawn, `the section has a drawn plot titled "...${want}..."`);
  }
  const threshold = lio.odometry && lio.odometry.degenerate_std_m;
  check(typeof threshold === "number" && threshold > 0, `the summary carries the degeneracy threshold (${threshold})`);
  check(lio.plots.some((p) => p.title.includes(`degenerate above ${threshold} m`)),
    "the weakest-direction plot draws the summary's threshold");
  check(lio.note !== null && lio.note.includes(`${lio.odometry.frames} frames`), `the section states the odometry's figures ("${lio.note}")`);
  for (const want of ["estimate RMSE", "LIO frames"]) check(lio.cards.includes(want), `the header has the card "${want}"`);
  check(lio.errors.length === 0, `no console errors on the LIO flight's page${lio.errors.length ? ": " + lio.errors.join(" | ") : ""}`);

  const other = await open(browser, otherPath);
  check(other.columns.length === 0, "the other flight's data has no lio_* columns");
  check(other.headings.length > 0 && !other.headings.includes(HEADING), `the other flight's page has no "${HEADING}"`);
  check(!other.cards.includes("LIO frames"), "nor the odometry's header cards");
  check(other.errors.length === 0, `no console errors on the other flight's page${other.errors.length ? ": " + other.errors.join(" | ") : ""}`);
} finally {
  await browser.close();
}
finish();
