// The report's interactive page in a real headless Chromium (Debian's chromium, driven by
// playwright-core): served over HTTP, it must load with no console error or page error, draw a
// mesh in both views (pixels that differ from the background), and load every listed mesh with
// the triangle count the report lists. Then every control is used: each input in turn, each
// side's extractor, the wireframe and each colouring (each must change the picture), the
// captions must give the measures, and the address must keep the view (a second page opened at
// that address shows the same). Writes a screenshot to target/browser-check.png.
// Usage: node check.mjs [report directory] [chromium path]
import { chromium } from "playwright-core";
import http from "node:http";
import fs from "node:fs";
import path from "node:path";

const root = path.resolve(process.argv[2] || new URL("../../report", import.meta.url).pathname);
const executablePath = process.argv[3] || process.env.CHROMIUM || "/usr/bin/chromium";
const types = { ".html": "text/html", ".js": "text/javascript", ".glb": "model/gltf-binary", ".md": "text/markdown", ".png": "image/png" };
const server = http.createServer((req, res) => {
  const file = path.join(root, decodeURIComponent(new URL(req.url, "http://x").pathname));
  if (!file.startsWith(root) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    res.writeHead(404).end();
    return;
  }
  res.writeHead(200, { "content-type": types[path.extname(file)] || "application/octet-stream" });
  fs.createReadStream(file).pipe(res);
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const url = `http://127.0.0.1:${server.address().port}/index.html`;

const problems = [];
const browser = await chromium.launch({
  executablePath,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  page.on("console", (m) => { if (m.type() === "error") problems.push(`console error: ${m.text()}`); });
  page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
  page.on("requestfailed", (r) => problems.push(`request failed: ${r.url()}`));
  page.on("response", (r) => { if (r.status() >= 400) problems.push(`HTTP ${r.status()}: ${r.url()}`); });
  await page.goto(url);
  await page.waitForFunction(() => ["ready", "error", "file"].includes(document.body.dataset.status), null, { timeout: 60000 });
  const status = await page.evaluate(() => [document.body.dataset.status, document.getElementById("status").textContent]);
  if (status[0] !== "ready") problems.push(`viewer status ${status[0]}: ${status[1]}`);
  // Each view must show a mesh: count pixels unlike the background (the canvases keep their buffer).
  const drawn = await page.evaluate(() => ["canvas-left", "canvas-right"].map((id) => {
    const c = document.getElementById(id);
    const t = document.createElement("canvas");
    t.width = c.width; t.height = c.height;
    const g = t.getContext("2d");
    g.drawImage(c, 0, 0);
    const px = g.getImageData(0, 0, t.width, t.height).data;
    let n = 0;
    for (let i = 0; i < px.length; i += 4) if (Math.abs(px[i] - 246) + Math.abs(px[i + 1] - 246) + Math.abs(px[i + 2] - 246) > 30) n++;
    return n / (px.length / 4);
  }));
  drawn.forEach((f, k) => { if (!(f > 0.02)) problems.push(`view ${k}: only ${(100 * f).toFixed(2)}% of pixels show a mesh`); });
  fs.mkdirSync(new URL("../../target", import.meta.url).pathname, { recursive: true });
  const shot = new URL("../../target/browser-check.png", import.meta.url).pathname;
  await page.screenshot({ path: shot });
  // Every mesh the page lists loads, with the listed triangle count.
  const loaded = status[0] !== "ready" ? { count: -1, bad: [] } : await page.evaluate(async () => {
    const loader = new THREE.GLTFLoader();
    const bad = [];
    for (const m of window.ISOLAB_MESHES) {
      try {
        const gltf = await loader.loadAsync(m.path);
        let triangles = 0;
        gltf.scene.traverse((o) => { if (o.isMesh) triangles += o.geometry.index.count / 3; });
        if (triangles !== m.triangles) bad.push(`${m.path}: ${triangles} triangles, listed ${m.triangles}`);
      } catch (e) {
        bad.push(`${m.path}: ${e.message}`);
      }
    }
    return { count: window.ISOLAB_MESHES.length, bad };
  });
  problems.push(...loaded.bad);
  if (loaded.count === 0) problems.push("the page lists no meshes");
  const settle = () => page.waitForTimeout(300);
  const ready = async () => {
    await page.waitForFunction(() => document.body.dataset.status !== "loading", null, { timeout: 60000 });
    await page.waitForFunction(() => ["ready", "error"].includes(document.body.dataset.status), null, { timeout: 60000 });
  };
  // The captions give each mesh's measures.
  const captions = await page.evaluate(() => ["label-left", "label-right"].map((id) => document.getElementById(id).textContent));
  captions.forEach((c, k) => { if (!/closed (yes|no), manifold (yes|no), \d+ self-intersecting pairs; aspect ratio mean/.test(c)) problems.push(`caption ${k} lacks the measures: ${c}`); });
  captions.forEach((c, k) => { if (!/ at \d+ samples along the longest side: /.test(c)) problems.push(`caption ${k} lacks the mesh's resolution: ${c}`); });
  // A picture's signature: the left view's mean colour over its pixels.
  const signature = () => page.evaluate(() => {
    const c = document.getElementById("canvas-left");
    const t = document.createElement("canvas");
    t.width = c.width; t.height = c.height;
    const g = t.getContext("2d");
    g.drawImage(c, 0, 0);
    const px = g.getImageData(0, 0, t.width, t.height).data;
    const sum = [0, 0, 0];
    for (let i = 0; i < px.length; i += 4) for (let k = 0; k < 3; k++) sum[k] += px[i + k];
    return sum.map((v) => v / (px.length / 4));
  });
  const differ = (a, b) => a.some((v, k) => Math.abs(v - b[k]) > 0.05);
  // Each colouring changes the picture, on a mesh with something to mark (open, non-manifold or
  // self-intersecting) shown on the left.
  const flawed = await page.evaluate(() => window.ISOLAB_MESHES.find((m) => !m.closed || !m.manifold || m.intersecting_pairs > 0));
  if (!flawed) problems.push("no listed mesh has a defect to mark");
  else {
    await page.selectOption("#input", flawed.input);
    await ready();
    await page.selectOption("#left", flawed.algorithm);
    await ready();
    await settle();
  }
  const plain = await signature();
  const looks = { plain };
  for (const mode of ["quality", "defects"]) {
    await page.selectOption("#colour", mode);
    await settle();
    looks[mode] = await signature();
    if (!differ(looks[mode], plain)) problems.push(`colouring '${mode}' does not change the picture`);
    // Each colouring says what its colours mean.
    const key = await page.evaluate(() => document.getElementById("legend").textContent);
    const wanted = mode === "quality" ? /radius ratio/ : /open edge.*non-manifold.*self-intersecting/;
    if (!wanted.test(key)) problems.push(`colouring '${mode}' has no legend: '${key}'`);
  }
  await page.selectOption("#colour", "plain");
  await settle();
  // Turning the wireframe off changes the picture.
  const before = await signature();
  await page.click("#wireframe");
  await settle();
  if (!differ(await signature(), before)) problems.push("the wireframe toggle does not change the picture");
  // Each input in turn, then each side's extractor: the viewer comes back ready.
  const inputs = await page.evaluate(() => Array.from(document.getElementById("input").options).map((o) => o.value));
  for (const input of inputs) {
    await page.selectOption("#input", input);
    await ready();
    const st = await page.evaluate(() => document.body.dataset.status + ": " + document.getElementById("status").textContent);
    if (!st.startsWith("ready")) problems.push(`input ${input}: ${st}`);
  }
  for (const side of ["#left", "#right"]) {
    const values = await page.evaluate((s) => Array.from(document.querySelector(s).options).map((o) => o.value), side);
    await page.selectOption(side, values[1]);
    await ready();
  }
  await page.selectOption("#colour", "quality");
  await settle();
  // The address keeps the view: a second page opened there shows the same controls.
  const address = page.url();
  const shown = await page.evaluate(() => ({ input: document.getElementById("input").value, left: document.getElementById("left").value,
    right: document.getElementById("right").value, colour: document.getElementById("colour").value,
    wire: document.getElementById("wireframe").checked }));
  if (!address.includes("#") || !address.includes("input=" + encodeURIComponent(shown.input).replace(/%20/g, "+"))) problems.push(`the address does not keep the view: ${address}`);
  const second = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  second.on("console", (m) => { if (m.type() === "error") problems.push(`console error (linked view): ${m.text()}`); });
  second.on("pageerror", (e) => problems.push(`page error (linked view): ${e.message}`));
  await second.goto(address);
  await second.waitForFunction(() => ["ready", "error", "file"].includes(document.body.dataset.status), null, { timeout: 60000 });
  const linked = await second.evaluate(() => ({ input: document.getElementById("input").value, left: document.getElementById("left").value,
    right: document.getElementById("right").value, colour: document.getElementById("colour").value,
    wire: document.getElementById("wireframe").checked }));
  if (JSON.stringify(linked) !== JSON.stringify(shown)) problems.push(`the linked view differs: ${JSON.stringify(linked)} against ${JSON.stringify(shown)}`);
  await second.screenshot({ path: new URL("../../target/browser-check-linked.png", import.meta.url).pathname });
  console.log(`index.html: status ${status[0]}, mesh pixels ${drawn.map((f) => (100 * f).toFixed(1) + "%").join(" / ")}, ` +
    `${loaded.count} meshes loaded, ${inputs.length} inputs shown in turn, colourings and wireframe change the picture, ` +
    `linked view restored, screenshot ${path.relative(process.cwd(), shot)}`);
} finally {
  await browser.close();
  server.close();
}
if (problems.length) {
  console.error(`index.html failed ${problems.length} check(s):\n` + problems.join("\n"));
  process.exit(1);
}
