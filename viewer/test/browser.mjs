// The browser tests' headless Chromium (Debian's, driven by playwright-core) and how they open a
// report: one place for the launch options and for what "the page is ready" means.
import { existsSync } from "node:fs";
import { resolve } from "node:path";
import { pathToFileURL } from "node:url";

/** Headless Chromium with software WebGL (CI machines have no GPU); exits 1 when it is missing. */
export async function launchBrowser() {
  let chromium;
  try {
    ({ chromium } = await import("playwright-core"));
  } catch (e) {
    console.error(`FAIL playwright-core is not installed (npm ci in viewer/): ${e.message}`);
    process.exit(1);
  }
  const executablePath = process.env.CHROMIUM || "/usr/bin/chromium";
  if (!existsSync(executablePath)) {
    console.error(`FAIL no Chromium at ${executablePath}: install Debian's chromium (scripts/install-deps.sh) or set CHROMIUM`);
    process.exit(1);
  }
  return chromium.launch({
    executablePath,
    headless: true,
    args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"],
  });
}

/**
 * Opens the report at `path` in a new page and waits until the viewer says it is ready. Returns
 * the page and the console errors it logs (the list keeps growing while the page is open).
 */
export async function openReport(browser, path) {
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  const errors = [];
  page.on("console", (m) => {
    if (m.type() === "error") errors.push(m.text());
  });
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto(pathToFileURL(resolve(path)).href);
  await page.waitForFunction(() => window.rotorguardReport && window.rotorguardReport.ready === true, null, { timeout: 30000 });
  return { page, errors };
}
