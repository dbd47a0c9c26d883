// Drives the built viewer in Debian's headless Chromium through Playwright (playwright-core:
// no browser download). Prints one JSON object: load time, the leg end points, leg bodies, pose
// and joints at their limits (computed and as drawn) at the requested times, console errors,
// and the message for a file that is not a platform result.
//
//   node viewer/test/check.mjs <page url> <screenshot.png> <t1,t2,...>
import { chromium } from "playwright-core";

const [url, screenshot, timesArg] = process.argv.slice(2);
const times = timesArg.split(",").map(Number);
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});
const page = await browser.newPage({ viewport: { width: 1200, height: 760 } });
const errors = [];
page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
page.on("pageerror", (e) => errors.push(String(e)));
const start = Date.now();
await page.goto(url);
await page.waitForFunction(() => window.stewartViewer && window.stewartViewer.isReady(), null, { timeout: 60000 });
const loadSeconds = (Date.now() - start) / 1000;
const loadError = await page.evaluate(() => window.stewartViewer.error());
const samples = [];
for (const t of times) {
  samples.push(await page.evaluate((tt) => {
    window.stewartViewer.seek(tt);
    const v = window.stewartViewer;
    return { t: tt, time: v.time(), ends: v.legEndpoints(), pose: v.pose(), bodies: v.legBodies(), jointsAtLimit: v.jointsAtLimit(), highlighted: v.highlightedJoints() };
  }, t));
}
await page.evaluate((t) => window.stewartViewer.seek(t), times[times.length - 1]);
await page.waitForTimeout(300); // a few frames
await page.screenshot({ path: screenshot });
const rows = await page.evaluate(() => window.stewartViewer.rows());
const badFile = await page.evaluate(() => {
  window.stewartViewer.load('"time","r[1]","x"\n0,1,2\n', null);
  return { error: window.stewartViewer.error(), shown: document.getElementById("message").textContent };
});
await browser.close();
console.log(JSON.stringify({ loadSeconds, loadError, rows, samples, errors, badFile }));
