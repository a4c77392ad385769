// The report's 3D viewer (report/index.html): two meshes of one input side by side, turned
// together; wireframe on or off. Uses the pinned three.js in report/vendor/three (global THREE).
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
    return { canvas, label, renderer, scene, camera, controls, root: null, lines: [] };
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
  function show(v, mesh) {
    return new Promise((resolve, reject) => {
      loader.load(mesh.path, (gltf) => {
        if (v.root) v.scene.remove(v.root);
        v.lines = [];
        const root = gltf.scene;
        root.traverse((o) => {
          if (!o.isMesh) return;
          o.geometry.computeVertexNormals();
          o.material = new THREE.MeshStandardMaterial({ color: 0xc9d6e8, flatShading: true, metalness: 0, roughness: 0.85,
            polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
          const lines = new THREE.LineSegments(new THREE.WireframeGeometry(o.geometry),
            new THREE.LineBasicMaterial({ color: 0x334455, transparent: true, opacity: 0.45 }));
          lines.visible = wire.checked;
          o.add(lines);
          v.lines.push(lines);
        });
        v.scene.add(root);
        v.root = root;
        v.label.textContent = mesh.algorithm + ": " + mesh.triangles + " triangles";
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
      resize();
      draw();
      say("ready", input + " at " + chosen[0].resolution + " samples along its longest side: drag to turn both, scroll to zoom.");
    }).catch((err) => {
      say("error", "Could not load a mesh: " + err.message);
      console.error(err);
    });
  }
  wire.addEventListener("change", () => {
    for (const v of views) v.lines.forEach((l) => { l.visible = wire.checked; });
  });
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
  update();
})();
