// Opens the status page in Debian's Chromium (headless, through playwright-core from
// modules/inspect/js/node_modules: one pinned copy for the project, no browser download) and says what
// an operator would see: console messages, page errors, failed requests, the top line, the problems
// and every module's row (its level and cells).
// Usage: node status_page_check.mjs URL [--screenshot OUT.png] [--watch MODULE] [--timeout-s S]
//                                        [--restart MODULE --token TOKEN [--wrong-token WRONG]] [--images]
//                                        [--set-condition CONDITION --token TOKEN]
//                                        [--calibrate --token TOKEN [--calibration-shows WORDS]]
//   --images: waits until the camera frame and the projector image have loaded and reports their
//   natural widths and captions in "images".
//   --watch MODULE: once MODULE's row says "up", prints "watching" on stderr, then records every change
//   of the row's state, level and restarts until it has restarted and is up again (or the timeout): the test kills the module meanwhile.
//   --restart MODULE: the same watch, but the restart is the page's own: it types WRONG (when given) into
//   the token field and presses the module's restart button (the answer goes to "refused"), then TOKEN and
//   presses it again (the answer goes to "action").
//   --set-condition CONDITION: types TOKEN, chooses CONDITION in the display condition control and presses
//   "Set" (the answer goes to "set_condition"), then waits until the round's condition on the page (from
//   round_t, i.e. what projection reports it shows) reads CONDITION ("condition_after").
//   --calibrate: types TOKEN and presses "Calibrate now" twice: the first confirmation is dismissed (no
//   request may follow: "posts_after_dismiss" counts the POSTs to /action until then), the second accepted
//   (the answer goes to "calibrate"); "dialogs" are the confirmations' words; then waits until the
//   calibration line says WORDS (--calibration-shows WORDS; without it: until it changes) and reports it
//   ("calibration_line"); then presses "Correct the scale with blocks", accepted (its answer: "scale").
// Prints one JSON object on stdout; exits 2 when the browser cannot be started or the page not opened.
import { createRequire } from "node:module";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, "..", "..", "inspect", "js", "package.json"));
let chromium;
try {
  ({ chromium } = require("playwright-core"));
} catch (e) {
  console.error("status_page_check: playwright-core is not installed: run npm ci in modules/inspect/js (" + e.message + ")");
  process.exit(2);
}

const args = process.argv.slice(2);
const url = args[0];
const option = (name) => (args.indexOf(name) >= 0 ? args[args.indexOf(name) + 1] : undefined);
if (!url) {
  console.error("usage: node status_page_check.mjs URL [--screenshot OUT.png] [--watch MODULE] [--timeout-s S]");
  process.exit(2);
}
const timeout_ms = 1000 * Number(option("--timeout-s") ?? 30);
let browser;
try {
  browser = await chromium.launch({
    executablePath: option("--chromium") ?? "/usr/bin/chromium",
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
           "--disable-component-update", "--disable-sync"],
  });
} catch (e) {
  console.error(`status_page_check: cannot start Chromium: ${e.message}`);
  process.exit(2);
}
const result = { console: [], errors: [], failed_requests: [], transitions: [], dialogs: [] };
let actionPosts = 0;
const rows = (page) => page.evaluate(() => [...document.querySelectorAll("tr[data-module]")].map((r) => ({
  module: r.dataset.module, level: r.className, cells: [...r.cells].map((c) => c.textContent) })));
