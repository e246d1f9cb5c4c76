// Drives headless Chromium through the studio page of `nec serve` as a user would (see check_studio.sh):
// open the page, upload a rig, write a caption, press Generate, watch the result play, download its BVH.
//
//   node check_studio.mjs URL RIG.bvh OUT_DIR
//
// Checks: the page reaches "ready"; the uploaded rig is picked; the job ends "done"; the result page inside the
// frame loads its clip ("ok") and its canvas changes between two moments (the bones move); the downloaded BVH
// has the rig's joint names in the rig's order; no console error or page error. Writes OUT_DIR/downloaded.bvh
// and OUT_DIR/studio.png (a screenshot). Exit status 1 on the first failed check.
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";
import puppeteer from "puppeteer-core";

const [url, rig, out] = process.argv.slice(2);
const chromium = process.env.NEC_CHROMIUM || "chromium";
const errors = [];

function check(condition, message) {
  if (!condition) throw new Error(message);
  console.log("studio: ok: " + message);
}

function jointNames(bvh) {
  return [...bvh.matchAll(/^\s*(?:ROOT|JOINT)\s+(\S+)/gm)].map((m) => m[1]);
}

async function statusOf(page) {
  return JSON.parse(await page.$eval("#studio-status", (e) => e.textContent));
}

async function waitForState(page, wanted, seconds) {
  const until = Date.now() + seconds * 1000;
  let status;
  while (Date.now() < until) {
    status = await statusOf(page);
    if (wanted.includes(status.state)) return status;
    await new Promise((r) => setTimeout(r, 200));
  }
  throw new Error(`the page stayed "${status && status.state}" for ${seconds} s (waiting for ${wanted})`);
}

const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--window-size=1280,800"],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 800 });
  page.on("console", (message) => { if (message.type() === "error") errors.push("console: " + message.text()); });
  page.on("pageerror", (error) => errors.push("page: " + error.message));
  page.on("requestfailed", (request) => errors.push("request failed: " + request.url()));

  await page.goto(url, { waitUntil: "load" });
  await waitForState(page, ["ready"], 30);
  check(await page.$eval("#rig", (e) => e.options.length >= 10), "the page lists the zoo's rigs");

  const input = await page.$("#rig-file");
  await input.uploadFile(rig);
  await page.click("#upload");
  const uploaded = await waitForState(page, ["uploaded"], 30);
  check((await page.$eval("#rig", (e) => e.value)) === uploaded.rig, "the uploaded rig is picked");

  const caption = await page.$("#captions .caption .text");
  await caption.click({ clickCount: 3 });
  await caption.type("a person walks forward");
  await page.$eval("#captions .caption .seconds", (e) => { e.value = "2"; });
  await page.click("#generate");
  const done = await waitForState(page, ["done", "failed"], 180);
  check(done.state === "done", "the generate job ends done: " + JSON.stringify(done));
  check(done.files.includes("generated.bvh"), "it offers generated.bvh to download");

  // The result plays in the frame: nec view's page reports its clips, and its canvas changes over time.
  const frame = await (await page.waitForSelector("#result")).contentFrame();
  await frame.waitForFunction(() => {
    const s = document.getElementById("nec-status");
    const state = s && JSON.parse(s.textContent).state;
    return state === "ready" || state === "error";
  }, { timeout: 60000 });
  const viewStatus = JSON.parse(await frame.$eval("#nec-status", (e) => e.textContent));
  check(viewStatus.ok === true && viewStatus.clips.length === 1, "the result page loaded its clip: " +
        JSON.stringify({ ok: viewStatus.ok, state: viewStatus.state, errors: viewStatus.errors }));
  const canvas = await frame.$("canvas");
  const first = await canvas.screenshot();
  await new Promise((r) => setTimeout(r, 700));
  const second = await canvas.screenshot();
  check(Buffer.compare(first, second) !== 0, "the canvas changes between two moments 0.7 s apart");
  await page.screenshot({ path: path.join(out, "studio.png") });

  const bvh = await page.evaluate(async (job) => {
    const response = await fetch(`/api/jobs/${job}/files/generated.bvh`);
    return response.ok ? response.text() : "";
  }, done.job);
  writeFileSync(path.join(out, "downloaded.bvh"), bvh);
  const want = jointNames(readFileSync(rig, "utf8"));
  check(JSON.stringify(jointNames(bvh)) === JSON.stringify(want), `the downloaded BVH has the rig's ${want.length} joints`);
  check(errors.length === 0, "no console or page errors" + (errors.length ? ": " + errors.join("; ") : ""));
} catch (error) {
  console.log("studio: FAILED: " + error.message);
  if (errors.length) console.log("studio: errors seen: " + errors.join("; "));
  process.exitCode = 1;
} finally {
  await browser.close();
}
