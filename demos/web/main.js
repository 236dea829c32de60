// carom in a web page: hand-written glue for the plain `extern "C"` exports of
// src/lib.rs (no wasm-bindgen, no npm, no build step) and a 2D-canvas renderer with a
// perspective camera.
//
// Normal mode: pick a scene, watch it run at 60 steps a second, orbit the camera, throw
// boxes and fire bullets from it.
// Test mode, `index.html?scene=mixed&steps=1000&test=1`: load the scene, run exactly
// `steps` steps synchronously, draw the last frame, write the checksum into #checksum and
// set the title to `done 0x<checksum>` (`error: ...` on a failure), and POST the same
// outcome to the server's /result, which test.sh waits for.
"use strict";

const WASM_URL = "pkg/carom_demo_web.wasm";
const BODY_FLOATS = 16; // src/lib.rs BODY_FLOATS
const MAX_STEPS_PER_CALL = 100000; // src/lib.rs MAX_STEPS_PER_CALL
const DT_MS = 1000 / 60; // carom's default fixed step
const ERRORS = { "-1": "no such scene", "-2": "hulls could not be built",
  "-3": "invalid input", "-4": "world full", "-5": "carom refused the scene" };
const FLAG_STATIC = 1, FLAG_KINEMATIC = 2, FLAG_AWAKE = 4, FLAG_SPAWNED = 8;
const NEAR = 0.05; // near plane (m)
const LIGHT = norm([0.35, 1.0, 0.45]);

// Where each scene's camera looks: target, distance, yaw, pitch (radians).
const CAMERAS = {
  mixed: { target: [0, 1.5, 0], dist: 15, yaw: 0.55, pitch: 0.62 },
  bullets: { target: [0, 3, 0], dist: 15, yaw: 0.6, pitch: 0.35 },
  tower: { target: [0, 4.5, 0], dist: 15, yaw: 0.5, pitch: 0.4 },
  pyramid10: { target: [0, 3, 0], dist: 15, yaw: 0.35, pitch: 0.3 },
};
const DEFAULT_CAMERA = { target: [0, 2, 0], dist: 15, yaw: 0.5, pitch: 0.4 };

// --- small vector helpers --------------------------------------------------------------
function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function scale(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function cross(a, b) {
  return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
}
function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return scale(a, 1 / l); }
// Rotate v by the unit quaternion q = [x, y, z, w].
function rotate(q, v) {
  const u = [q[0], q[1], q[2]], w = q[3];
  const t = scale(cross(u, v), 2);
  return add(add(v, scale(t, w)), cross(u, t));
}

// --- the module ---------------------------------------------------------------------------
let ex = null; // the instance's exports
const hulls = []; // per reference hull: { verts: [[x,y,z]], faces: [[i, ...]] }
let sceneNames = [];

async function loadWasm() {
  const response = await fetch(WASM_URL);
  if (!response.ok) throw new Error(`${WASM_URL}: HTTP ${response.status}`);
  const { instance } = await WebAssembly.instantiate(await response.arrayBuffer(), {});
  ex = instance.exports;
  const names = [];
  for (let i = 0; i < ex.carom_scene_count(); i++) {
    const bytes = new Uint8Array(ex.memory.buffer, ex.carom_scene_name_ptr(i),
      ex.carom_scene_name_len(i));
    names.push(new TextDecoder().decode(bytes));
  }
  sceneNames = names;
  for (let i = 0; i < ex.carom_hull_count(); i++) {
    const len = ex.carom_hull(i);
    const f = new Float32Array(ex.memory.buffer, ex.carom_hull_ptr(), len).slice();
    const nv = f[0], nf = f[1];
    const verts = [];
    for (let k = 0; k < nv; k++) verts.push([f[2 + 3 * k], f[3 + 3 * k], f[4 + 3 * k]]);
    const faces = [];
    let at = 2 + 3 * nv;
    for (let k = 0; k < nf && at < len; k++) {
      const n = f[at];
      faces.push(Array.from(f.subarray(at + 1, at + 1 + n)));
      at += 1 + n;
    }
    hulls.push({ verts, faces });
  }
}

function checksumHex() {
  const hi = ex.carom_checksum_hi() >>> 0, lo = ex.carom_checksum_lo() >>> 0;
  return "0x" + hi.toString(16).padStart(8, "0") + lo.toString(16).padStart(8, "0");
}

