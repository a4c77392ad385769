// The report's 3D viewer (report/index.html): two meshes of one input side by side, turned
// together; wireframe on or off; triangles plain, coloured by shape (radius ratio) or marked where
// the mesh is open, non-manifold or self-intersecting; both sides shaded (open meshes show their
// inside); each mesh's measures under it; the view (input, extractors, options, camera) kept in
// the address's #fragment, so a view can be linked. Uses the pinned three.js in
// report/vendor/three (global THREE).
// It sets document.body.dataset.status to "ready" once both views have drawn a mesh, "file" when
// opened from file:// (browsers refuse fetch there), or "error"; the browser check reads it.
(function () {
  "use strict";
  const meshes = window.ISOLAB_MESHES || [];
  const status = document.getElementById("status");
  const say = (state, text) => {
    document.body.dataset.status = state;
    status.textContent = text;
  };
  if (location.protocol === "file:") {
    say("file", "The viewer loads its meshes with fetch, which browsers refuse for file:// pages. Serve the folder " +
      "(python3 -m http.server --directory report) and open the address it prints.");
    return;
  }
  if (!window.THREE || !THREE.GLTFLoader || !THREE.OrbitControls) {
    say("error", "The viewer's scripts (vendor/three) did not load.");
    return;
  }
  if (meshes.length === 0) {
    say("error", "No meshes: run the report's viewer experiment.");
    return;
  }
  const unique = (xs) => xs.filter((x, i) => xs.indexOf(x) === i);
  const inputs = unique(meshes.map((m) => m.input));
  const algorithms = unique(meshes.map((m) => m.algorithm));
  const select = (id, values, chosen) => {
    const el = document.getElementById(id);
    for (const v of values) {
      const o = document.createElement("option");
      o.value = o.textContent = v;
      el.appendChild(o);
    }
    el.value = chosen;
    return el;
  };
  const inputSelect = select("input", inputs, inputs.includes("stanford-bunny") ? "stanford-bunny" : inputs[0]);
  const sides = [
    select("left", algorithms, algorithms.includes("marching-cubes") ? "marching-cubes" : algorithms[0]),
    select("right", algorithms, algorithms.includes("regularised-marching-tetrahedra") ? "regularised-marching-tetrahedra" : algorithms[algorithms.length - 1]),
  ];
  const wire = document.getElementById("wireframe");
  const colour = document.getElementById("colour");

  // The view in the address: #input=..&left=..&right=..&wire=0|1&colour=..&cam=x,y,z,tx,ty,tz.
  const asked = new URLSearchParams(location.hash.replace(/^#/, ""));
  const pick = (el, key) => {
    const v = asked.get(key);
    if (v !== null && Array.from(el.options).some((o) => o.value === v)) el.value = v;
  };
  pick(inputSelect, "input");
  pick(sides[0], "left");
  pick(sides[1], "right");
  pick(colour, "colour");
  if (asked.get("wire") !== null) wire.checked = asked.get("wire") !== "0";
  const askedCamera = (asked.get("cam") || "").split(",").map(Number);
  let cameraFromAddress = askedCamera.length === 6 && askedCamera.every(Number.isFinite) ? askedCamera : null;
  const round = (x) => Math.round(x * 1000) / 1000;
  function remember() {
    const v = views[0];
    const q = new URLSearchParams({ input: inputSelect.value, left: sides[0].value, right: sides[1].value,
      wire: wire.checked ? "1" : "0", colour: colour.value,
      cam: [...v.camera.position.toArray(), ...v.controls.target.toArray()].map(round).join(",") });
    history.replaceState(null, "", "#" + q.toString());
  }

  function view(canvas, label) {
    const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0xf6f6f6);
    const camera = new THREE.PerspectiveCamera(35, 1, 0.001, 1000);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 0.9));
    const light = new THREE.DirectionalLight(0xffffff, 0.7);
    light.position.set(1, 2, 1.5);
    camera.add(light);
    scene.add(camera);
    const controls = new THREE.OrbitControls(camera, canvas);
    return { canvas, label, renderer, scene, camera, controls, root: null, lines: [], meshes: [] };
  }
  const views = [view(document.getElementById("canvas-left"), document.getElementById("label-left")),
    view(document.getElementById("canvas-right"), document.getElementById("label-right"))];

  // Turning one view turns the other.
  let syncing = false;
  views.forEach((v, k) => v.controls.addEventListener("change", () => {
    if (syncing) return;
    syncing = true;
    const o = views[1 - k];
    o.camera.position.copy(v.camera.position);
    o.controls.target.copy(v.controls.target);
    o.controls.update();
    syncing = false;
  }));

  function resize() {
    for (const v of views) {
      const w = v.canvas.clientWidth, h = v.canvas.clientHeight;
      v.renderer.setSize(w, h, false);
      v.camera.aspect = w / Math.max(h, 1);
      v.camera.updateProjectionMatrix();
    }
  }
  window.addEventListener("resize", resize);

  const loader = new THREE.GLTFLoader();
  const GREY = [0.79, 0.84, 0.91];
  const DEFECT = { boundary: [0.9, 0.1, 0.1], nonManifold: [1.0, 0.55, 0.0], intersecting: [0.85, 0.1, 0.8] };
  // Colour of a radius ratio R/2r (1 for equilateral): green at 1, red from 4 on.
  function shapeColour(ratio) {
    const t = Math.min(1, Math.max(0, Math.log(ratio) / Math.log(4)));
    return [0.2 + 0.75 * t, 0.75 - 0.55 * t, 0.3 - 0.1 * t];
  }
  // The radius ratio of triangle (a, b, c) of positions `p`, scaled per axis by `s` (the node's
  // scale: quantized positions are stored over the mesh's box).
  function radiusRatio(p, s, a, b, c) {
    const d = (i, j) => Math.hypot(s[0] * (p[3 * i] - p[3 * j]), s[1] * (p[3 * i + 1] - p[3 * j + 1]), s[2] * (p[3 * i + 2] - p[3 * j + 2]));
    const [x, y, z] = [d(b, c), d(a, c), d(a, b)];
    const half = (x + y + z) / 2;
    const area = Math.sqrt(Math.max(0, half * (half - x) * (half - y) * (half - z)));
    if (area <= 0) return Infinity;
    return (x * y * z / (4 * area)) / (2 * (area / half));
  }
  // Per-triangle colours of an indexed geometry: by shape, and the defects (boundary red,
  // non-manifold orange, self-intersecting magenta), with their counts.
  function triangleColours(geometry, mesh, scale) {
    const index = geometry.index.array;
    const p = geometry.attributes.position.array;
    const n = index.length / 3;
    const edges = new Map();
    const key = (a, b) => (a < b ? a * 4294967296 + b : b * 4294967296 + a);
    for (let t = 0; t < n; t++) {
      for (let k = 0; k < 3; k++) {
        const e = key(index[3 * t + k], index[3 * t + (k + 1) % 3]);
        edges.set(e, (edges.get(e) || 0) + 1);
      }
    }
    const crossing = new Set(mesh.intersecting_triangles || []);
    const shape = new Float32Array(9 * n), defects = new Float32Array(9 * n);
    const counts = { boundary: 0, nonManifold: 0, intersecting: 0 };
    for (let t = 0; t < n; t++) {
      const [a, b, c] = [index[3 * t], index[3 * t + 1], index[3 * t + 2]];
      const uses = [key(a, b), key(b, c), key(c, a)].map((e) => edges.get(e));
      let mark = GREY;
      if (crossing.has(t)) { mark = DEFECT.intersecting; counts.intersecting++; }
      else if (uses.some((u) => u > 2)) { mark = DEFECT.nonManifold; counts.nonManifold++; }
      else if (uses.some((u) => u === 1)) { mark = DEFECT.boundary; counts.boundary++; }
      const q = shapeColour(radiusRatio(p, scale, a, b, c));
      for (let k = 0; k < 3; k++) {
        shape.set(q, 9 * t + 3 * k);
        defects.set(mark, 9 * t + 3 * k);
      }
    }
    return { shape, defects, counts };
  }
  // The legend of the colouring chosen: what each colour means.
  const css = (c) => "rgb(" + c.map((x) => Math.round(255 * x)).join(",") + ")";
  function legend() {
    const box = document.getElementById("legend");
    if (!box) return;
    const swatch = (c, text) => '<span class="swatch" style="background:' + css(c) + '"></span>' + text;
    if (colour.value === "quality") {
      const stops = [1, 1.5, 2, 3, 4].map((r) => css(shapeColour(r)));
      box.innerHTML = "Triangle shape, radius ratio R/2r: 1 (equilateral)" +
        '<span class="ramp" style="background:linear-gradient(to right,' + stops.join(",") + ')"></span>4 or more';
    } else if (colour.value === "defects") {
      box.innerHTML = "Triangles:" + swatch(DEFECT.boundary, "on an open edge") + swatch(DEFECT.nonManifold, "on a non-manifold edge") +
        swatch(DEFECT.intersecting, "self-intersecting") + swatch(GREY, "none of these");
    } else {
      box.innerHTML = "";
    }
  }
  function paint(v) {
    for (const m of v.meshes) {
      const mode = colour.value;
      const colours = mode === "quality" ? m.colours.shape : mode === "defects" ? m.colours.defects : null;
      if (colours) m.object.geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
      m.object.material.vertexColors = colours !== null;
      m.object.material.color.setRGB(...(colours ? [1, 1, 1] : GREY));
      m.object.material.needsUpdate = true;
    }
  }
  const yes = (b) => (b ? "yes" : "no");
  function caption(mesh, counts) {
    const a = mesh.aspect || [NaN, NaN];
    return mesh.algorithm + " at " + mesh.resolution + " samples along the longest side: " + mesh.triangles + " triangles; closed " + yes(mesh.closed) + ", manifold " +
      yes(mesh.manifold) + ", " + (mesh.intersecting_pairs || 0) + " self-intersecting pairs; aspect ratio mean " +
      a[0].toFixed(2) + ", max " + a[1].toFixed(1) + " (marked: " + counts.boundary + " boundary, " + counts.nonManifold +
      " non-manifold, " + counts.intersecting + " self-intersecting triangles)";
  }
  function show(v, mesh) {
    return new Promise((resolve, reject) => {
      loader.load(mesh.path, (gltf) => {
        if (v.root) v.scene.remove(v.root);
        v.lines = [];
        v.meshes = [];
        const root = gltf.scene;
        root.updateMatrixWorld(true);
        const found = [];
        root.traverse((o) => { if (o.isMesh) found.push(o); });
        const counts = { boundary: 0, nonManifold: 0, intersecting: 0 };
        for (const o of found) {
          const colours = triangleColours(o.geometry, mesh, o.getWorldScale(new THREE.Vector3()).toArray());
          for (const k of Object.keys(counts)) counts[k] += colours.counts[k];
          // One vertex per triangle corner, so that each triangle takes its own colour.
          o.geometry = o.geometry.toNonIndexed();
          o.geometry.computeVertexNormals();
          o.material = new THREE.MeshStandardMaterial({ color: new THREE.Color(...GREY), flatShading: true, metalness: 0,
            roughness: 0.85, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
          const lines = new THREE.LineSegments(new THREE.WireframeGeometry(o.geometry),
            new THREE.LineBasicMaterial({ color: 0x334455, transparent: true, opacity: 0.45 }));
          lines.visible = wire.checked;
          o.add(lines);
          v.lines.push(lines);
          v.meshes.push({ object: o, colours });
        }
        paint(v);
        v.scene.add(root);
        v.root = root;
        v.label.textContent = caption(mesh, counts);
        resolve(root);
      }, undefined, (err) => reject(new Error(mesh.path + ": " + (err && err.message ? err.message : err))));
    });
  }

  function frame(root) {
    const box = new THREE.Box3().setFromObject(root);
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length() || 1;
    for (const v of views) {
      v.controls.target.copy(centre);
      v.camera.position.copy(centre).add(new THREE.Vector3(0.9, 0.6, 1.2).normalize().multiplyScalar(1.7 * size));
      v.camera.near = size / 1000;
      v.camera.far = size * 100;
      v.camera.updateProjectionMatrix();
      v.controls.update();
    }
  }

  let generation = 0;
  function update() {
    const input = inputSelect.value;
    const chosen = sides.map((s) => meshes.find((m) => m.input === input && m.algorithm === s.value));
    if (chosen.some((m) => !m)) {
      say("error", "No mesh of " + input + " for one of the chosen extractors.");
      return;
    }
    const mine = ++generation;
    say("loading", "Loading " + input + "...");
    Promise.all(chosen.map((m, k) => show(views[k], m))).then((roots) => {
      if (mine !== generation) return;
      frame(roots[0]);
      if (cameraFromAddress) {
        for (const v of views) {
          v.camera.position.fromArray(cameraFromAddress.slice(0, 3));
          v.controls.target.fromArray(cameraFromAddress.slice(3));
          v.controls.update();
        }
        cameraFromAddress = null;
      }
      resize();
      draw();
      remember();
      say("ready", input + " at " + chosen[0].resolution + " samples along its longest side: drag to turn both, scroll to zoom.");
    }).catch((err) => {
      say("error", "Could not load a mesh: " + err.message);
      console.error(err);
    });
  }
  wire.addEventListener("change", () => {
    for (const v of views) v.lines.forEach((l) => { l.visible = wire.checked; });
    remember();
  });
  colour.addEventListener("change", () => {
    views.forEach(paint);
    legend();
    remember();
  });
  views.forEach((v) => v.controls.addEventListener("end", remember));
  inputSelect.addEventListener("change", update);
  sides.forEach((s) => s.addEventListener("change", update));

  function draw() {
    for (const v of views) v.renderer.render(v.scene, v.camera);
  }
  (function loop() {
    draw();
    requestAnimationFrame(loop);
  })();
  resize();
  legend();
  update();
})();
