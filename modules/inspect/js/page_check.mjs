// Opens a report page in Debian's Chromium (headless, through playwright-core: no browser download)
// and says what a person would see: console messages and page errors, and for every plot whether its
// image decoded and how many of its pixels are coloured (data: gnuplot draws axes and text in black
// and grey, the data in colour). Optionally saves a screenshot.
// Usage: node page_check.mjs PAGE.html [--screenshot OUT.png [--full-page]] [--chromium /usr/bin/chromium]
// Prints one JSON object on stdout; exits 2 when the browser cannot be started or the page not opened.
import { pathToFileURL } from "node:url";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
const page_path = args[0];
const option = (name) => (args.indexOf(name) >= 0 ? args[args.indexOf(name) + 1] : undefined);
if (!page_path) {
  console.error("usage: node page_check.mjs PAGE.html [--screenshot OUT.png] [--chromium PATH]");
  process.exit(2);
}
let browser;
try {
  browser = await chromium.launch({
    executablePath: option("--chromium") ?? "/usr/bin/chromium",
    // The flags this machine kind needs: no sandbox as root, no GPU, and no background connections
    // (the closed network refuses them).
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
           "--disable-component-update", "--disable-sync"],
  });
} catch (e) {
  console.error(`page_check: cannot start Chromium: ${e.message}`);
  process.exit(2);
}
const result = { console: [], errors: [], failed_requests: [], images: [] };
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 1400 } });
  page.on("console", (m) => result.console.push({ type: m.type(), text: m.text() }));
  page.on("pageerror", (e) => result.errors.push(String(e)));
  page.on("requestfailed", (r) => result.failed_requests.push(r.url().slice(0, 120)));
  await page.goto(pathToFileURL(page_path).href, { waitUntil: "load" });
  result.title = await page.title();
  result.images = await page.evaluate(async () => {
    const out = [];
    for (const img of document.querySelectorAll("img")) {
      try {
        await img.decode();
      } catch {
        // reported below as naturalWidth 0
      }
      let coloured = 0;
      if (img.naturalWidth > 0) {
        const canvas = document.createElement("canvas");
        canvas.width = img.naturalWidth;
        canvas.height = img.naturalHeight;
        const ctx = canvas.getContext("2d");
        ctx.drawImage(img, 0, 0);
        const px = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
        for (let i = 0; i < px.length; i += 4) {
          const r = px[i], g = px[i + 1], b = px[i + 2];
          if (Math.max(r, g, b) - Math.min(r, g, b) > 60) ++coloured;
        }
      }
      out.push({ id: img.id, alt: img.alt, width: img.naturalWidth, height: img.naturalHeight, coloured });
    }
    return out;
  });
  result.tables = await page.evaluate(() => [...document.querySelectorAll("table")].map((t) => ({ id: t.id, rows: t.tBodies[0]?.rows.length ?? 0 })));
  const shot = option("--screenshot");
  if (shot) await page.screenshot({ path: shot, fullPage: args.includes("--full-page") });
} catch (e) {
  console.error(`page_check: ${e.message}`);
  await browser.close();
  process.exit(2);
}
await browser.close();
console.log(JSON.stringify(result));