// Run `n` steps; returns the wall time in ms measured with performance.now().
function runSteps(n) {
  const t0 = performance.now();
  while (n > 0) {
    const k = Math.min(n, MAX_STEPS_PER_CALL);
    ex.carom_step(k);
    n -= k;
  }
  return performance.now() - t0;
}

// --- camera -----------------------------------------------------------------------------
const cam = { target: [0, 2, 0], dist: 15, yaw: 0.5, pitch: 0.4, eye: [0, 0, 0],
  f: [0, 0, 1], r: [1, 0, 0], u: [0, 1, 0], focal: 500, cx: 0, cy: 0 };

function setCamera(name) {
  const c = CAMERAS[name] || DEFAULT_CAMERA;
  cam.target = c.target.slice();
  cam.dist = c.dist;
  cam.yaw = c.yaw;
  cam.pitch = c.pitch;
}

function updateCamera(width, height) {
  const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
  const offset = [cp * Math.sin(cam.yaw), sp, cp * Math.cos(cam.yaw)];
  cam.eye = add(cam.target, scale(offset, cam.dist));
  cam.f = norm(sub(cam.target, cam.eye));
  cam.r = norm(cross(cam.f, [0, 1, 0]));
  cam.u = cross(cam.r, cam.f);
  cam.focal = 0.5 * height / Math.tan((50 * Math.PI / 180) / 2); // 50° vertical field
  cam.cx = width / 2;
  cam.cy = height / 2;
}

function toCamera(p) {
  const d = sub(p, cam.eye);
  return [dot(d, cam.r), dot(d, cam.u), dot(d, cam.f)];
}

function project(c) {
  return [cam.cx + cam.focal * c[0] / c[2], cam.cy - cam.focal * c[1] / c[2]];
}

// Clip a camera-space polygon to z >= NEAR (Sutherland-Hodgman against one plane).
function clipNear(poly) {
  const out = [];
  for (let i = 0; i < poly.length; i++) {
    const a = poly[i], b = poly[(i + 1) % poly.length];
    const ina = a[2] >= NEAR, inb = b[2] >= NEAR;
    if (ina) out.push(a);
    if (ina !== inb) {
      const t = (NEAR - a[2]) / (b[2] - a[2]);
      out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), NEAR]);
    }
  }
  return out;
}

// --- drawing ----------------------------------------------------------------------------
const canvas = document.getElementById("canvas");
const ctx = canvas.getContext("2d");

const CUBE_FACES = [ // corner indices (bit 0: +x, bit 1: +y, bit 2: +z), outward winding
  [0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5],
];

function baseColor(kind, flags) {
  if (flags & FLAG_SPAWNED) return kind === 0 ? [255, 90, 80] : [250, 200, 70];
  if (flags & FLAG_STATIC) return [120, 130, 150];
  switch (kind) {
    case 0: return [235, 140, 70]; // sphere
    case 1: return [70, 190, 170]; // capsule
    case 2: return [90, 140, 230]; // cuboid
    case 3: return [175, 120, 220]; // hull
    default: return [200, 200, 200];
  }
}

function shade(rgb, k, asleep, alpha) {
  let [r, g, b] = rgb.map((x) => x * k);
  if (asleep) { // desaturate sleeping bodies
    const grey = (r + g + b) / 3;
    r = 0.45 * r + 0.55 * grey; g = 0.45 * g + 0.55 * grey; b = 0.45 * b + 0.55 * grey;
  }
  return `rgba(${r | 0},${g | 0},${b | 0},${alpha})`;
}

