// End-to-end check of a chainlight report in headless Chromium (playwright-core driving
// /usr/bin/chromium): images decode, the comparison slider moves, zoom and pan stay in sync
// across the panes, the pixel inspector and exposure respond, no request leaves the file.
// Usage: node scripts/browser/report_check.mjs REPORT.html SCREENSHOT.png
// Prints one JSON line with what it measured; exit code 0 when every check holds, 1 otherwise.
import { chromium } from "playwright-core";
import { pathToFileURL } from "node:url";
import path from "node:path";

const [report, screenshot] = process.argv.slice(2);
if (!report || !screenshot) {
  console.error("usage: report_check.mjs REPORT.html SCREENSHOT.png");
  process.exit(2);
}
const failures = [];
const check = (ok, what) => { if (!ok) failures.push(what); };
const external = [];
const pageErrors = [];

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  timeout: 30000,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const result = {};
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  page.setDefaultTimeout(10000);
  page.on("pageerror", (e) => pageErrors.push(String(e)));
  await page.route("**/*", (route) => {
    const url = route.request().url();
    if (url.startsWith("file:") || url.startsWith("data:")) return route.continue();
    external.push(url);
    return route.abort();
  });
  await page.goto(pathToFileURL(path.resolve(report)).href, { waitUntil: "load" });

  // Images decode: every <img> has loaded with a positive natural size.
  const imgs = await page.$$eval("img", (els) => els.map((e) => ({ ok: e.complete && e.naturalWidth > 0, alt: e.alt })));
  result.images = imgs.length;
  check(imgs.length > 0, "the report has no <img>");
  for (const i of imgs) check(i.ok, `image did not decode: ${i.alt}`);
  // The float data decoded and was painted: the A canvas is not all black.
  const lit = () => page.$eval("#view-a canvas", (c) => {
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let s = 0; for (let i = 0; i < d.length; i += 4) s += d[i] + d[i + 1] + d[i + 2];
    return s / (c.width * c.height);
  });
  result.brightness = await lit();
  check(result.brightness > 0, "canvas A is black: pixel data did not decode");
  check(await page.$eval("#convergence-plot", (e) => e.tagName === "DIV" ? e.querySelector("svg") !== null : true), "convergence SVG missing");

  // Zoom stays in sync: zoom with the button and the wheel, pan by dragging pane A.
  const transforms = () => page.$$eval("#view-a canvas, #view-b canvas, #view-s canvas", (cs) => cs.map((c) => c.style.transform));
  const before = await transforms();
  await page.click("#zoom-in");
  const boxB = await page.locator("#view-b").boundingBox();
  await page.mouse.move(boxB.x + 100, boxB.y + 120);
  await page.mouse.wheel(0, -200);
  await page.waitForTimeout(100);
  const boxA = await page.locator("#view-a").boundingBox();
  await page.mouse.move(boxA.x + 240, boxA.y + 240);
  await page.mouse.down();
  await page.mouse.move(boxA.x + 200, boxA.y + 190, { steps: 4 });
  await page.mouse.up();
  const after = await transforms();
  result.transform = after[0];
  check(after.every((t) => t === after[0]), `zoom/pan out of sync: ${JSON.stringify(after)}`);
  check(after[0] !== before[0] && /scale\((?!1\))/.test(after[0]), `zoom did not change the view: ${after[0]}`);

  // Pixel inspection.
  await page.mouse.move(boxA.x + 150, boxA.y + 150);
  result.inspect = await page.textContent("#inspect");
  check(/pixel \(\d+, \d+\)/.test(result.inspect) && /reference/.test(result.inspect), `inspector: ${result.inspect}`);

  // Exposure brightens the image.
  await page.click("#zoom-reset");
  const dim = await lit();
  await page.$eval("#exposure", (e) => { e.value = "2"; e.dispatchEvent(new Event("input")); });
  const bright = await lit();
  check(bright > dim, `exposure +2 EV did not brighten (${dim} -> ${bright})`);
  await page.$eval("#exposure", (e) => { e.value = "0"; e.dispatchEvent(new Event("input")); });

  // The slider: switch mode, click a quarter of the way along the range input.
  await page.check("#mode-slider");
  check(await page.isVisible("#view-s"), "slider view not shown");
  const clip0 = await page.$eval("#slider-top", (e) => e.style.clipPath);
  const range = await page.locator("#slider").boundingBox();
  await page.mouse.click(range.x + range.width * 0.25, range.y + range.height / 2);
  const value = Number(await page.$eval("#slider", (e) => e.value));
  const clip1 = await page.$eval("#slider-top", (e) => e.style.clipPath);
  result.slider = { value, clip: clip1 };
  check(value > 10 && value < 40 && clip1 !== clip0, `slider did not move: ${value}, ${clip0} -> ${clip1}`);
  // Zoom in slider mode keeps both layers together.
  await page.click("#zoom-in");
  const layers = await page.$$eval("#view-s canvas", (cs) => cs.map((c) => c.style.transform));
  check(layers.length === 2 && layers[0] === layers[1], `slider layers out of sync: ${layers}`);
  await page.click("#zoom-reset");
  await page.$eval("#slider", (e) => { e.value = "50"; e.dispatchEvent(new Event("input")); });

  await page.screenshot({ path: screenshot, fullPage: true });
  result.screenshot = screenshot;
} catch (e) {
  failures.push(`driver error: ${e && e.message ? e.message : e}`);
} finally {
  await browser.close();
}
for (const u of external) failures.push(`external request blocked: ${u}`);
for (const e of pageErrors) failures.push(`page error: ${e}`);
result.failures = failures;
console.log(JSON.stringify(result));
process.exit(failures.length ? 1 : 0);
