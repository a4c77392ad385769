// isolab's neuroglancer mesh sources in neuroglancer itself: the viewer of the `neuroglancer`
// Python package (its bundled client) and its static file server (HTTP Range requests, which the
// multi-resolution and sharded formats need), started on 127.0.0.1 by tests/reference/ng_viewer.py,
// opened in headless Chromium (Debian's chromium, driven by playwright-core). Two views: the segmentation volume with its unsharded mesh source,
// and the sharded mesh source on its own. Each must load with no console or page error and draw
// the selected segments: its screenshot must differ from the same view with no segment selected.
// Writes target/neuroglancer-<view>.png (by default the views unsharded and sharded).
// Usage: node neuroglancer.mjs PYTHON NG_VIEWER_PY DATA_DIR SEGMENTS(comma-separated) CHROMIUM
//        [NAME=PATH ...] [OUT=DIR]   (views as ng_viewer.py takes them; screenshots into DIR)
import { chromium } from "playwright-core";
import { spawn } from "node:child_process";
import fs from "node:fs";

const [python, viewerScript, dataDir, segmentList] = process.argv.slice(2, 6);
const executablePath = process.argv[6] || process.env.CHROMIUM || "/usr/bin/chromium";
const segments = segmentList.split(",");
// Further arguments: NAME=PATH views (ng_viewer.py's), and OUT=DIR for the screenshots.
const extra = process.argv.slice(7);
const outDir = (extra.find((a) => a.startsWith("OUT=")) || `OUT=${new URL("../../target/", import.meta.url).pathname}`).slice(4);
const viewArgs = extra.filter((a) => !a.startsWith("OUT="));

// The Python side serves the data and the viewers; its first line names the views.
const helper = spawn(python, [viewerScript, dataDir, segmentList, ...viewArgs], { stdio: ["pipe", "pipe", "inherit"] });
const views = await new Promise((resolve, reject) => {
  let text = "";
  helper.stdout.on("data", (d) => {
    text += d;
    if (text.includes("\n")) resolve(JSON.parse(text.split("\n")[0]));
  });
  helper.on("exit", (code) => reject(new Error(`ng_viewer.py exited with ${code}`)));
});

const problems = [];
const browser = await chromium.launch({
  executablePath,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});

async function settle(page) {
  // Neuroglancer has no "done" signal: screenshots until two in a row (a second apart) agree.
  let last = null;
  for (let i = 0; i < 90; i++) {
    await page.waitForTimeout(1000);
    const shot = await page.screenshot();
    if (last && shot.equals(last) && i > 4) return shot;
    last = shot;
  }
  problems.push("the view never settled");
  return last;
}

async function view(name) {
  const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
  // The one error ignored: the browser's own request for /favicon.ico, which neuroglancer's
  // Python server does not have.
  page.on("console", (m) => {
    const where = m.location().url;
    if (m.type() === "error" && !where.endsWith("/favicon.ico")) problems.push(`${name}: console error: ${m.text()} (${where})`);
  });
  page.on("pageerror", (e) => problems.push(`${name}: page error: ${e.message}`));
  // Neuroglancer cancels fetches it no longer needs (a finer level arrived): those are aborts,
  // not failures.
  page.on("requestfailed", (r) => {
    const why = r.failure()?.errorText || "";
    if (why !== "net::ERR_ABORTED") problems.push(`${name}: request failed (${why}): ${r.url()}`);
  });
  page.on("response", (r) => { if (r.status() >= 400) problems.push(`${name}: HTTP ${r.status()}: ${r.url()}`); });
  await page.goto(views[name]);
  const shot = await settle(page);
  await page.close();
  return shot;
}

let checked = 0;
const names = Object.keys(views).filter((n) => !n.endsWith(" (no segment)"));
try {
  for (const name of names) {
    const empty = await view(`${name} (no segment)`);
    const drawn = await view(name);
    fs.mkdirSync(outDir, { recursive: true });
    fs.writeFileSync(`${outDir}/neuroglancer-${name}.png`, drawn);
    // PNG bytes differ if any pixel does; ask for a real difference: compare decoded pixels.
    const page = await browser.newPage();
    const differing = await page.evaluate(async ([a, b]) => {
      const load = async (b64) => {
        const img = new Image();
        img.src = `data:image/png;base64,${b64}`;
        await img.decode();
        const c = document.createElement("canvas");
        c.width = img.width; c.height = img.height;
        const g = c.getContext("2d");
        g.drawImage(img, 0, 0);
        return g.getImageData(0, 0, c.width, c.height).data;
      };
      const [p, q] = [await load(a), await load(b)];
      let n = 0;
      for (let i = 0; i < p.length; i += 4) if (Math.abs(p[i] - q[i]) + Math.abs(p[i + 1] - q[i + 1]) + Math.abs(p[i + 2] - q[i + 2]) > 30) n++;
      return n;
    }, [empty.toString("base64"), drawn.toString("base64")]);
    await page.close();
    if (differing < 2000) problems.push(`${name}: the segments changed only ${differing} pixels of the view`);
    console.log(`${name}: ${differing} pixels drawn by ${segments.length} segments`);
    checked++;
  }
} finally {
  await browser.close();
  helper.stdin.end();
}
if (problems.length || checked !== names.length || checked === 0) {
  console.error(problems.join("\n"));
  process.exit(1);
}
console.log(`neuroglancer drew ${checked} source(s) with no error`);