// A polygon item for the painter's sort; `world` are world-space corners, counter-
// clockwise seen from outside. Returns null when culled.
function polygonItem(world, rgb, flags) {
  const isStatic = (flags & FLAG_STATIC) !== 0;
  const n = norm(cross(sub(world[1], world[0]), sub(world[2], world[0])));
  const facing = dot(n, sub(cam.eye, world[0])) > 0;
  if (!facing && !isStatic) return null;
  const pts = clipNear(world.map(toCamera));
  if (pts.length < 3) return null;
  let depth = 0;
  for (const p of pts) depth += p[2];
  depth /= pts.length;
  const k = 0.4 + 0.6 * Math.max(0, dot(n, LIGHT));
  const asleep = !(flags & FLAG_AWAKE) && !isStatic;
  return {
    depth, isStatic,
    draw() {
      ctx.beginPath();
      pts.forEach((p, i) => {
        const s = project(p);
        if (i === 0) ctx.moveTo(s[0], s[1]); else ctx.lineTo(s[0], s[1]);
      });
      ctx.closePath();
      if (isStatic) {
        ctx.fillStyle = shade(rgb, k, false, facing ? 0.16 : 0.1);
        ctx.fill();
        ctx.strokeStyle = "rgba(170,180,200,0.35)";
      } else {
        ctx.fillStyle = shade(rgb, k, asleep, 1);
        ctx.fill();
        ctx.strokeStyle = shade(rgb, k * 0.55, asleep, 1);
      }
      ctx.lineWidth = 1;
      ctx.stroke();
    },
  };
}

function sphereItem(pos, q, radius, vel, rgb, flags) {
  const c = toCamera(pos);
  if (c[2] < NEAR + radius) return null;
  const s = project(c);
  // Fast balls (bullets) get a streak: where they were a step ago.
  const fast = dot(vel, vel) > 20 * 20;
  const tail = fast ? toCamera(sub(pos, scale(vel, DT_MS / 1000))) : null;
  const r = Math.max(1.5, cam.focal * radius / c[2]);
  const pole = toCamera(add(pos, rotate(q, [0, radius, 0])));
  const asleep = !(flags & FLAG_AWAKE);
  return {
    depth: c[2], isStatic: false,
    draw() {
      if (tail && tail[2] > NEAR) {
        const t = project(tail);
        ctx.beginPath();
        ctx.moveTo(t[0], t[1]);
        ctx.lineTo(s[0], s[1]);
        ctx.strokeStyle = shade(rgb, 1, false, 0.6);
        ctx.lineWidth = Math.max(1, r);
        ctx.stroke();
      }
      const g = ctx.createRadialGradient(s[0] - 0.35 * r, s[1] - 0.35 * r, 0.1 * r,
        s[0], s[1], r);
      g.addColorStop(0, shade(rgb, 1.15, asleep, 1));
      g.addColorStop(1, shade(rgb, 0.5, asleep, 1));
      ctx.beginPath();
      ctx.arc(s[0], s[1], r, 0, 2 * Math.PI);
      ctx.fillStyle = g;
      ctx.fill();
      if (r > 4 && pole[2] < c[2] && pole[2] > NEAR) { // a mark that shows it rolling
        const p = project(pole);
        ctx.beginPath();
        ctx.moveTo(s[0], s[1]);
        ctx.lineTo(p[0], p[1]);
        ctx.strokeStyle = shade(rgb, 0.35, asleep, 0.8);
        ctx.lineWidth = Math.max(1, r / 8);
        ctx.stroke();
      }
    },
  };
}

function capsuleItem(pos, q, halfHeight, radius, rgb, flags) {
  const a = toCamera(add(pos, rotate(q, [0, -halfHeight, 0])));
  const b = toCamera(add(pos, rotate(q, [0, halfHeight, 0])));
  if (a[2] < NEAR + radius || b[2] < NEAR + radius) return null;
  const depth = 0.5 * (a[2] + b[2]);
  const sa = project(a), sb = project(b);
  const w = Math.max(2, 2 * cam.focal * radius / depth);
  const asleep = !(flags & FLAG_AWAKE);
  return {
    depth, isStatic: false,
    draw() {
      ctx.lineCap = "round";
      ctx.beginPath();
      ctx.moveTo(sa[0], sa[1]);
      ctx.lineTo(sb[0], sb[1]);
      ctx.strokeStyle = shade(rgb, 0.5, asleep, 1);
      ctx.lineWidth = w;
      ctx.stroke();
      ctx.strokeStyle = shade(rgb, 0.95, asleep, 1);
      ctx.lineWidth = w * 0.7;
      ctx.stroke();
      ctx.lineCap = "butt";
    },
  };
}

