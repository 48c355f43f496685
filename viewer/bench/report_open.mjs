// How long a report takes to open: loads REPORT.html RUNS times in headless Chromium (a fresh page
// each time) and prints the file's size and the median time from navigation start until the page
// is drawn (header, 3D replay and every plot). Software WebGL, as on a machine without a GPU.
//   node bench/report_open.mjs REPORT.html [RUNS]      (RUNS defaults to 7)
import { statSync } from "node:fs";
import { resolve } from "node:path";
import { pathToFileURL } from "node:url";
import { launchBrowser } from "../test/browser.mjs";

const [reportPath, runsText = "7"] = process.argv.slice(2);
const runs = Number.parseInt(runsText, 10);
if (!reportPath || !(runs >= 1)) {
  console.error("usage: node bench/report_open.mjs REPORT.html [RUNS >= 1]");
  process.exit(2);
}
const browser = await launchBrowser();
const times = [];
try {
  for (let k = 0; k < runs; k += 1) {
    const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
    await page.goto(pathToFileURL(resolve(reportPath)).href);
    await page.waitForFunction(() => window.rotorguardReport && window.rotorguardReport.ready === true, null, { timeout: 60000 });
    times.push(await page.evaluate(() => window.rotorguardReport.readyMs));
    await page.close();
  }
} finally {
  await browser.close();
}
times.sort((a, b) => a - b);
const median = times[Math.floor((times.length - 1) / 2)];
console.log(JSON.stringify({
  report: reportPath,
  size_mb: statSync(reportPath).size / 1e6,
  runs,
  open_ms_median: Math.round(median),
  open_ms_min: Math.round(times[0]),
  open_ms_max: Math.round(times[times.length - 1]),
}));
