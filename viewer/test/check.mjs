// Drives the built viewer in Debian's headless Chromium through Playwright (playwright-core:
// no browser download). Prints one JSON object: load time, the leg end points, leg bodies, pose
// and joints at their limits (computed and as drawn) at the requested times; the page as
// shown (the plots' ranges, time ticks and keys, the force colour scale and its legend, the
// dataset menu, the message line); console errors; and the messages for a file that is not a
// platform result and for results whose pose is not a number (NaN) from the first row or later.
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
const shown = await page.evaluate(() => {
  const v = window.stewartViewer;
  return { plots: v.plots(), forceScale: v.forceScale(), legend: v.legend(), datasets: v.datasets(), message: v.message(), info: v.info() };
});
const badFile = await page.evaluate(() => {
  window.stewartViewer.load('"time","r[1]","x"\n0,1,2\n', null);
  return { error: window.stewartViewer.error(), shown: document.getElementById("message").textContent };
});
// A result whose pose turns NaN at its fourth row, and one that is NaN from the first.
const pose = (z) => `${z},1,0,0,0,1,0,0,0,1`;
const header = '"time","r[1]","r[2]","r[3]","R[1,1]","R[1,2]","R[1,3]","R[2,1]","R[2,2]","R[2,3]","R[3,1]","R[3,2]","R[3,3]"\n';
const nan = await page.evaluate(([head, rowsText, firstText]) => {
  const v = window.stewartViewer;
  v.load(head + rowsText, null);
  const later = { error: v.error(), message: v.message(), rows: v.rows() };
  v.load(head + firstText, null);
  return { later, first: { error: v.error(), message: v.message() } };
}, [header, ["0,0,0," + pose(1.9), "0.1,0,0," + pose(1.9), "0.2,0,0," + pose(1.9), "0.3,0,nan," + pose(1.9), "0.4,0,0," + pose(1.9)].join("\n"),
    "0,0,0," + pose("nan") + "\n0.1,0,0," + pose(1.9) + "\n"]);
await browser.close();
console.log(JSON.stringify({ loadSeconds, loadError, rows, samples, shown, errors, badFile, nan }));