function draw() {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  updateCamera(w, h);
  const sky = ctx.createLinearGradient(0, 0, 0, h);
  sky.addColorStop(0, "#262b36");
  sky.addColorStop(1, "#111318");
  ctx.fillStyle = sky;
  ctx.fillRect(0, 0, w, h);

  const n = ex.carom_bodies();
  const f = new Float32Array(ex.memory.buffer, ex.carom_bodies_ptr(), n * BODY_FLOATS);
  const items = [];
  for (let i = 0; i < n; i++) {
    const o = i * BODY_FLOATS;
    const kind = f[o], flags = f[o + 1];
    const pos = [f[o + 2], f[o + 3], f[o + 4]];
    const q = [f[o + 5], f[o + 6], f[o + 7], f[o + 8]];
    const p0 = f[o + 9], p1 = f[o + 10], p2 = f[o + 11];
    const hull = f[o + 15];
    const rgb = baseColor(kind, flags);
    const corner = (local) => add(pos, rotate(q, local));
    if (kind === 0) {
      items.push(sphereItem(pos, q, p0, [f[o + 12], f[o + 13], f[o + 14]], rgb, flags));
    } else if (kind === 1) {
      items.push(capsuleItem(pos, q, p0, p1, rgb, flags));
    } else if (kind === 2 || (kind === 3 && !hulls[hull])) { // hulls unknown: their box
      const c = [];
      for (let k = 0; k < 8; k++) {
        c.push(corner([k & 1 ? p0 : -p0, k & 2 ? p1 : -p1, k & 4 ? p2 : -p2]));
      }
      for (const face of CUBE_FACES) items.push(polygonItem(face.map((k) => c[k]), rgb, flags));
    } else if (kind === 3) {
      const geom = hulls[hull];
      const verts = geom.verts.map(corner);
      for (const face of geom.faces) {
        if (face.length >= 3) items.push(polygonItem(face.map((k) => verts[k]), rgb, flags));
      }
    }
    // Half-spaces and triangles: not used by the page's scenes, not drawn.
  }
  // Static bodies (ground, walls) first and see-through, then the rest far to near.
  const drawn = items.filter((x) => x);
  drawn.sort((a, b) => (a.isStatic === b.isStatic ? b.depth - a.depth : a.isStatic ? -1 : 1));
  for (const item of drawn) item.draw();
}

// --- page -------------------------------------------------------------------------------
const $ = (id) => document.getElementById(id);
let playing = true;
let lastStepMs = NaN;
let avgStepMs = NaN;

function showError(code, what) {
  $("error").textContent = code < 0 ? `${what}: ${ERRORS[code] || code}` : "";
}

function loadScene(index) {
  const code = ex.carom_load(index);
  showError(code, "load");
  setCamera(sceneNames[index]);
  lastStepMs = NaN;
  avgStepMs = NaN;
  $("scene").value = String(index);
  const url = new URL(window.location.href);
  if (url.searchParams.get("scene") !== sceneNames[index] && !url.searchParams.has("test")) {
    url.searchParams.set("scene", sceneNames[index]);
    window.history.replaceState(null, "", url);
  }
  return code;
}

function stepTimed(n) {
  const ms = runSteps(n) / n;
  lastStepMs = ms;
  avgStepMs = Number.isNaN(avgStepMs) ? ms : 0.95 * avgStepMs + 0.05 * ms;
}

function ms(x) { return `${x.toFixed(x < 1 ? 3 : 2)} ms`; }

function updateStats() {
  $("steps").textContent = String(ex.carom_step_count());
  $("steptime").textContent = Number.isNaN(lastStepMs) ? "-"
    : `${ms(lastStepMs)} (avg ${ms(avgStepMs)})`;
  $("bodies").textContent = String(ex.carom_body_count());
  $("awake").textContent = String(ex.carom_awake_count());
  $("contacts").textContent = String(ex.carom_contact_count());
  $("checksum").textContent = checksumHex();
  $("play").textContent = playing ? "pause" : "play";
}

// Spawn in front of the camera, moving along its view direction.
function throwBox() {
  const p = add(cam.eye, cam.f);
  const v = add(scale(cam.f, 14), [0, 2, 0]);
  showError(ex.carom_throw_box(p[0], p[1], p[2], v[0], v[1], v[2], 0.3), "throw");
}

function fireBullet() {
  const p = add(cam.eye, cam.f);
  const v = scale(cam.f, 150);
  showError(ex.carom_fire_bullet(p[0], p[1], p[2], v[0], v[1], v[2]), "fire");
}

function fillScenePicker() {
  sceneNames.forEach((name, i) => {
    const opt = document.createElement("option");
    opt.value = String(i);
    opt.textContent = name;
    $("scene").appendChild(opt);
  });
}