try {
  // A phone's width: the page is meant for one.
  const page = await browser.newPage({ viewport: { width: 420, height: 900 }, deviceScaleFactor: 2 });
  page.on("console", (m) => result.console.push({ type: m.type(), text: m.text() }));
  page.on("pageerror", (e) => result.errors.push(String(e)));
  page.on("requestfailed", (r) => result.failed_requests.push(r.url().slice(0, 120)));
  page.on("request", (r) => { if (r.method() === "POST" && r.url().endsWith("/action")) ++actionPosts; });
  // Confirmations: dismissed while acceptDialogs is false (the operator's "Cancel"), else accepted.
  let acceptDialogs = false;
  page.on("dialog", async (d) => {
    result.dialogs.push(d.message());
    await (acceptDialogs ? d.accept() : d.dismiss());
  });
  await page.goto(url, { waitUntil: "load" });
  result.title = await page.title();
  // The first answer of /state.json has been drawn once a module row is there.
  await page.waitForSelector("tr[data-module]", { timeout: timeout_ms });
  const restart = option("--restart");
  const watch = option("--watch") ?? restart;
  const press = async (token, selector = `tr[data-module="${restart}"] button`) => {
    await page.fill("#token", token);
    await page.dispatchEvent("#token", "change");
    const before = await page.textContent("#action-result");
    await page.click(selector);
    // The answer replaces the result line (the same words twice would not show a change: clear first).
    await page.waitForFunction((b) => document.querySelector("#action-result").textContent !== b, before, { timeout: 10000 });
    const text = await page.textContent("#action-result");
    await page.evaluate(() => { document.querySelector("#action-result").textContent = ""; });
    return text;
  };
  if (watch) {
    const seen = async () => {
      const r = (await rows(page)).find((x) => x.module === watch);
      return r ? { state: r.cells[1], level: r.level, restarts: Number(r.cells[2]) } : { state: "absent", level: "absent", restarts: -1 };
    };
    const end = Date.now() + timeout_ms;
    while ((await seen()).state !== "up" && Date.now() < end) await page.waitForTimeout(100);
    let last = await seen();
    result.transitions.push(last);
    console.error("watching");
    if (restart) {
      if (option("--wrong-token") !== undefined) result.refused = await press(option("--wrong-token"));
      result.action = await press(option("--token") ?? "");
    }
    // A restart faster than the launcher's once-a-second state may never show as "restarting": the
    // restart count going up says it happened.
    const first = last.restarts;
    while (Date.now() < end && !(last.restarts > first && last.state === "up")) {
      await page.waitForTimeout(100);
      const now = await seen();
      if (now.state !== last.state || now.level !== last.level || now.restarts !== last.restarts) {
        result.transitions.push(now);
        last = now;
      }
    }
  }
  const condition = option("--set-condition");
  if (condition) {
    await page.selectOption("#condition-choice", condition);
    result.set_condition = await press(option("--token") ?? "", 'button[data-action="set_condition"]');
    await page.waitForFunction((c) => document.getElementById("condition").textContent === c, condition,
      { timeout: timeout_ms });
    result.condition_after = await page.textContent("#condition");
  }
  if (args.includes("--calibrate")) {
    const line = await page.textContent("#calibration");
    await page.fill("#token", option("--token") ?? "");
    await page.dispatchEvent("#token", "change");
    await page.click('button[data-action="calibrate"]:not([data-step])');  // confirm() returns once the dialog is dismissed
    result.posts_after_dismiss = actionPosts;
    acceptDialogs = true;
    result.calibrate = await press(option("--token") ?? "", 'button[data-action="calibrate"]:not([data-step])');
    // The calibrate node's answer comes in its next heartbeat: wait for the words asked for, else any change.
    await page.waitForFunction(([b, want]) => {
      const now = document.getElementById("calibration").textContent;
      return want ? now.includes(want) : now !== b;
    }, [line, option("--calibration-shows")], { timeout: timeout_ms });
    result.calibration_line = await page.textContent("#calibration");
    // The scale step's button (accepted): its own confirmation, its own request.
    result.scale = await press(option("--token") ?? "", 'button[data-action="calibrate"][data-step="scale-from-blocks"]');
  }
  result.action_posts = actionPosts;
  if (args.includes("--images")) {
    await page.waitForFunction(() => ["camera-img", "projector-img"].every((id) => document.getElementById(id).naturalWidth > 0),
      null, { timeout: timeout_ms });
    result.images = await page.evaluate(() => Object.fromEntries(["camera", "projector"].map((n) => [n, {
      natural_width: document.getElementById(n + "-img").naturalWidth,
      caption: document.getElementById(n + "-age").textContent }])));
    result.condition = await page.textContent("#condition");
  }
  result.overall = await page.textContent("#overall");
  result.problems = await page.evaluate(() => [...document.querySelectorAll("#problems li")].map((l) => l.textContent));
  result.rows = await rows(page);
  const shot = option("--screenshot");
  if (shot) await page.screenshot({ path: shot, fullPage: true });
} catch (e) {
  console.error(`status_page_check: ${e.message}`);
  await browser.close();
  process.exit(2);
}
await browser.close();
console.log(JSON.stringify(result));