function setupControls() {
  const select = $("scene");
  select.addEventListener("change", () => loadScene(Number(select.value)));
  $("reset").addEventListener("click", () => loadScene(ex.carom_scene()));
  $("play").addEventListener("click", () => { playing = !playing; });
  $("stepone").addEventListener("click", () => { playing = false; stepTimed(1); });
  $("throw").addEventListener("click", throwBox);
  $("fire").addEventListener("click", fireBullet);
  window.addEventListener("keydown", (e) => {
    if (e.target instanceof HTMLSelectElement) return;
    const key = e.key.toLowerCase();
    if (key === " ") { playing = !playing; e.preventDefault(); }
    else if (key === "s") { playing = false; stepTimed(1); }
    else if (key === "b") throwBox();
    else if (key === "f") fireBullet();
    else if (key === "r") loadScene(ex.carom_scene());
  });
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY };
    canvas.setPointerCapture(e.pointerId);
    canvas.style.cursor = "grabbing";
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    cam.yaw -= (e.clientX - drag.x) * 0.006;
    cam.pitch = Math.min(1.5, Math.max(-1.5, cam.pitch + (e.clientY - drag.y) * 0.006));
    drag = { x: e.clientX, y: e.clientY };
  });
  const release = () => { drag = null; canvas.style.cursor = "grab"; };
  canvas.addEventListener("pointerup", release);
  canvas.addEventListener("pointercancel", release);
  canvas.addEventListener("wheel", (e) => {
    cam.dist = Math.min(200, Math.max(2, cam.dist * Math.exp(e.deltaY * 0.001)));
    e.preventDefault();
  }, { passive: false });
}

// Run the page at 60 steps per second of wall time (at most 4 steps per frame).
function animate() {
  let last = performance.now();
  let owed = 0;
  const frame = (now) => {
    if (playing) {
      owed = Math.min(owed + (now - last), 4 * DT_MS);
      const n = Math.floor(owed / DT_MS);
      if (n > 0) {
        owed -= n * DT_MS;
        stepTimed(n);
      }
    } else {
      owed = 0;
    }
    last = now;
    draw();
    updateStats();
    requestAnimationFrame(frame);
  };
  requestAnimationFrame(frame);
}

// Test mode: exactly `steps` steps, one frame, the checksum in #checksum and the title.
function runTest(params) {
  const name = params.get("scene") || "mixed";
  const index = sceneNames.indexOf(name);
  if (index < 0) throw new Error(`unknown scene ${name}`);
  const stepsText = params.get("steps") || "";
  if (!/^[0-9]{1,9}$/.test(stepsText)) throw new Error(`bad steps "${stepsText}"`);
  const steps = Number(stepsText);
  const code = loadScene(index);
  if (code < 0) throw new Error(`load ${name}: ${ERRORS[code] || code}`);
  playing = false;
  const ms = runSteps(steps);
  // Under headless Chromium's virtual time the clock stands still during the run: 0 ms.
  lastStepMs = steps > 0 && ms > 0 ? ms / steps : NaN;
  avgStepMs = lastStepMs;
  draw();
  updateStats();
  const hex = checksumHex();
  $("checksum").textContent = hex;
  document.title = `done ${hex}`;
  console.log(`carom test: ${name} ${steps} ${hex} in ${ms.toFixed(0)} ms`);
  reportResult(`${name} ${steps} ${hex} ${ms.toFixed(0)}`);
}

// Test mode: tell the server (serve.mjs) how the run ended; test.sh reads its log.
function reportResult(line) {
  fetch("result", { method: "POST", body: line }).catch((e) => console.error(e));
}

async function main() {
  const params = new URLSearchParams(window.location.search);
  try {
    await loadWasm();
    fillScenePicker();
    if (params.get("test") === "1") {
      runTest(params);
      return;
    }
    setupControls();
    const wanted = sceneNames.indexOf(params.get("scene") || "");
    loadScene(wanted >= 0 ? wanted : 0);
    animate();
  } catch (e) {
    $("error").textContent = String(e && e.message ? e.message : e);
    document.title = `error: ${$("error").textContent}`;
    console.error(e);
    if (params.get("test") === "1") reportResult(document.title);
  }
}

main();
